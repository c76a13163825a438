"""Discrete elastic rods (Sec 3.5, 3.6: Def 3.6, 3.7, Lemma 3.12, Thm 3.11, 3.13)."""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax.smooth import kirchhoff
from ddgjax import quaternion as qt
from ddgjax.verify import check
from energies import rod
from solvers import solve

from ._shared import euclidean_motion_fit, planar_elastica

GROUP = "clamped elastica"  # share the solved elastica of _shared (one compilation per size)

E2, E3 = jnp.array([0.0, 1.0, 0.0]), jnp.array([0.0, 0.0, 1.0])
START = qt.from_axis_angle(E3, np.pi / 2)  # tangent e1 -> e2
END = qt.from_axis_angle(E3, -np.pi / 2)  # tangent e1 -> -e2
CHORD, ALPHA = 0.6, 0.7


@functools.cache
def clamped_rod(n: int, twist: float):
    """The rod from tangent e2 to −e2 with chord (0.6, 0, 0), the end frame twisted by `twist`."""
    end = qt.mul(qt.from_axis_angle(-E2, twist), END)
    problem = rod.clamped(n, alpha=ALPHA, chord=[CHORD, 0, 0], frame_start=START, frame_end=end)
    return problem, solve(problem)


@check("Lemma 3.12 (discrete)", "the twist angles θ_k of a critical twisted rod are all equal (τ' = 0)",
       quantity="max_k |θ_k − θ_1| (twist 2.5)", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def rod_twist_is_constant(ctx, n):
    _, sol = clamped_rod(n, 2.5)
    theta = np.asarray(rod.twist_angles(sol.x))
    gamma = np.asarray(dg.curves.from_tangents(rod.tangents(sol.x), edge_length=1.0 / n))
    dg.plot.curve(gamma, path=ctx.figure("twisted_rod.png"))
    return float(np.max(np.abs(theta - theta[0]))) if abs(theta[0]) > 1e-3 else float("inf")


@check("Def 3.6", "an untwisted planar rod is the discrete elastica with the same ends",
       quantity="max_k |T_k(rod) − T_k(elastica)|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def untwisted_rod_is_elastica(ctx, n):
    _, sol = clamped_rod(n, 0.0)
    _, curve = planar_elastica(n, CHORD)
    return float(jnp.max(jnp.abs(rod.tangents(sol.x) - curve.x)))


@check("Def 3.7", "at a twisted rod, Heisenberg flow + c·tangent flow is an infinitesimal Euclidean motion (c ≠ 0)",
       quantity="least-squares residual / max |w|", at_most=1e-10, quick=dict(n=32), full=dict(n=200))
def rod_combined_flow_is_euclidean(ctx, n):
    _, sol = clamped_rod(n, 2.5)
    gamma = np.asarray(dg.curves.from_tangents(rod.tangents(sol.x), edge_length=1.0 / n))
    w = np.asarray(dg.curves.heisenberg_flow(gamma, closed=False))[1:-1]
    v = np.asarray(dg.curves.tangent_flow(gamma, closed=False))[1:-1]
    residual, (*_, c) = euclidean_motion_fit(gamma[1:-1], w, extra=v)
    if abs(c) <= 1e-3:
        raise AssertionError(f"c = {c:.2e}: not a genuine combination with the tangent flow")
    return residual / float(np.max(np.abs(w)))


@functools.cache
def vertex_clamped_rods(ns: tuple[int, ...]):
    """Twisted 3D rods with second-order (vertex) clamps and the smooth rod by shooting."""
    e1 = jnp.array([1.0, 0.0, 0.0])
    end = qt.mul(qt.from_axis_angle(E3, 2.0), qt.from_axis_angle(e1, 1.5))
    rods = {}
    for n in ns:
        problem = rod.clamped(n, alpha=0.6, chord=[0.5, 0.3, 0.15], frame_start=[1.0, 0, 0, 0], frame_end=end,
                              clamp="vertex")
        rods[n] = (problem, solve(problem))
    return rods, kirchhoff.from_discrete(*rods[ns[len(ns) // 2]])


@check("Thm 3.13", "discrete rods (vertex clamps) converge to the smooth rod computed by shooting with the Lagrange top",
       quantity="fitted order of max_k |γ_k − γ(kh)|", target=2.0, within=0.3,
       quick=dict(ns=(16, 32, 64)), full=dict(ns=(16, 32, 64, 128, 256)), full_only=True)
def rod_smooth_limit(ctx, ns):
    rods, smooth = vertex_clamped_rods(ns)
    table = dg.limits.convergence(lambda n: kirchhoff.discrete_errors(*rods[n], smooth)["position"], list(ns))
    return ctx.convergence(table, "convergence_rod_centreline").fitted_order


@check("Thm 3.11", "a solved rod's tangent and angular velocity solve the Lagrange top equations with its a and α",
       quantity="fitted order of the top-equation residual", target=2.0, within=0.3,
       quick=dict(ns=(16, 32, 64)), full=dict(ns=(16, 32, 64, 128, 256)), full_only=True)
def rod_is_a_top_motion(ctx, ns):
    rods, _ = vertex_clamped_rods(ns)

    def residual(n):
        problem, sol = rods[n]
        r = kirchhoff.discrete_top_residual(sol.x, problem.params["h"], 0.6, rod.load(sol))
        return float(jnp.max(jnp.abs(r)))

    return ctx.convergence(dg.limits.convergence(residual, list(ns)), "convergence_rod_top_residual").fitted_order
