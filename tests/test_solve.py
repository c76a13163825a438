"""Acceptance tests of `solvers.solve` (issue: foundation).

Each test asserts a number the mathematics fixes: a KKT residual, an eigenvalue, a closed-form
multiplier, bit-for-bit fixed entries.
"""

import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import tree_max_abs_diff

import ddgjax as dg
from solvers import solve
from solvers.problems import random_symmetric, rayleigh, unit_chain


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_rayleigh_quotient_multiplier_is_eigenvalue(seed):
    """∇(xᵀAx) = λ∇(|x|²) ⇔ Ax = λx: the multiplier is an eigenvalue, x its eigenvector."""
    n = 50
    A = random_symmetric(n, seed)
    x0 = np.random.default_rng(100 + seed).normal(size=n)
    sol = solve(rayleigh(A, x0))
    assert sol.converged and float(sol.residual) <= 1e-10
    lam = float(sol.multipliers[0])
    eigenvalues = np.linalg.eigh(A)[0]
    assert np.min(np.abs(eigenvalues - lam)) <= 1e-10
    x = np.asarray(sol.x)
    assert np.linalg.norm(A @ x - lam * x, np.inf) <= 1e-10
    assert abs(x @ x - 1) <= 1e-10  # the constraint part of the KKT residual


def test_equality_constrained_qp_one_newton_step():
    """E = ½xᵀQx + cᵀx, Bx = b: one Newton step; λ from the KKT system in closed form."""
    rng = np.random.default_rng(7)
    n, m = 12, 4
    M = rng.normal(size=(n, n))
    Q, c = M @ M.T + n * np.eye(n), rng.normal(size=n)
    B, b = rng.normal(size=(m, n)), rng.normal(size=m)
    problem = dg.Problem(
        lambda x, _: 0.5 * x @ Q @ x + c @ x, np.zeros(n), constraints=lambda x, _: B @ x - b
    )
    sol = solve(problem)
    # ∇E − Bᵀλ = 0, Bx = b  ⇔  [[Q, −Bᵀ], [B, 0]] (x, λ) = (−c, b)
    K = np.block([[Q, -B.T], [B, np.zeros((m, m))]])
    closed = np.linalg.solve(K, np.concatenate([-c, b]))
    assert int(sol.steps) == 1
    assert np.max(np.abs(np.asarray(sol.x) - closed[:n])) <= 1e-10
    assert np.max(np.abs(np.asarray(sol.multipliers) - closed[n:])) <= 1e-10


def test_fixed_entries_bit_for_bit():
    problem = unit_chain(12, local=False)
    x0 = np.asarray(problem.x0)
    sol = solve(problem)
    assert sol.converged
    fixed = np.asarray(problem.fixed)
    x = np.asarray(sol.x)
    assert np.array_equal(x[fixed].view(np.int64), x0[fixed].view(np.int64))
    assert np.max(np.abs(x[~fixed] - x0[~fixed])) > 1e-3  # the free entries did move


def test_fixed_entries_in_a_pytree():
    """`fixed` follows the pytree of x0; unconstrained quadratic with a pinned leaf entry."""
    x0 = {"a": np.array([1.0, 2.0, 3.0]), "b": np.array(5.0)}
    fixed = {"a": np.array([False, True, False]), "b": np.array(False)}

    def energy(x, _):
        return jnp.sum((x["a"] - 7.0) ** 2) + (x["b"] + x["a"][1]) ** 2

    sol = solve(dg.Problem(energy, x0, fixed=fixed))
    assert float(sol.x["a"][1]) == 2.0
    np.testing.assert_allclose(np.asarray(sol.x["a"])[[0, 2]], 7.0, atol=1e-12)
    np.testing.assert_allclose(float(sol.x["b"]), -2.0, atol=1e-12)


def _thomson(n, seed):
    def coulomb(X, _):
        i, j = np.triu_indices(len(X), 1)
        return jnp.sum(1.0 / jnp.linalg.norm(X[i] - X[j], axis=1))

    X0 = np.random.default_rng(seed).normal(size=(n, 3))
    return dg.Problem(coulomb, X0, constraints=lambda X, _: jnp.sum(X**2, axis=1) - 1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_continuous_symmetry_singular_kkt_converges(seed):
    """Charges on a sphere: E is SO(3)-invariant, so K has a 3-dimensional kernel at x*."""
    problem = _thomson(7, seed)
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10
    # the KKT matrix at the answer really is singular: three (near-)zero singular values
    w = jnp.concatenate([jnp.ravel(sol.x), sol.multipliers])
    n = 21

    def lagrangian(w):
        X = w[:n].reshape(7, 3)
        return problem.energy(X, None) - w[n:] @ problem.constraints(X, None)

    s = np.linalg.svd(np.asarray(jax.hessian(lagrangian)(w)), compute_uv=False)
    assert np.sum(s <= 1e-8 * s[0]) >= 3


def test_rotation_invariant_chain_converges():
    """A closed chain of unit vectors with E = Σ (<X_k, X_{k+1}> − ½)²: SO(3)-invariant."""
    n = 9

    def energy(X, _):
        return jnp.sum((jnp.sum(X * jnp.roll(X, -1, axis=0), axis=1) - 0.5) ** 2)

    X0 = np.random.default_rng(3).normal(size=(n, 3))
    problem = dg.Problem(energy, X0, constraints=lambda X, _: jnp.sum(X**2, axis=1) - 1.0)
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10
    assert int(sol.first_order_steps) == 0  # Newton alone got there: no retry reported


def test_history_records_quadratic_convergence():
    """Newton near the answer: each residual is at most C·(previous)² for the last steps."""
    A = random_symmetric(20, 5)
    sol = solve(rayleigh(A, np.linalg.eigh(A)[1][:, 3] + 0.05))
    h = np.asarray(sol.history)
    assert len(h) == int(sol.steps) + 1 and h[-1] <= 1e-10
    assert h[-1] <= 10 * h[-2] ** 2 * max(1.0, 1 / h[-3])


def test_euler_lagrange_vanishes_at_solution_and_on_fixed_entries():
    problem = unit_chain(10, local=False, chord=(8.0, 4.2, 0.3))
    sol = solve(problem)
    el = dg.euler_lagrange(problem)(sol.x, sol.multipliers)
    assert float(jnp.max(jnp.abs(el))) <= 1e-10
    el0 = np.asarray(dg.euler_lagrange(problem)(problem.x0, sol.multipliers))
    assert np.all(el0[np.asarray(problem.fixed)] == 0.0) and np.max(np.abs(el0)) > 1e-3


def test_sparse_and_dense_paths_agree():
    """The KLU path on the assembled KKT matrix gives the dense path's answer."""
    dense = solve(unit_chain(40, chord=(32.0, 17.0, 0.5), local=False), method="dense")
    sparse = solve(unit_chain(40, chord=(32.0, 17.0, 0.5)), method="sparse")
    local_dense = solve(unit_chain(40, chord=(32.0, 17.0, 0.5)), method="dense")
    assert float(sparse.residual) <= 1e-10 and float(dense.residual) <= 1e-10
    assert float(jnp.max(jnp.abs(sparse.x - dense.x))) <= 1e-10
    assert tree_max_abs_diff(sparse.multipliers, dense.multipliers) <= 1e-10
    assert float(jnp.max(jnp.abs(local_dense.x - dense.x))) <= 1e-10


@pytest.mark.parametrize("cells_per_chunk", [1 << 13, 3])
def test_sparse_kkt_matrix_equals_dense_hessian(monkeypatch, cells_per_chunk):
    """Assembled cell blocks (incl. −λ·∇²g and ±J) equal jax.hessian of the Lagrangian, also
    when the cells are assembled in chunks (3 cells per chunk: 3 chunks, the last one padded)."""
    import solvers._sparse
    from solvers._kkt import KKT, spec_of

    monkeypatch.setattr(solvers._sparse, "CELLS_PER_CHUNK", cells_per_chunk)
    from solvers._sparse import build_pattern, index_arrays, kkt_values

    problem = unit_chain(8, chord=(6.5, 3.5, 0.2))
    spec = spec_of(problem)
    pattern = build_pattern(spec, problem.x0, problem.params)
    z0 = spec.layout.ravel(problem.x0)
    kkt = KKT(spec, z0, problem.params)
    rng = np.random.default_rng(0)
    w = jnp.asarray(rng.normal(size=spec.n + spec.m))
    coo = np.asarray(jax.jit(lambda w: kkt_values(pattern, index_arrays(pattern), kkt, w))(w))
    identity = np.asarray(jax.jit(lambda w: kkt_values(pattern, index_arrays(pattern), kkt, w, True))(w))
    K = np.zeros((spec.n + spec.m,) * 2)
    K[pattern.rows, pattern.cols] = identity
    dense = np.asarray(jax.jit(jax.hessian(kkt.lagrangian))(w))
    assert np.array_equal(K[: spec.n, : spec.n], np.eye(spec.n)) and np.max(np.abs(K[spec.n :] - dense[spec.n :])) <= 1e-12
    K = np.zeros((spec.n + spec.m,) * 2)
    K[pattern.rows, pattern.cols] = coo
    dense = np.asarray(jax.jit(jax.hessian(kkt.lagrangian))(w))
    assert np.max(np.abs(K - dense)) <= 1e-12


def test_index_arrays_share_the_pattern_buffers():
    """The solver's index arrays are the pattern's own buffers (64-byte aligned int32, which
    `jax.device_put` shares on the CPU), not copies; an unaligned array would be copied."""
    from solvers._kkt import spec_of
    from solvers._sparse import ALIGNMENT, build_pattern, device_ready, index_arrays

    problem = unit_chain(8, chord=(6.5, 3.5, 0.2))
    pattern = build_pattern(spec_of(problem), problem.x0, problem.params)
    index = index_arrays(pattern)
    for name in ("rows", "cols", "diagonal"):
        assert np.shares_memory(getattr(pattern, name), np.asarray(index[name])), name
    assert all(v.dtype == jnp.int32 and np.asarray(v).ctypes.data % ALIGNMENT == 0 for v in index.values())
    unaligned = device_ready(np.arange(17))[1:]  # 4 bytes past a 64-byte boundary
    assert not np.shares_memory(unaligned, np.asarray(jax.device_put(unaligned)))  # negative control
    assert np.array_equal(device_ready(unaligned), unaligned) and device_ready(unaligned).ctypes.data % ALIGNMENT == 0


def test_auto_uses_sparse_path_for_local_problems():
    from solvers._kkt import spec_of
    from solvers._klu import KLU
    from solvers._solve import linear_solver_of

    problem = unit_chain(600, noise=0.5 / 600)
    assert isinstance(linear_solver_of(problem, spec_of(problem), "auto", None), KLU)
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10


def test_lbfgs_method_solves_minimisation_alone():
    from solvers.problems import nearest_point_on_sphere

    c = np.array([1.0, 2.0, -0.5])
    sol = solve(nearest_point_on_sphere(c, 1.5), method="lbfgs", tol=1e-9)
    assert float(sol.residual) <= 1e-9
    np.testing.assert_allclose(np.asarray(sol.x), 1.5 * c / np.linalg.norm(c), atol=1e-9)
    np.testing.assert_allclose(float(sol.multipliers[0]), 1 - np.linalg.norm(c) / 1.5, atol=1e-9)


def test_lbfgs_stops_when_no_critical_point_is_near():
    """Two parallel planes x₀ = 1 and x₀ = 2 admit no point: the augmented Lagrangian stops once
    STALL_OUTER outer steps have not lowered the residual, long before `max_steps` (the bound it
    ran to before); a feasible problem with the same budget converges (the control)."""
    from solvers._first_order import STALL_OUTER

    def parallel_planes(x, params):
        return jnp.stack([x[0] - 1.0, x[0] - params["b"]])

    def energy(x, params):
        return jnp.sum(x**2)

    infeasible = dg.Problem(energy, np.zeros(3), constraints=parallel_planes, params={"b": 2.0})
    sol = solve(infeasible, method="lbfgs", max_steps=200, throw=False)
    assert not bool(sol.converged)
    assert STALL_OUTER <= int(sol.steps) <= 4 * STALL_OUTER
    feasible = solve(infeasible.with_params({"b": 1.0}), method="lbfgs", max_steps=200, throw=False)
    assert float(feasible.residual) <= 1e-10 and int(feasible.steps) < 4 * STALL_OUTER


def test_warm_start_reaches_minimum_from_far_away():
    """Six charges: L-BFGS phase then Newton; the minimum is the octahedron, E = 3/2 + 12/√2."""
    sol = solve(_thomson(6, 11), warm_start="lbfgs")
    assert float(sol.residual) <= 1e-10
    assert int(sol.first_order_steps) > 0  # the L-BFGS phase ran (and is reported)
    assert abs(float(sol.energy) - (1.5 + 12 / np.sqrt(2))) <= 1e-9


def test_residual_scale_is_applied():
    """`residual_scale` multiplies the stationarity and constraint parts of the residual."""
    A = random_symmetric(10, 2)
    x0 = np.random.default_rng(0).normal(size=10)
    plain = solve(rayleigh(A, x0), max_steps=2, throw=False)
    scaled = solve(rayleigh(A, x0, residual_scale=(1e-3, 1e-3)), max_steps=2, throw=False)
    np.testing.assert_allclose(float(scaled.residual), 1e-3 * float(plain.residual), rtol=1e-12)


@pytest.mark.parametrize("back_end", ["klu", "superlu"])
def test_sparse_solves_match_dense(back_end):
    """Our direct use of KLU (pre-sorted indices, reused symbolic analysis) and the host
    factorisation solve K x = b, and the Levenberg–Marquardt step (KᵀK + νI) d = −Kᵀ b (complex
    shift of K made on the device for KLU, on the host for `SparseDirect`)."""
    from solvers._direct import SparseDirect
    from solvers._kkt import KKT, spec_of
    from solvers._klu import KLU
    from solvers._sparse import build_pattern, index_arrays

    problem = unit_chain(9, chord=(7.5, 3.5, 0.2))
    spec = spec_of(problem)
    pattern = build_pattern(spec, problem.x0, problem.params)
    algebra = KLU(pattern) if back_end == "klu" else SparseDirect(pattern, index_arrays(pattern), factoriser=back_end)
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    rng = np.random.default_rng(3)
    w, b = (jnp.asarray(rng.normal(size=spec.n + spec.m)) for _ in range(2))
    # the bound back end is an argument, not a constant: KLU's analysis is an address of this
    # process, which as a constant would keep the program out of the persistent cache
    x = jax.jit(lambda algebra, w, b: algebra.solve(kkt, w, 0.0, b))(algebra, w, b)
    K = np.asarray(jax.jit(jax.hessian(kkt.lagrangian))(w))
    assert np.max(np.abs(K @ np.asarray(x) - np.asarray(b))) <= 1e-10
    d = jax.jit(lambda algebra, w, b: algebra.lm_solve_matrix(algebra.matrix(kkt, w), 0.3, b))(algebra, w, b)  # (KᵀK + νI) d = −Kᵀ b
    assert np.max(np.abs((K.T @ K + 0.3 * np.eye(len(K))) @ np.asarray(d) + K.T @ np.asarray(b))) <= 1e-10
    Kb = jax.jit(lambda algebra, w, b: algebra.matvec(algebra.matrix(kkt, w), b))(algebra, w, b)  # the assembled K times b
    assert np.max(np.abs(np.asarray(Kb) - K @ np.asarray(b))) <= 1e-12 * np.max(np.abs(K @ np.asarray(b)))


def _klu_chain(n: int, chord):
    """A KLU back end bound to `unit_chain(n)` (bordered with a chord), its KKT and a size."""
    from solvers._kkt import KKT, spec_of
    from solvers._klu import KLU
    from solvers._sparse import build_pattern

    problem = unit_chain(n, chord=chord)
    spec = spec_of(problem)
    kkt = KKT(spec, spec.layout.ravel(problem.x0), problem.params)
    return KLU(build_pattern(spec, problem.x0, problem.params)), kkt, spec.n + spec.m


@pytest.mark.parametrize("chord", [None, (7.5, 3.5, 0.2)], ids=["plain", "bordered"])
def test_klu_factorised_solves_match_one_shot_solves(chord):
    """`KLU.factorised` (one factorisation, several solves, the factors freed after) gives the
    one-shot `apply` to round-off, plain and bordered (the chord's Schur complement made once),
    for one matrix, a batch of matrices (vmap: a batch of factors, freed together), and one
    matrix shared by a batch of right-hand sides (its factors freed once: a second free of the
    same factors would crash the process)."""
    algebra, kkt, N = _klu_chain(9, chord)
    rng = np.random.default_rng(5)
    w, b1, b2 = (jnp.asarray(rng.normal(size=N)) for _ in range(3))

    def both(algebra, w, b1, b2):  # the bound KLU an argument (see test_sparse_solves_match_dense)
        fac = algebra.factor_matrix(kkt, algebra.matrix(kkt, w), 1e-14)
        once = (algebra.apply(fac, b1), algebra.apply(fac, b2))
        return once, algebra.factorised(fac, lambda solve: (solve(b1), solve(solve(b2))))

    (x1, x2), (y1, y2y) = jax.jit(both)(algebra, w, b1, b2)
    assert float(jnp.max(jnp.abs(x1 - y1))) <= 1e-12 * float(jnp.max(jnp.abs(x1)))
    x2x = algebra.apply(algebra.factor_matrix(kkt, algebra.matrix(kkt, w), 1e-14), x2)
    assert float(jnp.max(jnp.abs(x2x - y2y))) <= 1e-11 * float(jnp.max(jnp.abs(x2x)))
    K = np.asarray(jax.jit(jax.hessian(kkt.lagrangian))(w))
    assert np.max(np.abs(K @ np.asarray(y1) - np.asarray(b1))) <= 1e-10
    W, B1, B2 = (jnp.asarray(rng.normal(size=(4, N))) for _ in range(3))
    for axes in [(0, 0, 0), (None, 0, 0)]:  # a batch of matrices; one matrix, a batch of right-hand sides
        (X1, _), (Y1, _) = jax.jit(jax.vmap(both, in_axes=(None, *axes)))(algebra, W if axes[0] == 0 else w, B1, B2)
        assert float(jnp.max(jnp.abs(X1 - Y1))) <= 1e-12 * float(jnp.max(jnp.abs(X1)))


def test_is_staged_only_while_jit_traces():
    """`is_staged`: False outside `jit` (under `grad` or `vmap` alone too), True in a `jit`'s
    trace (and under `grad` or `vmap` inside it)."""
    from ddgjax._checks import is_staged

    seen = []

    def probe(x):
        seen.append(is_staged())
        return x * x

    probe(1.0)
    jax.grad(probe)(1.0)
    jax.vmap(probe)(jnp.ones(2))
    jax.jit(probe)(1.0)
    jax.jit(jax.grad(probe))(2.0)
    jax.jit(jax.vmap(probe))(jnp.ones(3))
    assert seen == [False, False, False, True, True, True]


@pytest.mark.parametrize("chord", [None, (7.5, 3.5, 0.2)], ids=["plain", "bordered"])
def test_klu_bound_while_jit_traces_analyses_inside_the_program(chord):
    """Bound outside any trace, KLU carries the address of its analysis (an argument of the
    programs); bound while `jit` traces, none, since the address would be a constant of the
    caller's program, different in every process (`tests/test_compile_cache_persistent.py`):
    each solve then analyses, factorises and solves in one call.  Both give the same solves,
    plain and bordered."""
    from solvers._klu import KLU

    algebra, kkt, N = _klu_chain(9, chord)
    assert "klu_symbolic" in algebra.index
    rng = np.random.default_rng(3)
    w, b = (jnp.asarray(rng.normal(size=N)) for _ in range(2))

    def solves(algebra):
        fac = algebra.factor_matrix(kkt, algebra.matrix(kkt, w), 1e-14)
        return algebra.apply(fac, b), algebra.factorised(fac, lambda solve: solve(solve(b)))

    staged = {}

    def inside(w_unused):
        staged["index"] = set(KLU(algebra.pattern).index)
        return solves(KLU(algebra.pattern))

    (x, y), (xs, ys) = solves(algebra), jax.jit(inside)(w)
    assert "klu_symbolic" not in staged["index"]
    assert float(jnp.max(jnp.abs(x - xs))) <= 1e-12 * float(jnp.max(jnp.abs(x)))
    assert float(jnp.max(jnp.abs(y - ys))) <= 1e-11 * float(jnp.max(jnp.abs(y)))


def test_klu_solutions_and_gradients_inside_jit_equal_those_outside():
    """The energy of the clamped elastica and its gradient in the chord (a bordered KKT matrix)
    through `solve` with KLU: under `jit` (analysis inside the program) as without (`grad`
    alone: the analysis' address an argument)."""
    from energies import elastica
    from solvers._klu import KLU

    problem = elastica.clamped(10, chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))

    def energy(c):
        return solve(problem.with_params({**problem.params, "chord": c}), linear_solver=KLU(), throw=False).energy

    c = jnp.array([0.45, 0.2, 0.0])
    (e, g), (e_jit, g_jit) = jax.value_and_grad(energy)(c), jax.jit(jax.value_and_grad(energy))(c)
    assert abs(float(e - e_jit)) <= 1e-12 * abs(float(e))
    assert float(jnp.max(jnp.abs(g - g_jit))) <= 1e-10 * float(jnp.max(jnp.abs(g)))


def _custom_calls_per_computation(hlo: str, target: str) -> dict:
    """`{computation: count}` of the custom calls to `target` in an optimised HLO module's text."""
    import collections
    import re

    where, current = collections.Counter(), None
    for line in hlo.splitlines():
        if heading := re.match(r"^(?:ENTRY )?%?([\w.\-]+) .*\{$", line):
            current = heading.group(1)
        if f'custom_call_target="{target}"' in line:
            where[current] += 1
    return dict(where)


def test_klu_analyses_inside_a_callers_program_are_each_freed_where_they_are_made():
    """A caller's `jit` with two solves of one declaration and a loop of solves: after XLA's
    optimisations every analysis made in the program sits in the computation (the loop's body
    or the entry) that frees it, once; the values equal the solves outside `jit`.  Negative
    control: the same analysis as a pure operation is merged by XLA's common-subexpression
    elimination and hoisted out of the loop, while the frees stay where they were (a double
    free and a use after free, not run here)."""
    import klujax

    import solvers._klu as klu
    from energies import elastica
    from solvers._klu import FREE_SYMBOLIC, KLU

    problem = elastica.clamped(12, chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))

    def energy(c):
        return solve(problem.with_params({**problem.params, "chord": c}), linear_solver=KLU(), throw=False).energy

    def program(c):
        return jax.lax.fori_loop(0, 3, lambda i, acc: acc + energy(c + 0.001 * i), 0.0) + energy(c) + energy(c)

    def placement():
        hlo = jax.jit(program).lower(c).compile().as_text()
        return _custom_calls_per_computation(hlo, "analyze"), _custom_calls_per_computation(hlo, FREE_SYMBOLIC)

    c = jnp.array([0.45, 0.2, 0.0])
    analyses, frees = placement()
    assert analyses == frees and sum(analyses.values()) == 3 and len(analyses) == 2
    expected = sum(float(energy(c + 0.001 * i)) for i in range(3)) + 2 * float(energy(c))
    assert abs(float(jax.jit(program)(c)) - expected) <= 1e-12 * abs(expected)
    analyze = klu._klu_analyze
    klu._klu_analyze = lambda rows, cols, size: klujax.analyze_p.bind(
        jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32), jnp.int32(size))
    try:
        jax.clear_caches()  # the solver's traces, which hold the analysis of the first placement
        analyses, frees = placement()
    finally:
        klu._klu_analyze = analyze
        jax.clear_caches()  # and here the pure one, which no later test may run
    assert sum(analyses.values()) < sum(frees.values()) and analyses != frees


def _rss_mib() -> float:
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1]) / 1024
    return float("nan")


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="reads VmRSS from /proc")
def test_klu_factors_made_inside_a_program_are_freed():
    """40 factorisations of a 6,000-unknown chain's KKT matrix inside one compiled loop leave
    the resident memory flat; the negative control, the same loop with the free left out, keeps
    every factorisation (about 1 MB each) and grows by about 40 MB."""
    import solvers._klu as klu

    algebra, kkt, N = _klu_chain(1500, None)
    w = jnp.asarray(np.random.default_rng(2).normal(size=N))

    def run(w):  # traced anew by each `growth()`: `jax.jit` of a new closure
        K = algebra.matrix(kkt, w)

        def one(i, acc):
            fac = algebra.factor_matrix(kkt, K, 1e-14 * (1.0 + i))
            return acc + algebra.factorised(fac, lambda solve: solve(w))

        return jax.lax.fori_loop(0, 40, one, jnp.zeros_like(w))

    def growth():
        program = jax.jit(lambda w: run(w)).lower(w).compile()
        jax.block_until_ready(program(w))  # the allocator's first use
        before = _rss_mib()
        jax.block_until_ready(program(w))
        return _rss_mib() - before

    assert growth() <= 8.0
    free, klu._klu_free = klu._klu_free, lambda numeric, after: None
    try:
        assert growth() >= 25.0
    finally:
        klu._klu_free = free


def test_finds_saddle_points_not_only_minima():
    """On the sphere the middle eigenvectors of A are saddles of xᵀAx; Newton converges to the
    one it starts near (the merit is |R|, not E)."""
    A = np.diag([1.0, 2.0, 3.0, 4.0, 5.0])
    x0 = np.array([0.05, 0.1, 1.0, -0.08, 0.02])
    sol = solve(rayleigh(A, x0))
    assert float(sol.residual) <= 1e-10
    assert abs(float(sol.multipliers[0]) - 3.0) <= 1e-12
    # second-order check: the Hessian of the Lagrangian on the tangent space is indefinite
    x = np.asarray(sol.x)
    tangent = np.linalg.svd(x[None])[2][1:]  # orthonormal basis of x^⊥
    reduced = tangent @ (2 * A - 2 * float(sol.multipliers[0]) * np.eye(5)) @ tangent.T
    eig = np.linalg.eigvalsh(reduced)
    assert eig[0] < -1 and eig[-1] > 1


def test_solve_inside_jit_returns_flags_instead_of_raising():
    from solvers.problems import nearest_point_on_sphere

    @jax.jit
    def radius_residual(r):
        sol = solve(nearest_point_on_sphere(np.array([1.0, 2.0, 2.0]), r))
        return jnp.linalg.norm(sol.x), sol.converged

    norm, converged = radius_residual(2.5)
    assert bool(converged) and abs(float(norm) - 2.5) <= 1e-12


def test_repeated_solves_reuse_the_compiled_solver():
    """Problems built from the same functions and shapes share one compilation."""
    from solvers._solve import compiled_solver_count

    A = random_symmetric(8, 0)
    solve(rayleigh(A, np.ones(8)))
    before = compiled_solver_count()
    for seed in range(3):
        solve(rayleigh(random_symmetric(8, seed), np.random.default_rng(seed).normal(size=8)))
    assert compiled_solver_count() == before


@pytest.mark.parametrize("tol", [0.0, -1.0, float("inf"), float("nan")])
def test_tol_must_be_finite_and_positive(tol):
    problem = dg.Problem(energy=lambda x, p: jnp.sum(x**2), x0=jnp.ones(2))
    with pytest.raises(dg.errors.InvalidInputError, match="tol must be finite and positive"):
        solve(problem, tol=tol)
    assert bool(solve(problem, tol=1e-10).converged)  # negative control


def test_stagnation_is_declared_after_the_residual_has_not_halved_in_twenty_steps():
    """`_newton._stagnant` on residual histories: halving every step never stagnates; a history
    that halves until step 5 and then stays flat stagnates exactly at step 5 + 20 (at step 24 the
    smallest residual before the last 20 steps is still twice the flat value); no verdict in the
    first 20 steps even on a flat history."""
    from solvers._newton import STAGNATION_STEPS, _stagnant

    assert STAGNATION_STEPS == 20
    steps = np.arange(61)
    halving = jnp.asarray(0.5**steps)
    assert not any(bool(_stagnant(halving, k)) for k in steps)
    flat = jnp.asarray(0.5 ** np.minimum(steps, 5))
    verdict = [bool(_stagnant(flat, k)) for k in steps]
    assert verdict.index(True) == 25 and all(verdict[25:])
    assert not any(bool(_stagnant(jnp.ones(61), k)) for k in range(20))


def test_newton_stops_on_a_problem_without_solution_once_it_stagnates():
    """|x|² + 1 = 0 has no real solution: the residual stays at 1 after the first steps, so Newton
    stops as stalled 20 steps after its last halving, not after the Levenberg–Marquardt damping
    has grown to its bound (56 steps)."""
    from solvers._newton import STALLED

    problem = dg.Problem(lambda x, _: jnp.sum(x**2), np.ones(2), constraints=lambda x, _: jnp.array([x @ x + 1.0]))
    sol = solve(problem, warm_start=None, throw=False)
    assert int(sol.status) == STALLED and int(sol.steps) <= 22 and float(sol.residual) >= 0.99
