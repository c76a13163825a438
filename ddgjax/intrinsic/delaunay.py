"""Intrinsic Delaunay triangulations by edge flips (Sec 7.2, 7.3).

- The angle criterion (Prop 7.9): an interior edge is Delaunay iff the two angles opposite to it
  sum to at most π, i.e. iff cot α + cot β ≥ 0 (eq 6.3: ν = ½ sin(α + β) / (sin α sin β)).
- The harmonic index h(T) = Σ_Δ (a² + b² + c²) / A(Δ) (Def 7.7) = 8 Σ_i E(φ_i) (Lemma 7.18);
  it strictly decreases at every flip of a non-Delaunay edge (Cor 7.16, 7.19) and is proper
  (Lemma 7.20), so the flip algorithm terminates (Thm 7.12), also on triangulations with
  arbitrarily long edges (Example 7.3).
- The edge-flip algorithm (Fig 7.13) as a sequential loop compiled by numba
  (`flip_algorithm`): a sweep over the edges; a non-Delaunay edge found by the sweep is flipped,
  and those of the four outer edges of its quadrilateral that then fail the test are tested and
  flipped depth-first (a stack), so that every non-Delaunay edge is on the stack or not yet
  swept.  Every flip is one step of Fig 7.13, recorded in the history.  The test keys
  cot + tol · s of all corners and the areas of all faces are cached and updated at each flip,
  so a test is two lookups.  The keys' cotangents are read off the triangle's Dirichlet energy
  by polarisation (`ddgjax.mesh.lengths.corner_cotangents`, compiled into the loop), those of
  the start as those of the triangles a flip creates; the cotan weights of the result are the
  autodiff Hessian of the same energy (`ddgjax.mesh.lengths.side_cotangent_columns`, one
  compiled call on all faces after the loop).

Surfaces with boundary (which the reference does not treat) keep their boundary edges; only
interior edges are tested and flipped, as in libigl's `intrinsic_delaunay_triangulation`.

Ties: an edge counts as non-Delaunay only if cot α + cot β < −tol · s with s = (h(Δ₁) + h(Δ₂))/4
the cotangent sums of its two triangles (Lemma 7.17; the rounding error of a cotangent computed
from lengths is about eps · s), so that the two diagonals of a (numerically) cocircular
quadrilateral are not flipped back and forth; the flipped edge of a genuinely non-Delaunay edge
is Delaunay (Lemma 7.11).  `tol` must be finite and positive (`InvalidInputError` otherwise).

Scale: the angle test, the harmonic index and the flips are invariant under l ↦ s l (a flip
scales the new diagonal by s).  The loop runs on the lengths divided by a power of two
(`ddgjax.mesh.lengths.normalised`: exact, and 1 at ordinary sizes), so that the squares and
areas it forms stay in float64 for lengths from 1e-300 to 1e300, and the flipped lengths are
scaled back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import check_positive
from ..errors import FlipBudgetError, InvalidInputError
from ..mesh.lengths import (
    face_harmonic_index,
    padded_size,
    power_of_two_scale,
    side_cotangent_columns,
    side_cotangents,
    triangle_area,
)
from .triangulation import (
    Triangulation,
    cotan_weights,
    from_faces,
    normalised_side_lengths,
    of_arrays,
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
    """(cot, s): per halfedge the cot of the angle opposite it (3 nf,), derived from the
    Dirichlet energy (`ddgjax.mesh.lengths.side_cotangents`); per face
    s = cot α + cot β + cot γ = (a² + b² + c²)/4A = h(Δ)/4 (nf,) (Lemma 7.17); from the
    normalised lengths (both are scale-invariant)."""
    L = normalised_side_lengths(tri)
    cots = side_cotangents(L * L)[0]
    return cots.reshape(-1), cots.sum(axis=1)


def edge_cotangent_sums(tri: Triangulation) -> np.ndarray:
    """(ne,) cot α + cot β of the angles opposite each edge (one cot on the boundary): the angle
    criterion of Prop 7.9 (law of cosines); the cotan weights are `cotan_weights`."""
    return np.bincount(tri.edge, _face_geometry(tri)[0], minlength=tri.n_edges)


def _non_delaunay(tri: Triangulation, tol: float) -> np.ndarray:
    """(ne,) bool: the interior edges between two distinct triangles that fail the angle test
    (one vectorised pass over the faces)."""
    check_positive(tol, "tol")
    cots, scales = _face_geometry(tri)
    scale = np.bincount(tri.edge, np.repeat(scales, 3), minlength=tri.n_edges)
    bad = np.bincount(tri.edge, cots, minlength=tri.n_edges) < -tol * scale
    out = np.zeros(tri.n_edges, dtype=bool)
    e = _interior(tri)
    out[e] = bad[e]
    return out


def delaunay_edges(tri: Triangulation, tol: float = DELAUNAY_TOL) -> np.ndarray:
    """(ne,) bool: the angle criterion of Prop 7.9 for each edge (boundary edges count as
    Delaunay; an edge lying twice on one triangle always is).  **Raises:** `InvalidInputError`
    unless `tol` is finite and positive."""
    return ~_non_delaunay(tri, tol)


def is_delaunay(F, lengths=None, *, tol: float = DELAUNAY_TOL) -> bool:
    """True iff every edge satisfies the angle criterion (Prop 7.9, Thm 7.7).  `F` is a
    `Triangulation`, a `FlipResult` or faces (nf, 3) with `lengths` ordered like
    `ddgjax.mesh.edges(F)`.  **Raises:** as `delaunay_edges`."""
    return bool(delaunay_edges(as_triangulation(F, lengths), tol).all())


def harmonic_index(F, lengths=None) -> float:
    """h(T) = Σ_Δ (a² + b² + c²) / A(Δ) (Def 7.7); scale-invariant, from the normalised
    lengths."""
    L = normalised_side_lengths(as_triangulation(F, lengths))
    a, b, c = L.T
    return float(np.sum(face_harmonic_index(a, b, c, triangle_area(a, b, c))))


@dataclass(frozen=True, eq=False)
class FlipResult:
    """Outcome of `flip_to_delaunay`.

    **Fields:** `triangulation` (the Delaunay triangulation; faces, gluing and lengths);
    `n_flips`; `n_rounds` (the longest cascade of flips, each of an edge that the one before
    made non-Delaunay; `flip_algorithm.flip_algorithm`); `harmonic_index`
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


def flip_to_delaunay(F, lengths=None, *, tol: float = DELAUNAY_TOL, max_flips: int | None = None,
                     record_history: bool = True) -> FlipResult:
    """Make a geodesic triangulation Delaunay by edge flips (Fig 7.13, Thm 7.12).

    **Arguments:** `F` and `lengths` as for `is_delaunay` (the input is not modified); `tol` the
    tie tolerance of the angle test (module docstring); `max_flips` the flip budget (default
    50 · nf + 1000); `record_history` records the harmonic index after every flip.

    **Returns:** a `FlipResult`.

    **Raises:** the errors of `triangulation.from_faces`; `InvalidInputError` unless `tol` is
    finite and positive; `FlipBudgetError` when the budget is used up (naming an edge that is
    still not Delaunay).
    """
    return flip_owned(as_triangulation(F, lengths), tol, max_flips, record_history, copy=True)


def flip_owned(tri: Triangulation, tol: float = DELAUNAY_TOL, max_flips: int | None = None,
               record_history: bool = False, copy: bool = False) -> FlipResult:
    """`flip_to_delaunay` of a triangulation whose arrays the caller owns: with `copy=False` they
    are flipped in place (and `tri` must not be used afterwards).  The loop runs on the lengths
    divided by the power of two s nearest the longest (module docstring), multiplied by s again
    at the end (exactly: s is a power of two)."""
    # numba is loaded here, not at `import ddgjax`; the loop is compiled once per machine
    from .flip_algorithm import flip_algorithm, interleaved, squared_sides

    check_positive(tol, "tol")
    budget = 50 * tri.n_faces + 1000 if max_flips is None else int(max_flips)
    arrays = tuple(np.ascontiguousarray(a) for a in (tri.F.reshape(-1), tri.edge, tri.halfedges, tri.lengths))
    if copy:
        arrays = tuple(a.copy() for a in arrays)
    lengths = arrays[3]
    s = float(power_of_two_scale(lengths.max())) if lengths.size else 1.0
    if s != 1.0:
        lengths *= 1.0 / s
    n_flips, n_rounds, steps, stuck, h0, key = flip_algorithm(*arrays, float(tol), budget, bool(record_history))
    # the derived cotangents of the result (the loop's keys hold the law of cosines)
    by_side = None if stuck >= 0 else side_cotangent_columns(
        squared_sides(arrays[1], lengths, padded_size(tri.n_faces)), tri.n_faces)
    if s != 1.0:
        lengths *= s
    if stuck >= 0:
        raise FlipBudgetError(
            f"flip budget of {budget} flips used up; edge {stuck} is still not Delaunay (raise "
            "max_flips, or check the lengths for near-degenerate triangles)"
        )
    out = of_arrays(*arrays, tri.n_vertices) if n_flips else tri
    cots = interleaved(*by_side, key)  # into the buffer of the loop's keys
    if record_history:
        history = h0 + np.concatenate([[0.0], np.cumsum(steps)])
    else:
        history = np.array([h0, 4.0 * float(cots.sum())])
    return FlipResult(out, int(n_flips), int(n_rounds), history, steps, cots)
