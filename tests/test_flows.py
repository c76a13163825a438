"""Flows: Lie brackets (so(3)), Hamiltonian spin flow, gradient flow, integration."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError, NonFiniteError

E1, E2, E3 = np.eye(3)


def rotation_field(a):
    """R_a(x) = a × x, the velocity of the rotation about a."""
    return lambda x: jnp.cross(jnp.asarray(a), x)


def test_lie_bracket_so3_relation(rng):
    """With [f, g] = Dg·f − Df·g: [R_e1, R_e2] = −R_e3, i.e. x ↦ x × e3 (so(3), opposite sign)."""
    X = jnp.asarray(rng.normal(size=(20, 3)))
    h = dg.lie_bracket(rotation_field(E1), rotation_field(E2))(X)
    assert float(jnp.max(jnp.abs(h + rotation_field(E3)(X)))) <= 1e-12
    # for the fields x ↦ x × a the bracket reproduces the so(3) relation with the + sign
    h2 = dg.lie_bracket(lambda x: jnp.cross(x, E1), lambda x: jnp.cross(x, E2))(X)
    assert float(jnp.max(jnp.abs(h2 - jnp.cross(X, E3)))) <= 1e-12
    assert float(jnp.max(jnp.abs(h))) > 0.1  # not trivially zero


def test_lie_bracket_of_commuting_fields_vanishes(rng):
    """R_e3 commutes with φ·R_e3 for φ = |x|² (rotation-invariant), and with the Euler field."""
    X = jnp.asarray(rng.normal(size=(20, 3)))
    f = rotation_field(E3)

    def g(x):
        return jnp.sum(x**2, axis=-1, keepdims=True) * f(x)

    assert float(jnp.max(jnp.abs(dg.lie_bracket(f, g)(X)))) <= 1e-12
    assert float(jnp.max(jnp.abs(dg.lie_bracket(f, lambda x: x)(X)))) <= 1e-12
    # sanity: a non-commuting pair is detected
    assert float(jnp.max(jnp.abs(dg.lie_bracket(g, rotation_field(E1))(X)))) > 1e-2


def _rotate(v, axis, angle):
    """Rodrigues' formula."""
    k = axis / np.linalg.norm(axis)
    return v * np.cos(angle) + np.cross(k, v) * np.sin(angle) + k * (k @ v) * (1 - np.cos(angle))


@pytest.mark.parametrize("method,steps", [("gauss6", 1000), ("dopri8", None)])
def test_hamiltonian_spin_flow_is_rotation_about_a(method, steps):
    """H = <S, a>: Ṡ = a × S, the rotation about a with angular speed |a| (closed form)."""
    a = np.array([0.3, -0.5, 0.8])
    S0 = np.array([[0.6, 0.0, 0.8]])
    f = dg.hamiltonian_flow(lambda S: jnp.sum(S @ a), dg.spin_poisson)
    ts, Ss = dg.integrate(f, jnp.asarray(S0), 10.0, steps=steps, method=method, rtol=1e-12)
    exact = np.array([_rotate(S0[0], a, np.linalg.norm(a) * t) for t in np.asarray(ts)])
    assert np.max(np.abs(np.asarray(Ss)[:, 0] - exact)) <= 1e-8
    assert np.max(np.abs(np.linalg.norm(np.asarray(Ss), axis=-1) - 1)) <= 1e-10


def test_gauss_legendre_orders():
    """Errors of the s-stage Gauss method shrink like h^(2s) on ẏ = Ay (rotation)."""
    a = np.array([0.0, 0.0, 1.0])
    f = dg.hamiltonian_flow(lambda S: jnp.sum(S @ a), dg.spin_poisson)
    S0 = jnp.asarray([[1.0, 0.0, 0.0]])
    exact = _rotate(np.array([1.0, 0, 0]), a, 4.0)
    for method, order in [("gauss2", 2), ("gauss4", 4)]:
        errors = [
            np.linalg.norm(np.asarray(dg.integrate(f, S0, 4.0, steps=k, method=method)[1][-1, 0]) - exact)
            for k in (40, 80)
        ]
        assert abs(np.log2(errors[0] / errors[1]) - order) <= 0.1


def test_projection_keeps_iterates_on_constraint_set():
    """Explicit-ish adaptive integration of a flow leaving the sphere, projected back each save."""
    def f(x):
        return jnp.array([1.0, 0.0, 0.0]) + 0.0 * x  # leaves the sphere

    ts, xs = dg.integrate(f, jnp.array([0.0, 1.0, 0.0]), 1.0, constraints=lambda x: jnp.array([x @ x - 1.0]))
    assert np.max(np.abs(np.linalg.norm(np.asarray(xs), axis=1) - 1)) <= 1e-12


def test_gradient_flow_is_tangent_and_decreases_energy(rng):
    A = rng.normal(size=(6, 6))
    A = A + A.T
    problem = dg.Problem(lambda x, _: x @ A @ x, rng.normal(size=6), constraints=lambda x, _: jnp.array([x @ x - 1.0]))
    f = dg.gradient_flow(problem)
    x = jnp.asarray(rng.normal(size=6))
    v = f(x)
    assert abs(float(2 * x @ v)) <= 1e-12  # J v = 0: tangent to the sphere through x
    dE = float(jax.jvp(lambda y: y @ A @ y, (x,), (v,))[1])
    assert abs(dE + float(v @ v)) <= 1e-10  # dE/dt = −|P∇E|²
    # integrated with projection it converges to the lowest eigenvector
    _, xs = dg.integrate(f, x / jnp.linalg.norm(x), 20.0, steps=2000, method="gauss2",
                         constraints=lambda y: jnp.array([y @ y - 1.0]))
    y = np.asarray(xs[-1])
    assert abs(y @ A @ y - np.linalg.eigvalsh(A)[0]) <= 1e-6


def test_gradient_flow_keeps_fixed_entries():
    x0 = np.array([1.0, 2.0, 3.0])
    problem = dg.Problem(lambda x, _: jnp.sum(x**2), x0, fixed=np.array([True, False, False]))
    v = np.asarray(dg.gradient_flow(problem)(jnp.asarray(x0)))
    assert v[0] == 0.0 and np.allclose(v[1:], [-4.0, -6.0])


def test_integrate_reports_divergence_instead_of_nan():
    """ẏ = −1000 y with h = 0.1: the stage fixed-point iteration diverges; say so, name the step."""
    from ddgjax.errors import ConvergenceError

    with pytest.raises(ConvergenceError, match="non-finite at saved step 1"):
        dg.integrate(lambda y: -1000.0 * y, jnp.ones(2), 1.0, steps=10)


def test_integrate_bad_input():
    with pytest.raises(NonFiniteError, match=r"index \(1,\)"):
        dg.integrate(lambda x: x, np.array([0.0, np.nan]), 1.0)
    with pytest.raises(InvalidInputError, match="fixed-step"):
        dg.integrate(lambda x: x, np.array([0.0, 1.0]), 1.0, method="gauss4")
