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
  and the four outer edges of every flipped quadrilateral for the next round.  Every flip is one
  step of Fig 7.13, recorded in the history.  The cotangents of all corners and the areas and
  harmonic indices of all faces are cached and updated at each flip, so a test is a few array
  lookups.  No JIT: numpy's vectorised gathers and scatters, about 0.5–1 µs per flip.

Surfaces with boundary (which the reference does not treat) keep their boundary edges; only
interior edges are tested and flipped, as in libigl's `intrinsic_delaunay_triangulation`.

Ties: an edge counts as non-Delaunay only if cot α + cot β < −tol · s with s = (h(Δ₁) + h(Δ₂))/4
the cotangent sums of its two triangles (Lemma 7.17; the rounding error of a cotangent computed
from lengths is about eps · s), so that the two diagonals of a (numerically) cocircular
quadrilateral are not flipped back and forth; the flipped edge of a genuinely non-Delaunay edge
is Delaunay (Lemma 7.11).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import FlipBudgetError, InvalidInputError
from .flips import flip_batch, quad
from .geometry import cotangent, face_harmonic_index, flipped_length, triangle_area
from .triangulation import Triangulation, from_faces, side_lengths

__all__ = [
    "DELAUNAY_TOL",
    "FlipResult",
    "as_triangulation",
    "delaunay_edges",
    "edge_cotangent_sums",
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
    """(cot, area, s): per halfedge the cot of the angle opposite it (3 nf,), per face its area
    and s = (a² + b² + c²)/4A = h(Δ)/4 (nf,)."""
    L = side_lengths(tri)
    A = triangle_area(L[:, 0], L[:, 1], L[:, 2])
    # side i of a face is opposite its corner i + 2
    cots = cotangent(L, np.roll(L, -1, axis=1), np.roll(L, 1, axis=1), A[:, None])
    return cots.reshape(-1), A, 0.25 * face_harmonic_index(L[:, 0], L[:, 1], L[:, 2], A)


def edge_cotangent_sums(tri: Triangulation) -> np.ndarray:
    """(ne,) cot α + cot β of the angles opposite each edge, 2ν(e) of eq 6.2 (one cot on the
    boundary)."""
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
    of the angle opposite each halfedge of the result, used by `cotan_weights()`).
    """

    triangulation: Triangulation
    n_flips: int
    n_rounds: int
    harmonic_index: np.ndarray
    harmonic_index_steps: np.ndarray
    halfedge_cotangents: np.ndarray | None = None  # (3 nf,) cot opposite each halfedge, if known

    def cotan_weights(self) -> np.ndarray:
        """(ne,) ν(e) = ½ (cot α + cot β) of the Delaunay triangulation (eq 6.2)."""
        cot = self.halfedge_cotangents
        if cot is None:
            cot = _face_geometry(self.triangulation)[0]
        return 0.5 * np.bincount(self.triangulation.edge, cot, minlength=self.triangulation.n_edges)

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
    """Mutable working copy for the flip loop: the flat gluing arrays; per halfedge the cot of the
    opposite angle and key = cot + tol · s(face), per face its area and s = h(Δ)/4 = Σ cot (kept
    up to date at each flip, so that the test of an edge, key(h) + key(t) < 0, is four lookups)."""

    F: np.ndarray
    edge: np.ndarray
    halfedges: np.ndarray
    lengths: np.ndarray
    cot: np.ndarray
    key: np.ndarray
    area: np.ndarray
    scale: np.ndarray
    scratch: np.ndarray
    tol: float

    @classmethod
    def of(cls, tri: Triangulation, tol: float) -> _Work:
        cots, A, scales = _face_geometry(tri)
        return cls(tri.F.reshape(-1).copy(), tri.edge.copy(), tri.halfedges.copy(), tri.lengths.copy(),
                   cots, cots + tol * np.repeat(scales, 3), A, scales,
                   np.full(tri.n_edges, np.iinfo(np.int64).max, dtype=np.int64), tol)

    def arrays(self):
        return self.F, self.edge, self.halfedges, self.lengths


def _failing(w: _Work, e):
    """bool mask over the interior edges `e`: the angle test fails (Prop 7.9 with the tie
    tolerance: cot α + tol s₁ + cot β + tol s₂ < 0), read from the cached keys."""
    return w.key[w.halfedges[:, 0][e]] + w.key[w.halfedges[:, 1][e]] < 0


def _priority(e):
    """A fixed pseudo-random priority, distinct for distinct edges: Knuth's multiplicative hash,
    a bijection of the 32-bit integers."""
    return (e * 2654435761) & 0xFFFFFFFF


def _independent(bad, sides, scratch) -> np.ndarray:
    """bool mask over `bad`: the edges of least priority among the non-Delaunay edges of both of
    their triangles (`sides`: the four other edges of those triangles)."""
    own = _priority(bad)
    scratch[bad] = own
    best = own
    for side in sides:
        best = np.minimum(best, scratch[side])
    scratch[bad] = np.iinfo(np.int64).max
    return own == best


def _unique(e: np.ndarray, scratch_marks: np.ndarray) -> np.ndarray:
    """The distinct entries of e, in O(len e) with a scratch array (the last occurrence wins)."""
    position = np.arange(e.size)
    scratch_marks[e] = position
    return e[scratch_marks[e] == position]


def _new_face_geometry(w: _Work, slots, l_cd, l_x, l_y):
    """Store area, s and the three opposite cotangents of the new faces with sides (cd, x, y) on
    the slots (first, next, next of next)."""
    B = triangle_area(l_cd, l_x, l_y)
    face = slots[0] // 3
    w.area[face] = B
    w.scale[face] = s = 0.25 * face_harmonic_index(l_cd, l_x, l_y, B)
    for slot, (a, b, c) in zip(slots, ((l_cd, l_x, l_y), (l_x, l_y, l_cd), (l_y, l_cd, l_x))):
        w.cot[slot] = cot = cotangent(a, b, c, B)
        w.key[slot] = cot + w.tol * s


def _flip_round(w: _Work, queue, record):
    """Test the edges `queue`, flip an independent set of the non-Delaunay ones.  Returns
    (flipped edges, harmonic-index steps or None, edges to test next: the non-Delaunay ones not
    flipped and the sides of the flipped quadrilaterals)."""
    bad = queue[_failing(w, queue)]
    if bad.size == 0:
        return bad, None, bad
    slots, sides, ls = quad(*w.arrays(), bad)
    chosen = _independent(bad, sides, w.scratch)
    sel = bad[chosen]
    slots, sides, ls = (tuple(x[chosen] for x in group) for group in (slots, sides, ls))
    f, g = slots[0] // 3, slots[3] // 3
    before = w.scale[f] + w.scale[g]
    new = flipped_length(*ls, w.area[f], w.area[g])
    flip_batch(*w.arrays(), sel, (slots, sides), new)
    _, l_bc, l_ca, l_ad, l_db = ls
    # (d, c, a) on h, h1, h2 with sides cd, ca, ad and (c, d, b) on t, t1, t2 with cd, db, bc
    _new_face_geometry(w, slots[:3], new, l_ca, l_ad)
    _new_face_geometry(w, slots[3:], new, l_db, l_bc)
    steps = 4.0 * (w.scale[f] + w.scale[g] - before) if record else None
    outer = np.concatenate(sides)
    h, t = w.halfedges[:, 0][outer], w.halfedges[:, 1][outer]
    outer = outer[(t >= 0) & (h // 3 != t // 3)]
    return sel, steps, np.concatenate([bad[~chosen], outer])


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
    tri = as_triangulation(F, lengths)
    budget = 50 * tri.n_faces + 1000 if max_flips is None else int(max_flips)
    w = _Work.of(tri, tol)
    marks = np.zeros(tri.n_edges, dtype=np.int64)
    queue = _interior(tri)
    queue = queue[_failing(w, queue)]
    h0 = 4.0 * float(w.scale.sum())
    steps, n_flips, n_rounds = [], 0, 0
    while queue.size:
        parts, before = [], n_flips
        for start in range(0, queue.size, CHUNK):
            flipped, step, more = _flip_round(w, queue[start:start + CHUNK], record_history)
            n_flips += flipped.size
            parts.append(more)
            if step is not None:
                steps.append(step)
            if n_flips > budget:
                raise FlipBudgetError(
                    f"flip budget of {budget} flips used up after {n_rounds} rounds; edge {more[0]} is "
                    "still not Delaunay (raise max_flips, or check the lengths for near-degenerate triangles)"
                )
        queue = _unique(np.concatenate(parts), marks)
        n_rounds += n_flips > before
    out = replace(tri, F=w.F.reshape(-1, 3), edge=w.edge, halfedges=w.halfedges, lengths=w.lengths)
    steps = np.concatenate(steps) if steps else np.zeros(0)
    history = h0 + np.concatenate([[0.0], np.cumsum(steps)]) if record_history else np.array([h0, 4.0 * float(w.scale.sum())])
    return FlipResult(out, n_flips, n_rounds, history, steps, w.cot)
