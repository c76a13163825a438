"""Quaternions and Euclidean motions (reference Section 3.2).

**Conventions.**  A quaternion is an array `[..., 4]`, real part first:
`q = q0 + q1 i + q2 j + q3 k` with `i² = j² = k² = ijk = −1` (3.1).  Vectors of R³ are the
imaginary quaternions `v1 i + v2 j + v3 k` (`from_vector` / `to_vector`).  Every function
broadcasts over leading axes and works under `jax.jit` and `jax.grad`; inputs are validated
(shape always, values only when concrete) and never mutated.

- Lemma 3.4: for imaginary v, w, `vw = −<v, w> + v × w`.
- Prop 3.6: for `q = cos α + sin α n` (|n| = 1), `R_q(v) = q v q⁻¹` is the rotation about n by
  the angle **2α**.  `from_axis_angle(axis, angle)` therefore returns
  `cos(angle/2) + sin(angle/2) n`: its rotation angle is `angle` (right-hand rule about `axis`).
- Remark 3.5: `R_{−q} = R_q` (double cover) and `R_{q2 q1} = R_{q2} ∘ R_{q1}`.
- `exp(v) = cos|v| + sin|v| v/|v|` for v ∈ Im H, so `exp(angle/2 · n) = from_axis_angle(n, angle)`;
  `log` is its inverse on unit quaternions (rotation vector / 2, angle in [0, π]).

**Euclidean motions** are pairs `Motion(q, p)` acting by `v ↦ q v q⁻¹ + p`, composed like maps:
`compose(m2, m1) = m2 ∘ m1 = (q2 q1, q2 p1 q2⁻¹ + p2)`.  An infinitesimal Euclidean motion
(Cor 3.7) is `v ↦ a × v + b = ½[a, v] + b`; along a flow `(q(t), p(t))` its angular and
translational velocities are `a = 2 q' q⁻¹`, `b = p' − ½[a, p] = p' − a × p`, and conversely
the flow solves `q' = ½ a q`, `p' = b + ½[a, p]` (`motion_ode`), in closed form for constant
(a, b) by `motion_exp`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._checks import check_finite, is_concrete
from .errors import InvalidInputError, ShapeError

__all__ = [
    "as_quaternion",
    "as_vector",
    "check_unit",
    "mul",
    "cross",
    "conj",
    "norm",
    "inv",
    "from_vector",
    "to_vector",
    "rotate",
    "from_axis_angle",
    "to_axis_angle",
    "to_matrix",
    "from_matrix",
    "exp",
    "log",
    "Motion",
    "identity_motion",
    "apply",
    "compose",
    "inverse",
    "infinitesimal_motion",
    "generator",
    "motion_ode",
    "motion_exp",
]

Quaternion = Float[Array, "... 4"]
Vector = Float[Array, "... 3"]

UNIT_TOL = 1e-8
"""Relative tolerance of `| |q| − 1 |` (and of `RᵀR = I`) where a unit quaternion (a rotation)
is required."""

ONE = np.array([1.0, 0.0, 0.0, 0.0])


# ---------------------------------------------------------------------------------------------
# validation


def _as_array(x, name: str, size: int, noun: str) -> Array:
    shape = np.shape(x)
    if len(shape) < 1 or shape[-1] != size:
        raise ShapeError(f"{name} must be an array [..., {size}] ({noun}), got shape {shape}")
    if is_concrete(x):
        check_finite(np.asarray(x, dtype=float), name)
    return jnp.asarray(x, dtype=float)


def as_quaternion(q, name: str = "q") -> Quaternion:
    """`q` as a float array [..., 4]; **Raises:** `ShapeError` naming `name`, `NonFiniteError`
    (concrete q) naming the entry."""
    return _as_array(q, name, 4, "quaternions, real part first")


def as_vector(v, name: str = "v") -> Vector:
    """`v` as a float array [..., 3]; raises as `as_quaternion`."""
    return _as_array(v, name, 3, "vectors of R³ = Im H")


def _first_bad(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.argwhere(mask)[0])


def _check_nonzero(q: Array, name: str) -> None:
    if is_concrete(q):
        sq = np.sum(np.asarray(q) ** 2, axis=-1)
        if np.any(sq == 0):
            raise InvalidInputError(f"{name} is the zero quaternion at index {_first_bad(sq == 0)}, which has no inverse")


def check_unit(q, name: str = "q", tol: float = UNIT_TOL) -> None:
    """Raise `InvalidInputError` naming the first entry of a concrete `q` with `| |q| − 1 | > tol`."""
    if is_concrete(q):
        defect = np.abs(np.linalg.norm(np.asarray(q, dtype=float), axis=-1) - 1)
        if np.any(defect > tol):
            index = _first_bad(defect > tol) if defect.ndim else ()
            value = float(defect[index]) if defect.ndim else float(defect)
            raise InvalidInputError(
                f"{name} must be a unit quaternion (|q| = 1): entry {index} has | |q| − 1 | = {value:.3g} > {tol:g}"
            )


# ---------------------------------------------------------------------------------------------
# the algebra H (3.1)


def _levi_civita() -> np.ndarray:
    """`ε_ijk`: the sign of the permutation (i, j, k) of (0, 1, 2), 0 when two indices agree."""
    eps = np.zeros((3, 3, 3))
    for i, j, k in [(0, 1, 2), (1, 2, 0), (2, 0, 1)]:
        eps[i, j, k], eps[i, k, j] = 1.0, -1.0
    return eps


LEVI_CIVITA = _levi_civita()
"""`(v × w)_i = Σ_jk ε_ijk v_j w_k` (3, 3, 3)."""


def _hamilton() -> np.ndarray:
    """The structure constants `C_ijk` of H, `(pq)_i = Σ_jk C_ijk p_j q_k` (3.1): 1 is the unit
    and, for imaginary basis vectors, `e_a e_b = −δ_ab + Σ_c ε_cab e_c` (Lemma 3.4)."""
    C = np.zeros((4, 4, 4))
    C[:, 0, :] = C[:, :, 0] = np.eye(4)
    C[0, 1:, 1:] = -np.eye(3)
    C[1:, 1:, 1:] = LEVI_CIVITA
    return C


HAMILTON = _hamilton()
"""`C_ijk` with `(pq)_i = Σ_jk C_ijk p_j q_k` (4, 4, 4)."""

CONJUGATION = np.array([1.0, -1.0, -1.0, -1.0])
"""`q̄ = CONJUGATION · q` (entrywise)."""

SANDWICH = np.einsum("icb,caj,b->iajb", HAMILTON[1:], HAMILTON[:, :, 1:], CONJUGATION)
"""`S_iajb` with `Im(q v q̄)_i = Σ_ajb S_iajb q_a v_j q_b` for v ∈ Im H (3, 4, 3, 4): the
rotation `R_q(v) = q v q̄ / |q|²` (Prop 3.6) as one contraction."""


def _cross(v: Array, w: Array) -> Array:
    return jnp.einsum("ijk,...j,...k->...i", LEVI_CIVITA, v, w)


def cross(v: Vector, w: Vector) -> Vector:
    """`v × w = Σ_jk ε_ijk v_j w_k = Im(vw)` (Lemma 3.4), broadcasting over leading axes.

    One contraction with `LEVI_CIVITA`, as `mul` is one with `HAMILTON` and `rotate` one with
    `SANDWICH`: their derivatives of every order are contractions too, so a density built from
    them differentiates into a few tensor products (the cell Hessians of a rod) rather than into
    the slices and concatenations of a componentwise formula.  **Raises:** `ShapeError`,
    `NonFiniteError`.
    """
    return _cross(as_vector(v, "v"), as_vector(w, "w"))


@jax.jit
def _mul(p: Array, q: Array) -> Array:
    return jnp.einsum("ijk,...j,...k->...i", HAMILTON, p, q)


def mul(p: Quaternion, q: Quaternion) -> Quaternion:
    """Hamilton product `pq` (3.1): `(p0 q0 − <p, q>, p0 q + q0 p + p × q)` on (real, imaginary).

    Broadcasts over leading axes.  **Raises:** `ShapeError`, `NonFiniteError`.
    """
    return _mul(as_quaternion(p, "p"), as_quaternion(q, "q"))


@jax.jit
def _conj(q: Array) -> Array:
    return q * CONJUGATION


def conj(q: Quaternion) -> Quaternion:
    """`q̄ = Re q − Im q`."""
    return _conj(as_quaternion(q))


def norm(q: Quaternion) -> Float[Array, "..."]:
    """`|q| = sqrt(q q̄)`, the Euclidean norm of R⁴ (multiplicative: |pq| = |p||q|)."""
    return jnp.linalg.norm(as_quaternion(q), axis=-1)


@jax.jit
def _inv(q: Array) -> Array:
    return _conj(q) / jnp.sum(q * q, axis=-1, keepdims=True)


def inv(q: Quaternion) -> Quaternion:
    """`q⁻¹ = q̄ / |q|²`.  **Raises:** `InvalidInputError` for q = 0 (naming the index)."""
    q = as_quaternion(q)
    _check_nonzero(q, "q")
    return _inv(q)


def from_vector(v: Vector) -> Quaternion:
    """The imaginary quaternion `v1 i + v2 j + v3 k` of `v ∈ R³`."""
    v = as_vector(v)
    return jnp.concatenate([jnp.zeros_like(v[..., :1]), v], axis=-1)


def to_vector(q: Quaternion) -> Vector:
    """`Im q` as a vector of R³ (the real part is dropped)."""
    return as_quaternion(q)[..., 1:]


# ---------------------------------------------------------------------------------------------
# rotations (Prop 3.6, Remark 3.5)


@jax.jit
def _rotate(q: Array, v: Array) -> Array:
    # q v q̄ / |q|² = ((q0² − |u|²) v + 2<u, v> u + 2 q0 u × v) / |q|², u = Im q, as one contraction
    return jnp.einsum("iajb,...a,...j,...b->...i", SANDWICH, q, v, q) / jnp.sum(q * q, axis=-1, keepdims=True)


def rotate(q: Quaternion, v: Vector) -> Vector:
    """`R_q(v) = q v q⁻¹` (Prop 3.6): for `q = cos α + sin α n`, the rotation about n by 2α.

    Any q ≠ 0 is allowed (|q| cancels, footnote 17); broadcasts q [..., 4] against v [..., 3].
    **Raises:** `ShapeError`, `NonFiniteError`, `InvalidInputError` (q = 0).
    """
    q = as_quaternion(q)
    _check_nonzero(q, "q")
    return _rotate(q, as_vector(v))


def _safe_norm(v: Array) -> Array:
    """|v| over the last axis (keepdims) with gradient 0 instead of NaN at v = 0."""
    sq = jnp.sum(v * v, axis=-1, keepdims=True)
    return jnp.where(sq > 0, jnp.sqrt(jnp.where(sq > 0, sq, 1.0)), 0.0)


def from_axis_angle(axis: Vector, angle) -> Quaternion:
    """The unit quaternion of the rotation about `axis` by `angle` (right-hand rule).

    `q = cos(angle/2) + sin(angle/2) n` with `n = axis/|axis|`: Prop 3.6 rotates by 2α, so
    α = angle/2 here and `rotate(from_axis_angle(n, θ), v)` is v turned by θ about n.
    **Arguments:** `axis` [..., 3] (any length ≠ 0), `angle` [...] (radians); broadcast.
    **Raises:** `ShapeError`, `NonFiniteError`, `InvalidInputError` (a zero axis, naming it).
    """
    axis = as_vector(axis, "axis")
    if is_concrete(axis):
        zero = np.all(np.asarray(axis) == 0, axis=-1)
        if np.any(zero):
            raise InvalidInputError(f"axis is the zero vector at index {_first_bad(np.atleast_1d(zero))}: no rotation axis")
    check_finite(angle, "angle")
    half = 0.5 * jnp.asarray(angle, dtype=float)[..., None]
    imag = jnp.sin(half) * (axis / _safe_norm(axis))
    real = jnp.broadcast_to(jnp.cos(half), imag.shape[:-1] + (1,))
    return jnp.concatenate([real, imag], axis=-1)


def to_axis_angle(q: Quaternion) -> tuple[Vector, Float[Array, "..."]]:
    """`(n, θ)` with `R_q` the rotation about the unit n by θ ∈ [0, π] (n = e1 when θ = 0).

    Inverse of `from_axis_angle` up to the double cover.  **Raises:** as `log`.
    """
    v = log(q)
    angle = 2 * _safe_norm(v)
    n = jnp.where(angle > 0, v / jnp.where(angle > 0, angle / 2, 1.0), jnp.asarray([1.0, 0.0, 0.0]))
    return n, angle[..., 0]


def _matrix(q: Array) -> Array:
    eye = jnp.eye(3)
    return jnp.stack([_rotate(q, eye[i]) for i in range(3)], axis=-1)


def to_matrix(q: Quaternion) -> Float[Array, "... 3 3"]:
    """The rotation matrix `R_q ∈ SO(3)` with `R_q v = q v q⁻¹`; its columns are the images of
    e1, e2, e3 (the frame (T, N, B) of Def 3.4).  Any q ≠ 0 (|q| cancels).
    **Raises:** `ShapeError`, `NonFiniteError`, `InvalidInputError` (q = 0)."""
    q = as_quaternion(q)
    _check_nonzero(q, "q")
    return _matrix(q)


def _check_rotation(R: Array, tol: float) -> None:
    if not is_concrete(R):
        return
    R = np.asarray(R, dtype=float)
    defect = np.max(np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)), axis=(-2, -1))
    det = np.linalg.det(R)
    bad = (defect > tol) | (det <= 0)
    if np.any(bad):
        index = _first_bad(np.atleast_1d(bad)) if bad.ndim else ()
        d, dt = (float(x[index]) if x.ndim else float(x) for x in (defect, det))
        why = f"max |RᵀR − I| = {d:.3g} > {tol:g}" if d > tol else f"det R = {dt:.3g} (a reflection)"
        raise InvalidInputError(f"R is not a rotation matrix at index {index}: {why}; from_matrix needs R ∈ SO(3)")


def from_matrix(R: Float[Array, "... 3 3"], *, tol: float = UNIT_TOL) -> Quaternion:
    """The unit quaternion q with `to_matrix(q) = R`, sign fixed by `q0 ≥ 0` (Remark 3.5).

    Shepperd's method: of `4q0² = 1 + tr R` and `4qi² = 1 + 2R_ii − tr R` the largest (≥ 1, as
    they sum to 4) is taken under the square root and the other components come from the
    off-diagonal sums and differences, so no branch divides by a small number.
    **Raises:** `ShapeError` (not [..., 3, 3]), `NonFiniteError`, `InvalidInputError` (R not in
    SO(3): `max |RᵀR − I| > tol` or det R ≤ 0, naming the index).
    """
    shape = np.shape(R)
    if len(shape) < 2 or shape[-2:] != (3, 3):
        raise ShapeError(f"R must be an array [..., 3, 3] of rotation matrices, got shape {shape}")
    if is_concrete(R):
        check_finite(np.asarray(R, dtype=float), "R")
    R = jnp.asarray(R, dtype=float)
    _check_rotation(R, tol)
    d0, d1, d2 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    s = jnp.stack([1 + d0 + d1 + d2, 1 + d0 - d1 - d2, 1 - d0 + d1 - d2, 1 - d0 - d1 + d2], axis=-1)
    a = R[..., 2, 1] - R[..., 1, 2]  # 4 q0 q1
    b = R[..., 0, 2] - R[..., 2, 0]  # 4 q0 q2
    c = R[..., 1, 0] - R[..., 0, 1]  # 4 q0 q3
    d = R[..., 0, 1] + R[..., 1, 0]  # 4 q1 q2
    e = R[..., 0, 2] + R[..., 2, 0]  # 4 q1 q3
    f = R[..., 1, 2] + R[..., 2, 1]  # 4 q2 q3
    # row i: 4 q_i q_j for j = 0..3 (the diagonal entry is 4 q_i² = s_i)
    rows = jnp.stack(
        [
            jnp.stack([s[..., 0], a, b, c], axis=-1),
            jnp.stack([a, s[..., 1], d, e], axis=-1),
            jnp.stack([b, d, s[..., 2], f], axis=-1),
            jnp.stack([c, e, f, s[..., 3]], axis=-1),
        ],
        axis=-2,
    )
    i = jnp.argmax(s, axis=-1)
    row = jnp.take_along_axis(rows, i[..., None, None], axis=-2)[..., 0, :]
    big = jnp.take_along_axis(s, i[..., None], axis=-1)  # ≥ 1
    q = row / (2 * jnp.sqrt(big))
    return jnp.where(q[..., :1] < 0, -q, q)


# ---------------------------------------------------------------------------------------------
# exp and log of imaginary quaternions


def _exp(v: Array) -> Array:
    r = _safe_norm(v)
    return jnp.concatenate([jnp.cos(r), jnp.sinc(r / jnp.pi) * v], axis=-1)


def exp(v: Vector) -> Quaternion:
    """`exp(v) = cos|v| + sin|v| v/|v|` for `v ∈ Im H` (a unit quaternion; exp(0) = 1).

    `exp(θ/2 · n)` rotates by θ about n; `exp(t a/2)` solves `q' = ½ a q`, q(0) = 1.
    """
    return _exp(as_vector(v))


def _log(q: Array) -> Array:
    u = q[..., 1:]
    r = _safe_norm(u)
    # atan2(|u|, q0)/|u|, with its limit 1/q0 at u = 0 (q0 > 0 there after the sign flip)
    angle = jnp.arctan2(r, q[..., :1])
    factor = jnp.where(r > 0, angle / jnp.where(r > 0, r, 1.0), 1 / jnp.where(r > 0, 1.0, q[..., :1]))
    return factor * u


def log(q: Quaternion, *, tol: float = UNIT_TOL) -> Vector:
    """`v ∈ Im H` with `exp(v) = ±q` and |v| ≤ π/2: half the rotation vector of `R_q`.

    The sign of q is chosen with `q0 ≥ 0` (the rotation angle 2|v| ∈ [0, π]).
    **Raises:** `InvalidInputError` when a concrete q is not unit (naming the entry), and as `mul`.
    """
    q = as_quaternion(q)
    check_unit(q, "q", tol)
    return _log(jnp.where(q[..., :1] < 0, -q, q))


# ---------------------------------------------------------------------------------------------
# Euclidean motions (Section 3.2.1)


class Motion(NamedTuple):
    """The Euclidean motion `v ↦ q v q⁻¹ + p`: q [..., 4] unit, p [..., 3] (a pytree)."""

    q: Quaternion
    p: Vector


def identity_motion() -> Motion:
    return Motion(jnp.asarray(ONE), jnp.zeros(3))


def _as_motion(m, name: str) -> Motion:
    q, p = m
    return Motion(as_quaternion(q, name + ".q"), as_vector(p, name + ".p"))


def apply(m: Motion, v: Vector) -> Vector:
    """`m(v) = q v q⁻¹ + p`."""
    q, p = _as_motion(m, "m")
    return _rotate(q, as_vector(v)) + p


def compose(m2: Motion, m1: Motion) -> Motion:
    """`m2 ∘ m1 = (q2 q1, q2 p1 q2⁻¹ + p2)`: first m1, then m2 (Remark 3.5 for the rotations)."""
    q2, p2 = _as_motion(m2, "m2")
    q1, p1 = _as_motion(m1, "m1")
    return Motion(_mul(q2, q1), _rotate(q2, p1) + p2)


def inverse(m: Motion) -> Motion:
    """`m⁻¹ = (q⁻¹, −q⁻¹ p q)`."""
    q, p = _as_motion(m, "m")
    _check_nonzero(q, "m.q")
    qi = _inv(q)
    return Motion(qi, -_rotate(qi, p))


def infinitesimal_motion(a: Vector, b: Vector, v: Vector) -> Vector:
    """Cor 3.7: the velocity `½[a, v] + b = a × v + b` of the point v."""
    return _cross(as_vector(a, "a"), as_vector(v)) + as_vector(b, "b")


def generator(m: Motion, m_dot: Motion) -> tuple[Vector, Vector]:
    """Cor 3.7: `(a, b)` with `a = 2 q' q⁻¹` and `b = p' − ½[a, p] = p' − a × p`, so that
    `d/dt m(t)(v) = a × m(t)(v) + b` (the angular and translational velocity in space)."""
    q, p = _as_motion(m, "m")
    q_dot, p_dot = _as_motion(m_dot, "m_dot")
    a = 2 * _mul(q_dot, _inv(q))[..., 1:]
    return a, p_dot - _cross(a, p)


def motion_ode(a: Vector, b: Vector, m: Motion) -> Motion:
    """The right-hand side `(q', p') = (½ a q, b + ½[a, p])` whose flow is generated by the
    infinitesimal motion `v ↦ a × v + b` (Section 3.2.1, after Cor 3.7)."""
    q, p = _as_motion(m, "m")
    a, b = as_vector(a, "a"), as_vector(b, "b")
    return Motion(0.5 * _mul(jnp.concatenate([jnp.zeros_like(a[..., :1]), a], axis=-1), q), b + _cross(a, p))


def _series(x2: Array, coefficients) -> Array:
    out = jnp.zeros_like(x2)
    for c in reversed(coefficients):
        out = out * x2 + c
    return out


def motion_exp(a: Vector, b: Vector, t=1.0) -> Motion:
    """The motion at time t of the flow of the constant field `v ↦ a × v + b`, from the identity.

    `q(t) = exp(t a / 2)` and `p(t) = ∫_0^t R_{q(s)} b ds = c1 b + c2 <a, b> a + c3 a × b` with
    `ω = |a|`, `c1 = sin(ωt)/ω`, `c2 = (t − sin(ωt)/ω)/ω²`, `c3 = (1 − cos ωt)/ω²` (Taylor
    series for ωt < 0.1, so ω → 0 gives the translation t b).  The flow from m0 is
    `compose(motion_exp(a, b, t), m0)`.
    """
    a, b = as_vector(a, "a"), as_vector(b, "b")
    t = jnp.asarray(t, dtype=float)[..., None]
    w = _safe_norm(a)
    x = w * t
    x2 = x * x
    small = x < 0.1
    ws = jnp.where(small, 1.0, w)
    c1 = jnp.where(small, t * _series(x2, [1, -1 / 6, 1 / 120, -1 / 5040, 1 / 362880]), jnp.sin(x) / ws)
    c2 = jnp.where(small, t**3 * _series(x2, [1 / 6, -1 / 120, 1 / 5040, -1 / 362880, 1 / 39916800]), (t - jnp.sin(x) / ws) / ws**2)
    c3 = jnp.where(small, t**2 * _series(x2, [1 / 2, -1 / 24, 1 / 720, -1 / 40320, 1 / 3628800]), (1 - jnp.cos(x)) / ws**2)
    ab = jnp.sum(a * b, axis=-1, keepdims=True)
    p = c1 * b + c2 * ab * a + c3 * _cross(a, b)
    return Motion(_exp(0.5 * t * a), p)
