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
from ddgjax.intrinsic.delaunay import DELAUNAY_TOL
from ddgjax.intrinsic.flips import flip_batch, quad
from ddgjax.intrinsic.geometry import flipped_length
from ddgjax.mesh.lengths import corner_cotangents, face_harmonic_index, triangle_area
from ddgjax.verify import check, figures

from ._flip_surfaces import SURFACES, opposite_angle_sums, surfaces
from energies.area import interior_residual


def _planar_skinny(n_inner: int = 150):
    """A flat disk triangulated with long skinny (non-Delaunay) triangles: the dome of Fig 7.26
    at height 0."""
    return dg.mesh.builtin.tall_dome(0, n_inner=n_inner, height=0.0)


def _convex_quadrilateral(rng):
    """Planar points a, b, c, d with a d b c convex: c above, d below the segment ab."""
    while True:
        a, b = np.array([0.0, 0.0]), np.array([rng.uniform(0.5, 2), 0.0])
        c = np.array([rng.uniform(0.1, 1.9) * b[0], rng.uniform(0.2, 2)])
        d = np.array([rng.uniform(0.1, 1.9) * b[0], -rng.uniform(0.2, 2)])
        if 0.05 < d[0] + (c[0] - d[0]) * (-d[1]) / (c[1] - d[1]) < 0.95 * b[0]:  # cd crosses ab inside
            return np.array([a, b, c, d])


def _quadrilateral_flip_error(P) -> float:
    """The two triangles (a, b, c), (b, a, d) of the convex planar quadrilateral P = (a, b, c, d):
    the largest relative error of the unfolding (Lemma 5.8) against the six distances of P and of
    the flipped edge's length against |c − d|; ∞ unless the flip gives the triangles (d, c, a), (c, d, b)."""
    tri = T.from_mesh(np.column_stack([P, np.zeros(4)]), np.array([[0, 1, 2], [1, 0, 3]]))
    e = int(np.flatnonzero(tri.halfedges[:, 1] >= 0)[0])
    distances = lambda X: np.linalg.norm(X[:, None] - X[None], axis=-1)  # noqa: E731
    D = distances(P)
    unfolding = float(np.max(np.abs(distances(T.unfold(tri, e)) - D)) / D.max())
    if not intrinsic.is_flippable(tri, e):
        return float("inf")
    flipped = intrinsic.flip(tri, e)
    if sorted(map(sorted, flipped.F.tolist())) != [[0, 2, 3], [1, 2, 3]]:
        return float("inf")
    return max(unfolding, abs(flipped.lengths[e] - D[2, 3]) / D[2, 3])


@check("Lemma 5.8", "flipping an edge of a flat surface gives the other diagonal of the unfolded quadrilateral",
       quantity="max over all flippable edges of a skinny flat disk of |l(flipped) − |v_c − v_d|| / l and of the change "
       "of cone angles (∞ unless on random convex quadrilaterals the unfolding, the new diagonal and the new faces are "
       "right to 1e-13)", at_most=1e-10, quick=dict(n_inner=60, quadrilaterals=20),
       full=dict(n_inner=300, quadrilaterals=200))
def flip_length_is_the_other_diagonal(ctx, n_inner, quadrilaterals):
    rng = np.random.default_rng(0)
    if max(_quadrilateral_flip_error(_convex_quadrilateral(rng)) for _ in range(quadrilaterals)) > 1e-13:
        return float("inf")
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


@functools.cache
def _flipped(level: int, bumps: float = 0.0):
    """The stretched icosphere, its triangulation and the result of the flip algorithm."""
    V, F = dg.mesh.builtin.stretched_sphere(level, bumps=bumps)
    tri = T.from_mesh(V, F)
    return tri, intrinsic.flip_to_delaunay(tri)




def _interior(halfedges) -> np.ndarray:
    """The edges between two distinct triangles (the only ones the angle test can fail)."""
    return np.flatnonzero((halfedges[:, 1] >= 0) & (halfedges[:, 0] // 3 != halfedges[:, 1] // 3))


def _quarter_h(x, y, z, A):
    return (x * x + y * y + z * z) / (4 * A)


def _quad_flips(F, edge, halfedges, lengths, e) -> dict:
    """Each interior edge e = ab of `e` flipped on its own (Lemma 5.8), from its five lengths by the law
    of cosines, independent of the flip algorithm's keys: `g_old`, `g_new` the tie-normalised angle test
    (cot α + cot β) / s of ab and of the new diagonal cd, s = (h(Δ₁) + h(Δ₂)) / 4 of the two triangles
    (Lemma 7.17; the library's test is g < −1e-12); `area` |A(adc) + A(bcd) − A(abc) − A(bad)| / A (0 iff
    the unfolded quadrilateral is convex: e can be flipped); `dh` the change of h(T); `cd` the new length."""
    _, _, (ab, bc, ca, ad, db) = quad(F, edge, halfedges, lengths, e)
    with np.errstate(invalid="ignore", divide="ignore"):  # a non-convex quadrilateral: NaN areas
        return _quad_flip_terms(ab, bc, ca, ad, db)


def _quad_flip_terms(ab, bc, ca, ad, db) -> dict:
    A1, A2 = triangle_area(ab, bc, ca), triangle_area(ab, ad, db)
    cd = flipped_length(ab, bc, ca, ad, db, A1, A2)
    B1, B2 = triangle_area(ad, cd, ca), triangle_area(bc, cd, db)
    s_old, s_new = _quarter_h(ab, bc, ca, A1) + _quarter_h(ab, ad, db, A2), _quarter_h(ad, cd, ca, B1) + _quarter_h(bc, cd, db, B2)
    cot_old = (bc * bc + ca * ca - ab * ab) / (4 * A1) + (ad * ad + db * db - ab * ab) / (4 * A2)
    cot_new = (ad * ad + ca * ca - cd * cd) / (4 * B1) + (bc * bc + db * db - cd * cd) / (4 * B2)
    return dict(g_old=cot_old / s_old, g_new=cot_new / s_new, area=np.abs(B1 + B2 - A1 - A2) / (A1 + A2),
                dh=4 * (s_new - s_old), cd=cd)


def _of(tri) -> dict:
    """`_quad_flips` of every interior edge of `tri`."""
    return _quad_flips(tri.F.reshape(-1), tri.edge, tri.halfedges, tri.lengths, _interior(tri.halfedges))


def _rounds(tri, seed: int) -> dict:
    """Fig 7.13 with other choices than the library's sweep: in rounds, a random maximal set of
    non-Delaunay edges no two on one face (each stays non-Delaunay until its turn: its two faces are
    untouched) is flipped one after the other (`flips.flip_batch`).  Records at every state every
    non-Delaunay edge flipped on its own (`g_new`, `area`: Lemma 7.11), and per flip Δh (Cor 7.19),
    h(T) and an upper bound of the longest edge l(T) (the running maximum; Lemma 7.20)."""
    F, edge, halfedges, lengths = (np.array(a) for a in (tri.F.reshape(-1), tri.edge, tri.halfedges, tri.lengths))
    rng = np.random.default_rng(seed)
    steps, longest, g_new, area = [], [[tri.lengths.max()]], [], []
    for _ in range(10 * tri.n_faces):
        e = _interior(halfedges)
        q = _quad_flips(F, edge, halfedges, lengths, e)
        bad = q["g_old"] < -DELAUNAY_TOL
        g_new.append(q["g_new"][bad])
        area.append(q["area"][bad])
        if not bad.any():
            break
        used, batch = set(), []
        for k in rng.permutation(np.flatnonzero(bad)):
            faces = set((halfedges[e[k]] // 3).tolist())
            if not faces & used:
                used |= faces
                batch.append(k)
        longest.append(np.maximum(lengths.max(), np.maximum.accumulate(q["cd"][batch])))
        steps.append(q["dh"][batch])
        flip_batch(F, edge, halfedges, lengths, e[batch])
    steps = np.concatenate(steps)
    return dict(end=T.of_arrays(F, edge, halfedges, lengths, tri.n_vertices), steps=steps,
                h=intrinsic.harmonic_index(tri) + np.concatenate([[0.0], np.cumsum(steps)]),
                longest=np.concatenate(longest), g_new=np.concatenate(g_new), area=np.concatenate(area))


@functools.cache
def _runs(level: int, n_inner: int, torus: tuple[int, int]) -> dict:
    """name → (start, the library's `flip_to_delaunay`, `_rounds`) on the surfaces of
    `_flip_surfaces.surfaces` (stretched icosphere with and without bumps, skinny noisy torus,
    skinny flat disk)."""
    return {name: (start, intrinsic.flip_to_delaunay(start), _rounds(start, seed=1))
            for name, (start, _) in surfaces(level, n_inner, torus).items()}


def _total_area(tri) -> float:
    return float(np.sum(triangle_area(*T.side_lengths(tri).T)))


@check("Prop 7.9, Thm 7.12", "the flip algorithm terminates on a stretched icosphere (symmetric, and with bumps), a "
       "skinny noisy torus and a skinny flat disk with α + β ≤ π at every interior edge, and keeps the metric (the cone "
       "angles); so does Fig 7.13 with random choices (rounds of flips of disjoint non-Delaunay edges)",
       quantity="max over the 8 runs and their interior edges of α + β − π after flipping, and of the change of the cone "
       "angles (∞ unless every run flips > 10 edges and every edge passes the angle test, cot α + cot β ≥ −1e-12 s)",
       at_most=1e-12, **SURFACES)
def flips_reach_angle_criterion(ctx, level, n_inner, torus):
    worst = 0.0
    for start, result, rounds in _runs(level, n_inner, torus).values():
        for end, n_flips in ((result.triangulation, result.n_flips), (rounds["end"], len(rounds["steps"]))):
            if n_flips <= 10 or not intrinsic.is_delaunay(end) or np.any(_of(end)["g_old"] < -DELAUNAY_TOL):
                return float("inf")
            worst = max(worst, float(np.max(opposite_angle_sums(end)[_interior(end.halfedges)])) - np.pi,
                        float(np.max(np.abs(T.cone_angles(end) - T.cone_angles(start)))))
    return worst


@check("Prop 7.9", "negative control: before flipping, each of the four surfaces has edges with α + β > π",
       quantity="min over the starts of max over edges of α + β − π", at_least=0.1, **SURFACES)
def skinny_start_violates_angle_criterion(ctx, level, n_inner, torus):
    return min(float(np.max(opposite_angle_sums(start)) - np.pi) for start, _, _ in _runs(level, n_inner, torus).values())


@check("Prop 7.10", "the cotan weights of the Delaunay triangulation are ≥ 0 at every interior edge",
       quantity="max over the four surfaces of max(0, −min ν) / max ν over the interior edges after flipping",
       at_most=1e-12, **SURFACES)
def delaunay_weights_nonnegative(ctx, level, n_inner, torus):
    worst = 0.0
    for _, result, _ in _runs(level, n_inner, torus).values():
        nu = result.cotan_weights()
        worst = max(worst, -float(nu[_interior(result.triangulation.halfedges)].min()) / float(nu.max()))
    return worst


@check("Prop 7.10, eq (6.3)", "negative control: the start triangulations (not Delaunay) have negative cotan weights",
       quantity="min over the four starts of −min ν / max ν (the torus: 6e-3)", at_least=1e-3, **SURFACES)
def start_weights_negative(ctx, level, n_inner, torus):
    weights = (intrinsic.cotan_weights(start) for start, _, _ in _runs(level, n_inner, torus).values())
    return min(-float(nu.min()) / float(nu.max()) for nu in weights)


def _lemma_7_17_error(count: int) -> float:
    """max relative error of h(Δ) = (a² + b² + c²) / A = 4 (cot α + cot β + cot γ) over random triangles."""
    rng = np.random.default_rng(0)
    a, b = rng.uniform(0.5, 2, count), rng.uniform(0.5, 2, count)
    c = rng.uniform(np.abs(a - b) + 0.01, a + b - 0.01)
    A = triangle_area(a, b, c)
    h, cots = face_harmonic_index(a, b, c, A), 4 * sum(corner_cotangents(a * a, b * b, c * c, A))
    return float(np.max(np.abs(np.asarray(h) - np.asarray(cots)) / np.asarray(h)))


@check("Cor 7.19, Lemma 7.17, 7.18", "the harmonic index h(T) strictly decreases at every flip of every run (the "
       "library's and Fig 7.13 with random choices, on the four surfaces); h(Δ) = 4 Σ cot on every triangle and h(T) = "
       "8 Σ E(φ_i) = 4 tr L before and after flipping",
       quantity="max over all flips of all 8 runs of Δh / h(T_0) (∞ unless h(Δ) = 4 Σ cot on random triangles and h(T) "
       "= 4 tr L at both ends agree to 1e-12 relative, the recorded h(T_0) to 1e-14, and both runs end at one h)",
       at_most=-1e-12, quick=dict(SURFACES["quick"], triangles=100), full=dict(SURFACES["full"], triangles=10_000))
def harmonic_index_decreases(ctx, level, n_inner, torus, triangles):
    trace = lambda t: 4.0 * float(intrinsic.cotan_laplacian(t).diagonal().sum())  # noqa: E731
    identities, worst = _lemma_7_17_error(triangles), -np.inf
    for start, result, rounds in _runs(level, n_inner, torus).values():
        h, h_start = result.harmonic_index, intrinsic.harmonic_index(start)
        if not result.n_flips or abs(h[0] - h_start) / h[0] > 1e-14:
            return float("inf")
        identities = max(identities, abs(h_start - trace(start)) / h[0], abs(h[-1] - trace(result.triangulation)) / h[-1],
                         abs(rounds["h"][-1] - h[-1]) / h[-1])
        worst = max(worst, float(np.max(result.harmonic_index_steps)) / h[0], float(np.max(rounds["steps"])) / h[0])
    return float("inf") if identities > 1e-12 else worst


@check("Lemma 7.11", "every non-Delaunay edge can be flipped and the flipped edge is then Delaunay: every non-Delaunay "
       "edge of every state of Fig 7.13 with random choices on the four surfaces, flipped on its own",
       quantity="max over those edges of −(cot α + cot β) / s of the new diagonal (s = (h(Δ₁) + h(Δ₂)) / 4) and of the "
       "convexity defect |ΔA| / A of the unfolded quadrilateral (∞ unless ≥ 1000 edges are tested)", at_most=1e-12,
       **SURFACES)
def flipped_edge_is_delaunay(ctx, level, n_inner, torus):
    runs = [rounds for _, _, rounds in _runs(level, n_inner, torus).values()]
    if sum(r["g_new"].size for r in runs) < 1000:
        return float("inf")
    return max(max(float(np.max(-r["g_new"])), float(np.max(r["area"]))) for r in runs)


@check("Lemma 7.11, Lemma 5.8", "negative control: Delaunay edges of the starts are not flippable (their unfolded "
       "quadrilateral is not convex) or become non-Delaunay when flipped",
       quantity="min over the four starts of the number of Delaunay interior edges with convexity defect > 1e-9 (or "
       "NaN: no triangle) or a flipped diagonal failing the angle test", at_least=50, **SURFACES)
def delaunay_edges_fail_lemma_7_11(ctx, level, n_inner, torus):
    counts = []
    for start, _, _ in _runs(level, n_inner, torus).values():
        q = _of(start)
        good = q["g_old"] >= -DELAUNAY_TOL
        counts.append(int(np.sum(good & ~((q["area"] <= 1e-9) & (q["g_new"] >= -DELAUNAY_TOL)))))
    return float(min(counts))


@check("Lemma 7.20, Example 7.3", "the harmonic index bounds the longest edge: h(T) ≥ l(T)² / A at every flip of every "
       "run (the four surfaces and the cube made with edges longer than 3; the reference prints l(T)/A, but its proof "
       "uses l(T) ≤ √(h(T) A))", quantity="max over the runs and their states of l(T)² / (A h(T)) (l(T) bounded by "
       "the running maximum of the lengths; ∞ unless every run keeps the total area A to 1e-12)", at_most=1.0,
       quick=dict(SURFACES["quick"], steps=25), full=dict(SURFACES["full"], steps=40))
def harmonic_index_bounds_longest_edge(ctx, level, n_inner, torus, steps):
    V, F = dg.mesh.cube(triangulated=True)
    cube = _lengthen(T.from_mesh(V, F), steps, seed=3)
    if cube.lengths.max() <= 3.0:
        return float("inf")
    runs = [(start, rounds) for start, _, rounds in _runs(level, n_inner, torus).values()]
    worst = 0.0
    for start, rounds in runs + [(cube, _rounds(cube, seed=1))]:
        A = _total_area(start)
        if abs(_total_area(rounds["end"]) - A) > 1e-12 * A:
            return float("inf")
        worst = max(worst, float(np.max(rounds["longest"] ** 2 / (A * rounds["h"]))))
    return worst


@check("Fig 7.13, Prop 7.9", "figure: a flat disk with skinny triangles before and after flipping to Delaunay",
       quantity="number of non-Delaunay edges after flipping", at_most=0, quick=dict(n_inner=60),
       full=dict(n_inner=300))
def flip_figure(ctx, n_inner):
    V, F, _ = _planar_skinny(n_inner)
    result = dg.plot.intrinsic.before_after(V, F, ctx.figure("intrinsic_delaunay_flips.png"))
    return float(np.sum(~intrinsic.delaunay_edges(result.triangulation))) if result.n_flips else float("inf")


def _lengthen(tri, steps: int, seed: int):
    """`steps` flips ignoring the Delaunay criterion, each, among up to 40 flippable edges taken in
    a random order, of the one whose flip leaves the longest edge: triangulations with long edges
    (Example 7.3)."""
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        options = [intrinsic.flip(tri, e) for e in rng.permutation(tri.n_edges)[:40] if intrinsic.is_flippable(tri, e)]
        tri = max(options, key=lambda option: option.lengths.max())
    return tri


def _laplacian_after_bad_start(V, F, steps: int, seed: int) -> tuple[float, float, object]:
    """From a triangulation made bad by `_lengthen`, flip to Delaunay: `(max |L − L_B|, longest
    start edge, flip result)` with L_B the Laplace–Beltrami operator of (V, F); the error is ∞
    unless the start is not Delaunay and the flips reach a Delaunay triangulation with h(T)
    strictly decreasing."""
    bad = _lengthen(T.from_mesh(V, F), steps, seed)
    result = intrinsic.flip_to_delaunay(bad)
    L = intrinsic.cotan_laplacian(result.triangulation).toarray()
    error = float(np.max(np.abs(L - intrinsic.laplace_beltrami(V, F).toarray())))
    ok = not intrinsic.is_delaunay(bad) and intrinsic.is_delaunay(result) and np.all(np.diff(result.harmonic_index) < 0)
    return error if ok else float("inf"), float(bad.lengths.max()), result


@check("Example 7.2", "the tetrahedron from a bad triangulation: flips reach the Delaunay one (same Laplace–Beltrami operator)",
       quantity="max |L(flipped) − L(Delaunay)|", at_most=1e-12, quick=dict(steps=6))
def tetrahedron_from_bad_triangulation(ctx, steps):
    V, F = dg.mesh.tetrahedron()
    return _laplacian_after_bad_start(V, F, steps, seed=4)[0]


@check("Example 7.3, Lemma 7.20, Thm 7.5", "the cube triangulated with edges longer than 3 (its diameter is √3): the flip "
       "algorithm terminates at the unique Delaunay tessellation (six squares)",
       quantity="max |L(flipped) − L(Delaunay)|", at_most=1e-12, quick=dict(steps=25), full=dict(steps=40))
def cube_with_long_edges(ctx, steps):
    V, F = dg.mesh.cube(triangulated=True)
    error, longest, result = _laplacian_after_bad_start(V, F, steps, seed=3)
    cells = intrinsic.delaunay_tessellation(result.triangulation)
    squares = cells.n_cells == 6 and np.all(cells.cell_size == 2)
    return error if longest > 3.0 and squares else float("inf")


def _random_quadrilaterals(count: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.2, 2.0, (count, 4)), rng.uniform(0.2, np.pi - 0.2, count), rng.standard_normal((count, 4))


_energies = jax.jit(jax.vmap(dg.laplace.triangle_dirichlet_energy))


def _split_energy(P, u, triangles) -> np.ndarray:
    """(count,) Dirichlet energies of the interpolants affine on the two `triangles` of each quad."""
    t = np.array(triangles)
    P3 = np.concatenate([np.asarray(P), np.zeros(P.shape[:2] + (1,))], axis=2)
    per = [_energies(u[:, k], P3[:, k]) for k in t]
    return np.asarray(per[0]) + np.asarray(per[1])


def _split_energy_direct(P, u, triangles) -> np.ndarray:
    """`_split_energy` from first principles: Σ ½ |∇u|² A over the two triangles, ∇u solved from
    the affine interpolation of the values at the corners."""
    total = 0.0
    for t in map(list, triangles):
        X = np.concatenate([P[:, t], np.ones((len(P), 3, 1))], axis=2)
        gradient = np.linalg.solve(X, u[:, t, None])[:, :2, 0]
        e1, e2 = P[:, t[1]] - P[:, t[0]], P[:, t[2]] - P[:, t[0]]
        total = total + 0.25 * np.sum(gradient**2, axis=1) * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return total


@check("Lemma 7.14", "Rippa: E(u₁₃) − E(u₂₄) = ¼(u₀ − u₀*)²/sin θ · (r₁+r₃)(r₂+r₄)/(r₁r₂r₃r₄) · (r₁r₃ − r₂r₄)",
       quantity="max relative error of eq (7.2) against the two energies (by `triangle_dirichlet_energy` and by "
       "solving for the gradients)", at_most=1e-10, quick=dict(count=200), full=dict(count=5000))
def rippa_formula(ctx, count):
    r, theta, u = _random_quadrilaterals(count)
    P = np.stack([rippa.quadrilateral(r[k], theta[k]) for k in range(count)])
    formula = np.array([rippa.dirichlet_energy_difference(u[k], r[k], theta[k]) for k in range(count)])
    worst = 0.0
    for energy in (_split_energy, _split_energy_direct):
        difference = energy(P, u, [(0, 1, 2), (0, 2, 3)]) - energy(P, u, [(1, 2, 3), (1, 3, 0)])
        worst = max(worst, float(np.max(np.abs(formula - difference) / (1e-3 + np.abs(difference)))))
    return worst


def _diagonal_24_is_delaunay(r, theta) -> bool:
    """The angle criterion (Prop 7.9) for the diagonal (24) of Q(r, θ), by the flip algorithm's test."""
    P = np.column_stack([rippa.quadrilateral(r, theta), np.zeros(4)])
    tri = T.from_mesh(P, np.array([[1, 2, 3], [1, 3, 0]]))
    return bool(intrinsic.delaunay_edges(tri).all())


def _diagonal_24_angle_sum(r, theta) -> float:
    """α + β opposite the diagonal (24) of Q(r, θ): the angles at vertices 1 and 3, by arccos."""
    Q = rippa.quadrilateral(r, theta)
    angle = lambda p, q, x: np.arccos(np.dot(q - p, x - p) / np.linalg.norm(q - p) / np.linalg.norm(x - p))  # noqa: E731
    return float(angle(Q[0], Q[1], Q[3]) + angle(Q[2], Q[3], Q[1]))


@check("Lemma 7.15, Cor 7.16", "Q(r, θ) is circular iff r₁r₃ = r₂r₄, and the sign of r₁r₃ − r₂r₄ says which diagonal is Delaunay",
       quantity="max |r₁r₃ − r₂r₄| / r₁r₃ on circles + number of mismatches (`is_circular` on circles; the sign against "
       "the flip algorithm's test and against α + β ≤ π by arccos)", at_most=1e-10,
       quick=dict(count=100), full=dict(count=2000))
def circularity_criterion(ctx, count):
    rng = np.random.default_rng(1)
    worst, mismatches = 0.0, 0
    for _ in range(count):
        phi = np.sort(rng.uniform(0, 2 * np.pi, 4))  # four points on the unit circle: the chords (13), (24) meet at O
        P = np.stack([np.cos(phi), np.sin(phi)], 1)
        s = np.linalg.solve(np.column_stack([P[2] - P[0], P[1] - P[3]]), P[1] - P[0])[0]
        r = np.linalg.norm(P - (P[0] + s * (P[2] - P[0])), axis=1)
        worst = max(worst, abs(rippa.circularity(r)) / (r[0] * r[2]))
        mismatches += not rippa.is_circular(r, rtol=1e-9)
    r, theta, _ = _random_quadrilaterals(count, seed=2)
    for k in range(count):
        positive = rippa.circularity(r[k]) > 0
        mismatches += (positive != _diagonal_24_is_delaunay(r[k], theta[k])) + (
            positive != (_diagonal_24_angle_sum(r[k], theta[k]) <= np.pi))
    return worst + mismatches


def _dirichlet_energies(tri, f) -> np.ndarray:
    """(k,) E(f_T) = ½ fᵀ L_T f for the k columns of f."""
    return 0.5 * np.einsum("ik,ik->k", f, intrinsic.cotan_laplacian(tri) @ f)


@check("Thm 7.21", "the Delaunay triangulation minimises the Dirichlet energy of every f among triangulations: "
       "no single flip and no random walk of 3 flips from it lowers E(f_T)",
       quantity="min over flips, walks and 5 random f of (E(f_T) − E(f_Delaunay)) / E(f_Delaunay)", at_least=-1e-14,
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
    if len(flippable) <= 0.8 * tri.n_edges:  # not vacuous: most edges are flipped
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
       quantity="max |L_a − L_b| / max |L_a| (∞ unless the cube's two triangulations differ, its operators agree to "
       "1e-14 and its Delaunay tessellation is six squares)", at_most=1e-12, quick=dict(n_inner=100),
       full=dict(n_inner=1000))
def laplace_beltrami_independent_of_triangulation(ctx, n_inner):
    V, F = dg.mesh.cube()
    triangulations = [dg.mesh.triangulate(np.roll(F, k, axis=1)) for k in (0, 1)]
    cube = [intrinsic.laplace_beltrami(V, G) for G in triangulations]
    disk = [intrinsic.laplace_beltrami(*_two_triangulations(n_inner, k)) for k in (0, 1)]
    cells = intrinsic.delaunay_tessellation(intrinsic.from_mesh(V, triangulations[0]))
    differ = np.any(np.sort(triangulations[0], 1) != np.sort(triangulations[1], 1))
    if not differ or abs(cube[0] - cube[1]).max() > 1e-14 or cells.n_cells != 6 or np.any(cells.cell_size != 2):
        return float("inf")
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
    normal = np.linalg.svd(V[ring] - centre)[2][-1]
    pushed = V.copy()
    pushed[0] = V[0] - 2 * np.dot(V[0] - centre, normal) * normal
    L, L_pushed = intrinsic.laplace_beltrami(V, F), intrinsic.laplace_beltrami(pushed, F)
    coplanar = np.abs((V[ring] - centre) @ normal).max() < 1e-12  # the reflection is an isometry of the star
    moved = np.linalg.norm(pushed[0] - V[0]) > 0.1
    return float(abs(L - L_pushed).max() / abs(L).max()) if coplanar and moved else float("inf")


_fig_7_26 = functools.cache(figures.fig_7_26)
# the sizes of the Fig 7.26 checks: the tall domes of these seeds, `budget` iterations each
FIG_7_26 = dict(quick=dict(seeds=(0, 1, 2), budget=30), full=dict(seeds=(0, 1, 2, 3), budget=200))


@check("Fig 7.26", "negative control: the cotan iteration (Fig 6.5) from the skinny tall dome does not converge",
       quantity="min over the domes of the area-gradient residual when the budget ran out or an iterate degenerated",
       at_least=1e-6, **FIG_7_26)
def cotan_iteration_stuck(ctx, seeds, budget):
    cotans = [_fig_7_26(seed, budget)[3][2] for seed in seeds]
    return min(float(info["residual"]) if not info["converged"] else 0.0 for info in cotans)


@check("Def 7.9, Fig 7.23, 7.26", "from the same start Fig 7.23 (flips + Laplace–Beltrami) converges within 5 steps to a "
       "minimal surface in the narrow sense: Delaunay, Δf = 0, the boundary kept, the flat 32-gon",
       quantity="max over the domes of max |Δf| at free vertices + |A − A(32-gon)| / A", at_most=1e-9, **FIG_7_26)
def narrow_minimal_surface_converges(ctx, seeds, budget):
    worst = 0.0
    for seed in seeds:
        V, F, boundary, cotan, (W, F1, info) = _fig_7_26(seed, budget)
        tri = info["triangulation"]
        fixed = np.zeros(len(W), dtype=bool)
        fixed[boundary] = True
        residual = interior_residual(intrinsic.cotan_laplacian(tri), W, fixed)
        if seed == seeds[0]:
            figures.draw_fig_7_26(ctx.figure("fig_7_26.png"), V, F, cotan, (W, F1, info))
        polygon = 0.5 * 32 * np.sin(2 * np.pi / 32)
        ok = (info["converged"] and info["iterations"] <= 5 and intrinsic.is_delaunay(tri) and info["flips"].sum() > 0
              and np.array_equal(W[boundary], V[boundary]))
        worst = max(worst, residual + abs(info["area"][-1] - polygon) / polygon if ok else float("inf"))
    return worst


@check("Remark 7.10, Prop 6.8", "maximum principle: every free vertex of the narrow-sense minimal surface is the "
       "weighted mean of its Delaunay neighbours with weights ≥ 0",
       quantity="max over the domes of max |f(i) − Σ ν_ij f(j) / Σ ν_ij| (∞ unless every ν_ij ≥ −1e-12)", at_most=1e-9,
       **FIG_7_26)
def narrow_minimal_surface_maximum_principle(ctx, seeds, budget):
    worst = 0.0
    for seed in seeds:
        _, _, boundary, _, (W, _, info) = _fig_7_26(seed, budget)
        L = intrinsic.cotan_laplacian(info["triangulation"]).tocsr()
        D = L.diagonal()
        off = (L - sp.diags(D)).tocsr()
        if off.max() > 1e-12:  # a negative weight ν_ij = −L_ij
            return float("inf")
        free = np.setdiff1d(np.arange(len(W)), boundary)
        mean = -(off @ W)[free] / D[free][:, None]
        worst = max(worst, float(np.max(np.abs(W[free] - mean))))
    return worst
