"""Discrete curves and curvatures (Sec 1, Remark 2.1)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from ddgjax import curves
from ddgjax.verify import check

from ._shared import unit_rows

ORDER_2 = dict(target=2.0, within=0.1)
QUICK_NS, FULL_NS = (16, 32, 64, 128), (16, 32, 64, 128, 256, 512, 1024)


def catenary(s):
    """(asinh s, √(1 + s²)), by arc length: signed curvature 1/(1 + s²)."""
    return jnp.array([jnp.arcsinh(s), jnp.sqrt(1 + s**2)])


def catenary_curvature(s):
    return 1.0 / (1.0 + s**2)


@functools.cache
def sampled_catenary(n: int):
    """n equal chords inscribed in the catenary over s ∈ [−2, 2], and the vertex parameters."""
    gamma, s = curves.sample(catenary, n, length=4.0, start=-2.0, equal_chords=True, return_parameters=True)
    return np.asarray(gamma), np.asarray(s)


def random_polygon(n: int, seed: int = 0) -> np.ndarray:
    """An open arc-length polygon in R³ with turning angles up to about 1 radian."""
    rng = np.random.default_rng(seed)
    steps = unit_rows(np.array([1.0, 0.0, 0.0]) + 0.8 * rng.normal(size=(n, 3)))
    return np.asarray(curves.from_tangents(steps))


@check("Def 1.4", "the vertex curvature of three points on a circle of radius R is ±1/R at any spacing (+ counter-clockwise)",
       quantity="max_k |κ_k ∓ 1/R| (planar both ways, tilted circle; random points)", at_most=1e-12, quick=dict(points=12))
def vertex_curvature_of_circle(ctx, points):
    R, rng = 1.7, np.random.default_rng(1)
    angles = np.sort(rng.uniform(0.0, 5.0, size=points))
    planar = R * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    tilted = np.column_stack([planar, np.zeros(points)]) @ Q.T
    signed = ((planar, 1 / R), (tilted, 1 / R), (planar[::-1], -1 / R))  # clockwise: negative in the plane
    return max(float(np.max(np.abs(np.asarray(curves.curvature(gamma, "vertex")) - k))) for gamma, k in signed)


@check("Def 1.5, 1.6", "the regular n-gon's edge and arc-length curvatures are 1/(R cos(π/n)) (inscribed circle), its vertex curvature 1/R",
       quantity="max |κ − exact| over the three kinds and n = 5, n", at_most=1e-12, quick=dict(n=12))
def polygon_curvatures(ctx, n):
    R, worst = 2.5, 0.0
    for m in (5, n):
        angles = 2 * np.pi * np.arange(m) / m
        gamma = R * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        exact = {"vertex": 1 / R, "edge": 1 / (R * np.cos(np.pi / m)), "arclength": 1 / (R * np.cos(np.pi / m))}
        worst = max([worst] + [float(np.max(np.abs(np.asarray(curves.curvature(gamma, kind, closed=True)) - k)))
                               for kind, k in exact.items()])
    return worst


@check("Remark 2.1", "the vertex tangent has length 1/cos(φ_k/2) and the direction of T_k + T_{k−1}",
       quantity="max_k (| |v_k| cos(φ_k/2) − 1 | + |v_k × (T_k + T_{k−1})|)", at_most=1e-12, quick=dict(n=16))
def vertex_tangent_length(ctx, n):
    gamma = random_polygon(n)
    v = np.asarray(curves.vertex_tangent(gamma))
    T = np.asarray(curves.tangents(gamma))
    half = np.cos(np.asarray(curves.turning_angles(gamma)) / 2)
    bisector = T[1:] + T[:-1]
    return float(np.max(np.abs(np.linalg.norm(v, axis=1) * half - 1) + np.linalg.norm(np.cross(v, bisector), axis=1)))


def _curvature_error(kind: str, n: int) -> float:
    gamma, s = sampled_catenary(n)
    at = ((s[1:] + s[:-1]) / 2)[1:-1] if kind == "edge" else s[1:-1]
    return float(np.max(np.abs(np.asarray(curves.curvature(gamma, kind)) - catenary_curvature(at))))


def _register_curvature_limit(kind: str) -> None:
    def limit(ctx, ns):
        table = dg.limits.convergence(functools.partial(_curvature_error, kind), ns, label=f"‖κ_{kind} − κ‖∞")
        return ctx.convergence(table, f"convergence_curvature_{kind}").fitted_order

    check("Sec 1.3", f"the {kind} curvature of equal chords inscribed in a catenary converges to κ with order 2",
          quantity="fitted order", name=f"curvature_{kind}_smooth_limit", quick=dict(ns=QUICK_NS),
          full=dict(ns=FULL_NS), **ORDER_2)(limit)


for _kind in ("vertex", "edge", "arclength"):
    _register_curvature_limit(_kind)


@jax.jit
def _catenary_velocity(s):
    return jax.vmap(jax.jacfwd(catenary))(s)


@check("Remark 2.1", "the vertex tangent converges to γ' with order 2", quantity="fitted order",
       quick=dict(ns=QUICK_NS), full=dict(ns=FULL_NS), **ORDER_2)
def vertex_tangent_smooth_limit(ctx, ns):
    def error(n):
        gamma, s = sampled_catenary(n)
        return np.max(np.abs(np.asarray(curves.vertex_tangent(gamma)) - np.asarray(_catenary_velocity(s[1:-1]))))

    table = dg.limits.convergence(error, ns, label="‖v_k − γ′(s_k)‖∞")
    return ctx.convergence(table, "convergence_vertex_tangent").fitted_order
