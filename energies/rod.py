"""Discrete isotropic elastic rods (Def 3.6, 3.7, Remark 3.16): a framed polygon declared as an
energy of unit quaternion edge frames.

Unknowns: one unit quaternion Φ_k per edge (n, 4); the edge tangent is `T_k = Φ_k i Φ_k⁻¹`
(`quaternion.rotate(Φ_k, e1)`).  With edge length h = L/n the energy is

    (2/h) Σ_k E_k(T_{k−1}, T_k)  +  (α / 2h) Σ_k θ_k²,

the discrete elastica's bending term (`elastica.bending_density`, → ½∫κ²) plus α times the
squared discrete twist angles θ_k of `Φ_k Φ_{k−1}⁻¹ = t_k b_k` (`frames.twist_angle`, θ_k/h → τ),
so that the smooth limit is ½∫(κ² + ατ²) ds.  Constraints: |Φ_k|² = 1 for the free frames and
the chord `c − h Σ T_k = 0`; the end frames Φ_0, Φ_{n−1} are fixed (clamped rod).

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

from .elastica import bending_density, checked_chord, clamp_ends, starting_array

__all__ = ["clamped", "tangents", "twist_angles"]

E1 = jnp.array([1.0, 0.0, 0.0])


def _vertex_energy(Phi2, p):
    T_prev, T_next = qt.rotate(Phi2[0], E1), qt.rotate(Phi2[1], E1)
    theta = frames.twist_angle(Phi2[0], Phi2[1])
    return (2.0 / p["h"]) * bending_density(T_prev, T_next) + (p["alpha"] / (2.0 * p["h"])) * theta**2


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


def clamped(n: int, *, alpha: float, length: float = 1.0, chord, frame_start, frame_end, x0=None) -> dg.Problem:
    """A clamped discrete elastic rod: n unit quaternion edge frames (n, 4), twist stiffness α.

    `frame_start`, `frame_end`: unit quaternions [4] of the clamped end edges (their tangents are
    `rotate(frame, e1)`).

    **Raises:** `InfeasibleChordError` (|chord| ≥ length), `InvalidInputError` (α ≤ 0, n < 3,
    non-unit frames), `ShapeError`.
    """
    if int(n) < 3:
        raise InvalidInputError(f"a clamped rod needs at least 3 edges, got n = {n}")
    if not (np.isfinite(alpha) and alpha > 0):
        raise InvalidInputError(
            f"the twist stiffness alpha must be positive (the reference requires α ≠ 0; α = 0 leaves "
            f"the frames' twist undetermined), got {alpha}"
        )
    chord = checked_chord(chord, length)
    qt.check_unit(frame_start, "frame_start")
    qt.check_unit(frame_end, "frame_end")
    q0, q1 = np.asarray(frame_start, dtype=float), np.asarray(frame_end, dtype=float)
    n, h = int(n), float(length) / int(n)
    Phi0, fixed = clamp_ends(starting_array(x0, lambda: _interpolated_frames(q0, q1, n), (n, 4)), q0, q1)
    edges = np.arange(n)
    energy = dg.local_sum(_vertex_energy, np.stack([edges[:-1], edges[1:]], axis=1))
    constraints = dg.concat(
        dg.local_map(_unit, edges[1:-1, None]),
        dg.local_sum(_chord, edges[:, None], data=np.full(n, 1.0 / n)),
    )
    params = {"h": h, "alpha": jnp.asarray(float(alpha)), "chord": jnp.asarray(chord)}
    return dg.Problem(energy, Phi0, constraints=constraints, params=params, fixed=fixed, name=f"clamped rod (n={n})")


def tangents(Phi) -> jnp.ndarray:
    """Edge tangents T_k = Φ_k i Φ_k⁻¹ (n, 3)."""
    return qt.rotate(jnp.asarray(Phi), E1)


def twist_angles(Phi) -> jnp.ndarray:
    """Discrete twist angles θ_k at the interior vertices (n − 1,)."""
    return frames.edge_frame_split(Phi)[1]
