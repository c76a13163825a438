"""The Lagrange top (Section 3.4.1): equations of motion from the action (3.10) by autodiff.

Checks: (i) the autodiff equations are the Euler–Lagrange equations of (3.10) written in Φ, Φ'
(constrained to H_1: the residual is normal to the sphere) and agree with the hand-derived
Euler–Poisson form; (ii) over t = 100 the Gauss6 integration keeps the energy, the axial
momentum and |Φ|² (quadratic/linear invariants: round-off) and the vertical momentum (cubic:
order-6 error) to 1e-9.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from ddgjax import quaternion as qt
from ddgjax.smooth import top
from ddgjax.errors import InvalidInputError, ShapeError

ALPHA = 2.5
A = np.array([0.0, 0.0, -1.0])


def random_states(rng, n=4):
    Phi = rng.normal(size=(n, 4))
    Phi /= np.linalg.norm(Phi, axis=1, keepdims=True)
    return [top.initial_state(P, W, alpha=ALPHA, a=A) for P, W in zip(Phi, rng.normal(size=(n, 3)) * 2)]


def test_momentum_is_2_J_omega(rng):
    """M = ∂L/∂Ω = 2JΩ with J = diag(α, 1, 1) (from (3.8)–(3.10)); H = <Ω, JΩ> − 2<a, T>."""
    Phi = qt.from_axis_angle(np.array([1.0, 2.0, 0.5]), 1.1)
    Omega = np.array([0.7, -1.2, 0.4])
    state = top.initial_state(Phi, Omega, alpha=ALPHA, a=A)
    assert np.max(np.abs(state.M - 2 * np.array([ALPHA, 1, 1]) * Omega)) <= 1e-13
    T = qt.rotate(Phi, np.array([1.0, 0, 0]))
    energy = Omega @ (np.array([ALPHA, 1, 1]) * Omega) - 2 * A @ T
    assert abs(top.hamiltonian(alpha=ALPHA, a=A)(state) - energy) <= 1e-13


def test_equations_of_motion_are_euler_lagrange_of_3_10(rng):
    """Along the vector field, d/dt ∂L/∂Φ' − ∂L/∂Φ = λΦ for L = action_density(Φ, Φ') (3.10):
    the Euler–Lagrange equations on H_1 (a multiplier for |Φ|² = 1).  Exact identity, evaluated
    by nested autodiff on O(10) data: 1e-11.  The torque with the wrong sign fails it by O(1)."""
    f = top.vector_field(alpha=ALPHA, a=A)
    L = lambda Phi, dPhi: top.action_density(Phi, dPhi, alpha=ALPHA, a=A)  # noqa: E731

    @jax.jit
    def residual(state, sign):
        def flow(s):
            v = f(s)
            spin = jnp.cross(s.M, 2 * qt.to_vector(qt.mul(qt.conj(s.Phi), v.Phi)))  # M × Ω
            return top.TopState(v.Phi, spin + sign * (v.M - spin))

        def p(s):
            return jax.grad(L, argnums=1)(s.Phi, flow(s).Phi)

        dp = jax.jvp(p, (state,), (flow(state),))[1]
        R = dp - jax.grad(L, argnums=0)(state.Phi, flow(state).Phi)
        return R - (R @ state.Phi) * state.Phi

    for state in random_states(rng):
        assert np.max(np.abs(residual(state, 1.0))) <= 1e-11
        assert np.max(np.abs(residual(state, -1.0))) >= 1e-2  # M' = M × Ω − torque is not it


def test_torque_matches_hand_derived_euler_poisson(rng):
    """M' = M × Ω + 2 e1 × Γ with Ω = (2J)⁻¹M and the body gravity Γ = Φ⁻¹ a Φ; Φ' = ½ΦΩ."""
    f = top.vector_field(alpha=ALPHA, a=A)
    for state in random_states(rng):
        Omega = state.M / (2 * np.array([ALPHA, 1, 1]))
        Gamma = qt.rotate(qt.conj(state.Phi), A)
        v = f(state)
        assert np.max(np.abs(v.M - (np.cross(state.M, Omega) + 2 * np.cross([1.0, 0, 0], Gamma)))) <= 1e-12
        assert np.max(np.abs(v.Phi - 0.5 * qt.mul(state.Phi, qt.from_vector(Omega)))) <= 1e-13


def test_long_run_keeps_energy_and_momenta():
    """t = 100, 4000 Gauss6 steps (h = 0.025) of a fast top (spin Ω1 = 3) tilted 52° from a:
    energy, axial momentum <M, e1> and |Φ|² (quadratic/linear invariants: round-off, observed
    ~3e-14 on |H| ≈ 20) within 1e-11; vertical momentum <ΦMΦ⁻¹, a>/|a| (cubic: O(h⁶) per unit
    time, observed ~4e-12) within 1e-9; and the motion is not trivial (T moves by > 0.1)."""
    Phi0 = qt.from_axis_angle(np.array([1.0, 1.0, 0.0]), 0.9)
    ts, states = top.simulate(Phi0, np.array([3.0, 0.4, -0.2]), 100.0, alpha=ALPHA, a=A, steps=4000)
    c = top.conserved_quantities(states, alpha=ALPHA, a=A)
    drift = {k: float(jnp.max(jnp.abs(v - v[0]))) for k, v in c.items()}
    assert drift["energy"] <= 1e-11 and drift["axial_momentum"] <= 1e-11 and drift["norm_squared"] <= 1e-12, drift
    assert drift["vertical_momentum"] <= 1e-9, drift
    T = qt.rotate(states.Phi, np.array([1.0, 0, 0]))
    assert float(jnp.max(jnp.linalg.norm(T - T[0], axis=-1))) > 0.1


def test_bad_input():
    with pytest.raises(InvalidInputError, match="unit quaternion"):
        top.initial_state(np.array([1.0, 1.0, 0, 0]), np.zeros(3), alpha=ALPHA, a=A)
    with pytest.raises(InvalidInputError, match="alpha"):
        top.vector_field(alpha=-1.0, a=A)
    with pytest.raises(ShapeError):
        top.initial_state(qt.ONE, np.zeros(4), alpha=ALPHA, a=A)
