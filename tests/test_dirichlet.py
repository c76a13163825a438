"""The Dirichlet energy on graphs and meshes (Sec 6.2, 6.3): the sparse path against `solve`,
differentiability in the weights, bad input.  Thm 6.1, 6.2, 6.5, Cor 6.3, 6.4 and their failure
with a negative weight are `ddgjax verify` checks (`sec6_laplace`)."""

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


def test_cotan_solve_equals_sparse_path():
    V, F = dg.mesh.disk(4, 12)
    V[:, 2] = 0.3 * V[:, 0] ** 2
    b = dg.mesh.boundary_loops(F)[0]
    values = np.cos(3 * np.arctan2(V[b, 1], V[b, 0]))
    sol = solve(dirichlet.cotan(V, F, b, values), tol=1e-12)
    f = dirichlet.cotan_sparse(V, F, b, values)
    assert np.max(np.abs(np.asarray(sol.x) - f)) < 1e-10


def test_singular_interior_block_is_named():
    """Weights 1, −1 at the only interior vertex make L_II = 0: the sparse path says it is singular
    (that the theorems fail with negative weights is a `ddgjax verify` check)."""
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
