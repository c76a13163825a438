"""The multigrid-preconditioned Krylov back end (`Krylov(preconditioner="amg")`, `solvers/_amg.py`):
agreement with the sparse direct solve, iteration counts nearly independent of the mesh size
(with the Jacobi metric as the negative control), a symmetric positive definite cycle on an
indefinite matrix, the Galerkin index maps, and the errors it raises."""

import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError
from energies import area
from solvers import Krylov, SparseDirect, solve
from solvers import _amg
from solvers._kkt import KKT, spec_of
from solvers._newton import NEWTON_MU


def _saddle(k: int):
    """The saddle grid (`mesh.saddle_grid`, as `benchmarks/scale.py`, smaller) after two
    Pinkall–Polthier steps."""
    V, F, boundary = dg.mesh.saddle_grid(k)
    W = area.minimal_surface(V, F, boundary, method="cotan", max_iter=2, throw=False)[0]
    return area.simplicial(W, F, boundary)


def _first_step_iterations(problem, linear_solver):
    """MINRES iterations of the first Newton step's solve `H d = −∇E` at x0."""
    spec = spec_of(problem)
    algebra = linear_solver.bind(problem, spec)
    z0 = spec.layout.ravel(problem.x0)
    kkt = KKT(spec, z0, problem.params)

    @jax.jit
    def run(algebra, w):
        K = algebra.matrix(kkt, w)
        fac = algebra.factor_matrix(kkt, K, NEWTON_MU)
        R = kkt.residual(w)
        d, iterations = algebra.apply_counted(fac, -R)
        return iterations, jnp.linalg.norm(K.hvp(d) + fac.mu * d + R) / jnp.linalg.norm(R)

    iterations, residual = run(algebra, z0[spec.layout.free])
    return int(iterations), float(residual)


def test_amg_krylov_converges_to_the_sparse_direct_answer():
    problem = _saddle(16)
    amg = solve(problem, linear_solver=Krylov(preconditioner="amg"), tol=1e-10)
    direct = solve(problem, linear_solver=SparseDirect(), tol=1e-10)
    assert bool(amg.converged) and float(amg.residual) <= 1e-10
    assert float(jnp.max(jnp.abs(amg.x - direct.x))) <= 1e-9
    assert abs(int(amg.steps) - int(direct.steps)) <= 1


def test_method_krylov_takes_the_multigrid_cycle_on_unconstrained_meshes_only():
    """`method="krylov"` (what `method="auto"` runs for large problems on an accelerator): the
    multigrid cycle for an unconstrained mesh, whose answer is the direct one; the Jacobi
    metric for a constrained mesh (a bubble: the cycle takes no constraints) and the
    block-tridiagonal preconditioner for a chain (the elastica)."""
    from energies import elastica
    from solvers._solve import linear_solver_of

    def chosen(problem):
        return linear_solver_of(problem, spec_of(problem), "krylov", None)

    mesh = _saddle(12)
    assert chosen(mesh).preconditioner == "amg" and chosen(mesh).hierarchy is not None
    V, F = dg.mesh.icosphere(1)
    bubble = area.with_volume(V, F, 4.0)
    assert chosen(bubble).preconditioner == "jacobi"
    curve = elastica.clamped(12, chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))
    assert chosen(curve).preconditioner == "jacobi" and chosen(curve).chain is not None
    krylov, direct = solve(mesh, method="krylov", tol=1e-10), solve(mesh, method="sparse", tol=1e-10)
    assert float(jnp.max(jnp.abs(krylov.x - direct.x))) <= 1e-9


def test_rows_with_some_entries_fixed_are_padded():
    """Vertices with only some coordinates fixed: their free entries join a padded block."""
    import ddgjax as dg

    problem = _saddle(16)
    fixed = np.array(problem.fixed)
    interior = np.flatnonzero(~fixed[:, 0])
    fixed[interior[::7], 2] = True
    fixed[interior[3::11], 0] = True
    problem = dg.Problem(problem.energy, problem.x0, fixed=fixed)
    amg = solve(problem, linear_solver=Krylov(preconditioner="amg"), tol=1e-10)
    direct = solve(problem, linear_solver=SparseDirect(), tol=1e-10)
    assert float(jnp.max(jnp.abs(amg.x - direct.x))) <= 1e-9


def test_amg_iterations_stay_nearly_constant_under_refinement_and_jacobi_ones_do_not():
    """16² → 32² vertices (2 → 3 levels): the multigrid iteration count stays within 2×; the
    Jacobi-preconditioned MINRES (the negative control) needs several times more on the finer
    grid, and many times more than multigrid."""
    small, large = _saddle(16), _saddle(32)
    amg_small, res_small = _first_step_iterations(small, Krylov(preconditioner="amg"))
    amg_large, res_large = _first_step_iterations(large, Krylov(preconditioner="amg"))
    assert res_small <= 1e-9 and res_large <= 1e-9  # both solves converged
    assert 0 < amg_large <= 2 * amg_small, (amg_small, amg_large)
    jac_small, _ = _first_step_iterations(small, Krylov())
    jac_large, _ = _first_step_iterations(large, Krylov())
    assert jac_large >= 2.5 * jac_small, (jac_small, jac_large)
    assert jac_large >= 10 * amg_large, (jac_large, amg_large)


def test_the_cycle_is_symmetric_positive_definite_on_an_indefinite_matrix():
    """H − σI with σ inside H's spectrum: the cycle B, as a matrix, is symmetric with positive
    eigenvalues (module docstring of `_amg`), so it can precondition MINRES there too."""
    problem = _saddle(16)
    spec = spec_of(problem)
    algebra = Krylov(preconditioner="amg").bind(problem, spec)
    z0 = spec.layout.ravel(problem.x0)
    kkt = KKT(spec, z0, problem.params)
    K = algebra.matrix(kkt, z0[spec.layout.free])
    H = np.asarray(jax.vmap(K.hvp)(jnp.eye(spec.n)))
    sigma = float(np.median(np.linalg.eigvalsh(H)))
    h, ix = algebra.hierarchy, algebra.index

    @jax.jit
    def matrix(values):
        levels = _amg.setup(h, ix, values, -sigma)
        return jax.vmap(lambda e: _amg.precondition(h, ix, levels, e))(jnp.eye(spec.n))

    B = np.asarray(matrix(K.values[ix["h_at"]]))
    assert np.min(np.linalg.eigvalsh(H - sigma * np.eye(spec.n))) < 0  # indefinite
    assert np.max(np.abs(B - B.T)) <= 1e-10 * np.max(np.abs(B))
    assert np.min(np.linalg.eigvalsh(0.5 * (B + B.T))) > 0


def test_galerkin_maps_give_the_triple_product():
    """`galerkin_terms` + `galerkin_values` equal `Pᵀ A P` computed densely."""
    rng = np.random.default_rng(3)
    n, nc, r, c = 12, 4, 2, 3
    A = rng.normal(size=(n * r, n * r)) * np.kron(rng.random((n, n)) < 0.3, np.ones((r, r)))
    P = rng.normal(size=(n * r, nc * c)) * np.kron(rng.random((n, nc)) < 0.4, np.ones((r, c)))
    A += np.kron(np.eye(n), np.ones((r, r)))  # every block row has a block
    P[: nc * r] += np.kron(np.eye(nc), np.ones((r, c)))[: nc * r]

    def blocks(M, r, c):
        B = M.reshape(M.shape[0] // r, r, M.shape[1] // c, c).transpose(0, 2, 1, 3)
        rows, cols = np.nonzero(np.abs(B).sum((2, 3)))
        return rows, cols, B[rows, cols]

    a_rows, a_cols, a = blocks(A, r, r)
    p_rows, p_cols, p = blocks(P, r, c)
    maps, (y_rows, _), (z_rows, z_cols) = _amg.galerkin_terms(a_rows, a_cols, p_rows, p_cols, nc)
    Z = _amg.galerkin_values(maps, y_rows.size, z_rows.size, a, p)
    dense = np.zeros((nc * c, nc * c))
    for (i, j), block in zip(zip(z_rows, z_cols), Z):
        dense[i * c : (i + 1) * c, j * c : (j + 1) * c] = block
    assert np.allclose(dense, P.T @ A @ P, atol=1e-12)


def test_amg_rejects_constraints_unknown_names_and_non_local_problems():
    from solvers.problems import rayleigh, unit_chain

    with pytest.raises(InvalidInputError, match="unconstrained"):
        solve(unit_chain(8), linear_solver=Krylov(preconditioner="amg"))
    with pytest.raises(InvalidInputError, match="dg.local_sum"):
        solve(rayleigh(np.diag([1.0, 2.0, 3.0]), np.array([0.1, 1.0, 0.2])), linear_solver=Krylov(preconditioner="amg"))
    with pytest.raises(InvalidInputError, match="preconditioner"):
        Krylov(preconditioner="ilu")


def test_pyamg_is_imported_only_when_a_hierarchy_is_built():
    code = "import sys, ddgjax, solvers; print('pyamg' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out[-1] == "False"
