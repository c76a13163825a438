"""Arc-length preserving flows of smooth planar curves (reference Sec 2.1, Ex 2.2, Ex 2.3).

**The flows.**  A planar geometric flow `∂_t γ = α T + β N` (2.2), with `T' = κ N`, `N' = −κ T`,
changes the speed by `∂_t |γ'| = α' − κβ` (Ex 2.2), so it preserves arc length (2.3) iff
`α' = κβ`.  Then `∂_t κ = (κα + β')'`.  Two solutions:

- `α = 1, β = 0`: the tangent flow `∂_t γ = T` (Ex 2.3), `γ(s, t) = γ(s + t)`, `∂_t κ = κ'`;
- `α = ½κ², β = κ'`: the mKdV flow `∂_t γ = ½κ² T + κ' N` (`mkdv_velocity`), under which the
  curvature obeys the mKdV equation `∂_t κ = κ''' + (3/2) κ² κ'` (`mkdv`).

**A test curve.**  `θ(s) = s + c sin(ms)` is the tangent angle of an arc-length curve of length
2π with curvature `κ = θ' = 1 + cm cos(ms)` (`curvature`).  By Jacobi–Anger,
`e^{iθ} = Σ_j J_j(c) e^{i(1 + jm)s}`, so

    γ(s) = Σ_j J_j(c) e^{i(1 + jm)s} / (i(1 + jm))                               (`position`)

(`γ' = e^{iθ}` term by term).  For m ≥ 2 no frequency 1 + jm vanishes: γ is periodic, a closed
curve.  Its curvature and frame are exact (no quadrature); only the position sums a Bessel
series, truncated where `J_j(c)` falls below round-off.

Everything here is written from the smooth formulas, independently of the discrete flows of
`ddgjax.curves`.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import scipy.special
from jaxtyping import Array, Float

from ..errors import InvalidInputError

__all__ = ["angle", "curvature", "frame", "position", "mkdv", "mkdv_velocity"]

BESSEL_TERMS = 30
"""`|j| ≤ BESSEL_TERMS` in the series of `position`: `J_30(1) ≈ 4e-42`, far below round-off for |c| ≤ 1."""


def _check_parameters(c: float, m: int) -> None:
    if not (isinstance(m, (int, np.integer)) and m >= 2):
        raise InvalidInputError(f"the curve with θ = s + c sin(ms) closes for integer m >= 2, got m = {m!r}")
    if not abs(c) <= 1:
        raise InvalidInputError(f"need |c| <= 1 (the Bessel series of `position` is truncated for it), got c = {c!r}")


def angle(s, c: float, m: int) -> np.ndarray:
    """Tangent angle `θ(s) = s + c sin(ms)` of the test curve (numpy)."""
    _check_parameters(c, m)
    return np.asarray(s) + c * np.sin(m * np.asarray(s))


def curvature(s, c: float, m: int, derivative: int = 0) -> np.ndarray:
    """`κ^{(j)}(s)` of the test curve, j = `derivative`: `κ = 1 + cm cos(ms)`, and
    `κ^{(j)} = c m^{j+1} cos(ms + jπ/2)` for j ≥ 1 (numpy)."""
    _check_parameters(c, m)
    s = np.asarray(s, dtype=float)
    wave = c * m ** (derivative + 1) * np.cos(m * s + derivative * np.pi / 2)
    return (1.0 if derivative == 0 else 0.0) + wave


def frame(s, c: float, m: int) -> tuple[np.ndarray, np.ndarray]:
    """`(T, N)` (n, 2) of the test curve: `T = (cos θ, sin θ)`, `N = iT = (−sin θ, cos θ)` (numpy)."""
    theta = angle(s, c, m)
    return np.stack([np.cos(theta), np.sin(theta)], axis=-1), np.stack([-np.sin(theta), np.cos(theta)], axis=-1)


def position(c: float, m: int):
    """The test curve `s ↦ γ(s)` (2,), JAX-traceable, parametrised by arc length with period 2π.

    `γ(s) = Σ_{|j| ≤ BESSEL_TERMS} J_j(c) e^{i(1 + jm)s} / (i(1 + jm))` (Jacobi–Anger).
    **Raises:** `InvalidInputError` unless m ≥ 2 is an integer (closed curve) and |c| ≤ 1.
    """
    _check_parameters(c, m)
    j = np.arange(-BESSEL_TERMS, BESSEL_TERMS + 1)
    frequency = 1.0 + j * m
    amplitude = scipy.special.jv(j, c) / frequency  # γ = Σ amplitude · (sin, −cos)(frequency · s)

    def gamma(s) -> Float[Array, "2"]:
        phase = frequency * s
        return jnp.array([jnp.sum(amplitude * jnp.sin(phase)), -jnp.sum(amplitude * jnp.cos(phase))])

    return gamma


def mkdv(kappa, dkappa, d3kappa):
    """The mKdV equation's right-hand side `∂_t κ = κ''' + (3/2) κ² κ'` (Ex 2.2), from
    `∂_t κ = (κα + β')'` with `α = ½κ²`, `β = κ'`."""
    return d3kappa + 1.5 * kappa**2 * dkappa


def mkdv_velocity(kappa, dkappa, T, N):
    """The mKdV flow `∂_t γ = ½κ² T + κ' N` (Ex 2.2): (n, 2) from κ, κ' (n,) and T, N (n, 2)."""
    return 0.5 * np.asarray(kappa)[:, None] ** 2 * T + np.asarray(dkappa)[:, None] * N
