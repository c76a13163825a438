"""Willmore energy: ∫H² dA and the conformal energy (Thm 6.7; Willmore's theorem; Bobenko 2005), and
the Clifford torus as the Willmore torus of revolution (Willmore 1965; Marques–Neves 2014)."""

from __future__ import annotations

import functools

import jax
import numpy as np

import ddgjax as dg
from ddgjax import mesh
from ddgjax.verify import check
from energies import willmore


def _energy(problem) -> float:
    return float(jax.jit(problem.energy)(problem.x0, problem.params))


def _willmore_of_icosphere(level: int) -> float:
    return _energy(willmore.helfrich(*mesh.icosphere(level)))


@check("Willmore's theorem: W ≥ 4π, equality for round spheres; Thm 6.7",
       "∫H² dA with H = ⟨∇A, N⟩ / 2A_i (the area gradient of Thm 6.7) tends to 4π on icospheres, order 2 in the "
       "edge length (from below: the discrete W of an icosphere is < 4π)",
       quantity="observed order between successive levels farthest from 2 (n = 2^level; ∞ unless every level's "
       "W < 4π)", target=2.0, within=0.1, quick=dict(levels=(1, 2, 3)), full=dict(levels=(1, 2, 3, 4, 5)))
def willmore_icosphere_order(ctx, levels):
    W = {2**k: _willmore_of_icosphere(k) for k in levels}
    if any(w >= 4 * np.pi for w in W.values()):
        return float("inf")  # not approached from below
    errors = {n: 4 * np.pi - w for n, w in W.items()}
    table = dg.limits.convergence(errors.get, sorted(errors), label="|W − 4π|")
    orders = ctx.convergence(table, "convergence_willmore_icosphere").orders
    return float(max(orders, key=lambda p: abs(p - 2.0)))


@check("Thm 6.7", "the mean curvature derived by autodiff of the area and volume of the vertex stars equals the cotan "
       "formula ⟨(L f)(i), N_i⟩ / 2A_i (oracle: the cotan Laplacian) on a perturbed sphere and on icosphere(1)",
       quantity="max |H − H_cotan|", at_most=1e-12, quick=dict(level=2), full=dict(level=4))
def willmore_mean_curvature_is_cotan(ctx, level):
    rng = np.random.default_rng(0)
    worst = 0.0
    for V, F in (mesh.icosphere(1), mesh.icosphere(level)):
        V = np.asarray(V) * (1.0 + 0.1 * rng.uniform(-1, 1, size=(len(V), 1)))
        H, A = willmore.mean_curvature(V, F)
        a, b, c = (V[F[:, i]] for i in range(3))
        vectors = 0.5 * np.cross(b - a, c - a)
        normal = np.zeros_like(V)
        for i in range(3):
            np.add.at(normal, F[:, i], vectors)
        H_cotan = np.sum((dg.laplace.cotan_laplacian(V, F) @ V) * normal, axis=1) / np.linalg.norm(normal, axis=1) / (2 * A)
        worst = max(worst, float(np.max(np.abs(H - H_cotan))))
    return worst


@check("Bobenko 2005", "the conformal energy W = Σ_e β_e − π|V| vanishes on convex meshes inscribed in a sphere "
       "(icospheres, the convex hull of random points on a sphere)",
       quantity="max |W|", at_most=1e-11, quick=dict(level=2, points=60), full=dict(level=4, points=400))
def conformal_vanishes_inscribed(ctx, level, points):
    U = np.random.default_rng(1).normal(size=(points, 3))
    U = 1.7 * U / np.linalg.norm(U, axis=1, keepdims=True) + np.array([1.0, 2.0, 3.0])
    meshes = [mesh.icosphere(level), (U, mesh.builtin._hull_faces(U))]
    return max(abs(_energy(willmore.conformal(V, F))) for V, F in meshes)


def random_moebius(V, rng):
    """x ↦ s R ι(x) + t: ι the inversion in a sphere of radius ρ ∈ [0.5, 3] centred at distance
    2.5–4 from the origin (outside meshes within radius ~1.5), then a rotation R, a scale s and a
    translation t, all drawn from `rng`."""
    c = rng.normal(size=3)
    c *= rng.uniform(2.5, 4.0) / np.linalg.norm(c)
    X = c + rng.uniform(0.5, 3.0) ** 2 * (V - c) / np.sum((V - c) ** 2, axis=1, keepdims=True)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return rng.uniform(0.3, 3.0) * X @ Q.T + rng.normal(size=3)


@check("Bobenko 2005", "the conformal energy is Möbius invariant (random inversions composed with similarities of a "
       "perturbed icosphere), W ≥ 0; negative control: ∫H² dA of the same mesh is not (it changes by ≥ 1e-2)",
       quantity="max |ΔW| / W of the conformal energy (NaN if W < 0 or the H² energy is invariant)",
       at_most=1e-12, quick=dict(level=2, maps=4), full=dict(level=3, maps=10))
def conformal_moebius_invariance(ctx, level, maps):
    rng = np.random.default_rng(2)
    V, F = mesh.icosphere(level)
    V = np.asarray(V) * (1.0 + 0.15 * rng.uniform(-1, 1, size=(len(V), 1)))
    W, W_h = _energy(willmore.conformal(V, F)), _energy(willmore.helfrich(V, F))
    worst, least_h = 0.0, np.inf
    for _ in range(maps):
        X = random_moebius(V, rng)
        worst = max(worst, abs(_energy(willmore.conformal(X, F)) - W) / W)
        least_h = min(least_h, abs(_energy(willmore.helfrich(X, F)) - W_h))
    return worst if W > 0 and least_h > 1e-2 else float("nan")


@functools.lru_cache(maxsize=8)
def clifford_solve(m: int, n: int) -> dict:
    """The critical point of `willmore.torus_of_revolution(m, n)` from R/r = 2.5: the problem, the
    solution, W/2π² and R/r of the profile (its centroid's ρ over its mean distance to it)."""
    from solvers import solve

    problem = willmore.torus_of_revolution(m, n)
    sol = solve(problem)
    P = np.asarray(sol.x)
    centre = P.mean(axis=0)
    r = float(np.mean(np.linalg.norm(P - centre, axis=1)))
    return {"problem": problem, "solution": sol, "W": float(sol.energy) / (2 * np.pi**2), "ratio": float(centre[0]) / r}


def _clifford_order(ctx, sizes, key, target, label, figure):
    errors = {n: abs(clifford_solve(m, n)[key] - target) for m, n in sizes}
    table = dg.limits.convergence(errors.get, sorted(errors), label=label)
    orders = ctx.convergence(table, figure).orders
    return float(max(orders, key=lambda p: abs(p - 2.0)))


CLIFFORD_SIZES = dict(quick=dict(sizes=((24, 12), (32, 16), (48, 24))),
                      full=dict(sizes=((24, 12), (32, 16), (48, 24), (64, 32), (96, 48))))


@check("Marques–Neves 2014; Willmore 1965",
       "minimising W = ∫H² dA among tori of revolution (an equilateral profile polygon of n points revolved into m = 2n "
       "meridians, started at R/r = 2.5) reaches the Clifford torus: W → 2π² at order 2 in 1/n",
       quantity="observed order of |W/2π² − 1| farthest from 2 (n profile points)", target=2.0, within=0.15,
       **CLIFFORD_SIZES)
def clifford_torus_energy_order(ctx, sizes):
    return _clifford_order(ctx, sizes, "W", 1.0, "|W/2π² − 1|", "convergence_clifford_energy")


@check("Willmore 1965; Langer–Singer 1984",
       "the Willmore torus of revolution of the discrete problem above has R/r → √2 (the Clifford torus) at order 2",
       quantity="observed order of |R/r − √2| farthest from 2 (n profile points)", target=2.0, within=0.15,
       **CLIFFORD_SIZES)
def clifford_torus_ratio_order(ctx, sizes):
    return _clifford_order(ctx, sizes, "ratio", np.sqrt(2.0), "|R/r − √2|", "convergence_clifford_ratio")


@check("Marques–Neves 2014", "the Willmore torus of revolution above is a minimum: the reduced Hessian of the "
       "Lagrangian (equal profile edges, p_0 and the mean height fixed) has no negative eigenvalue (solvers.stability)",
       quantity="stability index at the finest resolution", at_most=0, **CLIFFORD_SIZES)
def clifford_torus_is_a_minimum(ctx, sizes):
    from solvers import stability

    found = clifford_solve(*max(sizes))
    return float(stability(found["problem"], found["solution"]).index)
