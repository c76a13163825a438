"""Discrete elastica (Def 3.2, Thm 3.8, Cor 3.9, Remark 3.7) and their smooth limit."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import elastica_exact as exact
from ddgjax.errors import InvalidInputError, NonFiniteError
from energies import elastica
from solvers import solve


def heisenberg_vertex_field(T):
    """W_k = T_k × T_{k−1} / (1 + <T_k, T_{k−1}>) at the interior vertices (test oracle)."""
    T = np.asarray(T)
    return np.cross(T[1:], T[:-1]) / (1 + np.sum(T[1:] * T[:-1], axis=1))[:, None]


def space_elastica(n, clamp):
    return elastica.clamped(
        n, chord=[0.5, 0.3, 0.2], t_start=[0.0, 1.0, 0.3], t_end=[0.2, -1.0, 0.5], clamp=clamp
    )


@pytest.mark.parametrize("clamp", ["edge", "vertex"])
def test_thm_3_8_euler_lagrange_holds_with_a_from_the_multipliers(clamp):
    """W_k − a × γ_k is the same vector b at every interior vertex, a = (h/2)·(chord multipliers)."""
    problem = space_elastica(40, clamp)
    sol = solve(problem)
    assert float(sol.residual) <= 1e-10
    gamma = np.asarray(elastica.curve(sol.x, problem))
    a = np.asarray(elastica.theorem_3_8_a(sol, problem))
    b = heisenberg_vertex_field(sol.x) - np.cross(a, gamma[1:-1])
    assert np.max(np.abs(b - b[0])) <= 1e-10
    assert np.linalg.norm(a) > 1e-2  # a real load, so the check is not vacuous
    # with the opposite sign of a the equation fails
    b_wrong = heisenberg_vertex_field(sol.x) + np.cross(a, gamma[1:-1])
    assert np.max(np.abs(b_wrong - b_wrong[0])) > 1e-3


def test_open_elastica_heisenberg_flow_is_infinitesimal_euclidean_motion():
    """Cor 3.9, infinitesimally: at the interior vertices the Heisenberg flow is a × γ + b."""
    problem = space_elastica(30, "edge")
    sol = solve(problem)
    gamma = np.asarray(elastica.curve(sol.x, problem))
    w = np.asarray(dg.curves.heisenberg_flow(gamma, closed=False))[1:-1]
    # least squares for (a, b) in w_k = a × γ_k + b:  a × γ = −[γ]× a
    rows = [np.hstack([-_cross_matrix(g), np.eye(3)]) for g in gamma[1:-1]]
    A, rhs = np.vstack(rows), w.ravel()
    ab = np.linalg.lstsq(A, rhs, rcond=None)[0]
    assert np.max(np.abs(A @ ab - rhs)) <= 1e-10


def _cross_matrix(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def procrustes_residual(X, Y):
    """max |R X_i + t − Y_i| over the best rotation R and translation t (Kabsch)."""
    Xc, Yc = X - X.mean(0), Y - Y.mean(0)
    U, _, Vt = np.linalg.svd(Xc.T @ Yc)
    D = np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))])
    R = (U @ D @ Vt).T
    return np.max(np.abs(Xc @ R.T - Yc))


def lemniscate_tangents(n):
    """Unit tangents of Bernoulli's lemniscate sampled (nearly) by arc length: a rough start."""
    t = np.linspace(0, 2 * np.pi, 20001)
    xy = np.stack([np.cos(t), np.sin(t) * np.cos(t)], axis=1) / (1 + np.sin(t) ** 2)[:, None]
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
    u = np.interp(np.arange(n + 1) * s[-1] / n, s, t)
    pts = np.stack([np.cos(u), np.sin(u) * np.cos(u), 0 * u], axis=1) / (1 + np.sin(u) ** 2)[:, None]
    E = np.diff(pts, axis=0)
    return E / np.linalg.norm(E, axis=1, keepdims=True)


@pytest.fixture(scope="module")
def figure_eight():
    n = 48
    problem = elastica.closed(n, x0=lemniscate_tangents(n))
    return problem, solve(problem)


def test_figure_eight_is_a_closed_elastica_and_a_saddle(figure_eight):
    """Euler's figure-eight: found from a lemniscate start; energy → ½∫κ² of the exact one;
    the Hessian of the Lagrangian on the tangent space of the constraints is indefinite."""
    problem, sol = figure_eight
    n = 48
    assert float(sol.residual) <= 1e-10
    T = np.asarray(sol.x)
    assert np.max(np.abs(T[:, 2])) == 0.0  # stays planar
    gamma = np.asarray(dg.curves.from_tangents(T, edge_length=1.0 / n))
    assert np.max(np.abs(gamma[-1] - gamma[0])) <= 1e-10  # closed
    angle_total = np.sum(np.asarray(dg.curves.turning_angles(gamma[:-1, :2], closed=True)))
    assert abs(angle_total) <= 1e-9  # turning number 0: a figure-eight, not a circle
    unit_length = exact.figure_eight(lam=exact.figure_eight(lam=1.0).period)  # period 4K/λ = 1
    half_energy = 0.5 * unit_length.bending_energy()
    assert abs(float(sol.energy) - half_energy) <= 20.0 / n**2 * half_energy
    # second-order test: a negative direction exists (saddle), besides the rotation zeros
    w = jnp.concatenate([jnp.ravel(sol.x), sol.multipliers])
    L = lambda w: problem.energy(w[: 3 * n].reshape(n, 3), problem.params) - w[3 * n :] @ problem.constraints(
        w[: 3 * n].reshape(n, 3), problem.params
    )
    H = np.asarray(jax.hessian(L)(w))[: 3 * n, : 3 * n]
    J = np.asarray(jax.jacobian(lambda x: problem.constraints(x.reshape(n, 3), problem.params))(jnp.ravel(sol.x)))
    Z = np.linalg.svd(J)[2][np.linalg.matrix_rank(J) :].T
    eig = np.linalg.eigvalsh(Z.T @ H @ Z)
    assert eig[0] < -1e-3 * np.max(np.abs(eig))


def test_cor_3_9_heisenberg_flow_moves_closed_elastica_rigidly(figure_eight):
    problem, sol = figure_eight
    n = 48
    gamma = np.asarray(dg.curves.from_tangents(sol.x, edge_length=1.0 / n))[:-1]
    flow = lambda g: dg.curves.heisenberg_flow(g, closed=True)
    _, path = dg.integrate(flow, jnp.asarray(gamma), 1.0, steps=100)
    moved = np.asarray(path[-1])
    assert np.max(np.abs(moved - gamma)) > 1e-3  # it does move
    assert procrustes_residual(gamma, moved) <= 1e-8
    # a closed equilateral polygon that is not an elastica is deformed, not moved rigidly
    k = np.arange(n)
    theta = 2 * np.pi * k / n + 0.3 * np.sin(4 * np.pi * k / n)  # θ_{k+n/2} = θ_k + π: closes
    T = np.stack([np.cos(theta), np.sin(theta), np.zeros(n)], axis=1)
    other = np.asarray(dg.curves.from_tangents(T, edge_length=1.0 / n))[:-1]
    _, path = dg.integrate(flow, jnp.asarray(other), 1.0, steps=100)
    assert procrustes_residual(other, np.asarray(path[-1])) > 1e-5


def test_regular_polygon_is_the_closed_elastica_minimum():
    """From a perturbed n-gon Newton returns to the regular n-gon: E = (2/h)·n·log(1 + tan²(π/n))."""
    n = 24
    k = np.arange(n)
    theta = 2 * np.pi * k / n + 0.05 * np.random.default_rng(0).normal(size=n)
    T = np.stack([np.cos(theta), np.sin(theta), 0.05 * np.random.default_rng(1).normal(size=n)], axis=1)
    sol = solve(elastica.closed(n, x0=T / np.linalg.norm(T, axis=1, keepdims=True)))
    assert float(sol.residual) <= 1e-10
    exact_energy = 2 * n * n * np.log1p(np.tan(np.pi / n) ** 2)
    assert abs(float(sol.energy) - exact_energy) <= 1e-10 * exact_energy
    turning = np.asarray(dg.curves.turning_angles(np.asarray(dg.curves.from_tangents(sol.x))[:-1], closed=True))
    assert np.max(np.abs(turning - 2 * np.pi / n)) <= 1e-8


QUICK = [16, 32, 64, 128]
FULL = [16, 32, 64, 128, 256, 512, 1024]
RANGES = [pytest.param(QUICK, id="n16-128"), pytest.param(FULL, id="n16-1024", marks=pytest.mark.slow)]


def smooth_limit_table(clamp, ns):
    """Max vertex distance between the solved discrete clamped elastica and the exact one."""
    smooth = exact.inflectional(0.8, lam=4.0, u0=0.3, length=1.0)
    data = smooth.boundary_data()
    errors, load_errors, T = [], [], None
    for n in ns:
        problem = elastica.clamped(
            n, chord=data.chord, t_start=data.start_tangent, t_end=data.end_tangent, clamp=clamp,
            x0=None if T is None else elastica.resample(T, n),
        )
        sol = solve(problem, warm_start="lbfgs" if T is None else None)  # continuation in n
        T = np.asarray(sol.x)
        gamma = np.asarray(elastica.curve(sol.x, problem, start=data.start))
        errors.append(np.max(np.linalg.norm(gamma - smooth.gamma(np.arange(n + 1) / n), axis=1)))
        load_errors.append(np.linalg.norm(np.asarray(elastica.load(sol)) - smooth.a))
    return (
        dg.limits.ConvergenceTable.from_errors(ns, errors, "max |γ_j − γ(s_j)|"),
        dg.limits.ConvergenceTable.from_errors(ns, load_errors, "|λ − a|"),
    )


@pytest.mark.parametrize("ns", RANGES)
def test_smooth_limit_vertex_clamp_is_second_order(ns):
    """Clamping the end vertex tangents (ghost edges) gives O(h²) (n = 16…1024 under -m slow)."""
    curve_table, load_table = smooth_limit_table("vertex", ns)
    assert abs(curve_table.fitted_order - 2) <= 0.2
    assert abs(load_table.fitted_order - 2) <= 0.2  # the multiplier converges to the load a
    assert curve_table.errors[-1] <= 1e-6 * (1024 / ns[-1]) ** 2


@pytest.mark.parametrize("ns", RANGES)
def test_smooth_limit_edge_clamp_is_first_order(ns):
    """Def 3.2 fixes T_0, the tangent at s = h/2, to the smooth tangent at s = 0: O(h)."""
    curve_table, load_table = smooth_limit_table("edge", ns)
    assert abs(curve_table.fitted_order - 1) <= 0.2
    assert abs(load_table.orders[-1] - 1) <= 0.2  # pre-asymptotic at small n: the last order


def test_bad_input():
    with pytest.raises(elastica.InfeasibleChordError, match="not shorter than the length"):
        elastica.clamped(10, length=1.0, chord=[1.2, 0, 0], t_start=[1, 0, 0], t_end=[1, 0, 0])
    T = np.tile([1.0, 0.0, 0.0], (10, 1))
    T[4, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"index \(4, 1\)"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], x0=T)
    with pytest.raises(InvalidInputError, match="clamp"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], clamp="free")
    with pytest.raises(InvalidInputError, match="t_start"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 0, 0], t_end=[0, -1, 0])
