"""Delaunay tessellations from the empty-circle side (Sec 7.1, 7.2: Thm 7.1, 7.2, 7.5, 7.7, Lemma 7.3).

The oracle of this module tests circles, not angles: the power of a point x with respect to the
circumcircle (centre o, radius R) of a planar triangle, |x − o|² − R², is negative exactly when x
lies strictly inside (Def 7.1, 7.4).  On an interior edge ab of a triangulated piecewise flat
surface the two triangles (a, b, c), (b, a, d) are unfolded into the plane from their edge lengths
(as `intrinsic.unfold` does, Lemma 5.8) and the dimensionless margin of d is

    m_d = −pow_abc(d) / (|da| |db|)  =  −sin(α + β) / sin α      (α at c, β at d),

positive iff d lies inside the circumcircle of (a, b, c); likewise m_c for c and (b, a, d).  Lemma
7.3 says m_d > 0 ⇔ α + β > π, m_d = 0 ⇔ α + β = π; the library's test is cot α + cot β ≥ 0
(Prop 7.9, `intrinsic.delaunay_edges`), which shares no code with the circle test.  Margins within
`TIE` of 0 count as "on the circle".
"""

from __future__ import annotations


import numpy as np
from scipy.spatial import ConvexHull, Delaunay

import ddgjax as dg
from ddgjax import intrinsic
from ddgjax.intrinsic import triangulation as T
from ddgjax.intrinsic.flips import quad
from ddgjax.intrinsic.geometry import apex
from ddgjax.mesh.lengths import normalised, triangle_area
from ddgjax.verify import check

from ._flip_surfaces import SURFACES, opposite_angle_sums, surfaces

TIE = 1e-9  # |margin| below this: on the circle (the library's tie band is 1e-12 in cot α + cot β)


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _power(A, B, C, X):
    """(…,) |X − o|² − R² for the circumcircle (o, R) of the planar triangles (A, B, C) (…, 2):
    with b = B − A, c = C − A, x = X − A the centre is o = (c_y|b|² − b_y|c|², b_x|c|² − c_x|b|²)
    / 2(b × c), and |x − o|² − |o|² = |x|² − 2 x·o (no cancellation of R²)."""
    b, c, x = B - A, C - A, X - A
    bb, cc = np.sum(b * b, -1), np.sum(c * c, -1)
    o = np.stack([c[..., 1] * bb - b[..., 1] * cc, b[..., 0] * cc - c[..., 0] * bb], -1) / (2 * _cross(b, c))[..., None]
    return np.sum(x * x, -1) - 2 * np.sum(x * o, -1)


def _circumradius2(A, B, C):
    """(…,) R² = |ab|² |bc|² |ca|² / (2 |ab × ac|)²."""
    ab, bc, ca = (np.sum((u - v) ** 2, -1) for u, v in ((A, B), (B, C), (C, A)))
    return ab * bc * ca / (2 * _cross(B - A, C - A)) ** 2


def unfolded_margins(tri) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(e, m_d, m_c)`: the interior edges between two distinct triangles and the margins (module
    docstring) of their far vertices d, c in the quadrilateral a d b c unfolded from the five
    lengths as in `intrinsic.unfold` (a = 0, b = (l_ab, 0), c above, d below; vectorised)."""
    h = tri.halfedges
    e = np.flatnonzero((h[:, 1] >= 0) & (h[:, 0] // 3 != h[:, 1] // 3))
    ab, bc, ca, ad, db = normalised(np.stack(quad(tri.F.reshape(-1), tri.edge, h, tri.lengths, e)[2]))[0]
    a, b = np.zeros((len(e), 2)), np.column_stack([ab, np.zeros(len(e))])
    c = np.column_stack(apex(ab, ca, bc, triangle_area(ab, bc, ca), +1.0))
    d = np.column_stack(apex(ab, ad, db, triangle_area(ab, ad, db), -1.0))
    return e, -_power(a, b, c, d) / (ad * db), -_power(b, a, d, c) / (ca * bc)


def _side(m) -> np.ndarray:
    """+1 inside, 0 on, −1 outside the circle, for margins m."""
    return np.where(m > TIE, 1, np.where(m < -TIE, -1, 0))


def _disagreements(tri) -> tuple[int, int]:
    """`(disagreements, inside)`: the number of interior edges where the empty-circle oracle and the
    library's angle criterion disagree (d inside but the edge passes `delaunay_edges`, d outside but
    it fails, d on the circle but |α + β − π| > 1e-8, or c and d on different sides), and the
    number of edges whose far vertex lies strictly inside."""
    e, m_d, m_c = unfolded_margins(tri)
    side = _side(m_d)
    fails = ~intrinsic.delaunay_edges(tri)[e]
    off_pi = np.abs(opposite_angle_sums(tri)[e] - np.pi) > 1e-8
    wrong = ((side == 1) & ~fails) | ((side == -1) & fails) | ((side == 0) & off_pi) | (side != _side(m_c))
    return int(wrong.sum()), int(np.sum(side == 1))


@check("Def 7.4, Lemma 7.3, Lemma 7.8, Thm 7.7", "on unfolded edges, the empty-circumdisk test agrees edge by edge with "
       "the angle criterion α + β ≤ π: on the start triangulations (stretched icosphere with and without bumps, skinny "
       "torus, skinny flat disk) and on their Delaunay triangulations by flips, where every circumdisk is empty",
       quantity="number of interior edges where the far vertex's side of the unfolded circumcircle (inside / on / "
       "outside, margin 1e-9) and `delaunay_edges` (or α + β = π to 1e-8) disagree, or c and d disagree (∞ unless every "
       "start has an edge failing both tests)", at_most=0, **SURFACES)
def empty_circumdisk_matches_angle_criterion(ctx, level, n_inner, torus):
    total = 0
    for start, flipped in surfaces(level, n_inner, torus).values():
        (wrong_start, inside_start), (wrong_flipped, _) = _disagreements(start), _disagreements(flipped)
        if inside_start == 0:
            return float("inf")
        total += wrong_start + wrong_flipped
    return float(total)


@check("Def 7.4, Thm 7.7", "negative control: each start triangulation has edges whose unfolded far vertex lies "
       "strictly inside the other triangle's circumcircle", quantity="min over the four start surfaces of the number of "
       "such edges", at_least=5, **SURFACES)
def start_circumdisks_not_empty(ctx, level, n_inner, torus):
    return float(min(_disagreements(start)[1] for start, _ in surfaces(level, n_inner, torus).values()))


def _triples(F) -> set:
    return set(map(tuple, np.sort(np.asarray(F), axis=1).tolist()))


def _insertion_triangulation(P, rng) -> np.ndarray:
    """A bad triangulation of planar points in general position, counter-clockwise: the fan of the
    convex hull from a random hull vertex, then the other points in random order, each splitting
    the triangle that contains it into three."""
    hull = ConvexHull(P).vertices
    hull = np.roll(hull, -int(rng.integers(len(hull))))
    F = np.stack([np.full(len(hull) - 2, hull[0]), hull[1:-1], hull[2:]], 1)
    for p in rng.permutation(np.setdiff1d(np.arange(len(P)), hull)):
        A, B, C = (P[F[:, k]] for k in range(3))
        f = np.flatnonzero((_cross(B - A, P[p] - A) > 0) & (_cross(C - B, P[p] - B) > 0) & (_cross(A - C, P[p] - C) > 0))[0]
        a, b, c = F[f]
        F = np.vstack([np.delete(F, f, 0), [[p, a, b], [p, b, c], [p, c, a]]])
    return F


def _flat(P, F):
    """The flip algorithm's result on the flat triangulation F of the planar points P."""
    return intrinsic.flip_to_delaunay(T.from_mesh(np.column_stack([P, np.zeros(len(P))]), F))


def _points_inside(P, F, tol: float = TIE) -> int:
    """The number of pairs (face, point) with the point strictly inside the face's circumcircle:
    pow < −tol · R² (Def 7.1, the global empty-disk property)."""
    A, B, C = (P[F[:, k]][:, None] for k in range(3))
    power = _power(A, B, C, P[None]) / _circumradius2(A, B, C)
    return int(np.sum(power < -tol))


@check("Thm 7.1, Def 7.1, Prop 7.4, Thm 7.7", "random points in the plane: flipping a bad triangulation (hull fan + "
       "point insertion) by the angle criterion gives the Delaunay triangulation of the points, whose circumdisks are "
       "empty of all points", quantity="number of faces in the symmetric difference with `scipy.spatial.Delaunay` + "
       "number of (face, point) with the point strictly inside the circumcircle (∞ unless the start is not Delaunay)",
       at_most=0, quick=dict(n=60, sets=3), full=dict(n=400, sets=10))
def flips_give_planar_delaunay(ctx, n, sets):
    total = 0
    for seed in range(sets):
        rng = np.random.default_rng(seed)
        P = rng.uniform(-1, 1, (n, 2))
        start = _insertion_triangulation(P, rng)
        delaunay = _triples(Delaunay(P).simplices)
        result = _flat(P, start)
        if _triples(start) == delaunay or _points_inside(P, start) == 0 or not result.n_flips:
            return float("inf")
        total += len(_triples(result.F) ^ delaunay) + _points_inside(P, result.F)
    return float(total)


def _stereographic(P) -> np.ndarray:
    """σ(x, y) = (2x, 2y, |z|² − 1) / (|z|² + 1): the plane onto S² from the north pole N = (0, 0, 1)."""
    r2 = np.sum(P * P, 1)[:, None]
    return np.column_stack([2 * P, r2 - 1]) / (r2 + 1)


@check("Remark 7.2, Thm 7.2", "the Delaunay triangulation of planar points is the stereographic image of the faces of "
       "the convex hull of their projections on S² not visible from the north pole (their planes cut empty caps, the "
       "images of empty disks)", quantity="number of faces in the symmetric difference with `scipy.spatial.Delaunay` "
       "(∞ unless some hull faces are visible from N)", at_most=0, quick=dict(n=60, sets=3), full=dict(n=1000, sets=10))
def delaunay_is_stereographic_hull(ctx, n, sets):
    total = 0
    for seed in range(sets):
        P = np.random.default_rng(seed).uniform(-1, 1, (n, 2))
        hull = ConvexHull(_stereographic(P))
        visible = hull.equations[:, 2] + hull.equations[:, 3] > 0  # n · N + offset > 0
        if not visible.any():
            return float("inf")
        total += len(_triples(hull.simplices[~visible]) ^ _triples(Delaunay(P).simplices))
    return float(total)


def _empty_disk_triangles(P, pole=None) -> tuple[set, set]:
    """`(kept, dropped)`: the Delaunay triangles of P whose circumdisk does not / does contain the
    point `pole` (all kept for None)."""
    F = Delaunay(P).simplices
    if pole is None:
        return _triples(F), set()
    A, B, C = (P[F[:, k]] for k in range(3))
    contains = _power(A, B, C, np.broadcast_to(pole, A.shape)) < 0
    return _triples(F[~contains]), _triples(F[contains])


def _image_defect(P, Q, pole=None, image_of_infinity=None) -> tuple[int, int]:
    """`(defect, dropped)` for planar points P and their images Q under a map f with f(pole) = ∞:
    the triangles of D(P) whose circumdisk misses the pole against those of D(Q) whose circumdisk
    misses f(∞), symmetric difference, plus the dropped triangles of either that are Delaunay for
    the other (a disk containing the pole maps to the outside of a circle: not empty)."""
    kept_P, dropped_P = _empty_disk_triangles(P, pole)
    kept_Q, dropped_Q = _empty_disk_triangles(Q, image_of_infinity)
    all_P, all_Q = kept_P | dropped_P, kept_Q | dropped_Q
    return len(kept_P ^ kept_Q) + len(dropped_P & all_Q) + len(dropped_Q & all_P), len(dropped_P)


def _random_points(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r, t = np.sqrt(rng.uniform(0, 1, n)), rng.uniform(0, 2 * np.pi, n)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def _complex(P):
    return P[:, 0] + 1j * P[:, 1]


def _plane(z) -> np.ndarray:
    return np.column_stack([z.real, z.imag])


def _mobius(n: int, seed: int):
    """`(P, f(P), p, f(∞))`: random points in the unit disk and a random f(z) = (a z + b)/(z − p)
    with its pole p on the circle of radius 1.1 (near the points: inside some circumdisks)."""
    rng = np.random.default_rng(100 + seed)
    P = _random_points(n, seed)
    p = 1.1 * np.exp(2j * np.pi * rng.uniform())
    a, b = rng.standard_normal(2) + 1j * rng.standard_normal(2)
    return P, _plane((a * _complex(P) + b) / (_complex(P) - p)), _plane(np.array([p]))[0], _plane(np.array([a]))[0]


MAPS = dict(quick=dict(n=60, maps=4), full=dict(n=1000, maps=20))


@check("Thm 7.2", "Möbius invariance of the empty disk property: for f(z) = (a z + b)/(z − p), the Delaunay triangles "
       "of P whose circumdisk misses the pole p are exactly those of f(P) whose circumdisk misses f(∞) = a, and the "
       "others are not Delaunay for the image", quantity="sum over random f (pole near the points) of the size of the "
       "symmetric difference + the dropped triangles Delaunay on the other side (∞ unless some circumdisk contains the "
       "pole)", at_most=0, **MAPS)
def mobius_preserves_empty_disks(ctx, n, maps):
    total, dropped = 0, 0
    for seed in range(maps):
        defect, k = _image_defect(*_mobius(n, seed))
        total, dropped = total + defect, dropped + k
    return float(total) if dropped else float("inf")


@check("Thm 7.2", "negative control: without the exclusion of the circumdisks through the pole, f does not map the "
       "Delaunay triangulation of P to that of f(P) (a disk containing the pole maps to the outside of a circle)",
       quantity="min over the random f of the size of the symmetric difference of D(P) and D(f(P))", at_least=2, **MAPS)
def mobius_pole_matters(ctx, n, maps):
    return float(min(_image_defect(*_mobius(n, seed)[:2])[0] for seed in range(maps)))


@check("Thm 7.2", "negative control: the conformal but not Möbius map z ↦ exp(1.5 z) changes the Delaunay triangulation "
       "(angles are kept infinitesimally, circles are not)", quantity="min over the point sets of the size of the "
       "symmetric difference of D(P) and D(exp(1.5 P))", at_least=2, **MAPS)
def conformal_map_changes_delaunay(ctx, n, maps):
    return float(min(_image_defect(P, _plane(np.exp(1.5 * _complex(P))))[0]
                     for P in (_random_points(n, seed) for seed in range(maps))))


def _counter_clockwise(P, F) -> np.ndarray:
    F = np.array(F)
    clockwise = _cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]) < 0
    F[clockwise] = F[clockwise][:, ::-1]
    return F


def _cells(tri) -> tuple[set, np.ndarray]:
    """`(cells, deleted)`: the vertex sets of the cells of the Delaunay tessellation
    (`intrinsic.delaunay_tessellation`, Remark 7.4) and the interior edges it deletes."""
    tess = intrinsic.delaunay_tessellation(tri)
    cells = [set() for _ in range(tess.n_cells)]
    for f, c in enumerate(tess.cell):
        cells[c].update(tri.F[f].tolist())
    return {frozenset(c) for c in cells}, np.flatnonzero(~tess.edge_mask)


def _planar_disk_defect(P, cells) -> float:
    """Def 7.3 by circles: max over cells of |pow(v)| / R² of its vertices for the circle through
    three of them, + the number of other points not strictly outside (pow / R² ≤ 1e-9)."""
    worst, violations = 0.0, 0
    for cell in cells:
        idx = np.array(sorted(cell))
        A, B, C = P[idx[:3]]
        power = _power(A, B, C, P) / _circumradius2(A, B, C)
        others = np.setdiff1d(np.arange(len(P)), idx)
        worst, violations = max(worst, float(np.max(np.abs(power[idx])))), violations + int(np.sum(power[others] <= TIE))
    return worst + violations


def _surface_disk_defect(tri, deleted) -> float:
    """Def 7.3, 7.4 on unfolded edges: the deleted edges have their far vertices on the circle
    (|m| ≤ 1e-9: max |m|), the kept ones strictly outside (the number of those that are not)."""
    e, m_d, _ = unfolded_margins(tri)
    on = np.isin(e, deleted)
    return float(np.max(np.abs(m_d[on]), initial=0.0)) + int(np.sum(m_d[~on] >= -TIE))


def _scrambled(tri, flips: int, seed: int):
    """`flips` random flips regardless of the Delaunay criterion: a bad start with the same metric."""
    rng = np.random.default_rng(seed)
    for e in rng.integers(tri.n_edges, size=flips):
        tri = intrinsic.flip(tri, int(e)) if intrinsic.is_flippable(tri, int(e)) else tri
    return tri


def _cocircular_cases(k: int, outer: int):
    """name → (the expected non-triangular cells, points P (None on the torus), two start triangulations):
    a k × (k − 1) grid of 1 × 0.6 rectangles (starts: Delaunay of the points sheared by ±2 in x); a
    regular octagon and `outer` random points in the annulus 1.6 < r < 2.5 (starts: fan + insertion);
    the torus of revolution with 2k × k vertices, whose grid quads are isosceles trapezoids (starts:
    4k² random flips)."""
    x, y = np.meshgrid(np.arange(k), 0.6 * np.arange(k - 1), indexing="ij")
    grid = np.column_stack([x.ravel(), y.ravel()])
    rectangles = {frozenset(q) for q in dg.mesh.builtin.grid_quads(k, k - 1, False, False).tolist()}
    sheared = [_counter_clockwise(grid, Delaunay(grid @ [[1, 0], [s, 1]]).simplices) for s in (2.0, -2.0)]
    rng = np.random.default_rng(0)
    t, r, a = np.arange(8) * np.pi / 4, rng.uniform(1.6, 2.5, outer), rng.uniform(0, 2 * np.pi, outer)
    octagon = np.vstack([np.column_stack([np.cos(t), np.sin(t)]), np.column_stack([r * np.cos(a), r * np.sin(a)])])
    inserted = [_insertion_triangulation(octagon, np.random.default_rng(seed)) for seed in (1, 2)]
    V, F = dg.mesh.torus(2 * k, k, 1.0, 0.4)
    torus = T.from_mesh(V, F)
    quads = {frozenset(q) for q in dg.mesh.builtin.grid_quads(2 * k, k, True, True).tolist()}
    return {"grid": (rectangles, grid, [_flat(grid, F).triangulation for F in sheared]),
            "octagon": ({frozenset(range(8))}, octagon, [_flat(octagon, F).triangulation for F in inserted]),
            "torus": (quads, None, [intrinsic.flip_to_delaunay(_scrambled(torus, 4 * k * k, s)).triangulation
                                    for s in (1, 2)])}


@check("Thm 7.5, Thm 7.1, Def 7.3, Remark 7.4", "points with cocircular subsets (a rectangular grid, a regular octagon "
       "among random points, the torus of revolution with its trapezoids): flips from two different starts give two "
       "different Delaunay triangulations but one Delaunay tessellation, whose cells are the cocircular polygons with "
       "empty circumdisks; inside a cell α + β = π",
       quantity="max |α + β − π| over the deleted edges + max deviation from cocircularity (pow / R², or the unfolded "
       "margin) + the number of mismatched cells (between the two triangulations and against the expected polygons) "
       "and of points not strictly outside a cell's circle (∞ unless in every case the two triangulations differ); the "
       "lengths of flipped edges carry the round-off of the unfoldings that made them (observed 1e-13 quick, 2e-12 full)",
       at_most=1e-10, quick=dict(k=4, outer=16), full=dict(k=12, outer=200))
def cocircular_cells_are_unique(ctx, k, outer):
    total = 0.0
    for expected, P, tris in _cocircular_cases(k, outer).values():
        (cells, deleted), (other, _) = _cells(tris[0]), _cells(tris[1])
        if _triples(tris[0].F) == _triples(tris[1].F):
            return float("inf")
        mismatch = len(cells ^ other) + len({c for c in cells if len(c) > 3} ^ expected)
        disk = _surface_disk_defect(tris[0], deleted) if P is None else _planar_disk_defect(P, cells)
        total += mismatch + disk + float(np.max(np.abs(opposite_angle_sums(tris[0])[deleted] - np.pi)))
    return total
