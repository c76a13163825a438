"""A local term's density is evaluated on its cells padded to a bucket (`locality.cell_bucket`).

The padded evaluation gives the values, Hessian blocks and Jacobian blocks of the cells alone
(the padding's rows are dropped), and problems whose terms fall in one bucket share the traced
and batched density: a second solve of another size in the bucket does not run the Python
density again, one in another bucket does (the negative control).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import locality
from solvers import solve

TRACES = {"spring": 0}


def spring(xl, rest, params):
    """(|x1 − x0| − rest)² · stiffness + the gravity potential of the edge's midpoint."""
    TRACES["spring"] += 1
    length = jnp.linalg.norm(xl[1] - xl[0])
    return params["stiffness"] * (length - rest) ** 2 + params["g"] * 0.5 * (xl[0, 1] + xl[1, 1])


def hanging_chain(n: int) -> dg.Problem:
    """A chain of n springs of rest length 1/n hanging between (0, 0) and (0.8, 0)."""
    s = np.linspace(0.0, 1.0, n + 1)
    x0 = np.stack([0.8 * s, -0.1 * np.sin(np.pi * s)], axis=1)
    fixed = np.zeros_like(x0, bool)
    fixed[[0, -1]] = True
    edges = np.stack([np.arange(n), np.arange(1, n + 1)], axis=1)
    return dg.Problem(dg.local_sum(spring, edges, data=np.full(n, 1.0 / n)), x0, fixed=fixed,
                      params={"stiffness": 50.0, "g": 1.0})


@pytest.mark.parametrize("cells", [5, 33])
def test_padded_cells_give_the_cells_values_and_derivatives(cells):
    """Buckets 32 and 128, padded from 5 and 33 cells."""
    rng = np.random.default_rng(cells)
    x = jnp.asarray(rng.normal(size=(cells, 2, 2)))
    rest = jnp.asarray(rng.uniform(0.5, 1.0, cells))
    params = {"stiffness": 3.0, "g": 0.7}
    term = locality.Term(spring, np.zeros((cells, 2), int), data=rest)
    one = lambda xl, r: spring(xl, r, params)  # noqa: E731
    direct = {"value": jax.vmap(one)(x, rest), "hessian": jax.vmap(jax.hessian(one))(x, rest)}
    w = jnp.asarray(rng.normal(size=(cells, 1)))
    assert locality.cell_bucket(cells) >= cells
    np.testing.assert_allclose(locality._on_cells(spring, "value", x, rest, params), direct["value"], rtol=1e-14)
    np.testing.assert_allclose(term.hessians(x, rest, params), direct["hessian"], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(term.hessians(x, rest, params, w), -w[:, 0, None, None, None, None] * direct["hessian"],
                               rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(term.jacobians(x, rest, params)[:, 0], jax.vmap(jax.grad(one))(x, rest), rtol=1e-13,
                               atol=1e-13)


def test_buckets_are_increasing_and_cover_every_size():
    assert list(locality.CELL_BUCKETS) == sorted(locality.CELL_BUCKETS)
    assert [locality.cell_bucket(k) for k in (1, 32, 33, 128, 129)] == [32, 32, 128, 128, 129]


def test_sizes_in_one_bucket_share_the_traced_density_and_another_bucket_traces_again():
    """n = 10 and n = 20 springs (bucket 32): the second solve runs `spring` no more (its jaxpr
    is reused); n = 40 (bucket 128) traces it again.  Each solve is a critical point:
    the residual ≤ 1e-10 and the energy gradient vanishes at the free vertices."""
    jax.clear_caches()
    counts = []
    for n in (10, 20, 40):
        before = TRACES["spring"]
        problem = hanging_chain(n)
        sol = solve(problem, tol=1e-11)
        counts.append(TRACES["spring"] - before)
        g = jax.grad(lambda x: problem.energy(x, problem.params))(sol.x)
        assert float(sol.residual) <= 1e-10 and float(jnp.max(jnp.abs(g[1:-1]))) <= 1e-9
    assert counts[0] > 0 and counts[1] == 0 and counts[2] > 0, counts
