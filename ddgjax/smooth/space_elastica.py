"""Smooth elastic curves in space, by the Kirchhoff analogy: the oracle for non-planar limits.

By Thm 3.1 an arc-length curve `γ: [0, L] → R³` is an elastic curve iff its tangent `T = γ'`
moves like a spherical pendulum, and by Thm 3.2 that motion is

    T'' = c(s) T + a,   c = −|T'|² − ⟨a, T⟩,

the multiplier `c` of `|T|² = 1` being fixed by differentiating `⟨T, T⟩ = 1` twice
(`⟨T, T''⟩ = −|T'|²`).  Given `T(0)`, `T'(0) ⊥ T(0)` and the load `a`, the curve is
`γ(s) = ∫₀^s T`, integrated with `(γ, T, T')` as one first-order system (scipy's DOP853, an
eighth-order Runge–Kutta method, at relative and absolute tolerance 1e-13, with its dense output).
Unlike the planar curves of `ddgjax.smooth.elastica` these have no closed form; by Remark 3.2
they span R³ when `γ(L) − γ(0)`, `T(0)`, `T(L)` do (`spans_space`).  Everything is numpy/scipy
float64, evaluated outside JAX, and uses no discrete energy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import InvalidInputError
from .elastica import BoundaryData

__all__ = ["SpaceElastica", "space_elastica", "pendulum_field"]

TOLERANCE = 1e-13


def pendulum_field(s: float, y: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The right side of `(γ, T, T')' = (T, T', cT + a)`, `c = −|T'|² − ⟨a, T⟩` (Thm 3.1, 3.2),
    for the state `y = (γ, T, T')` (9,)."""
    T, dT = y[3:6], y[6:9]
    c = -dT @ dT - a @ T
    return np.concatenate([T, dT, c * T + a])


@dataclass(frozen=True)
class SpaceElastica:
    """An elastic curve in R³ with `γ(0) = 0`, parametrised by arc length `s ∈ [0, length]`:
    the spherical pendulum `T'' = cT + a` started from `T(0)`, `T'(0)` (`space_elastica`).
    Methods take `s` of shape `(m,)` (or a scalar) within `[0, length]`."""

    a: np.ndarray
    length: float
    dense: object  # scipy's OdeSolution of (γ, T, T')

    def state(self, s) -> np.ndarray:
        """`(γ, T, T')` at the arc lengths s: shape `(..., 9)`.  **Raises:** `InvalidInputError`
        for an arc length outside [0, length] (the dense output would extrapolate)."""
        s = np.asarray(s, dtype=float)
        outside = ~((s >= 0.0) & (s <= self.length))
        if np.any(outside):
            raise InvalidInputError(f"arc length {s[outside].flat[0]!r} is outside [0, {self.length!r}]")
        return np.moveaxis(self.dense(s), 0, -1)

    def gamma(self, s) -> np.ndarray:
        return self.state(s)[..., 0:3]

    def tangent(self, s) -> np.ndarray:
        """`T(s)`, renormalised (the integrator keeps |T| = 1 to its tolerance)."""
        T = self.state(s)[..., 3:6]
        return T / np.linalg.norm(T, axis=-1, keepdims=True)

    def boundary_data(self) -> BoundaryData:
        end = self.gamma(self.length)
        return BoundaryData(start=np.zeros(3), end=end, chord=end, start_tangent=self.tangent(0.0),
                            end_tangent=self.tangent(self.length), length=self.length)

    def spans_space(self) -> float:
        """`|det(γ(L) − γ(0), T(0), T(L))|`: zero iff the curve lies in a plane through its chord
        and its end tangents (Remark 3.2)."""
        data = self.boundary_data()
        return abs(float(np.linalg.det(np.stack([data.chord, data.start_tangent, data.end_tangent]))))


def space_elastica(start_tangent, start_derivative, a, length: float = 1.0) -> SpaceElastica:
    """The elastic curve with `T(0) = start_tangent` (unit), `T'(0) = start_derivative` (its
    curvature vector, ⊥ T(0)) and load `a`, of arc length `length`.

    **Raises:** `InvalidInputError` for non-finite data, a tangent that is not a unit vector, a
    `T'(0)` not orthogonal to it, or a length that is not positive (each to 1e-12)."""
    T0, dT0, a = (np.asarray(v, dtype=float).reshape(3) for v in (start_tangent, start_derivative, a))
    if not all(np.all(np.isfinite(v)) for v in (T0, dT0, a)) or not np.isfinite(length) or length <= 0:
        raise InvalidInputError("space_elastica needs finite vectors and a finite positive length")
    if abs(np.linalg.norm(T0) - 1) > 1e-12:
        raise InvalidInputError(f"start_tangent must be a unit vector, |T(0)| = {np.linalg.norm(T0)!r}")
    if abs(T0 @ dT0) > 1e-12 * max(1.0, np.linalg.norm(dT0)):
        raise InvalidInputError(f"start_derivative must be orthogonal to start_tangent, ⟨T, T'⟩ = {T0 @ dT0!r}")
    solution = solve_ivp(pendulum_field, (0.0, float(length)), np.concatenate([np.zeros(3), T0, dT0]), method="DOP853",
                         rtol=TOLERANCE, atol=TOLERANCE, dense_output=True, args=(a,))
    return SpaceElastica(a=a, length=float(length), dense=solution.sol)
