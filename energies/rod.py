"""Discrete isotropic elastic rods (Def 3.6, 3.7, Remark 3.16): a framed polygon declared as an
energy of unit quaternion edge frames.

Unknowns: one unit quaternion Φ_k per edge (n, 4); the edge tangent is `T_k = Φ_k i Φ_k⁻¹`
(`quaternion.rotate(Φ_k, e1)`).  With edge length h = L/n the energy is

    (2/h) Σ_k E_k(T_{k−1}, T_k)  +  (α / 2h) Σ_k θ_k²,

the discrete elastica's bending term (`elastica.bending_density`, → ½∫κ²) plus α times the
squared discrete twist angles θ_k of `Φ_k Φ_{k−1}⁻¹ = t_k b_k` (`frames.twist_angle`, θ_k/h → τ),
so that the smooth limit is ½∫(κ² + ατ²) ds.  Constraints (named, as for the elastica):
`"unit"`, |Φ_k|² − 1 = 0 for the free frames, and `"chord"`, `c − h Σ T_k = 0` (3,).

**Clamps** (as for `elastica.clamped`).  `clamp="edge"`: the end frames Φ_0, Φ_{n−1} are fixed.
They are the frames of the first and last *edge*, i.e. of the smooth rod at s = h/2 and
L − h/2, so the discrete rod is only O(h) close to the smooth rod clamped at s = 0, L.
`clamp="vertex"` prescribes the frame at the end *vertex*: all n frames are free and the end
vertex gets the vertex energy at half weight with a ghost frame, the reflection of Φ_0 in the
clamp q in the group, `Φ_{−1} = q Φ_0⁻¹ q` (so q is the geodesic midpoint of Φ_{−1} and Φ_0;
if Φ_0 = q exp(v) then Φ_{−1} = q exp(−v)); likewise at the other end.  This boundary
condition is second order: the smooth-limit tests measure O(h²) against the smooth rod of
Thm 3.13 computed by shooting (`ddgjax.kirchhoff`).

**Multipliers.**  The Lagrangian `E − λ·(c − h Σ T_k)` tends to `½ ∫ (κ² + ατ² + 2<λ, T>) ds`,
half the rod functional `E_a` of Sec 3.5 with `a = λ`: `load(solution)` returns the chord
multipliers, the smooth load `a` of Thm 3.13 (i) in the limit.

Since the bending term does not see a rotation of Φ_k about T_k, stationarity in that direction
gives θ_k = θ_{k+1}: the discrete twist of a critical rod is constant (the analogue of
Lemma 3.12, τ' = 0), which the tests check.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import frames
from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError

from .elastica import bending_density, checked_chord, clamp_ends, starting_array, unit_and_chord

__all__ = ["clamped", "tangents", "twist_angles", "curve", "load", "ClampMismatchError"]


class ClampMismatchError(InvalidInputError):
    """An end frame whose tangent `Φ i Φ⁻¹` disagrees with the prescribed end tangent."""

E1 = jnp.array([1.0, 0.0, 0.0])


def _vertex_energy(Phi2, p):
    T_prev, T_next = qt.rotate(Phi2[0], E1), qt.rotate(Phi2[1], E1)
    theta = frames.twist_angle(Phi2[0], Phi2[1])
    return (2.0 / p["h"]) * bending_density(T_prev, T_next) + (p["alpha"] / (2.0 * p["h"])) * theta**2


def _reflected(Phi, q):
    """The reflection `q Φ⁻¹ q` of a unit quaternion Φ in q (q exp(v) ↦ q exp(−v))."""
    return qt.mul(qt.mul(q, qt.conj(Phi)), q)


def _ghost_vertex_energy(Phi1, which, p):
    """Half the vertex energy of an end vertex between its edge frame and the ghost frame."""
    q = jnp.where(which == 0, p["frame_start"], p["frame_end"])
    ghost = _reflected(Phi1[0], q)
    pair = jnp.where(which == 0, jnp.stack([ghost, Phi1[0]]), jnp.stack([Phi1[0], ghost]))
    return 0.5 * _vertex_energy(pair, p)


def _unit(Phi1, _):
    return jnp.dot(Phi1[0], Phi1[0]) - 1.0


def _chord(Phi1, share, p):
    return share * p["chord"] - p["h"] * qt.rotate(Phi1[0], E1)


def _interpolated_frames(q0: np.ndarray, q1: np.ndarray, n: int) -> np.ndarray:
    """Normalised linear interpolation of two unit quaternions (signs aligned): a start."""
    q1 = q1 if q0 @ q1 >= 0 else -q1
    s = np.linspace(0.0, 1.0, n)[:, None]
    Q = (1 - s) * q0 + s * q1
    return Q / np.linalg.norm(Q, axis=1, keepdims=True)


def _check_tangent(frame: np.ndarray, t, name: str) -> None:
    """Raise `ClampMismatchError` if the tangent of `frame` is not the prescribed unit vector t."""
    if t is None:
        return
    t = np.asarray(t, dtype=float)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise InvalidInputError(f"t_{name} must be a finite 3-vector, got {t!r}")
    T = np.asarray(qt.rotate(frame, E1))
    if np.linalg.norm(T - t / np.linalg.norm(t)) > 1e-10:
        raise ClampMismatchError(
            f"frame_{name} has the tangent Φ i Φ⁻¹ = {np.round(T, 12).tolist()}, which disagrees with "
            f"t_{name} = {t.tolist()} (end {'0' if name == 'start' else 'n−1'} of the rod)"
        )


def clamped(
    n: int,
    *,
    alpha: float,
    length: float = 1.0,
    chord,
    frame_start,
    frame_end,
    clamp: str = "edge",
    t_start=None,
    t_end=None,
    x0=None,
) -> dg.Problem:
    """A clamped discrete elastic rod: n unit quaternion edge frames (n, 4), twist stiffness α.

    `frame_start`, `frame_end`: unit quaternions [4], the clamped frames (their tangents are
    `rotate(frame, e1)`), of the end edges (`clamp="edge"`) or the end vertices
    (`clamp="vertex"`, second order; module docstring).  `t_start`, `t_end` (optional): the end
    tangents, checked against the frames.  Constraints `{"unit": (m,), "chord": (3,)}` with
    one unit entry per free frame (m = n − 2 for `clamp="edge"`, n for `"vertex"`).

    **Raises:** `InfeasibleChordError` (|chord| ≥ length), `InvalidInputError` (α ≤ 0, n < 3,
    non-unit frames, unknown clamp), `ClampMismatchError` (a frame's tangent is not the given
    end tangent), `ShapeError`.
    """
    if int(n) < 3:
        raise InvalidInputError(f"a clamped rod needs at least 3 edges, got n = {n}")
    if clamp not in ("edge", "vertex"):
        raise InvalidInputError(f"clamp must be 'edge' or 'vertex', got {clamp!r}")
    if not (np.isfinite(alpha) and alpha > 0):
        raise InvalidInputError(
            f"the twist stiffness alpha must be positive (the reference requires α ≠ 0; α = 0 leaves "
            f"the frames' twist undetermined), got {alpha}"
        )
    chord = checked_chord(chord, length)
    qt.check_unit(frame_start, "frame_start")
    qt.check_unit(frame_end, "frame_end")
    q0, q1 = np.asarray(frame_start, dtype=float), np.asarray(frame_end, dtype=float)
    _check_tangent(q0, t_start, "start")
    _check_tangent(q1, t_end, "end")
    n, h = int(n), float(length) / int(n)
    Phi0 = starting_array(x0, lambda: _interpolated_frames(q0, q1, n), (n, 4))
    edges = np.arange(n)
    energy = dg.local_sum(_vertex_energy, np.stack([edges[:-1], edges[1:]], axis=1))
    if clamp == "edge":
        Phi0, fixed = clamp_ends(Phi0, q0, q1)
        free_edges = edges[1:-1]
    else:
        energy = energy + dg.local_sum(_ghost_vertex_energy, np.array([[0], [n - 1]]), data=np.array([0, 1]))
        fixed, free_edges = np.zeros((n, 4), bool), edges
    constraints = unit_and_chord(free_edges, n, _unit, _chord)
    params = {
        "h": h, "alpha": jnp.asarray(float(alpha)), "chord": jnp.asarray(chord),
        "frame_start": jnp.asarray(q0), "frame_end": jnp.asarray(q1),
    }
    return dg.Problem(
        energy, Phi0, constraints=constraints, params=params, fixed=fixed, name=f"clamped rod (n={n}, clamp={clamp})"
    )


def tangents(Phi) -> jnp.ndarray:
    """Edge tangents T_k = Φ_k i Φ_k⁻¹ (n, 3)."""
    return qt.rotate(jnp.asarray(Phi), E1)


def twist_angles(Phi) -> jnp.ndarray:
    """Discrete twist angles θ_k at the interior vertices (n − 1,)."""
    return frames.edge_frame_split(Phi)[1]


def curve(Phi, problem: dg.Problem, start=(0.0, 0.0, 0.0)) -> jnp.ndarray:
    """The centreline γ_0 … γ_n (n + 1, 3) of edge frames Φ with the problem's edge length."""
    return dg.curves.from_tangents(tangents(Phi), start=start, edge_length=problem.params["h"])


def load(solution) -> jnp.ndarray:
    """The chord multipliers λ = `multipliers["chord"]` (3,): the load `a` of Thm 3.13 (i)
    (module docstring)."""
    return jnp.asarray(solution.multipliers["chord"])
