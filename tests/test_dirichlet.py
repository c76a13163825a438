"""The Dirichlet energy on graphs and meshes (Sec 6.2, 6.3): Thm 6.1, 6.2, 6.5, Cor 6.3, 6.4, their
failure with a negative weight, the sparse path against `solve`, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError, NonFiniteError, NonUniqueSolutionError
from energies import dirichlet
from solvers import solve


def random_connected_graph(seed, n=14, extra=12):
    """A random spanning tree plus random extra edges, positive weights."""
    rng = np.random.default_rng(seed)
    tree = np.stack([np.arange(1, n), [rng.integers(0, i) for i in range(1, n)]], 1)
    more = rng.integers(0, n, size=(extra, 2))
    more = more[more[:, 0] != more[:, 1]]
    edges = np.vstack([tree, more])
    return edges, rng.uniform(0.1, 2.0, len(edges)), rng


def test_thm_6_1_6_5_solve_equals_sparse_path():
    edges, weights, rng = random_connected_graph(0)
    boundary = rng.choice(14, size=4, replace=False)
    values = rng.normal(size=4)
    problem = dirichlet.graph(edges, weights, boundary, values)
    sol = solve(problem, tol=1e-12)
    f = dirichlet.graph_sparse(edges, weights, boundary, values)
    assert np.max(np.abs(np.asarray(sol.x) - f)) < 1e-10
    # Cor 6.4: a different start converges to the same solution
    other = solve(problem.with_x0(np.where(problem.fixed, problem.x0, 10 * rng.normal(size=14))), tol=1e-12)
    assert np.max(np.abs(np.asarray(other.x) - f)) < 1e-10


def test_solution_is_differentiable_in_the_weights():
    """The weights are `params`: d f_i / d ν by implicit differentiation through `solve` matches
    central differences of the sparse path (error O(ε²) ≈ 1e-10)."""
    edges, weights, rng = random_connected_graph(0)
    boundary = rng.choice(14, size=4, replace=False)
    values = rng.normal(size=4)
    problem = dirichlet.graph(edges, weights, boundary, values)
    vertex = int(np.setdiff1d(np.arange(14), boundary)[0])
    grad = jax.grad(lambda w: solve(problem.with_params({"weights": w}), tol=1e-12).x[vertex])(jnp.asarray(weights))
    eps = 1e-5
    step = lambda k, s: dirichlet.graph_sparse(edges, weights + s * eps * (np.arange(len(weights)) == k), boundary, values)
    central = [(step(k, 1) - step(k, -1))[vertex] / (2 * eps) for k in range(len(weights))]
    assert np.max(np.abs(np.asarray(grad) - central)) < 1e-8


@pytest.mark.parametrize("seed", range(20))
def test_thm_6_2_6_5_random_graphs_positive_weights(seed):
    """Harmonic off V0 (Thm 6.1), the unique minimum (Thm 6.5: the interior block is positive
    definite), the maximum principle (Thm 6.2)."""
    edges, weights, rng = random_connected_graph(seed)
    boundary = rng.choice(14, size=int(rng.integers(1, 6)), replace=False)
    values = rng.normal(size=len(boundary))
    f = dirichlet.graph_sparse(edges, weights, boundary, values)
    L = dg.laplace.graph_laplacian(edges, weights)
    interior = np.setdiff1d(np.arange(14), boundary)
    assert np.max(np.abs((L @ f)[interior])) < 1e-12
    assert np.linalg.eigvalsh(L[interior][:, interior].toarray()).min() > 0
    assert values.min() - 1e-12 <= f[interior].min() and f[interior].max() <= values.max() + 1e-12
    assert np.array_equal(f[boundary], values)


def test_cotan_solve_equals_sparse_path():
    V, F = dg.mesh.disk(4, 12)
    V[:, 2] = 0.3 * V[:, 0] ** 2
    b = dg.mesh.boundary_loops(F)[0]
    values = np.cos(3 * np.arctan2(V[b, 1], V[b, 0]))
    sol = solve(dirichlet.cotan(V, F, b, values), tol=1e-12)
    f = dirichlet.cotan_sparse(V, F, b, values)
    assert np.max(np.abs(np.asarray(sol.x) - f)) < 1e-10


@pytest.mark.parametrize("seed", range(3))
def test_cor_6_3_liouville(seed):
    """On a connected graph with positive weights the kernel of L is the constants."""
    edges, weights, _ = random_connected_graph(seed)
    eig, vec = np.linalg.eigh(dg.laplace.graph_laplacian(edges, weights).toarray())
    assert abs(eig[0]) < 1e-12 and eig[1] > 1e-6
    assert np.ptp(vec[:, 0]) < 1e-12


def test_negative_weight_breaks_the_theorems():
    """With a negative weight: the maximum principle (Thm 6.2), Liouville (Cor 6.3) and
    uniqueness (Cor 6.4) all fail."""
    # vertex 0 joined to boundary vertices 1 (c = 0, ν = 2) and 2 (c = 1, ν = −1): f_0 = −1 < min c
    f = dirichlet.graph_sparse([[0, 1], [0, 2]], [2.0, -1.0], [1, 2], [0.0, 1.0])
    assert abs(f[0] + 1.0) < 1e-14
    # a triangle with weights 1, 1, −½ has a non-constant harmonic function (ν12 ν23 + … = 0)
    L = dg.laplace.graph_laplacian([[0, 1], [1, 2], [2, 0]], [1.0, 1.0, -0.5]).toarray()
    eig, vec = np.linalg.eigh(L)
    kernel = vec[:, np.abs(eig) < 1e-12]
    assert kernel.shape[1] == 2
    # weights 1, −1 at one interior vertex: L_II = 0, no unique solution
    with pytest.raises(NonUniqueSolutionError, match="singular"):
        dirichlet.graph_sparse([[0, 1], [0, 2]], [1.0, -1.0], [1, 2], [0.0, 1.0])


def test_bad_input():
    edges, weights, _ = random_connected_graph(0)
    two_parts = np.vstack([edges, [[14, 15]]])
    with pytest.raises(NonUniqueSolutionError, match="vertex 14"):
        dirichlet.graph(two_parts, np.append(weights, 1.0), [0], [1.0])
    with pytest.raises(NonUniqueSolutionError, match="vertex 14"):
        dirichlet.graph_sparse(two_parts, np.append(weights, 1.0), [0], [1.0])
    with pytest.raises(InvalidInputError, match="boundary vertex 99"):
        dirichlet.graph(edges, weights, [0, 99], [1.0, 2.0])
    with pytest.raises(NonFiniteError):
        dirichlet.graph(edges, np.where(np.arange(len(weights)) == 3, np.nan, weights), [0], [1.0])
    V, F = dg.mesh.disk(2, 6)
    V[5, 0] = np.nan
    with pytest.raises(NonFiniteError, match="vertex 5"):
        dirichlet.cotan(V, F, [1], [0.0])
