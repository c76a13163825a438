"""Intrinsic Delaunay triangulations by edge flips (Sec 7.2, 7.3).

- The angle criterion (Prop 7.9): an interior edge is Delaunay iff the two angles opposite to it
  sum to at most π, i.e. iff cot α + cot β ≥ 0 (eq 6.3: ν = ½ sin(α + β) / (sin α sin β)).
- The harmonic index h(T) = Σ_Δ (a² + b² + c²) / A(Δ) (Def 7.7) = 8 Σ_i E(φ_i) (Lemma 7.18);
  it strictly decreases at every flip of a non-Delaunay edge (Cor 7.16, 7.19) and is proper
  (Lemma 7.20), so the flip algorithm terminates (Thm 7.12), also on triangulations with
  arbitrarily long edges (Example 7.3).
- The edge-flip algorithm (Fig 7.13) driven by a queue of edges to test, vectorised with numpy
  over batches of `CHUNK` queued edges: test every edge of the batch, choose among the
  non-Delaunay ones an independent set (no two share a triangle: the edge of smallest fixed
  pseudo-random priority, a hash of its index, in each of its triangles), flip them all at once
  (`flips.flip_batch`, equal to flipping them one after another), and queue the not-chosen ones
  and those of the four outer edges of every flipped quadrilateral that fail the test after the
  batch (an edge whose triangles change again later is tested again by that later flip, so the
  queue always holds every edge that may be non-Delaunay).  Every flip is one step of Fig 7.13,
  recorded in the history.  The test keys cot + tol · s of all corners and the areas of all
  faces are cached and updated at each flip, so a test is four array lookups.  The keys of
  the start and the cotan weights of the result are the derived ones (`triangulation.
  halfedge_cotangents`: the autodiff Hessian of the Dirichlet energy); the keys of the triangles
  a flip creates come from the law of cosines (`ddgjax.mesh.lengths.corner_cotangents`), one
  vectorised expression per round.  The flip loop itself is not jitted: numpy's vectorised
  gathers and scatters, where scattered writes and boolean compressions are the cost, so a flip writes as
  few entries as it can (`flips.flip_batch`).

Surfaces with boundary (which the reference does not treat) keep their boundary edges; only
interior edges are tested and flipped, as in libigl's `intrinsic_delaunay_triangulation`.

Ties: an edge counts as non-Delaunay only if cot α + cot β < −tol · s with s = (h(Δ₁) + h(Δ₂))/4
the cotangent sums of its two triangles (Lemma 7.17; the rounding error of a cotangent computed
from lengths is about eps · s), so that the two diagonals of a (numerically) cocircular
quadrilateral are not flipped back and forth; the flipped edge of a genuinely non-Delaunay edge
is Delaunay (Lemma 7.11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import FlipBudgetError, InvalidInputError
from ..mesh.lengths import corner_cotangents, face_harmonic_index, side_cotangents, triangle_area
from .flips import flip_batch, others
from .geometry import flipped_length
from .triangulation import (
    Triangulation,
    cotan_weights,
    halfedge_cotangents,
    from_faces,
    of_arrays,
    side_lengths,
)

__all__ = [
    "DELAUNAY_TOL",
    "FlipResult",
    "as_triangulation",
    "delaunay_edges",
    "edge_cotangent_sums",
    "flip_owned",
    "flip_to_delaunay",
    "harmonic_index",
    "is_delaunay",
]

DELAUNAY_TOL = 1e-12
CHUNK = 1 << 15  # queue entries per vectorised batch: small enough that temporaries stay in cache


def as_triangulation(F, lengths=None) -> Triangulation:
    """`F` itself if it is a `Triangulation` (or the triangulation of a `FlipResult`), else
    `triangulation.from_faces(F, lengths)`.
    """
    if isinstance(F, FlipResult):
        return F.triangulation
    if isinstance(F, Triangulation):
        return F
    if lengths is None:
        raise InvalidInputError("give edge lengths (ordered like ddgjax.mesh.edges(F)) with faces F")
    return from_faces(F, lengths)


def _interior(tri: Triangulation) -> np.ndarray:
    """Edges with two distinct triangles (the only ones that can be non-Delaunay)."""
    h = tri.halfedges
    return np.flatnonzero((h[:, 1] >= 0) & (h[:, 0] // 3 != h[:, 1] // 3))


def _face_geometry(tri: Triangulation):
    """(cot, area, s): per halfedge the cot of the angle opposite it (3 nf,), derived from the
    Dirichlet energy (`triangulation.halfedge_cotangents`); per face its area and
    s = cot α + cot β + cot γ = (a² + b² + c²)/4A = h(Δ)/4 (nf,) (Lemma 7.17)."""
    L = side_lengths(tri)
    cots, area = side_cotangents(L * L)
    return cots.reshape(-1), np.array(area), cots.sum(axis=1)  # the area is updated by the flips


def edge_cotangent_sums(tri: Triangulation) -> np.ndarray:
    """(ne,) cot α + cot β of the angles opposite each edge (one cot on the boundary): the angle
    criterion of Prop 7.9 (law of cosines); the cotan weights are `cotan_weights`."""
    return np.bincount(tri.edge, _face_geometry(tri)[0], minlength=tri.n_edges)


def _non_delaunay(tri: Triangulation, tol: float) -> np.ndarray:
    """(ne,) bool: the interior edges between two distinct triangles that fail the angle test
    (one vectorised pass over the faces)."""
    cots, _, scales = _face_geometry(tri)
    scale = np.bincount(tri.edge, np.repeat(scales, 3), minlength=tri.n_edges)
    bad = np.bincount(tri.edge, cots, minlength=tri.n_edges) < -tol * scale
    out = np.zeros(tri.n_edges, dtype=bool)
    e = _interior(tri)
    out[e] = bad[e]
    return out


def delaunay_edges(tri: Triangulation, tol: float = DELAUNAY_TOL) -> np.ndarray:
    """(ne,) bool: the angle criterion of Prop 7.9 for each edge (boundary edges count as
    Delaunay; an edge lying twice on one triangle always is)."""
    return ~_non_delaunay(tri, tol)


def is_delaunay(F, lengths=None, *, tol: float = DELAUNAY_TOL) -> bool:
    """True iff every edge satisfies the angle criterion (Prop 7.9, Thm 7.7).  `F` is a
    `Triangulation`, a `FlipResult` or faces (nf, 3) with `lengths` ordered like
    `ddgjax.mesh.edges(F)`."""
    return bool(delaunay_edges(as_triangulation(F, lengths), tol).all())


def harmonic_index(F, lengths=None) -> float:
    """h(T) = Σ_Δ (a² + b² + c²) / A(Δ) (Def 7.7)."""
    L = side_lengths(as_triangulation(F, lengths))
    a, b, c = L.T
    return float(np.sum(face_harmonic_index(a, b, c, triangle_area(a, b, c))))


@dataclass(frozen=True, eq=False)
class FlipResult:
    """Outcome of `flip_to_delaunay`.

    **Fields:** `triangulation` (the Delaunay triangulation; faces, gluing and lengths);
    `n_flips`; `n_rounds` (vectorised rounds of independent flips); `harmonic_index`
    ((n_flips + 1,) h(T) before the first and after every flip, or just the first and last value
    when the history was not recorded); `harmonic_index_steps` ((n_flips,) the change of h at each
    flip, all < 0 by Cor 7.19; empty when not recorded); `halfedge_cotangents` ((3 nf,) the cot
    of the angle opposite each halfedge of the result, derived from the Dirichlet energy).
    """

    triangulation: Triangulation
    n_flips: int
    n_rounds: int
    harmonic_index: np.ndarray
    harmonic_index_steps: np.ndarray
    halfedge_cotangents: np.ndarray | None = None

    def cotan_weights(self) -> np.ndarray:
        """(ne,) ν(e) = ½ (cot α + cot β) of the Delaunay triangulation (eq 6.2), derived from
        the Dirichlet energy (`triangulation.cotan_weights`)."""
        return cotan_weights(self.triangulation, self.halfedge_cotangents)

    @property
    def F(self) -> np.ndarray:
        """(nf, 3) the vertices of the new triangles (a face may repeat a vertex)."""
        return self.triangulation.F

    @property
    def lengths(self) -> np.ndarray:
        """(ne,) the new edge lengths; edge e keeps its index through flips."""
        return self.triangulation.lengths

    @property
    def edges(self) -> np.ndarray:
        """(ne, 2) the endpoints of each edge (loops and repeated pairs possible)."""
        return self.triangulation.edges


@dataclass(eq=False)
class _Work:
    """Mutable working copy for the flip loop: the flat gluing arrays; per halfedge the test key
    cot + tol · s(face) of the opposite angle (one more entry, +inf, read by the boundary's
    halfedge -1, so that boundary edges always pass), per face its area (kept up to date at each
    flip, so that the test of an edge, key(h) + key(t) < 0, is four lookups).  The derived
    cotangents of the result are computed once at the end."""

    F: np.ndarray
    edge: np.ndarray
    halfedges: np.ndarray
    lengths: np.ndarray
    key: np.ndarray
    area: np.ndarray
    scratch: np.ndarray
    tol: float

    @classmethod
    def of(cls, tri: Triangulation, tol: float, geometry, copy: bool = True) -> _Work:
        """The working copy (`copy=False`: work in the arrays of `tri`, which the caller owns)."""
        cots, A, scales = geometry
        key = np.empty(cots.size + 1)
        np.add(cots.reshape(-1, 3), tol * scales[:, None], out=key[:-1].reshape(-1, 3))
        key[-1] = np.inf
        arrays = (tri.F.reshape(-1), tri.edge, tri.halfedges, tri.lengths)
        if copy:
            arrays = tuple(a.copy() for a in arrays)
        return cls(*arrays, key, A, np.full(tri.n_edges, _NONE, dtype=np.int64), tol)

    def arrays(self):
        return self.F, self.edge, self.halfedges, self.lengths


def _failing(w: _Work, e):
    """bool mask over the edges `e`: the angle test fails (Prop 7.9 with the tie tolerance:
    cot α + tol s₁ + cot β + tol s₂ < 0), read from the cached keys."""
    return w.key[w.halfedges[:, 0][e]] + w.key[w.halfedges[:, 1][e]] < 0


_NONE = np.iinfo(np.int64).max


def _priority(e):
    """A fixed pseudo-random priority, distinct for distinct edges: Knuth's multiplicative hash,
    a bijection of the 32-bit integers."""
    return (e * 2654435761) & 0xFFFFFFFF


def _independent(bad, sides, scratch) -> np.ndarray:
    """bool mask over `bad` (distinct edges): the edges of least priority among the non-Delaunay
    edges of both of their triangles (`sides`: the four other edges of those triangles)."""
    own = _priority(bad)
    scratch[bad] = own
    best = own
    for side in sides:
        best = np.minimum(best, scratch[side])
    scratch[bad] = _NONE
    return own == best


def _unique(e: np.ndarray, scratch_marks: np.ndarray) -> np.ndarray:
    """The distinct entries of e, in O(len e) with a scratch array (the last occurrence wins)."""
    position = np.arange(e.size)
    scratch_marks[e] = position
    return e[scratch_marks[e] == position]


def _sums_of_squares(x, y, z, area):
    """s = (x² + y² + z²) / 4A = h(Δ)/4 (Def 7.7, Lemma 7.17) and the squares."""
    x2, y2, z2 = x * x, y * y, z * z
    return (x2 + y2 + z2) / (4.0 * area), (x2, y2, z2)


def _new_face_keys(w: _Work, slots, face, x, y, z):
    """Store the area of the new faces with sides x, y, z on `slots` (in order) and the keys
    cot + tol · s of the angles opposite them (cot opposite x = (y² + z² − x²)/4A); returns s
    and the three keys."""
    B = triangle_area(x, y, z)
    w.area[face] = B
    s, (x2, y2, z2) = _sums_of_squares(x, y, z, B)
    shift = w.tol * s
    keys = []
    for slot, cot in zip(slots, corner_cotangents(x2, y2, z2, B)):
        w.key[slot] = k = cot + shift
        keys.append(k)
    return s, keys


def _flip_round(w: _Work, queue, record):
    """Test the distinct edges `queue`, flip an independent set of the non-Delaunay ones (no
    two share a triangle; the other non-Delaunay ones wait for the next round).  Returns (number
    of flips, harmonic-index steps or None, edges to test next: the non-Delaunay ones not
    flipped and the sides of the flipped quadrilaterals that fail the test after the whole
    batch; a side whose triangles change again later is tested again by that flip).  Boundary
    edges pass the test (key +inf), and so does an edge lying twice on one triangle (its two
    opposite angles are equal and acute); the `f != g` guard only protects against rounding
    (such an edge is dropped, never flipped, so that a round cannot stall)."""
    e = queue[_failing(w, queue)]
    if e.size == 0:
        return 0, None, e
    F, edge, halfedges, lengths = w.arrays()
    h, t = halfedges[:, 0][e], halfedges[:, 1][e]
    f, g = h // 3, t // 3
    h1, h2 = others(h, f)
    t1, t2 = others(t, g)
    sides = (edge[h1], edge[h2], edge[t1], edge[t2])
    distinct = f != g
    chosen = _independent(e, sides, w.scratch) & distinct
    rest = e[~chosen & distinct]  # (an edge twice on one triangle is never flipped: not kept)
    if not chosen.all():
        e, h, t = e[chosen], h[chosen], t[chosen]
        sides = tuple(x[chosen] for x in sides)
        f, g = h // 3, t // 3
        h1, h2 = others(h, f)
        t1, t2 = others(t, g)
    l_ab = lengths[e]
    l_bc, l_ca, l_ad, l_db = (lengths[x] for x in sides)
    A1, A2 = w.area[f], w.area[g]
    new = flipped_length(l_ab, l_bc, l_ca, l_ad, l_db, A1, A2)
    flip_batch(F, edge, halfedges, lengths, e, ((h, h1, h2, t, t1, t2), sides), new)
    # (a, d, c) on h, h1, h2 with sides ad, dc, ca and (b, c, d) on t, t1, t2 with bc, cd, db
    s_f, (k_ad, _, k_ca) = _new_face_keys(w, (h, h1, h2), f, l_ad, new, l_ca)
    s_g, (k_bc, _, k_db) = _new_face_keys(w, (t, t1, t2), g, l_bc, new, l_db)
    steps = None
    if record:
        before = _sums_of_squares(l_ab, l_bc, l_ca, A1)[0] + _sums_of_squares(l_ab, l_ad, l_db, A2)[0]
        steps = 4.0 * (s_f + s_g - before)
    # the sides that now fail: own key (just computed) + key of the other halfedge (the other
    # column of halfedges[side]; -1 on the boundary, whose key is +inf)
    H0, H1 = halfedges[:, 0], halfedges[:, 1]
    pushed = [rest]
    for x, slot, k in zip(sides, (t, h2, h, t2), (k_bc, k_ca, k_ad, k_db)):
        pushed.append(x[k + w.key[H0[x] + H1[x] - slot] < 0])
    return e.size, steps, np.concatenate(pushed)


def flip_to_delaunay(F, lengths=None, *, tol: float = DELAUNAY_TOL, max_flips: int | None = None,
                     record_history: bool = True) -> FlipResult:
    """Make a geodesic triangulation Delaunay by edge flips (Fig 7.13, Thm 7.12).

    **Arguments:** `F` and `lengths` as for `is_delaunay` (the input is not modified); `tol` the
    tie tolerance of the angle test (module docstring); `max_flips` the flip budget (default
    50 · nf + 1000); `record_history` records the harmonic index after every flip.

    **Returns:** a `FlipResult`.

    **Raises:** the errors of `triangulation.from_faces`; `FlipBudgetError` when the budget is
    used up (naming an edge that is still not Delaunay).
    """
    return flip_owned(as_triangulation(F, lengths), tol, max_flips, record_history, copy=True)


def flip_owned(tri: Triangulation, tol: float = DELAUNAY_TOL, max_flips: int | None = None,
               record_history: bool = False, copy: bool = False) -> FlipResult:
    """`flip_to_delaunay` of a triangulation whose arrays the caller owns: with `copy=False` they
    are flipped in place (and `tri` must not be used afterwards)."""
    budget = 50 * tri.n_faces + 1000 if max_flips is None else int(max_flips)
    geometry = _face_geometry(tri)
    w = _Work.of(tri, tol, geometry, copy)
    marks = np.zeros(tri.n_edges, dtype=np.int64)
    queue = np.flatnonzero(_failing(w, slice(None)))  # boundary edges pass (key +inf)
    h0 = 4.0 * float(geometry[2].sum())
    steps, n_flips, n_rounds = [], 0, 0
    while queue.size:
        parts, before = [], n_flips
        for start in range(0, queue.size, CHUNK):
            flipped, step, more = _flip_round(w, queue[start:start + CHUNK], record_history)
            n_flips += flipped
            parts.append(more)
            if step is not None:
                steps.append(step)
            if n_flips > budget:
                raise FlipBudgetError(
                    f"flip budget of {budget} flips used up after {n_rounds} rounds; edge "
                    f"{more[0] if more.size else queue[start]} is still not Delaunay (raise max_flips, or "
                    "check the lengths for near-degenerate triangles)"
                )
        queue = _unique(np.concatenate(parts), marks)
        n_rounds += n_flips > before
    out, cots = tri, geometry[0]
    if n_flips:  # the derived cotangents of the new triangles (the keys hold the law of cosines)
        out = of_arrays(w.F, w.edge, w.halfedges, w.lengths, tri.n_vertices)
        cots = halfedge_cotangents(out)
    scales = cots.reshape(-1, 3).sum(axis=1)
    steps = np.concatenate(steps) if steps else np.zeros(0)
    history = h0 + np.concatenate([[0.0], np.cumsum(steps)]) if record_history else np.array([h0, 4.0 * float(scales.sum())])
    return FlipResult(out, n_flips, n_rounds, history, steps, cots)
