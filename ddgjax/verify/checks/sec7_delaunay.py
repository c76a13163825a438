"""Intrinsic Delaunay triangulations and the Laplace–Beltrami operator (Lemma 5.8, Sec 7: Prop 7.9–Def 7.9)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp

import ddgjax as dg
from ddgjax import intrinsic
from ddgjax.intrinsic import rippa
from ddgjax.intrinsic import triangulation as T
from ddgjax.verify import check, figures
from energies.area import interior_residual


def _planar_skinny(n_inner: int = 150):
    """A flat disk triangulated with long skinny (non-Delaunay) triangles: the dome of Fig 7.26
    at height 0."""
    return dg.mesh.builtin.tall_dome(0, n_inner=n_inner, height=0.0)


@check("Lemma 5.8", "flipping an edge of a flat surface gives the other diagonal of the unfolded quadrilateral",
       quantity="max over all flippable edges of |l(flipped) − |v_c − v_d|| / l, and of the change of cone angles",
       at_most=1e-10, quick=dict(n_inner=60), full=dict(n_inner=300))
def flip_length_is_the_other_diagonal(ctx, n_inner):
    V, F, _ = _planar_skinny(n_inner)
    tri = T.from_mesh(V, F)
    cones = T.cone_angles(tri)
    worst, flipped = 0.0, 0
    for e in range(tri.n_edges):
        if intrinsic.is_flippable(tri, e):
            other = intrinsic.flip(tri, e)
            c, d = other.edges[e]
            worst = max(worst, abs(other.lengths[e] - np.linalg.norm(V[c] - V[d])) / other.lengths[e],
                        float(np.max(np.abs(T.cone_angles(other) - cones))))
            flipped += 1
    return worst if flipped > tri.n_edges // 2 else float("inf")


def _opposite_angle_sums(tri) -> np.ndarray:
    """(ne,) α + β: the angles opposite each edge, from `corner_angles` (side i of a face is
    opposite its corner i + 2), independent of the cotangent test of the flip algorithm."""
    return np.bincount(tri.edge, np.roll(T.corner_angles(tri), -2, axis=1).reshape(-1), minlength=tri.n_edges)


@functools.cache
def _flipped(level: int, bumps: float = 0.0):
    """The stretched icosphere, its triangulation and the result of the flip algorithm."""
    V, F = dg.mesh.builtin.stretched_sphere(level, bumps=bumps)
    tri = T.from_mesh(V, F)
    return tri, intrinsic.flip_to_delaunay(tri)


@check("Prop 7.9, Thm 7.12", "the flip algorithm terminates on a skinny ellipsoid with α + β ≤ π at every edge",
       quantity="max over edges of α + β − π after flipping", at_most=1e-12, quick=dict(level=2), full=dict(level=4))
def flips_reach_angle_criterion(ctx, level):
    _, result = _flipped(level)
    excess = float(np.max(_opposite_angle_sums(result.triangulation)) - np.pi)
    return excess if result.n_flips > 0 and intrinsic.is_delaunay(result) else float("inf")


@check("Prop 7.9", "negative control: before flipping, the skinny ellipsoid has edges with α + β > π",
       quantity="max over edges of α + β − π before flipping", at_least=0.1, quick=dict(level=2), full=dict(level=4))
def skinny_start_violates_angle_criterion(ctx, level):
    tri, _ = _flipped(level)
    return float(np.max(_opposite_angle_sums(tri)) - np.pi)


@check("Prop 7.10", "the cotan weights of the Delaunay triangulation are ≥ 0",
       quantity="max(0, −min ν) / max ν after flipping", at_most=1e-12, quick=dict(level=2), full=dict(level=4))
def delaunay_weights_nonnegative(ctx, level):
    nu = _flipped(level)[1].cotan_weights()
    return max(0.0, -float(nu.min())) / float(nu.max())


@check("Prop 7.10, eq (6.3)", "negative control: the start triangulation (not Delaunay) has negative cotan weights",
       quantity="−min ν / max ν before flipping", at_least=1e-2, quick=dict(level=2), full=dict(level=4))
def start_weights_negative(ctx, level):
    nu = intrinsic.cotan_weights(_flipped(level)[0])
    return -float(nu.min()) / float(nu.max())


@check("Cor 7.19, Lemma 7.18", "the harmonic index h(T) strictly decreases at every flip, and h = 8 Σ E(φ_i) = 4 tr L",
       quantity="max over flips of Δh / h(T_0), plus |h − 4 tr L| / h at the end", at_most=-1e-12,
       quick=dict(level=2), full=dict(level=4))
def harmonic_index_decreases(ctx, level):
    tri, result = _flipped(level)
    h = result.harmonic_index
    trace = 4.0 * float(intrinsic.cotan_laplacian(result.triangulation).diagonal().sum())
    if not result.n_flips or not np.isclose(h[0], intrinsic.harmonic_index(tri), rtol=1e-13):
        return float("inf")
    return float(np.max(np.diff(h))) / h[0] + abs(h[-1] - trace) / h[-1]


@check("Fig 7.13, Prop 7.9", "figure: a flat disk with skinny triangles before and after flipping to Delaunay",
       quantity="number of non-Delaunay edges after flipping", at_most=0, quick=dict(n_inner=60),
       full=dict(n_inner=300))
def flip_figure(ctx, n_inner):
    V, F, _ = _planar_skinny(n_inner)
    result = dg.plot.intrinsic.before_after(V, F, ctx.figure("intrinsic_delaunay_flips.png"))
    return float(np.sum(~intrinsic.delaunay_edges(result.triangulation))) if result.n_flips else float("inf")


def _lengthen(tri, steps: int):
    """`steps` flips ignoring the Delaunay criterion, each of the flippable edge (other than the
    last one flipped) whose new diagonal is longest: triangulations with long edges (Example 7.3)."""
    last = -1
    for _ in range(steps):
        options = [(intrinsic.flip(tri, e), e) for e in range(tri.n_edges) if e != last and intrinsic.is_flippable(tri, e)]
        tri, last = max(options, key=lambda option: option[0].lengths[option[1]])
    return tri


def _laplacian_after_bad_start(V, F, steps: int) -> tuple[float, float, object]:
    """From a triangulation made bad by `_lengthen`, flip to Delaunay: `(max |L − L_B|, longest
    start edge, flip result)` with L_B the Laplace–Beltrami operator of (V, F)."""
    bad = _lengthen(T.from_mesh(V, F), steps)
    result = intrinsic.flip_to_delaunay(bad)
    L = intrinsic.cotan_laplacian(result.triangulation).toarray()
    return float(np.max(np.abs(L - intrinsic.laplace_beltrami(V, F).toarray()))), float(bad.lengths.max()), result


@check("Example 7.2", "the tetrahedron from a bad triangulation: flips reach the Delaunay one (same Laplace–Beltrami operator)",
       quantity="max |L(flipped) − L(Delaunay)|", at_most=1e-12, quick=dict(steps=4))
def tetrahedron_from_bad_triangulation(ctx, steps):
    V, F = dg.mesh.tetrahedron()
    error, _, result = _laplacian_after_bad_start(V, F, steps)
    return error if result.n_flips > 0 and np.all(np.diff(result.harmonic_index) < 0) else float("inf")


@check("Example 7.3, Lemma 7.20, Thm 7.5", "the cube triangulated with edges longer than its diameter √3: the flip "
       "algorithm terminates at the unique Delaunay tessellation (six squares)",
       quantity="max |L(flipped) − L(Delaunay)|", at_most=1e-12, quick=dict(steps=12), full=dict(steps=30))
def cube_with_long_edges(ctx, steps):
    V, F = dg.mesh.cube(triangulated=True)
    error, longest, result = _laplacian_after_bad_start(V, F, steps)
    cells = intrinsic.delaunay_tessellation(result.triangulation)
    squares = cells.n_cells == 6 and np.all(cells.cell_size == 2)
    return error if longest > np.sqrt(3.0) and squares else float("inf")


def _random_quadrilaterals(count: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.2, 2.0, (count, 4)), rng.uniform(0.2, np.pi - 0.2, count), rng.standard_normal((count, 4))


_energies = jax.jit(jax.vmap(dg.laplace.triangle_dirichlet_energy))


def _split_energy(P, u, triangles) -> np.ndarray:
    """(count,) Dirichlet energies of the interpolants affine on the two `triangles` of each quad."""
    t = np.array(triangles)
    P3 = jnp.concatenate([P, jnp.zeros(P.shape[:2] + (1,))], axis=2)
    per = [_energies(u[:, k], P3[:, k]) for k in t]
    return np.asarray(per[0] + per[1])


@check("Lemma 7.14", "Rippa: E(u₁₃) − E(u₂₄) = ¼(u₀ − u₀*)²/sin θ · (r₁+r₃)(r₂+r₄)/(r₁r₂r₃r₄) · (r₁r₃ − r₂r₄)",
       quantity="max relative error of eq (7.2) against the two energies", at_most=1e-10, quick=dict(count=200),
       full=dict(count=5000))
def rippa_formula(ctx, count):
    r, theta, u = _random_quadrilaterals(count)
    P = np.stack([rippa.quadrilateral(r[k], theta[k]) for k in range(count)])
    difference = _split_energy(P, u, [(0, 1, 2), (0, 2, 3)]) - _split_energy(P, u, [(1, 2, 3), (1, 3, 0)])
    formula = np.array([rippa.dirichlet_energy_difference(u[k], r[k], theta[k]) for k in range(count)])
    return float(np.max(np.abs(formula - difference) / (1e-3 + np.abs(difference))))


def _diagonal_24_is_delaunay(r, theta) -> bool:
    """The angle criterion (Prop 7.9) for the diagonal (24) of Q(r, θ), by the flip algorithm's test."""
    P = np.column_stack([rippa.quadrilateral(r, theta), np.zeros(4)])
    tri = T.from_mesh(P, np.array([[1, 2, 3], [1, 3, 0]]))
    return bool(intrinsic.delaunay_edges(tri).all())


@check("Lemma 7.15, Cor 7.16", "Q(r, θ) is circular iff r₁r₃ = r₂r₄, and the sign of r₁r₃ − r₂r₄ says which diagonal is Delaunay",
       quantity="max |r₁r₃ − r₂r₄| / r₁r₃ on circles + number of sign mismatches", at_most=1e-10,
       quick=dict(count=100), full=dict(count=2000))
def circularity_criterion(ctx, count):
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(count):
        phi = np.sort(rng.uniform(0, 2 * np.pi, 4))  # four points on the unit circle: the chords (13), (24) meet at O
        P = np.stack([np.cos(phi), np.sin(phi)], 1)
        s = np.linalg.solve(np.column_stack([P[2] - P[0], P[1] - P[3]]), P[1] - P[0])[0]
        r = np.linalg.norm(P - (P[0] + s * (P[2] - P[0])), axis=1)
        worst = max(worst, abs(rippa.circularity(r)) / (r[0] * r[2]))
    r, theta, _ = _random_quadrilaterals(count, seed=2)
    mismatches = sum((rippa.circularity(r[k]) > 0) != _diagonal_24_is_delaunay(r[k], theta[k]) for k in range(count))
    return worst + mismatches


def _dirichlet_energies(tri, f) -> np.ndarray:
    """(k,) E(f_T) = ½ fᵀ L_T f for the k columns of f."""
    return 0.5 * np.einsum("ik,ik->k", f, intrinsic.cotan_laplacian(tri) @ f)


@check("Thm 7.21", "the Delaunay triangulation minimises the Dirichlet energy of every f among triangulations: "
       "no single flip and no random walk of 3 flips from it lowers E(f_T)",
       quantity="min over flips, walks and 5 random f of (E(f_T) − E(f_Delaunay)) / E(f_Delaunay)", at_least=-1e-12,
       quick=dict(level=1, walks=10), full=dict(level=2, walks=30))
def delaunay_minimises_dirichlet_energy(ctx, level, walks):
    tri = _flipped(level, bumps=0.1)[1].triangulation  # generic: no cocircular quadrilaterals (ties)
    rng = np.random.default_rng(level)
    f = rng.standard_normal((tri.n_vertices, 5))
    E0 = _dirichlet_energies(tri, f)
    flippable = [e for e in range(tri.n_edges) if intrinsic.is_flippable(tri, e)]
    others = [intrinsic.flip(tri, e) for e in flippable]
    for _ in range(walks):  # three flips of distinct edges
        walk, used = tri, set()
        for _ in range(3):
            e = int(rng.choice([e for e in range(walk.n_edges) if e not in used and intrinsic.is_flippable(walk, e)]))
            walk, _ = intrinsic.flip(walk, e), used.add(e)
        others.append(walk)
    if len(flippable) < tri.n_edges // 2:
        return float("-inf")
    return float(min(np.min((_dirichlet_energies(t, f) - E0) / E0) for t in others))


@check("Thm 7.21, Cor 7.16", "negative control: at the start triangulation (not Delaunay) flipping a non-Delaunay edge "
       "lowers the Dirichlet energy", quantity="−min over non-Delaunay edges and 5 random f of ΔE / E", at_least=1e-4,
       quick=dict(level=1), full=dict(level=2))
def non_delaunay_flip_lowers_dirichlet_energy(ctx, level):
    tri = _flipped(level, bumps=0.1)[0]
    f = np.random.default_rng(level).standard_normal((tri.n_vertices, 5))
    E0 = _dirichlet_energies(tri, f)
    bad = np.flatnonzero(~intrinsic.delaunay_edges(tri))
    return -float(min(np.min((_dirichlet_energies(intrinsic.flip(tri, int(e)), f) - E0) / E0) for e in bad))


@check("Def 7.8, Remark 7.9", "the Laplace–Beltrami operator is independent of the triangulation: the cube with either "
       "diagonals, and a flat disk's two skinny triangulations (squeezed in x or in y)",
       quantity="max |L_a − L_b| / max |L_a|", at_most=1e-12, quick=dict(n_inner=100), full=dict(n_inner=1000))
def laplace_beltrami_independent_of_triangulation(ctx, n_inner):
    V, F = dg.mesh.cube()
    cube = [intrinsic.laplace_beltrami(V, dg.mesh.triangulate(np.roll(F, k, axis=1))) for k in (0, 1)]
    disk = [intrinsic.laplace_beltrami(*_two_triangulations(n_inner, k)) for k in (0, 1)]
    return max(abs(a - b).max() / abs(a).max() for a, b in (cube, disk))


def _two_triangulations(n_inner: int, which: int):
    """The flat disk of `_planar_skinny` triangulated by the Delaunay triangulation of its points
    squeezed in y (which = 0) or in x (which = 1)."""
    from scipy.spatial import Delaunay

    V, _, _ = _planar_skinny(n_inner)
    F = Delaunay(V[:, :2] * ([1.0, 5.0] if which == 0 else [5.0, 1.0])).simplices
    u, w = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    clockwise = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0] < 0
    F[clockwise] = F[clockwise][:, [0, 2, 1]]
    return V, F


@check("Def 7.8", "negative control: the extrinsic cotan Laplacians (Def 6.2) of the disk's two triangulations differ",
       quantity="max |L_a − L_b| / max |L_a| (cotan Laplacian of the triangulation itself)", at_least=1e-2,
       quick=dict(n_inner=100), full=dict(n_inner=1000))
def cotan_laplacian_depends_on_triangulation(ctx, n_inner):
    a, b = (dg.laplace.cotan_laplacian(*_two_triangulations(n_inner, k)) for k in (0, 1))
    return float(abs(a - b).max() / abs(a).max())


@check("Remark 7.9, Example 5.3", "the Laplace–Beltrami operator depends on the metric only: the icosahedron with one "
       "vertex pushed in (an isometric polyhedron, non-convex) has the same operator",
       quantity="max |L − L_pushed| / max |L|", at_most=1e-12, quick=dict())
def laplace_beltrami_isometry_invariant(ctx):
    V, F = dg.mesh.icosahedron()
    ring = np.unique(F[np.any(F == 0, axis=1)])
    ring = ring[ring != 0]
    centre = V[ring].mean(axis=0)
    normal = np.linalg.svd(V[ring] - centre)[2][-1]  # the five neighbours are coplanar
    pushed = V.copy()
    pushed[0] = V[0] - 2 * np.dot(V[0] - centre, normal) * normal
    L, L_pushed = intrinsic.laplace_beltrami(V, F), intrinsic.laplace_beltrami(pushed, F)
    return float(abs(L - L_pushed).max() / abs(L).max()) if np.linalg.norm(pushed[0] - V[0]) > 0.1 else float("inf")


_fig_7_26 = functools.cache(figures.fig_7_26)
FIG_7_26 = dict(quick=dict(seed=0, budget=30), full=dict(seed=1, budget=200))  # the sizes of the Fig 7.26 checks


@check("Fig 7.26", "negative control: the cotan iteration (Fig 6.5) from the skinny tall dome does not converge",
       quantity="area-gradient residual when the budget ran out or an iterate degenerated", at_least=1e-6, **FIG_7_26)
def cotan_iteration_stuck(ctx, seed, budget):
    *_, cotan, _ = _fig_7_26(seed, budget)
    return float(cotan[2]["residual"]) if not cotan[2]["converged"] else 0.0


@check("Def 7.9, Fig 7.23, 7.26", "from the same start Fig 7.23 (flips + Laplace–Beltrami) converges to a minimal surface "
       "in the narrow sense: Delaunay, Δf = 0, the flat 32-gon",
       quantity="max |Δf| at free vertices + |A − A(32-gon)| / A", at_most=1e-9, **FIG_7_26)
def narrow_minimal_surface_converges(ctx, seed, budget):
    V, F, boundary, cotan, (W, F1, info) = _fig_7_26(seed, budget)
    tri = info["triangulation"]
    fixed = np.zeros(len(W), dtype=bool)
    fixed[boundary] = True
    residual = interior_residual(intrinsic.cotan_laplacian(tri), W, fixed)
    figures.draw_fig_7_26(ctx.figure("fig_7_26.png"), V, F, cotan, (W, F1, info))
    polygon = 0.5 * 32 * np.sin(2 * np.pi / 32)
    ok = info["converged"] and intrinsic.is_delaunay(tri) and info["flips"].sum() > 0
    return residual + abs(info["area"][-1] - polygon) / polygon if ok else float("inf")


@check("Remark 7.10, Prop 6.8", "maximum principle: every free vertex of the narrow-sense minimal surface is the "
       "weighted mean of its Delaunay neighbours with weights ≥ 0",
       quantity="max |f(i) − Σ ν_ij f(j) / Σ ν_ij| + max(0, −min ν)", at_most=1e-9, **FIG_7_26)
def narrow_minimal_surface_maximum_principle(ctx, seed, budget):
    _, _, boundary, _, (W, _, info) = _fig_7_26(seed, budget)
    L = intrinsic.cotan_laplacian(info["triangulation"]).tocsr()
    D = L.diagonal()
    off = (L - sp.diags(D)).tocsr()
    free = np.setdiff1d(np.arange(len(W)), boundary)
    mean = -(off @ W)[free] / D[free][:, None]
    return float(np.max(np.abs(W[free] - mean))) + max(0.0, float(off.max()))
