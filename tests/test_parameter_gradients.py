"""The catalogue constructors are differentiable in their parameters: `jax.grad` through
`solve(constructor(p))` is the implicit derivative (Sec 3.1, the implicit function theorem at a
critical point).  For the elastica it equals a central difference of the solved energy and the
`Problem.with_params` route; elsewhere it equals the envelope theorem, `dE*/dp = ∂L/∂p` at the
critical point (one compilation instead of two).

Tolerances: the central difference with step 1e-5 has truncation error O(h²) ≈ 1e-10 and the
solved energy is accurate to O(tol²) (it is stationary), so 1e-6 relative leaves a wide margin;
the automatic routes and the envelope formulas agree to the solve's tolerance (1e-9 … 1e-10).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import quaternion as qt
from energies import dirichlet, elastica, heisenberg, pendulum, rod
from solvers import solve

H = 1e-5


def central_difference(f, p, h=H):
    """(f(p + h e_i) − f(p − h e_i)) / 2h for every entry i of the array p."""
    p = np.asarray(p, dtype=float)
    grad = np.zeros_like(p)
    for i in np.ndindex(p.shape):
        step = np.zeros_like(p)
        step[i] = h
        grad[i] = (float(f(jnp.asarray(p + step))) - float(f(jnp.asarray(p - step)))) / (2 * h)
    return grad


def assert_relative(a, b, tol):
    a, b = np.asarray(a), np.asarray(b)
    assert np.max(np.abs(a - b)) <= tol * np.max(np.abs(b)), (a, b)


# --- elastica: d E / d(chord, length) -------------------------------------------------------

N, T_START, T_END = 32, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
CHORD, LENGTH = jnp.array([0.5, 0.2, 0.0]), jnp.array(1.0, dtype=float)  # not weakly typed, as the
# constructor's own length: the with_params route then reuses the compiled solver


def elastica_energy(chord, length):
    return solve(elastica.clamped(N, length=length, chord=chord, t_start=T_START, t_end=T_END)).energy


@pytest.fixture(scope="module")
def elastica_gradient():
    return jax.grad(elastica_energy, argnums=(0, 1))(CHORD, LENGTH)


def test_elastica_gradient_in_chord_and_length_equals_central_differences(elastica_gradient):
    d_chord, d_length = elastica_gradient
    assert_relative(d_chord, central_difference(lambda c: elastica_energy(c, LENGTH), CHORD), 1e-6)
    assert_relative(d_length, central_difference(lambda L: elastica_energy(CHORD, L), LENGTH), 1e-6)


def test_elastica_gradient_equals_the_with_params_route(elastica_gradient):
    problem = elastica.clamped(N, chord=CHORD, t_start=T_START, t_end=T_END)

    def energy(chord, length):
        return solve(problem.with_params({**problem.params, "h": length / N, "chord": chord})).energy

    for ours, theirs in zip(elastica_gradient, jax.grad(energy, argnums=(0, 1))(CHORD, LENGTH)):
        assert_relative(ours, theirs, 1e-10)


def test_elastica_start_is_the_same_traced_and_concrete():
    """Under `jit` the default start is computed in jax.numpy (no concrete values): the same
    array as the NumPy start of a concrete call (a few fixed-point steps keep the compile short);
    `vmap` over the length gives h = L/n."""
    args = (N, LENGTH, CHORD, jnp.asarray(T_START), jnp.asarray(T_END))
    concrete = elastica.initial_tangents(*args, steps=3)
    traced = jax.jit(lambda c: elastica.initial_tangents(N, LENGTH, c, *args[3:], steps=3))(CHORD)
    assert isinstance(concrete, np.ndarray) and np.max(np.abs(np.asarray(traced) - concrete)) <= 1e-14
    h = jax.vmap(lambda L: elastica.clamped(N, length=L, chord=CHORD, t_start=T_START, t_end=T_END).params["h"])
    assert np.allclose(h(jnp.array([1.0, 2.0])), [1.0 / N, 2.0 / N], rtol=0, atol=1e-16)


# --- rod: the energy is differentiable in alpha through the constructor ----------------------

E3 = jnp.array([0.0, 0.0, 1.0])
FRAME_START, FRAME_END = qt.from_axis_angle(E3, np.pi / 2), qt.from_axis_angle(E3, -np.pi / 2)


def test_rod_energy_is_differentiable_in_the_twist_stiffness():
    """∂/∂α of `(2/h) Σ E_k + (α/2h) Σ θ_k²` (Def 3.7) is `Σ θ_k² / 2h` at any frames Φ (here
    random unit quaternions), with α passed to `rod.clamped` as a traced value."""
    n = 12
    Phi = np.random.default_rng(0).normal(size=(n, 4))
    Phi = jnp.asarray(Phi / np.linalg.norm(Phi, axis=1, keepdims=True))

    def energy(alpha):
        problem = rod.clamped(n, alpha=alpha, chord=(0.6, 0.0, 0.1), frame_start=FRAME_START, frame_end=FRAME_END)
        return problem.energy(Phi, problem.params)

    twist = float(np.sum(np.asarray(rod.twist_angles(Phi)) ** 2))
    assert twist > 1.0  # random frames are twisted: the check is not 0 = 0
    assert abs(float(jax.jit(jax.grad(energy))(0.7)) - twist / (2 / n)) <= 1e-12 * twist


# --- pendulum: d S / d a = −Σ T_k (the envelope theorem) -------------------------------------


def test_pendulum_gradient_in_gravity_is_minus_the_sum_of_tangents():
    """S = Σ log(1 + <T_k, T_{k−1}>) − Σ <a, T_k> (Def 3.3): at a critical point only the explicit
    dependence counts, dS/da = −Σ_k T_k; implicit differentiation must reproduce it."""

    def action_and_tangents(a):
        sol = solve(pendulum.action(12, a=a, T_first=(1.0, 0.0, 0.0), T_last=(0.0, 1.0, 0.0)), method="dense")
        return sol.energy, sol.x

    (_, T), grad = jax.value_and_grad(action_and_tangents, has_aux=True)(jnp.array([0.0, 0.0, 0.3]))
    assert np.max(np.abs(np.asarray(grad) + np.sum(np.asarray(T), axis=0))) <= 1e-9


# --- Dirichlet: d E / d(weights, boundary values) -------------------------------------------

EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [1, 4], [4, 2]])
WEIGHTS, BOUNDARY, VALUES = jnp.array([1.0, 2.0, 0.5, 1.5, 0.7, 1.2, 0.9]), np.array([0, 3]), jnp.array([1.0, -2.0])


def test_dirichlet_gradient_in_weights_and_boundary_values():
    """E = ½ Σ ν_ij (f_i − f_j)² (Def 6.1) at the harmonic f: dE/dν_ij = ½ (f_i − f_j)² (envelope
    theorem) and dE/dc_b = (L f)_b, the flux through the boundary vertex b (Thm 6.1)."""

    def energy_and_solution(weights, values):
        sol = solve(dirichlet.graph(EDGES, weights, BOUNDARY, values), tol=1e-12, method="dense")
        return sol.energy, sol.x

    (_, f), (d_weights, d_values) = jax.value_and_grad(energy_and_solution, argnums=(0, 1), has_aux=True)(WEIGHTS, VALUES)
    f = np.asarray(f)
    assert np.max(np.abs(np.asarray(d_weights) - 0.5 * (f[EDGES[:, 0]] - f[EDGES[:, 1]]) ** 2)) <= 1e-10
    flux = dg.laplace.graph_laplacian(EDGES, np.asarray(WEIGHTS)) @ f
    assert np.max(np.abs(np.asarray(d_values) - flux[BOUNDARY])) <= 1e-10
    assert np.max(np.abs(flux[BOUNDARY])) > 0.1  # a non-trivial check


# --- Heisenberg: H is linear in J -----------------------------------------------------------


def test_heisenberg_hamiltonian_is_differentiable_in_the_coupling():
    """dH/dJ = H/J exactly (H is linear in J); S: four orthogonal neighbours, H = 8 J log 2."""
    S = jnp.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    dH = jax.grad(lambda J: heisenberg.hamiltonian("integrable", J)(S))(0.3)
    assert abs(float(dH) - 8 * np.log(2.0)) <= 1e-14
