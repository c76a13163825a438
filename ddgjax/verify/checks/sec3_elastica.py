"""Elastic curves: smooth and discrete elastica (Sec 3.1, 3.3)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax.problem import constraint_values
from ddgjax.smooth import elastica as exact
from ddgjax.smooth import space_elastica as smooth_space
from ddgjax.verify import check
from energies import elastica
from solvers import solve

from ._shared import (
    edge_midpoint_tangents,
    euclidean_motion_residual,
    planar_elastica,
    smooth_clamped_elastica,
    space_elastica,
    thm_3_8_spread,
)

GROUP = "clamped elastica"  # share the solved elastica of _shared (one compilation per size)

FAMILY_CHORDS = (0.8, 0.6, 0.4, 0.2)


# --- the smooth oracle ------------------------------------------------------------------------


def _second_derivative(f, s, h=2e-3):
    """Fourth-order central difference: error ~h⁴|f⁽⁶⁾|/90 + 5δ/h², δ ≈ 1e-15 the accuracy of
    scipy's Jacobi functions: observed ≤ 1e-7 here."""
    return (-f(s + 2 * h) + 16 * f(s + h) - 30 * f(s) + 16 * f(s - h) - f(s - 2 * h)) / (12 * h**2)


@check("Thm 3.1, 3.2", "the exact elliptic elastica solve T'' = cT + a and θ'' = −λ² sin(θ − θ_a)",
       quantity="max |T'' − cT − a| + max |θ'' + λ² sin(θ − θ_a)| (finite differences)", at_most=1e-6,
       quick=dict(samples=41))
def exact_elastica_euler_lagrange(ctx, samples):
    worst = 0.0
    for curve in (exact.inflectional(0.7, lam=1.3, u0=0.4, length=5.0, load_angle=0.7),
                  exact.non_inflectional(0.5, lam=1.2, u0=0.3, length=7.0, load_angle=1.0)):
        s = np.linspace(0.1, curve.length - 0.1, samples)
        T2 = _second_derivative(curve.tangent, s)
        theta2 = _second_derivative(curve.tangent_angle, s)
        tangent_eq = np.max(np.abs(T2 - curve.c(s)[:, None] * curve.tangent(s) - curve.a))
        pendulum_eq = np.max(np.abs(theta2 + curve.lam**2 * np.sin(curve.tangent_angle(s) - curve.load_angle)))
        worst = max(worst, float(tangent_eq + pendulum_eq))
    return worst


# --- Thm 3.8 and Cor 3.9 ----------------------------------------------------------------------


def _thm_3_8_residual(problem, sol, sign=1.0) -> float:
    gamma = np.asarray(elastica.curve(sol.x, problem))
    return thm_3_8_spread(sol.x, gamma, sign * np.asarray(elastica.theorem_3_8_a(sol, problem)))


def _register_thm_3_8(clamp: str) -> None:
    def thm_3_8(ctx, n):
        return _thm_3_8_residual(*space_elastica(n, clamp))

    check("Thm 3.8", f"a clamped discrete space elastica (clamp={clamp}) satisfies "
          "T_k × T_(k−1)/(1 + <T_k, T_(k−1)>) = a × γ_k + b with a = (h/2)·(chord multipliers)",
          quantity="max_k |b_k − b_1|", at_most=1e-10, name=f"thm_3_8_{clamp}_clamp", quick=dict(n=32), full=dict(n=256))(thm_3_8)


for _clamp in ("edge", "vertex"):
    _register_thm_3_8(_clamp)


@check("Thm 3.8", "negative control: with a replaced by −a the identity of Thm 3.8 fails",
       quantity="max_k |b_k − b_1| with −a", at_least=1e-3, quick=dict(n=32), full=dict(n=256))
def thm_3_8_wrong_sign_fails(ctx, n):
    return _thm_3_8_residual(*space_elastica(n, "edge"), sign=-1.0)


@check("Thm 3.8", "a family of planar elastica with decreasing chord: Thm 3.8 along the family",
       quantity="max over the family of max_k |b_k − b_1|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def elastica_family(ctx, n):
    solved = [planar_elastica(n, c) for c in FAMILY_CHORDS]
    dg.plot.curves([np.asarray(elastica.curve(s.x, p))[:, :2] for p, s in solved], labels=[f"chord {c}" for c in FAMILY_CHORDS],
                   path=ctx.figure("elastica_family.png"))
    return max(_thm_3_8_residual(p, s) for p, s in solved)


@check("Cor 3.9", "on an open discrete elastica the Heisenberg flow is an infinitesimal Euclidean motion a × γ + b",
       quantity="least-squares residual max_k |w_k − a × γ_k − b|", at_most=1e-10, quick=dict(n=32), full=dict(n=256))
def open_elastica_heisenberg_is_euclidean(ctx, n):
    problem, sol = space_elastica(n, "edge")
    gamma = np.asarray(elastica.curve(sol.x, problem))
    w = np.asarray(dg.curves.heisenberg_flow(gamma, closed=False))[1:-1]
    return euclidean_motion_residual(gamma[1:-1], w)


# --- closed elastica: the regular polygon and Euler's figure-eight ----------------------------


@functools.cache
def figure_eight(n: int):
    """The closed discrete elastica found from the tangents of the exact figure-eight (Remark 3.2)."""
    eight = exact.figure_eight(lam=exact.figure_eight(lam=1.0).period)  # period 4K/λ = 1
    problem = elastica.closed(n, x0=edge_midpoint_tangents(eight, n))
    return problem, solve(problem), eight


@check("Remark 3.2, 3.7", "closed discrete elastica near Euler's figure-eight (closed, planar, turning number 0) have "
       "its bending energy ½∫κ² in the limit, order 2",
       quantity="fitted order of |E_n − ½∫κ²| / ½∫κ²", target=2.0, within=0.1, quick=dict(ns=(24, 48, 96)),
       full=dict(ns=(24, 48, 96, 192, 384)))
def figure_eight_energy(ctx, ns):
    def error(n):
        problem, sol, eight = figure_eight(n)
        gamma = np.asarray(elastica.curve(sol.x, problem))
        turning = float(np.sum(np.asarray(dg.curves.turning_angles(gamma[:-1, :2], closed=True))))
        if np.max(np.abs(gamma[:, 2])) > 0 or np.max(np.abs(gamma[-1] - gamma[0])) > 1e-10 or abs(turning) > 1e-9:
            raise AssertionError(f"n = {n}: not a planar closed curve of turning number 0 (total turning {turning:.3g})")
        if n == ns[-1]:
            dg.plot.curve(gamma[:, :2], path=ctx.figure("figure_eight.png"), color="k")
        half = 0.5 * eight.bending_energy()
        return abs(float(sol.energy) - half) / half

    table = dg.limits.convergence(error, list(ns), label="|E_n − ½∫κ²| / ½∫κ²")
    return ctx.convergence(table, "convergence_figure_eight_energy", title="Remark 3.7: figure-eight energy").fitted_order


@check("Remark 3.7", "the figure-eight is a saddle: the Hessian of the Lagrangian on the constraints' tangent space "
       "is indefinite",
       quantity="smallest / largest |eigenvalue|", at_most=-1e-3, quick=dict(n=48), full=dict(n=96))
def figure_eight_is_saddle(ctx, n):
    problem, sol, _ = figure_eight(n)
    x = jnp.ravel(sol.x)
    lagrangian = lambda y: dg.lagrangian(problem)(y.reshape(n, 3), sol.multipliers, problem.params)
    H = np.asarray(jax.jit(jax.hessian(lagrangian))(x))
    g = lambda y: constraint_values(problem, y.reshape(n, 3), problem.params)
    J = np.asarray(jax.jit(jax.jacobian(g))(x))
    Z = np.linalg.svd(J)[2][np.linalg.matrix_rank(J):].T
    eig = np.linalg.eigvalsh(Z.T @ H @ Z)
    return float(eig[0] / np.max(np.abs(eig)))


def _procrustes(X, Y) -> float:
    """max |R X_i + t − Y_i| over the best rotation R and translation t (Kabsch)."""
    Xc, Yc = X - X.mean(0), Y - Y.mean(0)
    U, _, Vt = np.linalg.svd(Xc.T @ Yc)
    R = (U @ np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))]) @ Vt).T
    return float(np.max(np.abs(Xc @ R.T - Yc)))


def _moved_by_heisenberg_flow(gamma, steps: int) -> np.ndarray:
    """The closed polygon after time 1 of the Heisenberg flow (Gauss–Legendre)."""
    _, path = dg.integrate(lambda g: dg.curves.heisenberg_flow(g, closed=True), jnp.asarray(gamma), 1.0, steps=steps)
    return np.asarray(path[-1])


@check("Cor 3.9", "the Heisenberg flow moves the closed elastica (figure-eight) by Euclidean motions",
       quantity="max distance to the best rigid image after t = 1", at_most=1e-8, quick=dict(n=48, steps=50),
       full=dict(n=96, steps=200))
def figure_eight_moves_rigidly(ctx, n, steps):
    problem, sol, _ = figure_eight(n)
    gamma = np.asarray(elastica.curve(sol.x, problem))[:-1]
    moved = _moved_by_heisenberg_flow(gamma, steps)
    if np.max(np.abs(moved - gamma)) <= 1e-3:
        raise AssertionError("the figure-eight did not move: the check would be vacuous")
    return _procrustes(gamma, moved)


@check("Cor 3.9", "negative control: a closed equilateral polygon that is not an elastica is deformed, not moved rigidly",
       quantity="max distance to the best rigid image after t = 1", at_least=1e-5, quick=dict(n=48, steps=50),
       full=dict(n=96, steps=200))
def non_elastica_is_deformed(ctx, n, steps):
    k = np.arange(n)
    theta = 2 * np.pi * k / n + 0.3 * np.sin(4 * np.pi * k / n)  # θ_{k+n/2} = θ_k + π: it closes
    T = np.stack([np.cos(theta), np.sin(theta), np.zeros(n)], axis=1)
    gamma = np.asarray(dg.curves.from_tangents(T, edge_length=1.0 / n))[:-1]
    return _procrustes(gamma, _moved_by_heisenberg_flow(gamma, steps))


@check("Remark 3.7", "the regular n-gon is the closed elastica minimum with E = 2n² log(1 + tan²(π/n))",
       quantity="|E − E_exact| / E_exact", at_most=1e-10, quick=dict(n=48), full=dict(n=96))
def regular_polygon_energy(ctx, n):
    k = np.arange(n)
    rng = np.random.default_rng(0)
    theta = 2 * np.pi * k / n + 0.05 * rng.normal(size=n)
    T = np.stack([np.cos(theta), np.sin(theta), 0.05 * rng.normal(size=n)], axis=1)
    sol = solve(elastica.closed(n, x0=T / np.linalg.norm(T, axis=1, keepdims=True)))
    exact_energy = 2 * n * n * np.log1p(np.tan(np.pi / n) ** 2)
    return abs(float(sol.energy) - exact_energy) / exact_energy


# --- smooth limit -----------------------------------------------------------------------------


@functools.cache
def smooth_space_curve() -> smooth_space.SpaceElastica:
    """A non-planar elastic curve (Thm 3.1): the spherical pendulum from T(0) = e1,
    T'(0) = (0, 2, 1.5) under the load a = (3, −4, 2), L = 1."""
    return smooth_space.space_elastica([1.0, 0.0, 0.0], [0.0, 2.0, 1.5], [3.0, -4.0, 2.0])


REFERENCES = {"planar": smooth_clamped_elastica, "space": smooth_space_curve}


@functools.cache
def _limit_tables(clamp: str, ns: tuple, reference: str = "planar"):
    """Max vertex distance to the smooth clamped elastica `REFERENCES[reference]` and |λ − a| at
    each n (Newton started from the smooth tangents at the edge midpoints)."""
    smooth = REFERENCES[reference]()
    data = smooth.boundary_data()
    curve_errors, load_errors = [], []
    for n in ns:
        problem = elastica.clamped(n, chord=data.chord, t_start=data.start_tangent, t_end=data.end_tangent,
                                   clamp=clamp, x0=edge_midpoint_tangents(smooth, n))
        sol = solve(problem)
        gamma = np.asarray(elastica.curve(sol.x, problem, start=data.start))
        curve_errors.append(np.max(np.linalg.norm(gamma - smooth.gamma(np.arange(n + 1) / n), axis=1)))
        load_errors.append(np.linalg.norm(np.asarray(elastica.load(sol)) - smooth.a))
    label = f"clamp={clamp}, {reference} elastica"
    return (dg.limits.ConvergenceTable.from_errors(ns, curve_errors, f"max_j dist(γ_j, γ(s_j)), {label}"),
            dg.limits.ConvergenceTable.from_errors(ns, load_errors, f"dist(λ, a), {label}"))


QUICK_NS, FULL_NS = (16, 32, 64), (16, 32, 64, 128, 256, 512, 1024)  # quick: n = 32 is compiled for Thm 3.8


@check("Thm 3.2, Def 3.2", "clamped discrete elastica (vertex clamp) converge to the exact elastica, order 2",
       quantity="fitted order of max_j |γ_j − γ(s_j)|", target=2.0, within=0.2, quick=dict(ns=QUICK_NS), full=dict(ns=FULL_NS))
def elastica_vertex_clamp_limit(ctx, ns):
    curve_table, _ = _limit_tables("vertex", ns)
    return ctx.convergence(curve_table, "convergence_elastica_vertex_clamp").fitted_order


@check("Thm 3.2", "the chord multipliers λ converge to the smooth load a (vertex clamp), order 2",
       quantity="fitted order of |λ − a|", target=2.0, within=0.2, quick=dict(ns=QUICK_NS), full=dict(ns=FULL_NS))
def elastica_load_limit(ctx, ns):
    _, load_table = _limit_tables("vertex", ns)
    return ctx.convergence(load_table, "convergence_elastica_load").fitted_order


@check("Def 3.2", "with Def 3.2's edge clamp (T_0 fixed at s = h/2) the limit is first order",
       quantity="fitted order of max_j |γ_j − γ(s_j)|", target=1.0, within=0.2, quick=dict(ns=QUICK_NS), full=dict(ns=FULL_NS))
def elastica_edge_clamp_limit(ctx, ns):
    curve_table, _ = _limit_tables("edge", ns)
    return ctx.convergence(curve_table, "convergence_elastica_edge_clamp").fitted_order


# --- non-planar elastica (Thm 3.1, 3.2 in space) ------------------------------------------------


def _non_planar(curve) -> smooth_space.SpaceElastica:
    if curve.spans_space() < 0.1:
        raise AssertionError(f"|det(chord, T(0), T(L))| = {curve.spans_space():.2e}: the reference is planar")
    return curve


def _b_spread(curve: smooth_space.SpaceElastica, a, samples: int) -> float:
    """max_s |b(s) − b(0)| for `b = γ'' × γ' − a × γ` along `curve` (Thm 3.2: constant iff elastic
    with load a)."""
    y = curve.state(np.linspace(0.0, curve.length, samples))
    gamma, T, dT = y[:, 0:3], y[:, 3:6], y[:, 6:9]
    b = np.cross(dT, T) - np.cross(a, gamma)
    return float(np.max(np.abs(b - b[0])))


@check("Thm 3.1, 3.2", "the non-planar smooth reference (the tangent a spherical pendulum, T'' = cT + a, integrated) "
       "satisfies the first form of Thm 3.2: b = γ'' × γ' − a × γ is constant",
       quantity="max_s |b(s) − b(0)| (257 samples)", at_most=1e-10, quick=dict(samples=257))
def space_elastica_euler_lagrange(ctx, samples):
    curve = _non_planar(smooth_space_curve())
    return _b_spread(curve, curve.a, samples)


@check("Thm 3.2", "negative control: with −a in place of the pendulum's gravity, b = γ'' × γ' − a × γ varies",
       quantity="max_s |b(s) − b(0)| with −a", at_least=1e-3, quick=dict(samples=257))
def space_elastica_wrong_load_fails(ctx, samples):
    curve = smooth_space_curve()
    return _b_spread(curve, -curve.a, samples)


@check("Thm 3.1, 3.2", "clamped discrete elastica (vertex clamp) converge to a non-planar smooth elastic curve "
       "(|det(chord, T(0), T(L))| ≈ 0.49), order 2",
       quantity="fitted order of max_j |γ_j − γ(s_j)|", target=2.0, within=0.2, quick=dict(ns=QUICK_NS),
       full=dict(ns=FULL_NS))
def elastica_space_limit(ctx, ns):
    _non_planar(smooth_space_curve())
    curve_table, _ = _limit_tables("vertex", ns, "space")
    return ctx.convergence(curve_table, "convergence_space_elastica").fitted_order


@check("Thm 3.1, 3.2", "on the non-planar elastica the chord multipliers λ converge to the pendulum's gravity a, "
       "order 2", quantity="fitted order of |λ − a|", target=2.0, within=0.2, quick=dict(ns=QUICK_NS),
       full=dict(ns=FULL_NS))
def elastica_space_load_limit(ctx, ns):
    _, load_table = _limit_tables("vertex", ns, "space")
    return ctx.convergence(load_table, "convergence_space_elastica_load").fitted_order
