"""The Lagrange top (reference Section 3.4.1): action (3.10), equations of motion by autodiff.

**The action.**  For a frame Φ(t) ∈ H_1 with symmetry axis `T = Φ i Φ⁻¹`, spatial angular
velocity `ω = 2 Φ' Φ⁻¹` and inertia `J = diag(α, 1, 1)` in the body frame,

    S[Φ] = ∫ <ω, ω> + (α − 1)<ω, T>² + 2<a, T> dt                                    (3.10)

(`action_density`): kinetic energy `<Ω, JΩ>` (3.8), (3.9) minus the potential `U = −2<a, T>`.
In the body angular velocity `Ω = 2 Φ⁻¹ Φ'` it reads `L(Φ, Ω) = <Ω, JΩ> + 2<a, T>`
(`lagrangian`, which evaluates `action_density(Φ, ½ Φ Ω)`).

**Equations of motion (derived here, evaluated by autodiff).**  Varying `Φ_ε = Φ exp(εη/2)`
gives `δΩ = η' + Ω × η`, and Hamilton's principle δS = 0 for all η vanishing at the ends gives
the Euler–Poincaré equation `M' = M × Ω + D_Φ L` with the body angular momentum
`M = ∂L/∂Ω = 2JΩ` and the body-frame torque `<D_Φ L, η> = d/dε L(Φ(1 + εη/2), Ω)|_0`.  After
the Legendre transform `H(Φ, M) = <M, Ω> − L` (so `∂H/∂M = Ω`, `D_Φ H = −D_Φ L`):

    Φ' = ½ Φ ∂H/∂M,        M' = M × ∂H/∂M − D_Φ H                                   (`vector_field`)

`M = ∂L/∂Ω`, Ω(Φ, M) (L is quadratic in Ω: one linear solve with its autodiff Hessian) and
the torque `D_Φ L = −D_Φ H` come from `jax.grad` of the action; nothing is typed in by hand.
By hand the torque is `D_Φ L = 2 e1 × Γ` with the body gravity `Γ = Φ⁻¹ a Φ` (Euler–Poisson),
and the flow satisfies the unreduced Euler–Lagrange equations of (3.10) in (Φ, Φ') on H_1,
`d/dt ∂L/∂Φ' − ∂L/∂Φ ∥ Φ` (both checked in the tests).

**Polynomial extension.**  Off H_1 the potential uses `T = Φ i Φ̄` (equal to Φ i Φ⁻¹ on H_1),
so `L(Φ, Ω) = <Ω, JΩ> + 2<a, Φ i Φ̄>` and H is a quadratic polynomial in the state
(Φ, M) ∈ R⁴ × R³ and an exact invariant there; the Gauss–Legendre integrator
(`ddgjax.integrate`, gauss6) therefore keeps H, |Φ|² and the axial momentum `<M, e1>` (linear)
to round-off.  The vertical momentum `<Φ M Φ⁻¹, a>/|a|` (the spatial angular momentum about the
gravity axis, Noether for rotations about a) is cubic and is kept to the method's order-6
accuracy (t = 100, h = 0.025: ~1e-12).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import quaternion as qt
from ..errors import InvalidInputError
from ..flows import integrate
from ..frames import angular_velocity

__all__ = [
    "TopState",
    "action_density",
    "lagrangian",
    "momentum",
    "hamiltonian",
    "vector_field",
    "equations_of_motion",
    "initial_state",
    "conserved_quantities",
    "simulate",
]

E1 = np.array([1.0, 0.0, 0.0])


class TopState(NamedTuple):
    """Phase-space point: the frame Φ (4,) and the body angular momentum M = ∂L/∂Ω (3,)."""

    Phi: Float[Array, "4"]
    M: Float[Array, "3"]


def _axis(Phi: Array) -> Array:
    """`T = Φ i Φ̄` (= Φ i Φ⁻¹ on H_1; a quadratic polynomial in Φ everywhere)."""
    return qt.mul(qt.mul(Phi, jnp.asarray([0.0, 1.0, 0.0, 0.0])), qt.conj(Phi))[..., 1:]


def action_density(Phi, dPhi, *, alpha: float, a) -> Float[Array, "..."]:
    """The integrand of (3.10): `<ω, ω> + (α − 1)<ω, T>² + 2<a, T>` with `ω = 2 Φ'Φ⁻¹`.

    `T = Φ i Φ⁻¹` in the kinetic term and `T = Φ i Φ̄` in the potential: equal on H_1, and this
    choice makes `lagrangian(Φ, Ω) = <Ω, JΩ> + 2<a, Φ i Φ̄>` for every Φ ≠ 0 (a polynomial).
    """
    omega = angular_velocity(Phi, dPhi)
    wT = jnp.sum(omega * qt.rotate(Phi, E1), axis=-1)
    return jnp.sum(omega * omega, axis=-1) + (alpha - 1) * wT**2 + 2 * jnp.sum(jnp.asarray(a) * _axis(Phi), axis=-1)


def lagrangian(Phi, Omega, *, alpha: float, a) -> Float[Array, "..."]:
    """`L(Φ, Ω) = action_density(Φ, ½ Φ Ω)`: (3.10) in the body angular velocity (= <Ω, JΩ> + 2<a, T>)."""
    dPhi = 0.5 * qt.mul(Phi, jnp.concatenate([jnp.zeros_like(Omega[..., :1]), Omega], axis=-1))
    return action_density(Phi, dPhi, alpha=alpha, a=a)


def momentum(Phi, Omega, *, alpha: float, a) -> Float[Array, "3"]:
    """Body angular momentum `M = ∂L/∂Ω` (= 2JΩ), by autodiff."""
    return _momentum(jnp.asarray(Phi, dtype=float), jnp.asarray(Omega, dtype=float), alpha, jnp.asarray(a, dtype=float))


@jax.jit
def _momentum(Phi, Omega, alpha, a):
    return jax.grad(lambda W: lagrangian(Phi, W, alpha=alpha, a=a))(Omega)


def _velocity_of_momentum(Phi, M, alpha, a) -> Array:
    """Ω with `∂L/∂Ω(Φ, Ω) = M`: L is quadratic in Ω, so Ω = K⁻¹(M − ∂L/∂Ω(Φ, 0)), K = ∂²L/∂Ω²."""
    zero = jnp.zeros(3)
    grad0 = momentum(Phi, zero, alpha=alpha, a=a)
    K = jax.hessian(lambda W: lagrangian(Phi, W, alpha=alpha, a=a))(zero)
    return jnp.linalg.solve(K, M - grad0)


def hamiltonian(*, alpha: float, a) -> Callable[[TopState], Array]:
    """`H(Φ, M) = <M, Ω> − L(Φ, Ω)` at `Ω = Ω(Φ, M)`: the energy `<Ω, JΩ> − 2<a, T>`."""

    def H(state: TopState) -> Array:
        Omega = _velocity_of_momentum(state.Phi, state.M, alpha, a)
        return state.M @ Omega - lagrangian(state.Phi, Omega, alpha=alpha, a=a)

    return jax.jit(H)


def _body_derivative(F: Callable, Phi: Array) -> Array:
    """`D_Φ F`: `<D_Φ F, η> = d/dε F(Φ(1 + εη/2))` at ε = 0 (body-frame variations of Φ)."""
    return jax.grad(lambda eta: F(Phi + 0.5 * qt.mul(Phi, jnp.concatenate([jnp.zeros(1), eta]))))(jnp.zeros(3))


def vector_field(*, alpha: float, a) -> Callable[[TopState], TopState]:
    """The equations of motion `Φ' = ½ Φ Ω`, `M' = M × Ω + D_Φ L(Φ, Ω)` at `Ω = ∂H/∂M = Ω(Φ, M)`
    (module docstring; `D_Φ L = −D_Φ H` by the Legendre transform, so this is Hamilton's form
    with one derivative fewer)."""
    _check_parameters(alpha, a)
    a = jnp.asarray(a, dtype=float)
    return jax.jit(lambda state: equations_of_motion(state, alpha, a))


def equations_of_motion(state: TopState, alpha, a) -> TopState:
    """`(Φ', M')` of `vector_field` without validation: traceable in α and a (for shooting,
    `ddgjax.smooth.kirchhoff`)."""
    Omega = _velocity_of_momentum(state.Phi, state.M, alpha, a)
    dPhi = 0.5 * qt.mul(state.Phi, jnp.concatenate([jnp.zeros(1), Omega]))
    torque = _body_derivative(lambda Phi: lagrangian(Phi, Omega, alpha=alpha, a=a), state.Phi)
    return TopState(dPhi, jnp.cross(state.M, Omega) + torque)


def _check_parameters(alpha, a) -> None:
    if not (np.ndim(alpha) == 0 and float(alpha) > 0):
        raise InvalidInputError(f"the inertia ratio alpha must be a positive number (J = diag(α, 1, 1)), got {alpha}")
    qt.as_vector(a, "a")


def initial_state(Phi0, Omega0, *, alpha: float, a) -> TopState:
    """`(Φ0, M0 = ∂L/∂Ω(Φ0, Ω0))` from a unit frame Φ0 and a body angular velocity Ω0.

    **Raises:** `InvalidInputError` (Φ0 not unit, α ≤ 0), `ShapeError`, `NonFiniteError`.
    """
    _check_parameters(alpha, a)
    Phi0 = qt.as_quaternion(Phi0, "Phi0")
    qt.check_unit(Phi0, "Phi0")
    Omega0 = qt.as_vector(Omega0, "Omega0")
    return TopState(Phi0, momentum(Phi0, Omega0, alpha=alpha, a=jnp.asarray(a, dtype=float)))


def conserved_quantities(states: TopState, *, alpha: float, a) -> dict[str, Array]:
    """The energy H, the vertical momentum `<Φ M Φ⁻¹, a>/|a|` (spatial angular momentum about the
    gravity axis), the axial momentum `<M, e1>` (= 2ατ, about the symmetry axis) and `|Φ|²`,
    for a state or a stack of states."""
    return _conserved(states.Phi, states.M, alpha, jnp.asarray(a, dtype=float))


@jax.jit
def _conserved(Phi, M, alpha, a):
    H = hamiltonian(alpha=alpha, a=a)
    energy = jnp.vectorize(lambda P, N: H(TopState(P, N)), signature="(4),(3)->()")(Phi, M)
    return {
        "energy": energy,
        "vertical_momentum": qt.rotate(Phi, M) @ a / jnp.linalg.norm(a),
        "axial_momentum": M[..., 0],
        "norm_squared": jnp.sum(Phi**2, axis=-1),
    }


def simulate(Phi0, Omega0, t1: float, *, alpha: float, a, steps: int, method: str = "gauss6"):
    """Integrate the top from `(Φ0, Ω0)` to `t1` with `ddgjax.integrate` (fixed steps).

    **Returns:** `(ts, states)` with `states` a `TopState` of stacked arrays (steps + 1 rows).
    """
    a = jnp.asarray(a, dtype=float)
    state0 = initial_state(Phi0, Omega0, alpha=alpha, a=a)
    return integrate(vector_field(alpha=alpha, a=a), state0, t1, steps=steps, method=method)
