"""Defaults that work: the documented calls solve without a hand-made start or tuned options.

- Euler buckling: `elastica.clamped` with straight, parallel end tangents and a shorter chord
  starts from the first buckling mode (`initial_tangents`) and converges to the Euler elastica
  (Def 3.2; the smooth inflectional elastica of Thm 3.2 as the oracle).
- Newton's step count does not grow with the resolution: a cantilever of unit tangents under a
  tip load (bending `Σ |T_{k+1} − T_k|²/h`, Def 3.2 to second order, and the load's potential
  `−⟨F, γ_n⟩ = −h Σ ⟨F, T_k⟩`).
- A start Newton alone cannot leave: a clamped elastica whose chord leaves the plane of the end
  tangents slightly.  Newton's merit |R|² stalls at a local minimum that is no solution; the
  default `warm_start="auto"` then solves again after the augmented-Lagrangian L-BFGS phase.
- Ill-conditioned problems: the regularisation is scaled row by row and the Newton step refined
  once with the unregularised K (`solvers/_linear.py`), so a diagonal quadratic with condition
  number 10¹⁴ or 10¹⁶ is solved in one step.
"""

from types import SimpleNamespace

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

import ddgjax as dg
from ddgjax.smooth import elastica as smooth
from energies import elastica
from solvers import DenseLU, solve
from solvers._linear import regularisation

E1 = np.array([1.0, 0.0, 0.0])
BUCKLED_CHORD = 0.8  # chord / length of the Euler elastica below


# --- Euler buckling ------------------------------------------------------------------------


def euler_elastica(chord: float, length: float = 1.0) -> smooth.PlanarElastica:
    """The clamped–clamped Euler elastica with T(0) = T(L) = e1 and chord `chord`·e1: the
    inflectional elastica over one period, λL = 4K(k²), whose chord over length is
    2E(k²)/K(k²) − 1 (module docstring of `ddgjax.smooth.elastica`)."""
    m = brentq(lambda m: 2.0 * ellipe(m) / ellipk(m) - 1.0 - chord / length, 1e-14, 1.0 - 1e-12, xtol=1e-15)
    return smooth.inflectional(np.sqrt(m), lam=4.0 * ellipk(m) / length, length=length)


def buckled(n: int, clamp: str) -> dg.Problem:
    return elastica.clamped(n, chord=(BUCKLED_CHORD, 0.0, 0.0), t_start=E1, t_end=E1, clamp=clamp)


def test_euler_buckling_default_start_meets_the_chord_and_the_clamps():
    """The default start is finite, unit, clamped and meets h Σ T = chord to round-off; the
    plain great-circle start it replaces (all tangents e1, shifted by one vector) cannot: it
    stays straight or divides by zero."""
    n = 24
    T0 = np.asarray(buckled(n, "edge").x0)
    assert np.all(np.isfinite(T0))
    assert np.max(np.abs(np.linalg.norm(T0, axis=1) - 1.0)) <= 1e-14
    assert np.array_equal(T0[0], E1) and np.array_equal(T0[-1], E1)
    assert np.max(np.abs(T0.mean(axis=0) - [BUCKLED_CHORD, 0, 0])) <= 1e-12
    for c in (0.8, 0.5):  # negative control: the plain start
        s = np.linspace(0.0, 1.0, n)
        with np.errstate(invalid="ignore", divide="ignore"):
            plain = elastica.chord_shifted(elastica.great_circle(E1, E1, s), np.array([c, 0, 0]), 50)
            miss = elastica.chord_mismatch(plain, np.array([c, 0, 0]))
        assert not np.isfinite(miss) or miss >= 0.1


@pytest.mark.parametrize("clamp", ["edge", "vertex"])
def test_euler_buckling_solves_to_a_planar_symmetric_elastica(clamp):
    """The documented call converges in a few steps: residual ≤ 1e-10, the clamped tangents
    exactly, the chord to round-off, the curve planar (in the plane of e1 and its buckling
    direction) and mirror symmetric about its middle, ψ(L − s) = −ψ(s): T_{n−1−k} is T_k with
    its component across e1 reversed."""
    n = 32
    problem = buckled(n, clamp)
    sol = solve(problem)
    T = np.asarray(sol.x)
    assert float(sol.residual) <= 1e-10 and int(sol.steps) <= 6
    if clamp == "edge":
        assert np.array_equal(T[0], E1) and np.array_equal(T[-1], E1)
    assert np.max(np.abs(T.sum(axis=0) / n - [BUCKLED_CHORD, 0, 0])) <= 1e-13
    gamma = np.asarray(elastica.curve(T, problem))
    across = gamma - np.outer(gamma @ E1, E1)
    direction = across[n // 2] / np.linalg.norm(across[n // 2])
    normal = np.cross(E1, direction)
    assert np.max(np.abs(gamma @ normal)) <= 1e-12
    mirrored = T - 2.0 * np.outer(T @ direction, direction)
    assert np.max(np.abs(T[::-1] - mirrored)) <= 1e-10


def test_euler_buckling_converges_to_the_smooth_euler_elastica():
    """With the vertex clamp (second order) the energy `(2/h) Σ E_k` tends to ½∫κ² ds of the
    smooth Euler elastica at order 2 (measured ratio 4.0 from n = 32 to 64), and the curve to
    the smooth one: x along e1 and the deflection across it at the vertices s = kh."""
    exact = euler_elastica(BUCKLED_CHORD)
    errors, shape_errors = [], []
    for n in (32, 64):
        problem = buckled(n, "vertex")
        sol = solve(problem)
        errors.append(abs(float(sol.energy) - 0.5 * exact.bending_energy()))
        gamma = np.asarray(elastica.curve(sol.x, problem))
        s = np.arange(n + 1) / n
        reference = exact.gamma(s)
        deflection = np.linalg.norm(gamma - np.outer(gamma @ E1, E1), axis=1)
        shape_errors.append(max(np.max(np.abs(gamma @ E1 - reference[:, 0])),
                                np.max(np.abs(deflection - np.abs(reference[:, 1])))))
    assert errors[0] <= 0.02 and 3.8 <= errors[0] / errors[1] <= 4.2
    assert shape_errors[1] <= 2e-3 and shape_errors[0] / shape_errors[1] >= 3.5
    # negative control: the straight column (energy 0) is not what was found
    assert 0.5 * exact.bending_energy() > 100 * errors[0]


# --- Newton steps that do not grow with n --------------------------------------------------


def _bend(T2, p):
    d = T2[1] - T2[0]
    return jnp.dot(d, d) / p["h"]


def _tip_load(T1, p):
    return -p["h"] * jnp.dot(p["F"], T1[0])


def _unit(T1, _):
    return jnp.dot(T1[0], T1[0]) - 1.0


def cantilever(n: int, start=(1.0, 0.0, 0.0), load=(0.0, -3.0, 0.0)) -> dg.Problem:
    """n unit tangents, T_0 = e1 clamped, every other T_k at `start`, tip load `load`."""
    edges = np.arange(n)
    energy = dg.local_sum(_bend, np.stack([edges[:-1], edges[1:]], axis=1)) + dg.local_sum(_tip_load, edges[:, None])
    x0 = jnp.tile(jnp.asarray(start, dtype=float), (n, 1)).at[0].set(E1)
    fixed = np.zeros((n, 3), bool)
    fixed[0] = True
    return dg.Problem(energy, x0, constraints=dg.local_map(_unit, edges[1:, None]),
                      params={"h": 1.0 / n, "F": jnp.asarray(load)}, fixed=fixed)


def cantilever_steps(ns, **kwargs) -> list[int]:
    steps = []
    for n in ns:
        sol = solve(cantilever(n, **kwargs), max_steps=200)
        assert float(sol.residual) <= 1e-10
        steps.append(int(sol.steps))
    return steps


@pytest.mark.parametrize("start", [(1.0, 0.0, 0.0), (0.0, -1.0, 0.0)], ids=["straight", "along-the-load"])
def test_cantilever_newton_steps_do_not_grow_with_n(start):
    """Measured: 5, 5, 5 from the straight start (5 also at n = 2,048) and 9, 11, 13 from
    tangents along the load (far away: the residual starts at ~2n)."""
    steps = cantilever_steps((16, 64, 256), start=start)
    assert max(steps) <= 2 * min(steps) and max(steps) <= 15, steps


@pytest.mark.slow
def test_cantilever_newton_steps_at_n_2048():
    steps = cantilever_steps((16, 2048))
    assert max(steps) <= 2 * min(steps) and max(steps) <= 8, steps


# --- a start Newton alone cannot leave ------------------------------------------------------


@pytest.mark.parametrize("z", [0.02, 0.1])
def test_slightly_non_planar_elastica_converges_with_the_default_call(z):
    """Def 3.2 with the chord (0.5, 0.2, z) and T_0 = e1, T_15 = e2: the solution is a critical
    point (KKT residual), on the constraints (|T_k| = 1, h Σ T_k = chord) to round-off.
    The solution is the retry's and says so (`first_order_steps` > 0, `steps` the retry's Newton
    steps, matching its history).  Negative control: Newton alone (`warm_start=None`) stops
    without converging."""
    chord = np.array([0.5, 0.2, z])
    problem = elastica.clamped(16, chord=chord, t_start=E1, t_end=(0.0, 1.0, 0.0))
    sol = solve(problem)
    T = np.asarray(sol.x)
    assert float(sol.residual) <= 1e-10
    assert int(sol.first_order_steps) > 0 and len(sol.history) == int(sol.steps) + 1
    assert np.max(np.abs(np.linalg.norm(T, axis=1) - 1.0)) <= 1e-10
    assert np.max(np.abs(T.sum(axis=0) / 16 - chord)) <= 1e-10
    with pytest.raises(dg.errors.ConvergenceError, match="did not converge"):
        solve(problem, warm_start=None)


# --- ill-conditioned problems --------------------------------------------------------------


def _quadratic_density(x1, db, _):
    return 0.5 * db[0] * x1[0, 0] ** 2 - db[1] * x1[0, 0]


def diagonal_quadratic(condition: float, local: bool, n: int = 20):
    """`E = ½ Σ d_i x_i² − Σ x_i` with d log-spaced from 1 to 1/condition; minimum x_i = 1/d_i."""
    d = np.logspace(0.0, -np.log10(condition), n)
    if local:
        energy = dg.local_sum(_quadratic_density, np.arange(n)[:, None], data=np.stack([d, np.ones(n)], axis=1))
        return dg.Problem(energy, jnp.zeros((n, 1))), 1.0 / d
    return dg.Problem(lambda x, p: 0.5 * jnp.sum(p * x**2) - jnp.sum(x), jnp.zeros(n), params=jnp.asarray(d)), 1.0 / d


@pytest.mark.parametrize("condition", [1e14, 1e16])
@pytest.mark.parametrize("method", ["dense", "sparse"])
def test_ill_conditioned_diagonal_quadratic_is_solved_in_one_step(condition, method):
    """Newton on a quadratic is exact in one step when the linear solve is: the row-scaled
    regularisation perturbs each row by 1e-14 relative (the small pivots keep 14 digits)."""
    problem, exact = diagonal_quadratic(condition, local=method == "sparse")
    sol = solve(problem, method=method)
    x = np.asarray(sol.x).ravel()
    assert int(sol.steps) <= 3 and float(sol.residual) <= 1e-10
    assert np.max(np.abs(x - exact) / exact) <= 1e-10


def test_row_scaled_regularisation_keeps_small_eigenvalues():
    """One regularised solve of `diag(d) x = 1` at condition 10¹⁶: row-scaled μ leaves the
    smallest component right to 1e-13; the former μ = 1e-14·max|K| on every row (negative
    control) gets it wrong by a factor ~100 (x = 1/(d + μ))."""
    d = jnp.asarray(np.logspace(0.0, -16.0, 9))
    kkt = SimpleNamespace(spec=SimpleNamespace(n=9, m=0))
    x = DenseLU().apply(DenseLU().factor_matrix(kkt, jnp.diag(d), 1e-14), jnp.ones(9))
    assert np.max(np.abs(np.asarray(x * d) - 1.0)) <= 1e-13
    uniform = np.linalg.solve(np.diag(d) + np.diag(regularisation(9, 0, 1e-14)), np.ones(9))
    assert abs(uniform[-1] * d[-1] - 1.0) >= 0.9


def test_iterative_refinement_squares_the_regularisation_error():
    """With μ comparable to a small eigenvalue λ of a full (rotated) matrix, the regularised
    solve is off by μ/(λ + μ) in that eigendirection and the refined one by its square."""
    lam, mu_rel = 1e-10, 1e-11
    Q = np.linalg.qr(np.random.default_rng(0).normal(size=(2, 2)))[0]
    K = jnp.asarray(Q @ np.diag([1.0, lam]) @ Q.T)
    b = jnp.asarray(Q[:, 1])  # the small eigendirection: the exact solution is b / λ
    kkt = SimpleNamespace(spec=SimpleNamespace(n=2, m=0))
    solver = DenseLU()
    fac = solver.factor_matrix(kkt, K, mu_rel)
    mu = mu_rel * float(np.max(np.abs(K), axis=1) @ np.abs(Q[:, 1]) ** 2)  # μ seen along b
    plain = float(np.dot(Q[:, 1], solver.apply(fac, b))) * lam
    refined = float(np.dot(Q[:, 1], solver.apply_refined(fac, K, b))) * lam
    ratio = mu / (lam + mu)
    assert abs((1.0 - plain) / ratio - 1.0) <= 0.05
    assert abs((1.0 - refined) / ratio**2 - 1.0) <= 0.05
