"""Bad input is named, never solved: 0-d leaves, the catalogue's parameters (lengths, counts,
stiffness, loads), anti-parallel spins of the integrable chain, and wrong shapes passed to a
flow.  Each check has a control: the valid call does not raise and gives the known value."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError, NonFiniteError, ShapeError, SingularVertexError
from energies import dirichlet, elastica, heisenberg, pendulum, rod
from solvers import solve

# --- 0-d leaves -------------------------------------------------------------------------------


@pytest.mark.parametrize("nan", [np.nan, np.float64(np.nan), jnp.asarray(np.nan)])
def test_scalar_nan_leaves_are_named(nan):
    with pytest.raises(NonFiniteError, match=r"x0 has the non-finite value nan at index \(\)"):
        dg.Problem(lambda x, p: (x - p) ** 2, nan, params=1.0)
    with pytest.raises(NonFiniteError, match=r"params\['a'\] has the non-finite value nan at index \(\)"):
        dg.Problem(lambda x, p: (x - p["a"]) ** 2, 0.0, params={"a": nan, "b": 1.0})


def test_scalar_leaves_control():
    """E = (x − a)² + 1 over a 0-d x: x* = a, E* = 1."""
    sol = solve(dg.Problem(lambda x, p: (x - p["a"]) ** 2 + 1.0, 0.0, params={"a": 2.0}))
    assert abs(float(sol.x) - 2.0) <= 1e-9 and abs(float(sol.energy) - 1.0) <= 1e-15


# --- elastica -----------------------------------------------------------------------------------

CLAMPS = dict(t_start=(1.0, 0.0, 0.0), t_end=(0.0, 1.0, 0.0))


def regular_polygon_tangents(n):
    angle = 2 * np.pi * np.arange(n) / n
    return np.stack([np.cos(angle), np.sin(angle), np.zeros(n)], axis=1)


@pytest.mark.parametrize("length", [-1.0, 0.0, np.nan, np.inf])
def test_closed_elastica_rejects_a_length_that_is_not_positive(length):
    with pytest.raises(InvalidInputError, match="length must be finite and positive"):
        elastica.closed(8, length=length, x0=regular_polygon_tangents(8))


def test_closed_elastica_control_regular_polygon_energy():
    """At the regular n-gon every turning angle is 2π/n: E = (2/h) n log(1 + tan²(π/n)), h = L/n."""
    n, L = 8, 2.0
    problem = elastica.closed(n, length=L, x0=regular_polygon_tangents(n))
    expected = (2 * n / L) * n * np.log1p(np.tan(np.pi / n) ** 2)
    assert abs(float(problem.energy(problem.x0, problem.params)) - expected) <= 1e-13 * expected


def test_length_is_checked_under_grad_too():
    """Under `jax.grad` (outside `jit`) the length is a tracer with a concrete value: still checked."""
    T = regular_polygon_tangents(8)

    def energy(length):
        problem = elastica.closed(8, length=length, x0=T)
        return problem.energy(problem.x0, problem.params)

    with pytest.raises(InvalidInputError, match="length"):
        jax.grad(energy)(-1.0)
    assert float(jax.grad(energy)(2.0)) < 0  # E ∝ 1/L


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(n=2), InvalidInputError, "must be at least 3, got 2"),
        (dict(n=10.5), InvalidInputError, "must be an integer"),
        (dict(length=-2.0), InvalidInputError, "length must be finite and positive"),
        (dict(chord=(np.nan, 0.0, 0.0)), NonFiniteError, "chord must be finite"),
        (dict(chord=(0.5, 0.0)), ShapeError, r"chord must have shape \(3,\), got \(2,\)"),
        (dict(chord=(1.5, 0.0, 0.0)), elastica.InfeasibleChordError, "not shorter than the length"),
        (dict(t_start=(np.nan, 0.0, 0.0)), InvalidInputError, "t_start must be a finite non-zero"),
        (dict(t_end=(0.0, 0.0)), ShapeError, r"t_end must have shape \(3,\), got \(2,\)"),
        (dict(x0=np.zeros((9, 3))), ShapeError, r"x0 must have shape \(10, 3\), got \(9, 3\)"),
    ],
)
def test_clamped_elastica_names_the_bad_parameter(kwargs, error, match):
    args = dict(n=10, chord=(0.5, 0.2, 0.0), **CLAMPS) | kwargs
    with pytest.raises(error, match=match):
        elastica.clamped(args.pop("n"), **args)


def test_clamped_elastica_control():
    """The valid call: h = L/n, the clamp tangent normalised, a start of unit tangents."""
    problem = elastica.clamped(10, length=2.0, chord=(0.5, 0.2, 0.0), t_start=(2.0, 0.0, 0.0), t_end=(0.0, 1.0, 0.0))
    assert float(problem.params["h"]) == 0.2
    assert np.array_equal(np.asarray(problem.x0[0]), [1.0, 0.0, 0.0])
    assert np.max(np.abs(np.linalg.norm(np.asarray(problem.x0), axis=1) - 1.0)) <= 1e-15


# --- rod, pendulum, Dirichlet -------------------------------------------------------------------

E3 = jnp.array([0.0, 0.0, 1.0])
ROD = dict(chord=(0.6, 0.0, 0.0), frame_start=qt.from_axis_angle(E3, np.pi / 2), frame_end=qt.from_axis_angle(E3, -np.pi / 2))


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(alpha=np.nan), InvalidInputError, "alpha must be positive"),
        (dict(alpha=np.inf), InvalidInputError, "alpha must be positive"),
        (dict(length=np.nan), InvalidInputError, "length must be finite and positive"),
        (dict(frame_end=jnp.array([np.nan, 0.0, 0.0, 1.0])), NonFiniteError, r"frame_end has the non-finite value nan at index \(0,\)"),
        (dict(frame_start=jnp.array([1.0, 0.0, 0.0])), ShapeError, r"frame_start must have shape \(4,\), got \(3,\)"),
    ],
)
def test_rod_names_the_bad_parameter(kwargs, error, match):
    with pytest.raises(error, match=match):
        rod.clamped(10, **({"alpha": 1.0} | ROD | kwargs))


def test_rod_control():
    problem = rod.clamped(10, alpha=0.5, length=2.0, **ROD)
    assert float(problem.params["alpha"]) == 0.5 and float(problem.params["h"]) == 0.2


def test_pendulum_names_the_bad_parameter():
    ends = dict(T_first=(1.0, 0.0, 0.0), T_last=(0.0, 1.0, 0.0))
    with pytest.raises(NonFiniteError, match=r"a has the non-finite value nan at index \(1,\)"):
        pendulum.action(10, a=(0.0, np.nan, 0.0), **ends)
    with pytest.raises(ShapeError, match=r"a must have shape \(3,\), got \(2,\)"):
        pendulum.action(10, a=(0.0, 1.0), **ends)
    with pytest.raises(InvalidInputError, match="must be at least 3, got 2"):
        pendulum.action(2, a=(0.0, 0.0, 1.0), **ends)
    with pytest.raises(InvalidInputError, match="T_last must be a finite non-zero"):
        pendulum.action(10, a=(0.0, 0.0, 1.0), T_first=(1.0, 0.0, 0.0), T_last=(0.0, 0.0, 0.0))
    problem = pendulum.action(10, a=(0.0, 0.0, 1.0), **ends)  # control: the potential −<a, T_k>
    assert float(problem.energy(jnp.tile(jnp.array([0.0, 0.0, 1.0]), (10, 1)), problem.params)) == pytest.approx(
        9 * np.log(2.0) - 10.0, abs=1e-13
    )


def test_dirichlet_names_nan_boundary_values():
    edges = np.array([[0, 1], [1, 2]])
    with pytest.raises(NonFiniteError, match=r"values has the non-finite value nan at index \(1,\)"):
        dirichlet.graph(edges, [1.0, 1.0], [0, 2], [0.0, np.nan])
    problem = dirichlet.graph(edges, [1.0, 3.0], [0, 2], [0.0, 4.0])  # control: c on V₀, its mean elsewhere
    assert np.array_equal(np.asarray(problem.x0), [0.0, 2.0, 4.0]) and np.array_equal(problem.fixed, [True, False, True])


# --- Heisenberg chain ---------------------------------------------------------------------------

SPINS = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]])


def test_integrable_chain_rejects_antiparallel_neighbours():
    with pytest.raises(SingularVertexError, match="spins 1 and 2 are anti-parallel"):
        heisenberg.hamiltonian("integrable")(SPINS)
    with pytest.raises(SingularVertexError, match="spins 1 and 2 are anti-parallel"):
        heisenberg.flow("integrable")(SPINS)
    wrapped = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(SingularVertexError, match="spins 3 and 0 are anti-parallel"):
        heisenberg.hamiltonian("integrable", J=0.5)(wrapped)


def test_antiparallel_neighbours_control():
    """The naive chain is regular there: H = −J Σ <S_i, S_{i+1}> = −J (0 − 1 + 0 + 0) = J; the
    integrable one at orthogonal neighbours: H = −2J Σ log(½) = 8 J log 2."""
    assert float(heisenberg.hamiltonian("naive", 2.0)(SPINS)) == 2.0
    orthogonal = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    assert abs(float(heisenberg.hamiltonian("integrable", 2.0)(orthogonal)) - 16 * np.log(2.0)) <= 1e-14


def test_heisenberg_parameters():
    with pytest.raises(InvalidInputError, match="J must be finite and non-zero"):
        heisenberg.hamiltonian("naive", np.nan)
    with pytest.raises(InvalidInputError, match="eps must be finite and positive"):
        heisenberg.scaled_hamiltonian("naive", 1.0, 0.0)
    with pytest.raises(ShapeError, match=r"spins must be an \(N, 3\) array"):
        heisenberg.hamiltonian("naive")(np.ones((4, 2)))


# --- flows --------------------------------------------------------------------------------------


def test_gradient_flow_names_expected_and_given_shape():
    problem = dg.Problem(lambda x, _: jnp.sum(x**2), np.array([1.0, 2.0, 3.0]))
    f = dg.gradient_flow(problem)
    with pytest.raises(ShapeError, match=r"x has shape \(4,\), expected \(3,\)"):
        f(jnp.ones(4))
    with pytest.raises(ShapeError, match=r"x has shape \(3, 1\), expected \(3,\)"):
        f(jnp.ones((3, 1)))
    assert np.array_equal(np.asarray(f(jnp.array([1.0, 2.0, 3.0]))), [-2.0, -4.0, -6.0])  # control: −∇E


def test_spin_poisson_and_integrate_name_shapes():
    H = dg.hamiltonian_flow(lambda S: jnp.sum(S**2), dg.spin_poisson)
    with pytest.raises(ShapeError, match=r"S must have shape \(n, 3\).*got \(4, 2\)"):
        H(jnp.ones((4, 2)))
    with pytest.raises(ShapeError, match=r"f\(x0\) has shape \(1,\), expected \(3,\)"):
        dg.integrate(lambda y: jnp.sum(y)[None], jnp.ones(3), 1.0, steps=2)
    with pytest.raises(ShapeError, match=r"g\(x\) has shape \(2,\), expected \(3,\)"):
        dg.lie_bracket(lambda x: x, lambda x: x[:2])(jnp.ones(3))
    # control: ∇H = 2S is parallel to S, so the spin flow is 0; ẏ = −y integrates to e^{−t}
    assert np.array_equal(np.asarray(H(jnp.ones((4, 3)))), np.zeros((4, 3)))
    _, ys = dg.integrate(lambda y: -y, jnp.ones(3), 1.0, steps=4)
    assert np.max(np.abs(np.asarray(ys[-1]) - np.exp(-1.0))) <= 1e-9
