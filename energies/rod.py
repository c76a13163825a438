"""Discrete elastic rods (Def 3.6, 3.7, Remark 3.16): a framed polygon declared as an energy of
unit quaternion edge frames, isotropic by default, anisotropic with `bending=(b1, b2)`.

Unknowns: one unit quaternion Φ_k per edge (n, 4); the edge tangent is `T_k = Φ_k i Φ_k⁻¹`
(`quaternion.rotate(Φ_k, e1)`).  With edge length h = L/n the energy is

    (2/h) Σ_k E_k(T_{k−1}, T_k)  +  (α / 2h) Σ_k θ_k²,

the discrete elastica's bending term (`elastica.bending_density`, → ½∫κ²) plus α times the
squared discrete twist angles θ_k of `Φ_k Φ_{k−1}⁻¹ = t_k b_k` (`frames.twist_angle`, θ_k/h → τ),
so that the smooth limit is ½∫(κ² + ατ²) ds.  Constraints (named, as for the elastica):
`"unit"`, |Φ_k|² − 1 = 0 for the free frames, and `"chord"`, `c − h Σ T_k = 0` (3,).

**Anisotropic bending** (Remark 3.16, `bending=(b1, b2)`).  The smooth energy
`½ ∫ (b1 κ1² + b2 κ2² + α τ²) ds` with `κ1 = <T', N>`, `κ2 = <T', B>` weighs the bending by
the direction of the curvature vector in the material frame.  Discretely, with the vertex
curvatures `(κ1, κ2)_k = (K3, −K2)` of the half-twisted frame (`frames.discrete_curvatures`),
the bending term becomes

    (2/h) w_k E_k,    w_k = (b1 κ1² + b2 κ2²) / (κ1² + κ2²),

the isotropic E_k = log(1 + h²κ²/4) times the stiffness in the direction of K_k (evaluated as
`(h²/4)(b1 κ1² + b2 κ2²) · log(1 + t)/t`, t = h²κ²/4, smooth at straight vertices).  So
`bending=(β, β)` is β times the isotropic energy with twist stiffness α/β, and `(1, 1)` is the
isotropic rod.  Lemma 3.12 needs isotropy: with b1 ≠ b2 the twist is not constant, the smooth
rod satisfies `α τ' = (b1 − b2) κ1 κ2` (the axial Euler equation of the top with inertia
`diag(α, b2, b1)`).

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

Since the isotropic bending term does not see a rotation of Φ_k about T_k, stationarity in that
direction gives θ_k = θ_{k+1}: the discrete twist of a critical rod is constant (the analogue of
Lemma 3.12, τ' = 0), which the tests check.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax import frames
from ddgjax import quaternion as qt
from ddgjax._checks import check_finite, checked_count, checked_shape, when_concrete
from ddgjax.errors import InvalidInputError

from .elastica import (
    bending_density, checked_chord, checked_length, clamp_ends, finite_scalar, start_data, starting_array,
    unit_and_chord,
)

__all__ = [
    "clamped", "loaded", "twisted_frame", "anisotropic_bending_density", "tangents", "twist_angles", "curve", "load", "ClampMismatchError",
]


class ClampMismatchError(InvalidInputError):
    """An end frame whose tangent `Φ i Φ⁻¹` disagrees with the prescribed end tangent."""

E1 = jnp.array([1.0, 0.0, 0.0])


def _log1p_ratio(t):
    """`log(1 + t)/t` for t ≥ 0, with its value 1 (and series) at t = 0 so that gradients stay finite."""
    small = t < 1e-6
    safe = jnp.where(small, 1.0, t)
    return jnp.where(small, 1.0 - t / 2 + t * t / 3, jnp.log1p(safe) / safe)


def anisotropic_bending_density(
    Phi_prev: Float[Array, "4"], Phi_next: Float[Array, "4"], bending: Float[Array, "2"]
) -> Float[Array, ""]:
    """`w_k E_k = (b1 k1² + b2 k2²)/4 · log(1 + t)/t`, `t = (k1² + k2²)/4 = tan²(φ_k/2)`, with
    `(k1, k2) = h (κ1, κ2)_k` the discrete curvatures of the pair of edge frames
    (`frames.discrete_curvatures` with h = 1) and `bending = (b1, b2)` (Remark 3.16, module
    docstring).  Equals `elastica.bending_density(T_{k−1}, T_k)` for `bending = (1, 1)`."""
    k1, k2, _ = frames.discrete_curvatures(jnp.stack([Phi_prev, Phi_next]), 1.0)
    k1, k2 = k1[0], k2[0]
    return 0.25 * (bending[0] * k1**2 + bending[1] * k2**2) * _log1p_ratio(0.25 * (k1**2 + k2**2))


def _bending_term(Phi2, p):
    """`E_k`, or `w_k E_k` when the problem has anisotropic stiffnesses `p["bending"]`."""
    if "bending" in p:
        return anisotropic_bending_density(Phi2[0], Phi2[1], p["bending"])
    return bending_density(qt.rotate(Phi2[0], E1), qt.rotate(Phi2[1], E1))


def _vertex_energy(Phi2, p):
    theta = frames.twist_angle(Phi2[0], Phi2[1])
    return (2.0 / p["h"]) * _bending_term(Phi2, p) + (p["alpha"] / (2.0 * p["h"])) * theta**2


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


def _interpolated_frames(q0, q1, n: int):
    """Normalised linear interpolation of two unit quaternions (signs aligned): a start, with no
    derivative (`elastica.start_data`)."""
    xp, (q0, q1) = start_data(q0, q1)
    q1 = xp.where(q0 @ q1 >= 0, q1, -q1)
    s = xp.linspace(0.0, 1.0, n)[:, None]
    Q = (1 - s) * q0 + s * q1
    return Q / xp.linalg.norm(Q, axis=1, keepdims=True)


def checked_frame(q, name: str) -> Float[Array, "4"]:
    """An end frame as a traceable (4,) array; when concrete, `NonFiniteError` for NaN and
    `InvalidInputError` unless it is a unit quaternion (naming it)."""
    q = jnp.asarray(q, dtype=float)
    checked_shape(q, (4,), name)
    check_finite(q, name)
    when_concrete(qt.check_unit)(q, name)
    return q


@when_concrete
def _check_tangent(frame, t, name: str) -> None:
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


@when_concrete
def _check_stiffness(alpha) -> None:
    """Raise `InvalidInputError` unless the twist stiffness α is finite and positive."""
    if not (np.isfinite(alpha) and alpha > 0):
        raise InvalidInputError(
            f"the twist stiffness alpha must be positive (the reference requires α ≠ 0; α = 0 leaves "
            f"the frames' twist undetermined), got {alpha}"
        )


def _checked_bending(bending) -> Float[Array, "2"]:
    """The stiffnesses (b1, b2) as a traceable (2,) array: `ShapeError` unless of shape (2,),
    `NonFiniteError` for NaN or inf, `InvalidInputError` unless positive (values when concrete)."""
    bending = jnp.asarray(bending, dtype=float)
    checked_shape(bending, (2,), "bending")
    check_finite(bending, "bending")
    _check_bending(bending)
    return bending


@when_concrete
def _check_bending(bending) -> None:
    """Raise `InvalidInputError` unless both bending stiffnesses are positive."""
    if not np.all(bending > 0):
        raise InvalidInputError(
            f"the bending stiffnesses (b1, b2) of κ1 = <T', N> and κ2 = <T', B> must be positive, "
            f"got {np.asarray(bending).tolist()}"
        )


def clamped(
    n: int,
    *,
    alpha: float,
    bending=None,
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

    `bending` (optional): the stiffnesses `(b1, b2)` of κ1 = <T', N> and κ2 = <T', B>, an
    anisotropic rod (Remark 3.16, module docstring); None, the default, is the isotropic rod
    (b1 = b2 = 1).

    `frame_start`, `frame_end`: unit quaternions [4], the clamped frames (their tangents are
    `rotate(frame, e1)`), of the end edges (`clamp="edge"`) or the end vertices
    (`clamp="vertex"`, second order; module docstring).  `t_start`, `t_end` (optional): the end
    tangents, checked against the frames.  Constraints `{"unit": (m,), "chord": (3,)}` with
    one unit entry per free frame (m = n − 2 for `clamp="edge"`, n for `"vertex"`).

    Differentiable in `alpha`, `bending`, `length`, `chord` and the end frames (traced values in
    `params` and the clamped rows of `x0`, as for `elastica.clamped`).

    **Raises:** `InfeasibleChordError` (|chord| ≥ length), `InvalidInputError` (α ≤ 0 or not
    finite, a bending stiffness ≤ 0, n < 3, a length that is not finite and positive, non-unit
    frames, unknown clamp), `NonFiniteError` (NaN in a frame or the chord, NaN or inf in
    `bending`), `ClampMismatchError` (a frame's tangent is not the given end tangent),
    `ShapeError` (also for `bending` not of shape (2,)).  Values are checked when concrete.
    """
    n = checked_count(n, 3, "n, the number of edges of a clamped rod,")
    if clamp not in ("edge", "vertex"):
        raise InvalidInputError(f"clamp must be 'edge' or 'vertex', got {clamp!r}")
    alpha = jnp.asarray(alpha, dtype=float)
    checked_shape(alpha, (), "alpha")
    _check_stiffness(alpha)
    stiffness = {} if bending is None else {"bending": _checked_bending(bending)}
    length = checked_length(length)
    chord = checked_chord(chord, length)
    q0, q1 = checked_frame(frame_start, "frame_start"), checked_frame(frame_end, "frame_end")
    _check_tangent(q0, t_start, "start")
    _check_tangent(q1, t_end, "end")
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
    params = {"h": length / n, "alpha": alpha, **stiffness, "chord": chord, "frame_start": q0, "frame_end": q1}
    return dg.Problem(
        energy, Phi0, constraints=constraints, params=params, fixed=fixed, name=f"clamped rod (n={n}, clamp={clamp})"
    )


def _load_potential(Phi1, p):
    return p["load"] * p["h"] * qt.rotate(Phi1[0], E1)[0]


def _lateral(Phi1, p):
    return p["h"] * qt.rotate(Phi1[0], E1)[1:]


def twisted_frame(angle):
    """The unit quaternion of the rotation by `angle` about e1: the end frame of a column
    twisted by `angle` (its tangent stays e1)."""
    half = 0.5 * jnp.asarray(angle, dtype=float)
    return jnp.stack([jnp.cos(half), jnp.sin(half), 0.0 * half, 0.0 * half])


def loaded(n: int, *, alpha: float, twist: float = 0.0, load: float = 0.0, length: float = 1.0,
           clamp: str = "vertex", x0=None) -> dg.Problem:
    """A twisted column (Greenhill 1883): the rod of `clamped` along e1, its start frame the
    identity and its end frame turned by ψ = `twist` about e1 (`twisted_frame`), under an end
    load P = `load` (compressive along e1); critical points of

        rod energy (module docstring) + P h Σ_k ⟨T_k, e1⟩    on {|Φ_k| = 1, h Σ_k T_k ⊥ e1},

    as `energies.elastica.loaded` (constraint `"lateral"` (2,): the far end stays on the axis;
    the axial chord is free).  The straight column with uniform twist, Φ_k the rotation by
    ψ s_k/L about e1 (s_k the edge midpoints; the default start), is critical for every (ψ, P):
    a twisting moment M = αψ/L and the load P act on it.  It loses stability in a bifurcation
    into a helical mode (the index jumps by 2: the mode and its turn about the axis): with P = 0
    at M L = 2ξ (bending stiffness 1), ξ the first positive root of tan ξ = ξ, M L ≈ 8.9868
    (Zajac 1962: the lateral displacement w = x + iy of the linearised rod solves w⁗ = iM w‴ with
    w = w′ = 0 at both ends), and with ψ = 0 at P = 4π²/L² (Euler).
    `solvers.continuation` in `twist` (`params["frame_end"] = twisted_frame(ψ)`) or in `load`
    reports it.

    Constraints `{"lateral": (2,), "unit": (m,)}`; params as `clamped` (without the chord) and
    `"load"`.  **Raises:** as `clamped`, and `InvalidInputError` for a non-finite twist or load.
    """
    twist, load = finite_scalar(twist, "twist"), finite_scalar(load, "load")
    n = checked_count(n, 3, "n, the number of edges of a twisted column,")
    q0, q1 = twisted_frame(0.0), twisted_frame(twist)
    s = (np.arange(n) + 0.5) / n if clamp == "vertex" else np.linspace(0.0, 1.0, n)
    column = jnp.stack([twisted_frame(twist * t) for t in s])
    base = clamped(n, alpha=alpha, length=length, chord=(0.5 * length, 0.0, 0.0), frame_start=q0, frame_end=q1,
                   clamp=clamp, x0=column if x0 is None else x0)
    edges = np.arange(n)
    energy = base.energy + dg.local_sum(_load_potential, edges[:, None])
    free_edges = edges[1:-1] if clamp == "edge" else edges
    constraints = dg.concat(unit=dg.local_map(_unit, free_edges[:, None]), lateral=dg.local_sum(_lateral, edges[:, None]))
    params = {k: v for k, v in base.params.items() if k != "chord"} | {"load": load}
    return dg.Problem(energy, base.x0, constraints=constraints, params=params, fixed=base.fixed,
                      name=f"twisted column (n={n}, clamp={clamp})")


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
