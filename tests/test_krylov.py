"""Issue 9: the matrix-free Newton–Krylov path (`method="krylov"`, `solvers/_krylov.py`) and the
`method="auto"` rule.  Agreement of sparse, Krylov and dense solves on the catalogue is in
`test_scale.py`."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from ddgjax.problem import flatten_multipliers
from solvers import solve, solve_batch
from solvers._krylov import minres
from solvers._solve import DENSE_MAX, choose_method
from solvers.problems import random_symmetric, rayleigh


def test_minres_solves_symmetric_indefinite_systems_to_round_off():
    """MINRES with a symmetric positive definite preconditioner on an indefinite A: |Ax − b| small."""
    rng = np.random.default_rng(0)
    Q = np.linalg.qr(rng.normal(size=(40, 40)))[0]
    eig = np.concatenate([-np.logspace(0, 3, 15), np.logspace(-1, 2, 25)])  # indefinite, cond 10⁴
    A = jnp.asarray(Q @ np.diag(eig) @ Q.T)
    b = jnp.asarray(rng.normal(size=40))
    d = jnp.asarray(rng.uniform(0.5, 2.0, 40))
    x, iterations, rel = jax.jit(lambda b: minres(lambda v: A @ v, b, lambda r: r / d, rtol=1e-13, maxiter=200))(b)
    exact = np.linalg.solve(np.asarray(A), np.asarray(b))
    assert float(np.max(np.abs(np.asarray(x) - exact))) <= 1e-10 * np.max(np.abs(exact))
    # exact arithmetic needs ≤ 40 iterations; in float64 the lost orthogonality costs more (scipy
    # minres: 129 on this system)
    assert float(rel) <= 1e-13 and 0 < int(iterations) <= 160


def test_krylov_finds_a_saddle_point_of_a_non_local_problem():
    """The reduced Hessian at a middle eigenvector is indefinite: MINRES, not CG, on the tangent
    space of the sphere (no locality declared: products by autodiff, no preconditioner)."""
    A = np.diag([1.0, 2.0, 3.0, 4.0, 5.0])
    sol = solve(rayleigh(A, np.array([0.05, 0.1, 1.0, -0.08, 0.02])), method="krylov")
    assert float(sol.residual) <= 1e-10
    assert abs(float(sol.multipliers[0]) - 3.0) <= 1e-12


def test_krylov_quadratic_convergence_and_agreement_with_dense():
    A = random_symmetric(20, 5)
    problem = rayleigh(A, np.linalg.eigh(A)[1][:, 3] + 0.05)
    k, d = solve(problem, method="krylov"), solve(problem, method="dense")
    h = np.asarray(k.history)
    assert h[-1] <= 1e-10 and h[-1] <= 10 * h[-2] ** 2 * max(1.0, 1 / h[-3])
    assert float(jnp.max(jnp.abs(k.x - d.x))) <= 1e-10
    assert float(jnp.max(jnp.abs(k.multipliers - d.multipliers))) <= 1e-10


def _elastica(n=9):
    from energies import elastica

    return elastica.clamped(n, chord=(0.5, 0.3, 0.1), t_start=(1, 0, 0), t_end=(0, 1, 0), clamp="vertex")


def test_krylov_derivatives():
    """Implicit differentiation through the Krylov solve equals the dense one."""
    problem = _elastica()

    def energy_of(chord, method):
        return solve(problem.with_params({**problem.params, "chord": chord}), method=method).energy

    chord = jnp.asarray(problem.params["chord"])
    g_k = jax.grad(lambda c: energy_of(c, "krylov"))(chord)
    g_d = jax.grad(lambda c: energy_of(c, "dense"))(chord)
    assert float(jnp.max(jnp.abs(g_k - g_d))) <= 1e-9 * float(jnp.max(jnp.abs(g_d)))


@pytest.mark.slow
def test_krylov_batches():
    """A vmapped batch equals single solves (the whole Krylov solver runs inside jit and vmap)."""
    problem = _elastica()
    chord = jnp.asarray(problem.params["chord"])
    chords = jnp.stack([chord * (1 - 0.05 * k) for k in range(3)])
    batch = solve_batch(problem, {"chord": chords}, method="krylov")
    for k in range(3):
        single = solve(problem.with_params({**problem.params, "chord": chords[k]}), method="dense")
        assert float(jnp.max(jnp.abs(batch.x[k] - single.x))) <= 1e-10


class _FakeSpec:
    """What `choose_method` reads of a `Spec`."""

    def __init__(self, n, m, local):
        self.n, self.m, self.is_local = n, m, local


@pytest.mark.parametrize(
    "n, m, local, backend, expected",
    [
        (10, 2, True, "cpu", "sparse"),
        (10**5, 10**5, True, "cpu", "sparse"),
        (10, 2, True, "gpu", "dense"),
        (DENSE_MAX - 2, 2, True, "gpu", "dense"),
        (DENSE_MAX, 1, True, "gpu", "krylov"),
        (10**5, 10**5, True, "tpu", "krylov"),
        (100, 0, False, "cpu", "dense"),
        (10**4, 10, False, "cpu", "krylov"),
    ],
)
def test_auto_picks_method_by_size_and_backend(n, m, local, backend, expected):
    assert choose_method(_FakeSpec(n, m, local), backend) == expected


def _kkt_at_solution(problem):
    from solvers._kkt import KKT, spec_of
    from solvers._solve import linear_solver_of

    spec = spec_of(problem)
    sol = solve(problem, method="sparse")
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    w = jnp.concatenate([spec.layout.ravel(sol.x)[spec.layout.free], flatten_multipliers(problem, sol.multipliers)])
    return kkt, w, linear_solver_of(problem, spec, "krylov", None)


def test_block_tridiagonal_solve_is_exact_on_a_chain_without_border():
    """The pendulum's action (unit constraints only, stencils on neighbouring rows): the block
    Thomas algorithm of `_banded` inverts the whole KKT matrix."""
    from energies import pendulum
    from solvers import _banded
    from solvers._dense import DenseLU

    problem = pendulum.action(12, a=[0.0, 0.0, -2.0], T_first=[1.0, 0.2, 0.0], T_last=[-0.2, 1.0, 0.4])
    kkt, w, algebra = _kkt_at_solution(problem)
    assert algebra.chain is not None and algebra.chain.size == 4  # (T_k, its multiplier) per block
    b = jnp.asarray(np.random.default_rng(0).normal(size=w.size))

    @jax.jit
    def block_solve(w, b):
        fac = algebra.factor_matrix(kkt, algebra.matrix(kkt, w), 0.0)
        return _banded.solve(algebra.chain, algebra.index, fac.chain, b)

    exact = np.linalg.solve(np.asarray(DenseLU().matrix(kkt, w)), np.asarray(b))
    assert float(np.max(np.abs(np.asarray(block_solve(w, b)) - exact))) <= 1e-10 * np.max(np.abs(exact))


def test_chain_preconditioned_gmres_solves_the_bordered_elastica_kkt_system():
    """The chord's three multipliers border the block-tridiagonal matrix; GMRES preconditioned by
    the block solve accounts for them: the Krylov solve equals the dense one."""
    from solvers._dense import DenseLU

    kkt, w, algebra = _kkt_at_solution(_elastica(12))
    assert algebra.chain is not None
    b = jnp.asarray(np.random.default_rng(1).normal(size=w.size))
    d = jax.jit(lambda w, b: algebra.solve(kkt, w, 0.0, b))(w, b)
    K = np.asarray(DenseLU().matrix(kkt, w))
    assert float(np.max(np.abs(K @ np.asarray(d) - np.asarray(b)))) <= 1e-9


def test_meshes_are_not_chains():
    """A 2-D mesh has no block-tridiagonal numbering with small blocks: the Krylov path then uses
    the tangent-space MINRES with the Jacobi metric."""
    from energies import area

    V, F = __import__("ddgjax").mesh.disk(4, 12)
    problem = area.simplicial(np.asarray(V, float) + [0.0, 0.0, 0.1], F)
    from solvers._kkt import spec_of
    from solvers._solve import linear_solver_of

    assert linear_solver_of(problem, spec_of(problem), "krylov", None).chain is None


def test_elastica_declared_alike_reuse_the_compiled_krylov_solver():
    """Each `elastica.clamped(n, ...)` call builds a new declaration (and pattern, and chain);
    equal structure must still hit jit's cache."""
    from solvers._solve import compiled_solver_count

    solve(_elastica(), method="krylov")
    before = compiled_solver_count()
    for k in range(2):
        problem = _elastica()
        solve(problem.with_params({**problem.params, "chord": jnp.asarray(problem.params["chord"]) * (0.95 - 0.05 * k)}),
              method="krylov")
    assert compiled_solver_count() == before
