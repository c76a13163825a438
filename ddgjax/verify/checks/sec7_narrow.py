"""Simplicial minimal surfaces in the narrow sense (Sec 7.5: Def 7.9, Remark 7.10, Fig 7.22–7.25).

Def 7.9: a simplicial surface f with triangulation T is minimal in the wide sense when Δf = 0 for
its Laplace–Beltrami operator Δ (Def 7.8, the cotan Laplacian of its intrinsic Delaunay
triangulation), and in the narrow sense when moreover T is Delaunay.  Only then is Δ the cotan
Laplacian of (f, T) itself, hence (Thm 6.7) ∇A(f, T) = Δf = 0, and all weights are ≥ 0, hence
every vertex lies in the convex hull of its neighbours (Remark 7.10, Prop 6.8).

The surfaces here span two coaxial unit circles 1 apart (`mesh.builtin.cylinder`): the start is the
cylinder grid with a random half of its edges flipped (Lemma 5.8), a random start triangulation
in the sense of Fig 7.25.  From it run
- Fig 7.23, `energies.area.harmonic_iteration(flip=True)`: with change of combinatorics;
- `without_change`: the same loop with the combinatorics kept, the Laplace–Beltrami operator of
  (f, T_start) at each step; its fixed points are minimal in the wide sense only;
- Fig 6.5, `harmonic_iteration(flip=False)`: the cotan Laplacian of (f, T_start), minimal in the
  sense of Sec 6.4 (∇A = 0 with the given combinatorics), which may violate the maximum principle
  (Fig 6.6, 7.22 left); Fig 7.23 applied to it gives Fig 7.22 right.

The maximum principle is measured by the distance of f(i) to the convex hull of its neighbours'
points (non-negative least squares), independent of the cotan weights that imply it.
"""

from __future__ import annotations

import functools

import jax
import numpy as np
from scipy.optimize import nnls

import ddgjax as dg
from ddgjax import intrinsic
from ddgjax.plot import save_figure
from ddgjax.plot._figure import pyplot
from ddgjax.verify import check
from ddgjax.verify.figures import draw_surface
from energies.area import face_area, harmonic_iteration, interior_residual
from energies.dirichlet import dirichlet_solve

TOL = 1e-12  # the iterations' tolerance on max |Δf(i)| at the free vertices (the boundary has radius 1)


def random_cylinder(n: int, seed: int):
    """`(V, F, boundary)`: `mesh.builtin.cylinder(n)` (n + 1 circles of 3n vertices, |z| ≤ ½) with
    a random half of its edges, in random order, flipped where the unfolded quadrilateral is convex
    (Lemma 5.8): a random triangulation of the cylinder's vertices; the two end circles fixed."""
    V, F = dg.mesh.builtin.cylinder(n)
    tri = intrinsic.from_mesh(V, F)
    rng = np.random.default_rng(seed)
    for e in rng.permutation(tri.n_edges)[: tri.n_edges // 2]:
        if intrinsic.is_flippable(tri, int(e)):
            tri = intrinsic.flip(tri, int(e))
    return V, tri.F, np.flatnonzero(np.isclose(np.abs(V[:, 2]), 0.5))


def without_change(V, F, boundary, *, tol: float = TOL, max_iter: int = 1000):
    """Fig 7.23 without change of combinatorics (Fig 7.25 middle): f ← f̃ with Δ_{(f, T)} f̃ = 0,
    Δ the Laplace–Beltrami operator of the simplicial surface (f, T) (Def 7.8), T = F kept, the
    boundary fixed.  Returns `(f, residual)`, residual max |Δf(i)| at the free vertices of the
    last f (0 at a minimal surface in the wide sense, Def 7.9)."""
    V = np.array(V, dtype=np.float64)
    fixed = np.zeros(len(V), dtype=bool)
    fixed[boundary] = True
    for _ in range(max_iter + 1):
        L = intrinsic.laplace_beltrami(V, F)
        residual = interior_residual(L, V, fixed)
        if residual <= tol:
            break
        V = dirichlet_solve(L, boundary, V[boundary])
    return V, residual


def area_gradient(V, F, boundary) -> np.ndarray:
    """(nv, 3) ∇A of the simplicial surface (V, F), A = Σ_F A(F) (`energies.area.face_area`) by
    autodiff, zero at the `boundary` vertices; Thm 6.7: ∇_{f(i)} A = (L f)(i), L the cotan
    Laplacian of (V, F)."""
    gradient = np.array(jax.jit(jax.grad(dg.local_sum(face_area, np.asarray(F))))(np.asarray(V), None))
    gradient[boundary] = 0.0
    return gradient


def hull_distance(p, Q) -> float:
    """dist(p, conv Q) = min |Σ λ_j q_j − p| over λ ≥ 0, Σ λ_j = 1 (non-negative least squares,
    the affine condition as a row weighted 1e3)."""
    w = 1e3 * max(1.0, float(np.abs(Q).max()))
    lam, _ = nnls(np.vstack([Q.T, np.full(len(Q), w)]), np.append(p, w))
    return float(np.linalg.norm(Q.T @ lam - p))


def hull_violations(V, edges, free) -> np.ndarray:
    """(len(free),) dist(f(i), conv{f(j) : ij ∈ edges}) / max_j |f(j) − f(i)|: 0 where f(i) lies in
    the convex hull of its neighbours (Prop 6.8, Remark 7.10)."""
    out = []
    for i in free:
        j = np.unique(np.concatenate([edges[edges[:, 0] == i, 1], edges[edges[:, 1] == i, 0]]))
        j = j[j != i]
        out.append(hull_distance(V[i], V[j]) / np.linalg.norm(V[j] - V[i], axis=1).max())
    return np.array(out)


def mesh_edges(F) -> np.ndarray:
    """(ne, 2) the edges of the faces F as vertex pairs (with repeats)."""
    F = np.asarray(F)
    return np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])


def delaunay_neighbours(tri) -> np.ndarray:
    """The edges of the Delaunay tessellation of `tri` (Remark 7.10): those with ν > 0 (up to
    1e-12 max ν)."""
    nu = intrinsic.cotan_weights(tri)
    return tri.edges[nu > 1e-12 * nu.max()]


def negative_weight(V, F) -> float:
    """−min ν / max ν over the off-diagonal entries −ν_ij of the cotan Laplacian of (V, F) (eq 6.2);
    ≤ 0 iff all weights are ≥ 0."""
    L = dg.laplace.cotan_laplacian(V, F).tocoo()
    nu = -L.data[L.row != L.col]
    return float(-nu.min() / nu.max())


def _free(V, boundary) -> np.ndarray:
    return np.setdiff1d(np.arange(len(V)), boundary)


def maximum_principle_defect(W, tri, boundary) -> float:
    """max of max_i dist(f(i), conv of its Delaunay neighbours) / longest spoke over the free
    vertices and of −min ν / max ν over the edges of `tri`: 0 up to rounding at a narrow-sense
    minimal surface (Remark 7.10)."""
    nu = intrinsic.cotan_weights(tri)
    hull = hull_violations(W, delaunay_neighbours(tri), _free(W, boundary))
    return max(float(hull.max()), -float(nu.min() / nu.max()))


def relative_area_gradient(X, F, boundary) -> float:
    """max |∇A(X, F)| at the free vertices / the boundary's diameter (`area_gradient`)."""
    return float(np.abs(area_gradient(X, F, boundary)).max()) / float(np.ptp(X[boundary], axis=0).max())


@functools.cache
def _runs(n: int, seed: int, budget: int):
    """(start, Fig 7.23 with change of combinatorics `(W, F, info)`, without change `(X, residual)`),
    `budget` steps each, from `random_cylinder(n, seed)`."""
    V, F, b = random_cylinder(n, seed)
    narrow = harmonic_iteration(V, F, b, flip=True, tol=TOL, max_iter=budget)
    return (V, F, b), narrow, without_change(V, F, b, max_iter=budget)


@functools.cache
def _fig_7_22(n: int, seed: int, budget: int):
    """(start, Fig 6.5 from it: `(Y, F, info)` minimal in the sense of Sec 6.4, Fig 7.23 from that)."""
    V, F, b = random_cylinder(n, seed)
    cotan = harmonic_iteration(V, F, b, flip=False, tol=TOL, max_iter=budget)
    return (V, F, b), cotan, harmonic_iteration(cotan[0], F, b, flip=True, tol=TOL, max_iter=budget)


def _narrow_ok(info) -> bool:
    """Fig 7.23 converged, flipped some edge on the way and ended Delaunay: minimal in the narrow sense."""
    return bool(info["converged"] and info["flips"].sum() > 0 and intrinsic.is_delaunay(info["triangulation"]))


def draw_surfaces(path, panels, title: str):
    """The simplicial surfaces `panels` = [(V, F, title)] side by side (faces repeating a vertex
    left out); saved to `path` (PNG)."""
    plt = pyplot()
    fig = plt.figure(figsize=(4.0 * len(panels), 4.0))
    for k, (X, G, name) in enumerate(panels):
        draw_surface(fig.add_subplot(1, len(panels), k + 1, projection="3d"), X, G, name)
    fig.suptitle(title)
    return save_figure(fig, path, dpi=90)


# starts (n, seed) of `random_cylinder` on which both loops converge within `budget` steps (Remark 7.10)
CRITICAL = dict(quick=dict(starts=((2, 25),), budget=1000), full=dict(starts=((2, 0), (2, 25), (2, 33), (3, 0)),
                                                                     budget=4000))
# Fig 7.25: the loop without change of combinatorics stopped after `budget` steps if not converged
FIG_7_25 = dict(quick=dict(starts=((2, 25),), budget=1000),
                full=dict(starts=((2, 3), (2, 25), (2, 29), (2, 33), (3, 0), (3, 1)), budget=3000))
# Fig 7.22: a random cylinder on which Fig 6.5 converges to a surface violating the maximum principle
FIG_7_22 = dict(quick=dict(n=2, seed=29, budget=1000), full=dict(n=2, seed=29, budget=3000))


@check("Remark 7.10, Def 7.9, Thm 6.7", "at a minimal surface in the narrow sense (Fig 7.23 from a random start "
       "triangulation of the catenoid's two circles: T Delaunay, Δf = 0) the simplicial area of (f, T) is critical",
       quantity="max over the starts of max |∇A| / diam at the free vertices (autodiff of the area; ∞ unless Fig "
       "7.23 converged to 1e-12, flipped and ended Delaunay)", at_most=1e-10, **CRITICAL)
def narrow_minimal_surface_is_critical(ctx, starts, budget):
    worst = 0.0
    for n, seed in starts:
        (_, _, b), (W, F, info), _ = _runs(n, seed, budget)
        if not _narrow_ok(info):
            return float("inf")
        worst = max(worst, relative_area_gradient(W, F, b))
    return worst


@check("Remark 7.10, Def 7.9", "negative control: a minimal surface in the wide sense only (Fig 7.23 without "
       "change of combinatorics: Δf = 0 for the Laplace–Beltrami operator, T not Delaunay) is not critical for the "
       "area of (f, T)",
       quantity="min over the starts of max |∇A| / diam at the free vertices (−∞ unless the wide-sense residual "
       "max |Δf| ≤ 1e-12 and T is not Delaunay)", at_least=1e-2, **CRITICAL)
def wide_minimal_surface_not_critical(ctx, starts, budget):
    worst = np.inf
    for n, seed in starts:
        (_, F, b), _, (X, residual) = _runs(n, seed, budget)
        if residual > TOL or intrinsic.is_delaunay(intrinsic.from_mesh(X, F)):
            return float("-inf")
        worst = min(worst, relative_area_gradient(X, F, b))
    return worst


@check("Fig 7.25, 7.24, Remark 7.10", "from a random start triangulation Fig 7.23 with change of combinatorics gives "
       "a minimal surface in the narrow sense: Delaunay, all cotan weights ≥ 0, every free vertex in the convex hull "
       "of its Delaunay neighbours",
       quantity="max over the starts of max_i dist(f(i), conv Delaunay neighbours) / longest spoke and of −min ν / "
       "max ν (∞ unless Fig 7.23 converged to 1e-12, flipped and ended Delaunay)", at_most=1e-9, **FIG_7_25)
def fig_7_25_with_change_maximum_principle(ctx, starts, budget):
    worst = 0.0
    for n, seed in starts:
        (V, F0, b), (W, F, info), (X, _) = _runs(n, seed, budget)
        if not _narrow_ok(info):
            return float("inf")
        worst = max(worst, maximum_principle_defect(W, info["triangulation"], b))
        if (n, seed) == starts[0]:
            draw_surfaces(ctx.figure("fig_7_25.png"), [
                (V, F0, "random start triangulation"), (X, F0, f"without change of combinatorics ({budget} steps)"),
                (W, F, f"with change (Fig 7.24): {info['iterations']} steps, {info['flips'].sum()} flips")],
                "Fig 7.25: Fig 7.23 without and with change of combinatorics")
    return worst


@check("Fig 7.25, Prop 6.8", "negative control: Fig 7.23 without change of combinatorics, from the same starts, "
       "ends with negative cotan weights and a vertex outside the convex hull of its neighbours",
       quantity="min over the starts of max_i dist(f(i), conv neighbours in T) / longest spoke (−∞ unless some "
       "cotan weight of (f, T) is < −1e-2 max ν)", at_least=1e-3, **FIG_7_25)
def fig_7_25_without_change_violates_maximum_principle(ctx, starts, budget):
    worst = np.inf
    for n, seed in starts:
        (V, F, b), _, (X, _) = _runs(n, seed, budget)
        if negative_weight(X, F) < 1e-2:
            return float("-inf")
        worst = min(worst, float(hull_violations(X, mesh_edges(F), _free(V, b)).max()))
    return worst


@check("Fig 7.22 left, Fig 6.6, Prop 6.8", "a simplicial minimal surface in the sense of Sec 6.4 (Fig 6.5: ∇A = 0 "
       "with the given combinatorics) violates the maximum principle: a vertex lies outside the convex hull of its "
       "neighbours", quantity="max_i dist(f(i), conv neighbours) / longest spoke (−∞ unless Fig 6.5 converged to "
       "max |Δf| ≤ 1e-12, max |∇A| ≤ 1e-11 by autodiff, and some cotan weight is < 0)", at_least=1e-3,
       **FIG_7_22)
def fig_7_22_cotan_minimal_violates_maximum_principle(ctx, n, seed, budget):
    (V, F, b), (Y, _, info), _ = _fig_7_22(n, seed, budget)
    critical = info["converged"] and np.abs(area_gradient(Y, F, b)).max() <= 10 * TOL
    if not critical or negative_weight(Y, F) <= 0:
        return float("-inf")
    return float(hull_violations(Y, mesh_edges(F), _free(V, b)).max())


@check("Fig 7.22 right, Remark 7.10", "Fig 7.23 applied to that surface gives a minimal surface in the narrow sense "
       "which satisfies the maximum principle",
       quantity="max of max_i dist(f(i), conv Delaunay neighbours) / longest spoke and −min ν / max ν (∞ unless "
       "Fig 7.23 converged to 1e-12, flipped and ended Delaunay)", at_most=1e-9, **FIG_7_22)
def fig_7_22_narrow_satisfies_maximum_principle(ctx, n, seed, budget):
    (V, F0, b), (Y, _, _), (W, F, info) = _fig_7_22(n, seed, budget)
    if not _narrow_ok(info):
        return float("inf")
    violation = hull_violations(Y, mesh_edges(F0), _free(V, b))
    draw_surfaces(ctx.figure("fig_7_22.png"), [
        (Y, F0, f"Sec 6.4 minimal (Fig 6.5): a vertex {violation.max():.1e} outside its hull"),
        (W, F, f"narrow sense (Fig 7.23 from it, {info['flips'].sum()} flips)")],
        "Fig 7.22: minimal in the sense of Sec 6.4 and in the narrow sense")
    return maximum_principle_defect(W, info["triangulation"], b)


# --- a non-planar boundary: Enneper's surface over |w| ≤ 0.8 (Fig 7.23 with Newton) --------------

ENNEPER = dict(quick=dict(rings=(4,)), full=dict(rings=(4, 8)))


def enneper_polar_disk(rings: int):
    """`(V, F, boundary)`: the polar disk `dg.mesh.disk(rings, 4 rings)` mapped by w = 0.8 (x + iy)
    to Enneper's surface (`references.enneper`), then the interior flattened to z = 0: the
    boundary is a non-planar space curve on the surface, the start is not."""
    from ddgjax.verify import references

    D, F = dg.mesh.disk(rings, 4 * rings)
    V = references.enneper(0.8 * (D[:, 0] + 1j * D[:, 1]))
    b = dg.mesh.boundary_vertices(F, len(V))
    V[np.setdiff1d(np.arange(len(V)), b), 2] = 0.0
    return V, F, b


@check("Fig 7.23, Def 7.9, Remark 7.10", "on a non-planar boundary (Enneper's surface over |w| ≤ 0.8, a polar disk) "
       "Fig 7.23 accelerated by Newton (`minimal_surface(method=\"delaunay\")`) converges to a minimal surface in the "
       "narrow sense: T Delaunay for the result, ∇A(f, T) = Δf = 0",
       quantity="max over the meshes of max |∇A| / diam at the free vertices (autodiff of the area; ∞ unless the "
       "method converged to 1e-12, flipped and ended Delaunay)", at_most=1e-10, **ENNEPER)
def narrow_minimal_surface_non_planar(ctx, rings):
    from energies.area import minimal_surface

    worst = 0.0
    for k in rings:
        V, F, b = enneper_polar_disk(k)
        W, FW, info = minimal_surface(V, F, b, method="delaunay", tol=TOL, throw=False)
        if not (info["converged"] and info["flips"].sum() > 0 and intrinsic.is_delaunay(intrinsic.from_mesh(W, FW))):
            return float("inf")
        worst = max(worst, relative_area_gradient(W, FW, b))
    return worst
