"""Exact smooth planar elastica from Jacobi elliptic functions: the oracle for smooth limits.

An arc-length curve `γ: [0, L] → R³` with tangent `T = γ'` is an elastic curve iff (Thm 3.2)

    T'' = c(s) T + a,   equivalently   T'' × T = a × T,   equivalently   γ'' × γ' = a × γ + b,

the Euler–Lagrange equation of `½⟨T', T'⟩ + ½c(s)(|T|² − 1) + ⟨a, T⟩`.  By the Kirchhoff analogy
(Thm 3.1) `T` moves like a spherical pendulum in the potential `−⟨a, T⟩`: it is pulled *towards*
`a`.  A planar elastica (Remark 3.2) lies in `z = 0` with `T = (cos θ, sin θ, 0)` and normal
`N = (−sin θ, cos θ, 0)`; then `T' = θ' N`, `T'' = θ'' N − θ'² T`, and the normal part of
`T'' = cT + a` is the planar pendulum

    θ'' = ⟨a, N⟩ = −λ² sin(θ − θ_a),   a = λ² (cos θ_a, sin θ_a, 0),

with stable rest `θ = θ_a` (the tangent along the load); the tangential part gives the multiplier
`c = −θ'² − ⟨a, T⟩`.  The signed curvature is `κ = θ'`.  Write `φ = θ − θ_a`, `m = k²`, and
`sn, cn, dn, am` for the Jacobi functions of modulus `k`.  The two families (Euler's
classification) are

- **inflectional** (the pendulum oscillates, `κ` changes sign), `u = λ s + u₀`:
  `sin(φ/2) = k sn u`, `κ = 2kλ cn u`, `(cos φ, sin φ) = (1 − 2k² sn² u, 2k sn u dn u)`,
  position `(1/λ)(2E(am u | m) − u, −2k cn u)` in the frame `(e_a, e_⊥)` of the load;
  `κ` has period `4K(m)/λ`.
- **non-inflectional** (the pendulum rotates, `κ > 0`), `u = λ s / k + u₀`:
  `φ = 2 am u`, `κ = (2λ/k) dn u`, `(cos φ, sin φ) = (1 − 2 sn² u, 2 sn u cn u)`,
  position `(k/λ)((1 − 2/k²) u + (2/k²) E(am u | m), −(2/k²) dn u)`; `κ` has period `2kK(m)/λ`.

Here `e_a = (cos θ_a, sin θ_a, 0)`, `e_⊥ = (−sin θ_a, cos θ_a, 0)`, and positions are shifted so
that `γ(0) = 0`.  The incomplete integral `E(φ | m)` is computed from Carlson's symmetric forms
(`elliptic_e`), not `scipy.special.ellipeinc` (scipy issue 19498: wrong values at isolated
inputs).  Everything is numpy/scipy float64, evaluated outside JAX.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipj, ellipk, elliprd, elliprf

from ..errors import InvalidInputError

__all__ = [
    "elliptic_e",
    "PlanarElastica",
    "BoundaryData",
    "inflectional",
    "non_inflectional",
    "figure_eight",
    "figure_eight_modulus",
]


def elliptic_e(phi, m):
    """Incomplete elliptic integral of the second kind `E(φ | m) = ∫₀^φ √(1 − m sin² t) dt`.

    For `φ = jπ + r`, `|r| ≤ π/2`: `E(φ | m) = 2j E(m) + E(r | m)` (quasi-periodicity), and

        E(r | m) = sin r R_F(cos² r, 1 − m sin² r, 1) − (m/3) sin³ r R_D(cos² r, 1 − m sin² r, 1)

    with Carlson's `R_F`, `R_D` (`scipy.special.elliprf`, `elliprd`).

    **Arguments:** `phi`, `m`: broadcastable float arrays (or scalars), `m ≤ 1`.
    **Returns:** `E(φ | m)` with the broadcast shape.
    **Raises:** `InvalidInputError` if a value is not finite or `m > 1`.
    """
    phi, m = np.broadcast_arrays(np.asarray(phi, dtype=float), np.asarray(m, dtype=float))
    _require(np.all(np.isfinite(phi)) and np.all(np.isfinite(m)), "phi and m must be finite")
    _require(np.all(m <= 1.0), f"the parameter m = k² must be ≤ 1, got max m = {np.max(m)}")
    j = np.round(phi / np.pi)
    r = phi - j * np.pi
    sin_r, cos2_r = np.sin(r), np.cos(r) ** 2
    y = 1.0 - m * sin_r**2
    with np.errstate(invalid="ignore", divide="ignore"):
        e_r = sin_r * elliprf(cos2_r, y, 1.0) - (m / 3.0) * sin_r**3 * elliprd(cos2_r, y, 1.0)
    # at m = 1, r = ±π/2 both R_F and R_D diverge; there E(r | 1) = sin r exactly
    e_r = np.where(m == 1.0, sin_r, e_r)
    return (2.0 * j * ellipe(m) + e_r)[()]


class _Jacobi(NamedTuple):
    """`u` and `sn u, cn u, dn u, am u` for one modulus."""

    u: np.ndarray
    sn: np.ndarray
    cn: np.ndarray
    dn: np.ndarray
    am: np.ndarray


class _Family(NamedTuple):
    """One of Euler's families, written at `λ = 1` in the elliptic argument `u = λ s / q + u₀`.

    `q(k)`: arc length per unit `u` at `λ = 1`; `turning(k, J)`: `(cos φ, sin φ)`;
    `position(k, J)`: a `u`-antiderivative of `(cos φ, sin φ)`; `dphi(k, J)`: `dφ/du`;
    `energy(k, J)`: a `u`-antiderivative of `(dφ/du)²`; `phi(k, J)`: `φ`; `u_period(K)`.
    """

    q: Callable
    turning: Callable
    position: Callable
    dphi: Callable
    energy: Callable
    phi: Callable
    u_period: Callable


_FAMILIES = {
    # sin(φ/2) = k sn u; ∫dn² du = E(am u), ∫k² cn² du = E(am u) − (1 − k²) u
    "inflectional": _Family(
        q=lambda k: 1.0,
        turning=lambda k, J: (1.0 - 2.0 * k**2 * J.sn**2, 2.0 * k * J.sn * J.dn),
        position=lambda k, J: (2.0 * elliptic_e(J.am, k**2) - J.u, -2.0 * k * J.cn),
        dphi=lambda k, J: 2.0 * k * J.cn,
        energy=lambda k, J: 4.0 * (elliptic_e(J.am, k**2) - (1.0 - k**2) * J.u),
        phi=lambda k, J: 2.0 * np.arcsin(k * J.sn),
        u_period=lambda K: 4.0 * K,
    ),
    # φ = 2 am u; sn² = (1 − dn²)/k²
    "non_inflectional": _Family(
        q=lambda k: k,
        turning=lambda k, J: (1.0 - 2.0 * J.sn**2, 2.0 * J.sn * J.cn),
        position=lambda k, J: (
            (1.0 - 2.0 / k**2) * J.u + (2.0 / k**2) * elliptic_e(J.am, k**2),
            -(2.0 / k**2) * J.dn,
        ),
        dphi=lambda k, J: 2.0 * J.dn,
        energy=lambda k, J: 4.0 * elliptic_e(J.am, k**2),
        phi=lambda k, J: 2.0 * J.am,
        u_period=lambda K: 2.0 * K,
    ),
}


@dataclass(frozen=True)
class BoundaryData:
    """What a clamped elastica solver needs (Section 3.1): ends, chord, end tangents, length.

    `start = γ(0)`, `end = γ(L)`, `chord = γ(L) − γ(0) = ∫₀^L T ds`, `start_tangent = T(0)`,
    `end_tangent = T(L)` (each shape (3,)), and `length = L`.
    """

    start: np.ndarray
    end: np.ndarray
    chord: np.ndarray
    start_tangent: np.ndarray
    end_tangent: np.ndarray
    length: float


@dataclass(frozen=True)
class PlanarElastica:
    """An exact planar elastica in `z = 0` of R³, parametrised by arc length `s ∈ [0, length]`.

    Build it with `inflectional`, `non_inflectional` or `figure_eight`; the module docstring
    has the formulas.  Methods take `s` of any shape `(...)` and return `(...)` or `(..., 3)`;
    they are valid for every real `s`, not only in `[0, length]`.

    **Fields:** `family` (`"inflectional"` or `"non_inflectional"`), modulus `k ∈ (0, 1)`,
    scale `lam = λ > 0` (`|a| = λ²`; the curve at `λ` is the curve at `λ = 1` shrunk by `1/λ`),
    phase `u0 = u₀` of the elliptic argument at `s = 0`, arc `length > 0`, and `load_angle = θ_a`,
    the direction of the load `a` in the plane.

    **Raises:** `InvalidInputError` for an unknown family, `k ∉ (0, 1)`, `lam ≤ 0`, `length ≤ 0`
    or a non-finite value.
    """

    family: str
    k: float
    lam: float
    u0: float
    length: float
    load_angle: float

    def __post_init__(self):
        _require(self.family in _FAMILIES, f"family must be one of {sorted(_FAMILIES)}, got {self.family!r}")
        for name in ("k", "lam", "u0", "length", "load_angle"):
            _require(np.isfinite(getattr(self, name)), f"{name} must be finite, got {getattr(self, name)}")
        _require(0.0 < self.k < 1.0, f"the elliptic modulus k must lie in (0, 1), got k = {self.k}")
        _require(self.lam > 0.0, f"the scale lam must be > 0, got lam = {self.lam}")
        _require(self.length > 0.0, f"the length must be > 0, got length = {self.length}")

    @property
    def _fam(self) -> _Family:
        return _FAMILIES[self.family]

    @property
    def _q(self) -> float:
        """Arc length per unit of the elliptic argument: `ds = (q/λ) du`."""
        return self._fam.q(self.k) / self.lam

    @property
    def _frame(self) -> tuple[np.ndarray, np.ndarray]:
        """`(e_a, e_⊥)`: the unit load direction and its left normal in the plane."""
        c, s = np.cos(self.load_angle), np.sin(self.load_angle)
        return np.array([c, s, 0.0]), np.array([-s, c, 0.0])

    def _jacobi(self, s) -> _Jacobi:
        u = np.asarray(s, dtype=float) / self._q + self.u0
        return _Jacobi(u, *ellipj(u, self.k**2))

    def _in_plane(self, x, y) -> np.ndarray:
        """`x e_a + y e_⊥`, shape `(..., 3)`."""
        e_a, e_perp = self._frame
        return np.asarray(x)[..., None] * e_a + np.asarray(y)[..., None] * e_perp

    @property
    def period(self) -> float:
        """The arc-length period of the curvature: `4K/λ` (inflectional), `2kK/λ` (non-infl.)."""
        return _period(self.family, self.k, self.lam)

    def gamma(self, s) -> np.ndarray:
        """`γ(s)`, shape `(..., 3)`, with `γ(0) = 0` (positions in the module docstring)."""
        x, y = self._fam.position(self.k, self._jacobi(s))
        x0, y0 = self._fam.position(self.k, self._jacobi(0.0))
        return self._q * self._in_plane(x - x0, y - y0)

    def tangent(self, s) -> np.ndarray:
        """`T(s) = γ'(s) = cos φ e_a + sin φ e_⊥ = (cos θ, sin θ, 0)`, shape `(..., 3)`."""
        return self._in_plane(*self._fam.turning(self.k, self._jacobi(s)))

    def normal(self, s) -> np.ndarray:
        """`N(s) = e_z × T = (−sin θ, cos θ, 0)`, so that `T' = κ N`; shape `(..., 3)`."""
        t = self.tangent(s)
        return np.stack([-t[..., 1], t[..., 0], np.zeros_like(t[..., 0])], axis=-1)

    def tangent_angle(self, s) -> np.ndarray:
        """`θ(s) = θ_a + φ(s)`, continuous in `s`; shape `(...)`."""
        return self.load_angle + self._fam.phi(self.k, self._jacobi(s))

    def curvature(self, s) -> np.ndarray:
        """Signed curvature `κ = θ'`: `2kλ cn u` (inflectional), `(2λ/k) dn u` (non-infl.)."""
        return self._fam.dphi(self.k, self._jacobi(s)) / self._q

    @property
    def a(self) -> np.ndarray:
        """The load `a = λ² e_a` of `T'' = cT + a` and `T'' × T = a × T` (Thm 3.2); shape (3,)."""
        return self.lam**2 * self._frame[0]

    @property
    def b(self) -> np.ndarray:
        """`b = γ'' × γ' − a × γ`, constant (Thm 3.2); `= −κ(0) e_z` since `γ(0) = 0`; shape (3,)."""
        return np.array([0.0, 0.0, -float(self.curvature(0.0))]) - np.cross(self.a, self.gamma(0.0))

    def c(self, s) -> np.ndarray:
        """The multiplier of `|T|² = 1` in `T'' = cT + a`: `c = −κ² − ⟨a, T⟩`; shape `(...)`."""
        return -self.curvature(s) ** 2 - self.tangent(s) @ self.a

    def bending_energy(self) -> float:
        """`∫₀^L κ² ds` in closed form: `(λ/q)[W(u₁) − W(u₀)]`, `u₁ = u₀ + λL/q`.

        `W(u) = 4(E(am u) − (1 − k²)u)` (inflectional, `q = 1`), `W(u) = 4E(am u)` (non-infl.,
        `q = k`), from `∫dn² du = E(am u)` and `k² cn² = dn² − (1 − k²)`.
        """
        w0, w1 = (self._fam.energy(self.k, self._jacobi(s)) for s in (0.0, self.length))
        return float((w1 - w0) / self._q)

    def boundary_data(self) -> BoundaryData:
        """The clamped boundary data at `s = 0` and `s = L` (see `BoundaryData`)."""
        start, end = self.gamma(0.0), self.gamma(self.length)
        return BoundaryData(
            start=start,
            end=end,
            chord=end - start,
            start_tangent=self.tangent(0.0),
            end_tangent=self.tangent(self.length),
            length=float(self.length),
        )


def inflectional(k: float, lam: float = 1.0, u0: float = 0.0, length: float | None = None,
                 load_angle: float = 0.0) -> PlanarElastica:
    """The inflectional elastica `sin((θ − θ_a)/2) = k sn(λs + u₀, k)`, `κ = 2kλ cn(λs + u₀, k)`.

    `length` defaults to one period `4K(k²)/λ`.  `u₀ = 0` starts at a curvature maximum with
    `T(0) = e_a`; `u₀ = K` starts at an inflection point.  Raises `InvalidInputError` for
    `k ∉ (0, 1)` and the other cases listed in `PlanarElastica`.
    """
    return _build("inflectional", k, lam, u0, length, load_angle)


def non_inflectional(k: float, lam: float = 1.0, u0: float = 0.0, length: float | None = None,
                     load_angle: float = 0.0) -> PlanarElastica:
    """The non-inflectional elastica `θ − θ_a = 2 am(λs/k + u₀, k)`, `κ = (2λ/k) dn(λs/k + u₀, k)`.

    `length` defaults to one period `2kK(k²)/λ`, over which `T` turns once.  `k → 0` tends to a
    circle.  Raises `InvalidInputError` as `inflectional`.
    """
    return _build("non_inflectional", k, lam, u0, length, load_angle)


@functools.lru_cache(maxsize=None)
def figure_eight_modulus() -> float:
    """The modulus `k ≈ 0.908909` of Euler's elastic figure-eight: the root of `2E(k²) = K(k²)`."""
    return brentq(lambda k: 2.0 * ellipe(k * k) - ellipk(k * k), 0.5, 0.99,
                  xtol=1e-16, rtol=4.0 * np.finfo(float).eps)


def figure_eight(lam: float = 1.0, u0: float = 0.0, load_angle: float = 0.0) -> PlanarElastica:
    """Euler's closed elastic figure-eight (Remark 3.2) over one period `L = 4K/λ`.

    The inflectional elastica with `2E(k²) = K(k²)`: its chord over a period,
    `(1/λ)(2E(am 4K) − 4K) e_a = (4/λ)(2E − K) e_a`, vanishes, so `γ(L) = γ(0)` and `T(L) = T(0)`.
    The double point is the pair of inflections `u = K, 3K`.
    """
    return inflectional(figure_eight_modulus(), lam=lam, u0=u0, load_angle=load_angle)


def _build(family, k, lam, u0, length, load_angle) -> PlanarElastica:
    # validate k before the default length evaluates K(k²)
    _require(np.isfinite(k) and 0.0 < k < 1.0, f"the elliptic modulus k must lie in (0, 1), got k = {k}")
    _require(np.isfinite(lam) and lam > 0.0, f"the scale lam must be finite and > 0, got lam = {lam}")
    if length is None:
        length = _period(family, k, lam)
    return PlanarElastica(family, float(k), float(lam), float(u0), float(length), float(load_angle))


def _period(family: str, k: float, lam: float) -> float:
    fam = _FAMILIES[family]
    return float(fam.q(k) * fam.u_period(ellipk(k * k)) / lam)


def _require(condition, message: str) -> None:
    if not condition:
        raise InvalidInputError(message)
