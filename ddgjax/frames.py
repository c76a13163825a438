"""Moving frames and framed curves as quaternion fields (reference Section 3.4, Defs 3.4, 3.5).

**Conventions.**  A frame is a unit quaternion Φ ([..., 4], `ddgjax.quaternion`); its vectors
are `T = Φ i Φ⁻¹, N = Φ j Φ⁻¹, B = Φ k Φ⁻¹` (`frame`), i.e. the columns of `to_matrix(Φ)`.
Along a frame field Φ(s):

- spatial angular velocity `ω = 2 Φ' Φ⁻¹`, `Φ' = ½ ω Φ` (3.5), and `T' = ω × T` etc. (3.7);
- body angular velocity `Ω = 2 Φ⁻¹ Φ' = Φ⁻¹ ω Φ`, `Φ' = ½ Φ Ω` (3.6);
- curvatures and torsion (Def 3.4) `κ1 = <T', N>`, `κ2 = <T', B>`, `τ = <N', B>` are the body
  components `Ω = (τ, −κ2, κ1)`, and (T, N, B)' = A (T, N, B) with A of (3.4); κ² = κ1² + κ2².

**Discrete edge frames** Φ_0 … Φ_{n−1} (one per edge of an arc-length polyline with edge length
h, `T_k = Φ_k i Φ_k⁻¹`).  At the interior vertex k (between edges k − 1 and k) the relative
rotation splits as `Φ_k Φ_{k−1}⁻¹ = t_k b_k`:

- `b_k` is the parallel transport: the rotation about `T_{k−1} × T_k` by the turning angle φ_k
  taking `T_{k−1}` to `T_k`, `b_k = (1 + <T_{k−1}, T_k> + T_{k−1} × T_k) / |·|`;
- `t_k` is the twist, the rotation about `T_k` by the twist angle θ_k ∈ (−π, π].

Equivalently `Φ_k = Ψ_k β_k c_k^{½}` with the half-twisted frame `Ψ_k = Φ_{k−1} c_k^{½}`
(`c_k` = rotation about e1 by θ_k) and the body bending `β_k = Ψ_k⁻¹ b_k Ψ_k = cos(φ/2) +
sin(φ/2) β̂`, β̂ ⊥ e1 — a symmetric (Strang) splitting of `exp(hΩ/2)`.  The discrete curvature
vector `K_k = 2 tan(φ_k/2) β̂ / h` (length: `curves.curvature(..., "arclength")`) and the discrete
torsion θ_k/h give `(κ1, κ2, τ)_k = (K3, −K2, θ/h)`, which converge at order 2 to the smooth
values at the vertex.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from . import quaternion as qt
from ._checks import is_concrete
from .curves import SINGULAR_TOL
from .errors import InvalidInputError, ShapeError, SingularVertexError
from .flows import integrate

__all__ = [
    "frame",
    "angular_velocity",
    "body_angular_velocity",
    "frame_velocity",
    "curvatures",
    "body_from_curvatures",
    "frame_equation_matrix",
    "curvatures_along",
    "frame_from_curvatures",
    "edge_frame_split",
    "discrete_curvatures",
]

E = np.eye(3)


def frame(Phi) -> tuple[Array, Array, Array]:
    """`(T, N, B) = (Φ i Φ⁻¹, Φ j Φ⁻¹, Φ k Φ⁻¹)` (Def 3.4), each [..., 3]."""
    return tuple(qt.rotate(Phi, E[i]) for i in range(3))


def angular_velocity(Phi, dPhi) -> Float[Array, "... 3"]:
    """Spatial angular velocity `ω = 2 Φ' Φ⁻¹` ((3.5): `Φ' = ½ ω Φ`), from Φ and Φ'."""
    return 2 * qt.to_vector(qt.mul(dPhi, qt.inv(Phi)))


def body_angular_velocity(Phi, dPhi) -> Float[Array, "... 3"]:
    """Body angular velocity `Ω = 2 Φ⁻¹ Φ' = Φ⁻¹ ω Φ` ((3.6): `Φ' = ½ Φ Ω`)."""
    return 2 * qt.to_vector(qt.mul(qt.inv(Phi), dPhi))


def frame_velocity(Phi, *, omega=None, Omega=None) -> Float[Array, "... 4"]:
    """`Φ' = ½ ω Φ` (3.5) from the spatial ω, or `Φ' = ½ Φ Ω` (3.6) from the body Ω (give one)."""
    if (omega is None) == (Omega is None):
        raise InvalidInputError("give exactly one of omega (spatial, (3.5)) and Omega (body, (3.6))")
    if omega is not None:
        return 0.5 * qt.mul(qt.from_vector(omega), Phi)
    return 0.5 * qt.mul(Phi, qt.from_vector(Omega))


def curvatures(Phi, dPhi) -> tuple[Array, Array, Array]:
    """`(κ1, κ2, τ) = (<T', N>, <T', B>, <N', B>) = (Ω3, −Ω2, Ω1)` (Def 3.4, Section 3.4)."""
    Omega = body_angular_velocity(Phi, dPhi)
    return Omega[..., 2], -Omega[..., 1], Omega[..., 0]


def body_from_curvatures(kappa1, kappa2, tau) -> Float[Array, "... 3"]:
    """`Ω = (τ, −κ2, κ1)`: the body angular velocity with these curvatures and torsion."""
    return jnp.stack(jnp.broadcast_arrays(*(jnp.asarray(x, dtype=float) for x in (tau, -jnp.asarray(kappa2), kappa1))), axis=-1)


def frame_equation_matrix(kappa1, kappa2, tau) -> Float[Array, "... 3 3"]:
    """A of (3.4): `(T, N, B)' = A (T, N, B)` with rows `(0, κ1, κ2), (−κ1, 0, τ), (−κ2, −τ, 0)`."""
    k1, k2, t = jnp.broadcast_arrays(*(jnp.asarray(x, dtype=float) for x in (kappa1, kappa2, tau)))
    z = jnp.zeros_like(k1)
    return jnp.stack([jnp.stack([z, k1, k2], -1), jnp.stack([-k1, z, t], -1), jnp.stack([-k2, -t, z], -1)], -2)


def curvatures_along(Phi_of_s: Callable, s) -> tuple[Array, Array, Array]:
    """`(κ1, κ2, τ)` of a smooth frame field `Phi_of_s(s) -> (4,)` at the parameters `s` (1-D);
    Φ' by forward-mode differentiation."""

    def at(s_):
        Phi, dPhi = jax.jvp(Phi_of_s, (s_,), (jnp.ones_like(s_),))
        return curvatures(Phi, dPhi)

    return jax.vmap(at)(jnp.asarray(s, dtype=float))


def frame_from_curvatures(Phi0, curvatures_of_s: Callable, length: float, *, steps: int, method: str = "gauss6"):
    """Remark 3.10: the frame with `Φ(0) = Φ0` and curvatures `curvatures_of_s(s) -> (κ1, κ2, τ)`,
    by integrating `Φ' = ½ Φ Ω(s)`, `Ω = (τ, −κ2, κ1)` (3.6) with `ddgjax.integrate` (the
    parameter s is carried as a state variable, s' = 1; Gauss methods keep |Φ| = 1).

    **Returns:** `(s, Phi)`: the steps + 1 parameters and frames (steps + 1, 4).
    **Raises:** `InvalidInputError` (Φ0 not unit), `ShapeError`, `NonFiniteError`.
    """
    Phi0 = qt.as_quaternion(Phi0, "Phi0")
    qt.check_unit(Phi0, "Phi0")

    def f(state):
        Phi, s = state
        Omega = body_from_curvatures(*curvatures_of_s(s))
        return frame_velocity(Phi, Omega=Omega), jnp.ones_like(s)

    s, (Phi, _) = integrate(f, (Phi0, jnp.zeros(())), length, steps=steps, method=method)
    return s, Phi


# ---------------------------------------------------------------------------------------------
# discrete edge frames


def _as_edge_frames(Phi) -> Array:
    shape = np.shape(Phi)
    if len(shape) != 2 or shape[1] != 4 or shape[0] < 2:
        raise ShapeError(f"Phi must be an (n, 4) array of unit quaternions, one frame per edge, n >= 2; got shape {shape}")
    Phi = qt.as_quaternion(Phi, "Phi")
    qt.check_unit(Phi, "Phi")
    return Phi


def _check_not_antiparallel(T: Array) -> None:
    if is_concrete(T):
        T = np.asarray(T)
        c = 1 + np.sum(T[:-1] * T[1:], axis=-1)
        bad = np.flatnonzero(c <= SINGULAR_TOL)
        if bad.size:
            k = int(bad[0]) + 1
            raise SingularVertexError(f"T_{k - 1} and T_{k} are anti-parallel at vertex {k}: the parallel transport is undefined")


def _split(Phi: Array) -> tuple[Array, Array, Array]:
    T = qt.rotate(Phi, jnp.asarray(E[0]))
    _check_not_antiparallel(T)
    T_prev, T_next = T[:-1], T[1:]
    b = jnp.concatenate([1 + jnp.sum(T_prev * T_next, -1, keepdims=True), qt.cross(T_prev, T_next)], -1)
    b = b / jnp.linalg.norm(b, axis=-1, keepdims=True)
    t = qt.mul(qt.mul(Phi[1:], qt.conj(Phi[:-1])), qt.conj(b))
    # t = ±(cos θ/2 + sin θ/2 T_k): pick the sign with cos θ/2 ≥ 0 so θ ∈ (−π, π]
    sign = jnp.where(t[..., 0] < 0, -1.0, 1.0)
    theta = 2 * jnp.arctan2(sign * jnp.sum(t[..., 1:] * T_next, -1), sign * t[..., 0])
    return T, b, theta


def edge_frame_split(Phi: Float[Array, "n 4"]) -> tuple[Float[Array, "m 4"], Float[Array, " m"]]:
    """Split `Φ_k Φ_{k−1}⁻¹ = t_k b_k` at the n − 1 interior vertices (see the module docstring).

    **Returns:** `(b, theta)`: the parallel transports b_k (n − 1, 4) (unit, real part ≥ 0) and
    the twist angles θ_k ∈ (−π, π] about T_k (n − 1,); `t_k = from_axis_angle(T_k, θ_k)`.
    **Raises:** `ShapeError`, `InvalidInputError` (non-unit frames, naming the edge),
    `SingularVertexError` (T_k = −T_{k−1}, naming the vertex), `NonFiniteError`.
    """
    Phi = _as_edge_frames(Phi)
    _, b, theta = _split(Phi)
    return b, theta


def discrete_curvatures(Phi: Float[Array, "n 4"], h: float = 1.0) -> tuple[Array, Array, Array]:
    """Discrete `(κ1, κ2, τ)` at the n − 1 interior vertices of edge frames with edge length h.

    `(κ1, κ2) = (K3, −K2)` for the body curvature vector `K = 2 tan(φ_k/2) β̂_k / h` in the
    half-twisted frame, `τ = θ_k / h` (module docstring); `sqrt(κ1² + κ2²)` is the arc-length
    curvature 2 tan(φ_k/2)/h of the polyline `curves.from_tangents(T, edge_length=h)`.
    **Raises:** as `edge_frame_split`; `InvalidInputError` for h ≤ 0.
    """
    if not h > 0:
        raise InvalidInputError(f"edge length h must be positive, got {h}")
    Phi = _as_edge_frames(Phi)
    _, b, theta = _split(Phi)
    half_twist = qt.from_axis_angle(jnp.asarray(E[0]), 0.5 * theta)
    Psi = qt.mul(Phi[:-1], half_twist)
    beta = qt.mul(qt.mul(qt.conj(Psi), b), Psi)
    K = 2 * beta[..., 1:] / (h * beta[..., :1])
    return K[..., 2], -K[..., 1], theta / h


def twist_angle(Phi_prev: Float[Array, "4"], Phi_next: Float[Array, "4"]) -> Float[Array, ""]:
    """The twist θ_k ∈ (−π, π] of one pair of edge frames (`edge_frame_split`), traceable and
    without validation: the density of a rod's twisting energy."""
    return _split(jnp.stack([Phi_prev, Phi_next]))[2][0]
