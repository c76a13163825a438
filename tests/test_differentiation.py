"""Implicit differentiation of `solve` and vmap over parameters."""

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from solvers import solve

from conftest import tree_max_abs_diff
from solvers.problems import nearest_point_on_sphere, random_symmetric, unit_chain


def _central_difference(f, p, h=1e-6):
    return (f(p + h) - f(p - h)) / (2 * h)


def test_grad_energy_and_x_match_finite_differences():
    c = np.array([1.0, 2.0, -0.5])

    def energy_of_r(r):
        return solve(nearest_point_on_sphere(c, r)).energy

    def x0_of_r(r):
        return solve(nearest_point_on_sphere(c, r)).x[0]

    r = 1.5
    for f in (energy_of_r, x0_of_r):
        g = float(jax.grad(f)(r))
        fd = float(_central_difference(lambda s: float(f(s)), r))
        assert abs(g - fd) <= 1e-6 * max(abs(fd), 1e-12)
    # closed forms: E = (|c| − r)², x_0 = r c_0/|c|
    assert abs(float(jax.grad(energy_of_r)(r)) + 2 * (np.linalg.norm(c) - r)) <= 1e-10
    assert abs(float(jax.grad(x0_of_r)(r)) - c[0] / np.linalg.norm(c)) <= 1e-10


def test_hellmann_feynman_multiplier_derivative():
    """A(p) = A₀ + pB on the sphere: dλ/dp = vᵀBv for the eigenpair (v, λ) Newton follows."""
    A0, B = random_symmetric(15, 0), random_symmetric(15, 1)
    v0 = np.linalg.eigh(A0)[1][:, 4]

    def problem(p):
        return dg.Problem(
            lambda x, p: x @ (A0 + p * B) @ x, v0 + 0.01, params=p,
            constraints=lambda x, p: jnp.array([x @ x - 1.0]),
        )

    p = 0.02
    sol = solve(problem(p))
    v = np.asarray(sol.x)
    dlam = float(jax.grad(lambda p: solve(problem(p)).multipliers[0])(p))
    assert abs(dlam - v @ B @ v) <= 1e-9
    fd = _central_difference(lambda s: float(solve(problem(s)).multipliers[0]), p)
    assert abs(dlam - fd) <= 1e-6 * abs(fd)


def test_jacobian_of_x_with_respect_to_a_vector_parameter():
    """x* = r c/|c|: the Jacobian dx*/dc = (r/|c|)(I − ĉĉᵀ)."""
    c, r = np.array([1.0, 2.0, -0.5]), 1.5

    def x_of_c(c):
        return solve(nearest_point_on_sphere(c, r)).x

    J = np.asarray(jax.jacobian(x_of_c)(jnp.asarray(c)))
    chat = c / np.linalg.norm(c)
    assert np.max(np.abs(J - r / np.linalg.norm(c) * (np.eye(3) - np.outer(chat, chat)))) <= 1e-10


def test_grad_through_sparse_path():
    """Derivative of the solved chain's energy with respect to its chord, sparse vs dense."""
    def energy(chord, method, local):
        problem = unit_chain(12, chord=(9.5, 5.0, 0.3), local=local).with_params(chord)
        return solve(problem, method=method).energy

    chord = jnp.array([9.5, 5.0, 0.3])
    g_sparse = jax.grad(energy)(chord, "sparse", True)
    g_dense = jax.grad(energy)(chord, "dense", False)
    assert float(jnp.max(jnp.abs(g_sparse - g_dense))) <= 1e-9
    fd = _central_difference(lambda s: float(energy(chord.at[0].set(s), "dense", False)), 9.5)
    assert abs(float(g_dense[0]) - fd) <= 1e-6 * abs(fd)
    # envelope theorem: dE*/dchord equals the chord multipliers
    sol = solve(unit_chain(12, chord=(9.5, 5.0, 0.3), local=False))
    assert float(jnp.max(jnp.abs(g_dense - sol.multipliers["chord"]))) <= 1e-9


def test_vmap_over_parameters_equals_loop():
    c = np.array([1.0, 2.0, -0.5])
    radii = jnp.linspace(0.5, 2.0, 16)

    def solve_r(r):
        return solve(nearest_point_on_sphere(c, r))

    batched = jax.vmap(solve_r)(radii)
    looped = [solve_r(r) for r in radii]
    assert np.all(np.asarray(batched.converged))
    for i, sol in enumerate(looped):
        assert tree_max_abs_diff(jax.tree_util.tree_map(lambda a: a[i], batched.x), sol.x) <= 1e-12
        assert abs(float(batched.energy[i]) - float(sol.energy)) <= 1e-12


def test_vmap_sparse_path():
    chords = jnp.stack([jnp.array([8.0 + 0.1 * k, 4.2, 0.3]) for k in range(4)])
    problem = unit_chain(10, chord=(8.0, 4.2, 0.3))
    batched = jax.vmap(lambda ch: solve(problem.with_params(ch), method="sparse"))(chords)
    for k in range(4):
        single = solve(problem.with_params(chords[k]), method="dense")
        assert float(jnp.max(jnp.abs(batched.x[k] - single.x))) <= 1e-10
