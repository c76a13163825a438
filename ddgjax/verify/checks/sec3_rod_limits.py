"""Smooth limits of discrete elastic rods (Sec 3.6: Thm 3.11, 3.13, Def 3.7).

Vertex-clamped discrete rods against the smooth rod with the same clamps, a motion of the
Lagrange top (the Kirchhoff analogy, Thm 3.11): in the quick run a top motion integrated forward
with the discrete rods clamped to its ends, in the full run the smooth rod shot to given clamps
(`ddgjax.smooth.kirchhoff`).  These checks share their rods and the top's compiled integrator,
not the elastica of `_shared`, so they run in a process of their own.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import quaternion as qt
from ddgjax.smooth import kirchhoff
from ddgjax.verify import check
from energies import rod
from solvers import solve

from ._shared import max_abs
from .sec3_rods import E1, E3, combined_flow_fit

# --- vertex-clamped rods and the smooth rod (Thm 3.11, 3.13) -----------------------------------

VERTEX_ALPHA, VERTEX_CHORD = 0.6, (0.5, 0.3, 0.15)
VERTEX_END_TURNS = ((E3, 2.0), (E1, 1.5))  # the end frame: turned by 2 about e3 after 1.5 about e1
QUICK_NS, FULL_NS = (8, 16, 32), (16, 32, 64, 128, 256)


@functools.cache
def vertex_clamped_rod(n: int):
    """`(problem, solution)` of the twisted 3D rod with second-order (vertex) clamps."""
    problem = rod.clamped(n, alpha=VERTEX_ALPHA, chord=VERTEX_CHORD, frame_start=[1.0, 0, 0, 0],
                          frame_end=qt.mul(*(qt.from_axis_angle(axis, angle) for axis, angle in VERTEX_END_TURNS)),
                          clamp="vertex")
    return problem, solve(problem)


@functools.cache
def smooth_rod(n: int | None) -> kirchhoff.SmoothRod:
    """The smooth rod with the clamps of the n-edge vertex-clamped rod, by shooting from it; for
    n = None the top motion from Φ(0) = 1, M(0) = (2.4, 3, −1), a = (16.2, 15.9, 1), α = 0.6: an
    elastic rod by Thm 3.11 with about the torsion (τ = M₁/2α = 2) and load of the shot one, and
    nothing to solve or shoot."""
    if n is None:
        return kirchhoff.SmoothRod(jnp.array([1.0, 0, 0, 0]), jnp.array([2.4, 3.0, -1.0]), jnp.array([16.2, 15.9, 1.0]),
                                   VERTEX_ALPHA, 1.0)
    return kirchhoff.from_discrete(*vertex_clamped_rod(n))


@functools.cache
def rod_and_limit(n: int, shot_from: int | None):
    """`(problem, solution, smooth)`: an n-edge vertex-clamped discrete rod and the smooth rod
    with the same clamps, chord and α, which it tends to as n grows.

    `shot_from = m`: the rod of `vertex_clamped_rod(n)` and the smooth rod shot to its clamps
    from the m-edge discrete rod (`smooth_rod(m)`).  `shot_from = None`: the top motion
    `smooth_rod(None)` (an elastic rod by Thm 3.11, nothing solved or shot) and the discrete rod
    clamped to its frames Φ(0), Φ(L) and chord γ(L), Newton started from its frames at the edge
    midpoints (the discrete critical point near the smooth one)."""
    smooth = smooth_rod(shot_from)
    if shot_from is not None:
        return (*vertex_clamped_rod(n), smooth)

    def unit(q):
        return q / np.linalg.norm(q, axis=-1, keepdims=True)

    s = np.concatenate([[0.0], (np.arange(n) + 0.5) / n, [1.0]]) * smooth.length
    Phi, gamma = (np.asarray(a) for a in kirchhoff.sample(smooth, s))  # the start, the edge midpoints, the end
    problem = rod.clamped(n, alpha=smooth.alpha, length=smooth.length, chord=gamma[-1], frame_start=unit(Phi[0]),
                          frame_end=unit(Phi[-1]), clamp="vertex", x0=unit(Phi[1:-1]))
    return problem, solve(problem), smooth


ROD_LIMIT_QUICK = dict(ns=QUICK_NS, shot_from=None)
ROD_LIMIT_FULL = dict(ns=FULL_NS, shot_from=FULL_NS[len(FULL_NS) // 2])


@check("Thm 3.13", "discrete rods (vertex clamps) converge to the smooth rod with their clamps (a Lagrange top "
       "motion; in the full run computed by shooting to the clamps)",
       quantity="fitted order of max_k |γ_k − γ(kh)|", target=2.0, within=0.3, quick=ROD_LIMIT_QUICK,
       full=ROD_LIMIT_FULL)
def rod_smooth_limit(ctx, ns, shot_from):
    table = dg.limits.convergence(lambda n: kirchhoff.discrete_errors(*rod_and_limit(n, shot_from))["position"],
                                  list(ns))
    return ctx.convergence(table, "convergence_rod_centreline").fitted_order


@check("Thm 3.11", "a solved rod's tangent and angular velocity solve the Lagrange top equations with its a and α",
       quantity="fitted order of the top-equation residual", target=2.0, within=0.3, quick=ROD_LIMIT_QUICK,
       full=ROD_LIMIT_FULL)
def rod_is_a_top_motion(ctx, ns, shot_from):
    def residual(n):
        problem, sol, _ = rod_and_limit(n, shot_from)
        return max_abs(kirchhoff.discrete_top_residual(sol.x, problem.params["h"], problem.params["alpha"],
                                                       rod.load(sol)))

    return ctx.convergence(dg.limits.convergence(residual, list(ns)), "convergence_rod_top_residual").fitted_order


@check("Thm 3.11", "negative control: with the opposite load −a in place of the rod's a, the top equations fail on "
       "the same rod",
       quantity="top-equation residual with −a / with a", at_least=100.0, quick=dict(n=32, shot_from=None),
       full=dict(n=64, shot_from=ROD_LIMIT_FULL["shot_from"]))
def rod_top_motion_wrong_load_fails(ctx, n, shot_from):
    problem, sol, _ = rod_and_limit(n, shot_from)

    def residual(a):
        return max_abs(kirchhoff.discrete_top_residual(sol.x, problem.params["h"], problem.params["alpha"], a))

    return residual(-rod.load(sol)) / residual(rod.load(sol))


def thm_3_13_defects(jet: kirchhoff.RodJet, alpha: float, a, c_sign: float = -1.0,
                     printed: bool = False) -> dict[str, float]:
    """The defects of Thm 3.13 along a smooth rod, with `τ = <ω, T>` and `c = c_sign · ατ`:
    `torsion` max |τ − τ(0)|; `i` max |ω' − (1 − α)τT' − T × a|; `ii` the spread max |b − b(0)| of
    `b = T' × T + cT − a × γ` (`γ'' × γ' + cγ' = a × γ + b`); `iii` max |T'' × T + cT' − a × T|,
    the derivative of (ii) (`printed`: with cT in place of cT', as the reference prints (iii))."""
    a, jet = np.asarray(a), jax.tree_util.tree_map(np.asarray, jet)  # NumPy: concrete values, nothing to compile
    tau = np.sum(jet.omega * jet.T, axis=1, keepdims=True)
    c = c_sign * alpha * tau
    b = np.cross(jet.dT, jet.T) + c * jet.T - np.cross(a, jet.gamma)
    iii = np.cross(jet.ddT, jet.T) + c * (jet.T if printed else jet.dT) - np.cross(a, jet.T)
    return {
        "torsion": max_abs(tau, tau[0]),
        "i": max_abs(jet.domega - (1 - alpha) * tau * jet.dT - np.cross(jet.T, a)),
        "ii": max_abs(b, b[0]),
        "iii": max_abs(iii),
    }


def _smooth_jet(shot_from: int | None, samples: int):
    smooth = smooth_rod(shot_from)
    if abs(kirchhoff.torsion(smooth)) <= 0.1:
        raise AssertionError(f"τ = {kirchhoff.torsion(smooth):.2e}: the check needs a twisted rod")
    return smooth, kirchhoff.jet(smooth, np.linspace(0.0, smooth.length, samples))


SMOOTH_QUICK, SMOOTH_FULL = dict(shot_from=None, samples=64), dict(shot_from=64, samples=256)  # multiples of kirchhoff.SAMPLE_BUCKET


@check("Thm 3.13", "along a smooth rod (a Lagrange top motion; in the full run the rod shot to the clamps) τ is "
       "constant and (i), (ii) γ''×γ' + cγ' = a × γ + b, (iii) T''×T + cT' = a × T hold with c = −ατ",
       quantity="max of the four defects / |a|", at_most=1e-10, quick=SMOOTH_QUICK, full=SMOOTH_FULL)
def smooth_rod_euler_lagrange(ctx, shot_from, samples):
    smooth, jet = _smooth_jet(shot_from, samples)
    return max(thm_3_13_defects(jet, smooth.alpha, smooth.a).values()) / float(np.linalg.norm(smooth.a))


@check("Thm 3.13", "negative controls: (ii) with c = +ατ, and (iii) as printed (cT in place of cT'), fail",
       quantity="min of the two defects / |a|", at_least=1e-3, quick=SMOOTH_QUICK, full=SMOOTH_FULL)
def smooth_rod_wrong_c_fails(ctx, shot_from, samples):
    smooth, jet = _smooth_jet(shot_from, samples)
    wrong_sign = thm_3_13_defects(jet, smooth.alpha, smooth.a, c_sign=1.0)["ii"]
    printed = thm_3_13_defects(jet, smooth.alpha, smooth.a, printed=True)["iii"]
    return min(wrong_sign, printed) / float(np.linalg.norm(smooth.a))


@check("Thm 3.13, Def 3.7", "the coefficient c of Def 3.7 at vertex-clamped rods, as 2c/h, converges to the smooth "
       "rod's c = −ατ",
       quantity="fitted order of |2c/h + ατ|", target=2.0, within=0.3, quick=ROD_LIMIT_QUICK, full=ROD_LIMIT_FULL)
def rod_c_limit(ctx, ns, shot_from):
    def error(n):
        problem, sol, smooth = rod_and_limit(n, shot_from)
        h = problem.params["h"]
        return abs(2 * combined_flow_fit(sol.x, h)[1] / h + smooth.alpha * kirchhoff.torsion(smooth))

    table = dg.limits.convergence(error, list(ns), label="|2c/h + ατ|")
    return ctx.convergence(table, "convergence_rod_c").fitted_order
