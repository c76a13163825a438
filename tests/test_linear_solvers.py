"""The linear solvers of `solve` as objects: every back end gives the same critical point,
multipliers, derivatives and batches; `SparseDirect`'s `LDLᵀ` reports the inertia."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest


import ddgjax as dg
from ddgjax.errors import InvalidInputError
from energies import area, elastica
from solvers import KLU, DenseLU, Krylov, LinearSolver, SparseDirect, solve, solve_batch
from solvers._direct import cholmod_available, default_factoriser, pardiso_available
from solvers._kkt import KKT, spec_of

needs_ldl = pytest.mark.skipif(default_factoriser() is None, reason="neither MKL Pardiso nor CHOLMOD installed")
LDL = [f for f, ok in (("pardiso", pardiso_available()), ("cholmod", cholmod_available())) if ok]

CLAMPED = dict(chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))
BACK_ENDS = [DenseLU(), KLU(), SparseDirect(), SparseDirect(factoriser="superlu"), Krylov()]
if cholmod_available():
    BACK_ENDS.append(SparseDirect(factoriser="cholmod"))


def _saddle(k: int = 8):
    """The saddle grid, near its minimal surface (5 Pinkall–Polthier steps)."""
    V, F, boundary = dg.mesh.saddle_grid(k, noise=0.07)
    V = area.minimal_surface(V, F, boundary, method="cotan", max_iter=5, throw=False)[0]
    return V, F, boundary


@pytest.fixture(scope="module")
def reference():
    problem = elastica.clamped(16, **CLAMPED)
    return problem, solve(problem, linear_solver=DenseLU())


@pytest.mark.parametrize("linear", BACK_ENDS, ids=repr)
def test_every_back_end_finds_the_same_elastica(reference, linear):
    problem, ref = reference
    sol = solve(problem, linear_solver=linear)
    assert float(sol.residual) <= 1e-10
    assert np.max(np.abs(np.asarray(sol.x) - np.asarray(ref.x))) <= 1e-10
    assert np.max(np.abs(np.asarray(sol.multipliers["chord"]) - np.asarray(ref.multipliers["chord"]))) <= 1e-8


@pytest.mark.parametrize("linear", [SparseDirect(), SparseDirect(factoriser="superlu"), KLU()]
                         + ([SparseDirect(factoriser="cholmod")] if cholmod_available() else []), ids=repr)
def test_sparse_back_ends_agree_on_a_minimal_surface(linear):
    V, F, boundary = _saddle()
    problem = area.simplicial(V, F, boundary)
    ref = solve(problem, linear_solver=DenseLU(), tol=1e-11)
    sol = solve(problem, linear_solver=linear, tol=1e-11)
    assert float(sol.residual) <= 1e-11
    assert np.max(np.abs(np.asarray(sol.x) - np.asarray(ref.x))) <= 1e-10


@needs_ldl
def test_method_sparse_takes_klu_on_chains_and_small_meshes_and_sparse_direct_on_larger_meshes():
    from solvers._solve import KLU_MAX, linear_solver_of

    chain = elastica.clamped(1200, **CLAMPED)
    small, large = (area.simplicial(*dg.mesh.saddle_grid(k)) for k in (8, 40))
    assert spec_of(small).n <= KLU_MAX < spec_of(large).n and KLU_MAX < spec_of(chain).n + spec_of(chain).m
    assert isinstance(linear_solver_of(chain, spec_of(chain), "sparse", None), KLU)
    assert isinstance(linear_solver_of(small, spec_of(small), "sparse", None), KLU)
    assert isinstance(linear_solver_of(large, spec_of(large), "sparse", None), SparseDirect)


def test_gradient_and_batch_through_sparse_direct(reference):
    """The adjoint solve (`apply_transpose`) and `vmap` (one host call per batch) of `SparseDirect`
    give the dense path's derivative and the loop of single solves."""
    problem, _ = reference

    def energy(chord, linear):
        return solve(problem.with_params({**problem.params, "chord": chord}), linear_solver=linear).energy

    chord = jnp.asarray(problem.params["chord"])
    g_dense = jax.grad(energy)(chord, DenseLU())
    g_direct = jax.grad(energy)(chord, SparseDirect())
    assert np.max(np.abs(g_direct - g_dense)) <= 1e-8 * np.max(np.abs(g_dense))
    chords = chord + jnp.linspace(0.0, 0.05, 3)[:, None] * jnp.array([1.0, 0.0, 0.0])
    batch = solve_batch(problem, {"chord": chords}, linear_solver=SparseDirect())
    for k in range(3):
        one = solve(problem.with_params({**problem.params, "chord": chords[k]}), linear_solver=KLU())
        assert np.max(np.abs(np.asarray(batch.x[k]) - np.asarray(one.x))) <= 1e-12


@needs_ldl
@pytest.mark.parametrize("factoriser", LDL)
def test_ldl_inertia_counts_negative_eigenvalues(factoriser):
    """Sylvester's law: the negative pivots of `LDLᵀ` count the negative eigenvalues, here of the
    area Hessian shifted between its 3rd and 4th eigenvalue (three negative ones)."""
    V, F, boundary = _saddle()
    problem = area.simplicial(V, F, boundary)
    spec = spec_of(problem)
    linear = SparseDirect(factoriser=factoriser).bind(problem, spec)
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    K = linear.matrix(kkt, spec.layout.ravel(problem.x0)[spec.layout.free])
    dense = np.zeros((spec.n, spec.n))
    dense[linear.pattern.rows, linear.pattern.cols] = np.asarray(K)
    eigenvalues = np.linalg.eigvalsh(dense)
    shift = 0.5 * (eigenvalues[2] + eigenvalues[3])
    shifted = K.at[linear.index["diagonal"]].add(-shift)
    _, negative = linear.factor_with_inertia(shifted, 0.0)
    assert int(negative) == 3
    # negative control: the sign flipped, the complementary count
    _, flipped = linear.factor_with_inertia(-shifted, 0.0)
    assert int(flipped) == spec.n - 3


@pytest.mark.parametrize("factoriser", ["superlu"] + LDL)
def test_sparse_direct_levenberg_marquardt_step_equals_the_dense_formula(factoriser):
    """The Levenberg–Marquardt step `d = −(K² + νI)⁻¹ K R = −Re[(K + i√ν I)⁻¹ R]` of
    `SparseDirect` equals the dense formula to 1e-10 on the KKT matrix of a bubble (the volume
    multiplier couples every vertex) away from the solution, where K is singular (the three
    translations).  Negative control: ν off by 10 % moves d by far more."""
    V, F = dg.mesh.subdivide(*dg.mesh.cube(triangulated=True))
    problem = area.with_volume(V - 0.5, F, 1.0)
    spec = spec_of(problem)
    linear = SparseDirect(factoriser=factoriser).bind(problem, spec)
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    w = jnp.concatenate([spec.layout.ravel(problem.x0)[spec.layout.free], jnp.array([0.7])])
    K = linear.matrix(kkt, w)
    size = spec.n + spec.m
    dense = np.zeros((size, size))
    dense[linear.pattern.rows, linear.pattern.cols] = np.asarray(K)
    R = np.asarray(kkt.residual(w))
    nu = 0.3 * np.linalg.norm(dense, 2) ** 2
    expected = -np.linalg.solve(dense @ dense + nu * np.eye(size), dense @ R)
    d = np.asarray(linear.lm_solve_matrix(K, nu, jnp.asarray(R)))
    assert np.linalg.norm(d - expected) <= 1e-10 * np.linalg.norm(expected)
    off = -np.linalg.solve(dense @ dense + 1.1 * nu * np.eye(size), dense @ R)
    assert np.linalg.norm(off - expected) > 1e-3 * np.linalg.norm(expected)


def test_linear_solver_errors():
    chain = elastica.clamped(8, **CLAMPED)
    with pytest.raises(InvalidInputError, match="LinearSolver"):
        solve(chain, linear_solver="klu")
    with pytest.raises(InvalidInputError, match="factoriser"):
        SparseDirect(factoriser="mumps")
    not_local = dg.Problem(lambda x, p: jnp.sum((x - 1.0) ** 2), np.zeros(3))
    with pytest.raises(InvalidInputError, match="dg.local_sum"):
        solve(not_local, linear_solver=KLU())
    assert isinstance(SparseDirect(), LinearSolver)


def _tilted_saddle(x, _):
    return x[0] ** 2 - x[1] ** 2 + x[1] ** 4


def test_minimize_leaves_the_saddle_that_solve_finds():
    """E = x² − y² + y⁴: Newton for critical points from near the origin stays at the saddle (0, 0);
    `minimize` (inertia correction) reaches a minimum (0, ±1/√2), Hessian diag(2, 4)."""
    from solvers import minimize

    problem = dg.Problem(_tilted_saddle, np.array([0.1, 1e-3]))
    saddle = solve(problem)
    assert np.max(np.abs(np.asarray(saddle.x))) < 1e-10  # negative control: solve finds the saddle
    minimum = minimize(problem)
    assert abs(abs(float(minimum.x[1])) - 2**-0.5) < 1e-12 and abs(float(minimum.x[0])) < 1e-12
    assert abs(float(minimum.energy) + 0.25) < 1e-14
    H = np.asarray(jax.hessian(lambda x: _tilted_saddle(x, None))(minimum.x))
    assert np.min(np.linalg.eigvalsh(H)) > 1.0
    with pytest.raises(InvalidInputError, match="constraints"):
        minimize(elastica.clamped(8, **CLAMPED))


@pytest.mark.skipif(not pardiso_available(), reason="MKL Pardiso not installed")
def test_pardiso_solvers_name_the_mkl_runtime_once_found(monkeypatch, tmp_path):
    """`pardiso_solver` leaves `PYPARDISO_MKL_RT` naming the MKL runtime the solver loaded, so
    later constructions (and child processes) skip pypardiso's search of the file system; a
    path the user set is kept."""
    import os

    import pypardiso

    from solvers._direct import pardiso_solver

    monkeypatch.delenv("PYPARDISO_MKL_RT", raising=False)
    solver = pardiso_solver(-2)
    path = os.environ["PYPARDISO_MKL_RT"]
    assert os.path.isfile(path) and "mkl_rt" in os.path.basename(path)
    assert os.path.samefile(pypardiso.PyPardisoSolver().libmkl._name, solver.libmkl._name)
    own = tmp_path / "libmkl_rt.so"  # the user's own name of the library, kept
    own.symlink_to(path)
    monkeypatch.setenv("PYPARDISO_MKL_RT", str(own))
    assert pardiso_solver(11).libmkl._name == str(own) and os.environ["PYPARDISO_MKL_RT"] == str(own)


@pytest.mark.parametrize("make", [KLU, SparseDirect, Krylov], ids=["KLU", "SparseDirect", "Krylov"])
def test_a_solver_bound_to_the_problems_pattern_binds_to_itself_and_to_another_pattern_anew(make):
    """`bind` keeps a solver already bound to the problem's sparsity pattern (`solve_batch` passes
    the bound solver, its index arrays traced, into `solve`), and binds one bound to another
    problem anew (negative control: keeping it would solve with the wrong pattern)."""
    small, large = (elastica.clamped(n, chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0)) for n in (8, 10))
    bound = make().bind(small, spec_of(small))
    assert bound.pattern is not None and bound.bind(small, spec_of(small)) is bound
    other = bound.bind(large, spec_of(large))
    assert other is not bound and other.pattern.n == spec_of(large).n != bound.pattern.n
