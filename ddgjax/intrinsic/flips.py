"""The intrinsic edge flip (Lemma 5.8, Example 5.4, Fig 5.11).

An interior edge ab between two distinct triangles (a, b, c) and (b, a, d) whose unfolding into
the plane is a convex quadrilateral a d b c can be replaced by the other diagonal cd; its length
is read off the unfolded quadrilateral (`geometry.flipped_length`).  The new triangles are
(d, c, a) and (c, d, b); the faces and the edge keep their indices, so that edges stay indexed
by halfedge, never by vertex pair (a flip may create loops and multiple edges).

`flip_batch` flips many edges at once on flat working arrays; it is correct whenever no two of
the edges share a face (each flip then touches disjoint halfedge slots), so the result equals
flipping them one after the other in any order.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError, MeshError
from ..mesh.lengths import normalised, triangle_area
from .geometry import apex, flipped_length
from .triangulation import Triangulation, of_arrays

__all__ = ["flip", "flip_batch", "is_flippable", "others", "quad"]


def others(h, f=None):
    """(next, previous) of the halfedges h in their triangles f = h // 3 (an integer division by
    a constant; % is several times slower)."""
    i = h - 3 * (h // 3 if f is None else f)
    return np.where(i == 2, h - 2, h + 1), np.where(i == 0, h + 2, h - 1)


def quad(F, edge, halfedges, lengths, e):
    """The quadrilateral around the interior edges `e` (an int array): the halfedges
    (h, h1, h2, t, t1, t2) = (ab, bc, ca, ba, ad, db), the side edges (bc, ca, ad, db) and the
    five lengths (l_ab, l_bc, l_ca, l_ad, l_db); `F`, `edge` flat (3 nf,).
    """
    h, t = halfedges[:, 0][e], halfedges[:, 1][e]  # column views: much faster than [e, 0]
    h1, h2 = others(h)
    t1, t2 = others(t)
    sides = (edge[h1], edge[h2], edge[t1], edge[t2])
    l = lengths
    return (h, h1, h2, t, t1, t2), sides, (l[e],) + tuple(l[s] for s in sides)


def _move(halfedges, e, old, new) -> None:
    """In `halfedges[e]`, replace the halfedge `old` by `new` (vectorised, sides read first)."""
    position = 2 * e + (halfedges[:, 0][e] != old)
    halfedges.reshape(-1)[position] = new


def flip_batch(F, edge, halfedges, lengths, e, around=None, new_lengths=None) -> None:
    """Flip the edges `e` in place on the flat arrays (`F`, `edge` of shape (3 nf,)); no two of
    them may share a face.  `around` = (halfedges, side edges) of `quad` and `new_lengths` (the
    diagonals cd) may be passed when already computed.

    The triangles (a, b, c) on the slots (h, h1, h2) and (b, a, d) on (t, t1, t2) become
    (a, d, c) and (b, c, d) on the same slots: the sides ca and db keep their slots, bc moves
    from h1 to t, ad from t1 to h, and the new edge dc lies on (h1, t1); so a flip writes two
    vertices and moves two sides (fewer scattered writes).
    """
    if around is None:
        *around, ls = quad(F, edge, halfedges, lengths, e)
        new_lengths = flipped_length(*ls)
    (h, h1, h2, t, t1, t2), (e_bc, _, e_ad, _) = around
    c, d = F[h2], F[t2]
    F[h1], F[t1] = d, c
    _move(halfedges, e_bc, h1, t)
    _move(halfedges, e_ad, t1, h)
    halfedges[:, 0][e], halfedges[:, 1][e] = h1, t1
    edge[h], edge[h1], edge[t], edge[t1] = e_ad, e, e_bc, e
    lengths[e] = new_lengths


def is_flippable(tri: Triangulation, e: int, margin: float = 1e-9) -> bool:
    """Lemma 5.8: e is interior, its two triangles are distinct, and their unfolding a d b c is a
    strictly convex quadrilateral, i.e. the diagonal cd crosses ab strictly between a and b, at
    least `margin` · l_ab away from both (so that the new triangles are not degenerate).
    Scale-invariant: the quadrilateral is unfolded from its lengths divided by a power of two
    (`ddgjax.mesh.lengths.normalised`).

    **Raises:** `InvalidInputError` unless 0 ≤ margin < ½.
    """
    if not 0.0 <= margin < 0.5:
        raise InvalidInputError(f"margin must be a number in [0, 0.5), got {margin!r}")
    h, t = tri.halfedges[e]
    if t < 0 or h // 3 == t // 3:
        return False
    _, _, ls = quad(tri.F.reshape(-1), tri.edge, tri.halfedges, tri.lengths, np.array([e]))
    l_ab, l_bc, l_ca, l_ad, l_db = normalised(np.concatenate(ls))[0]
    A1, A2 = triangle_area(l_ab, l_bc, l_ca), triangle_area(l_ab, l_ad, l_db)
    (xc, yc), (xd, yd) = apex(l_ab, l_ca, l_bc, A1, 1.0), apex(l_ab, l_ad, l_db, A2, -1.0)
    # the diagonal cd crosses the x-axis strictly between a = 0 and b = l_ab
    x_cross = xd + (xc - xd) * (-yd) / (yc - yd)
    return bool(margin * l_ab < x_cross < (1 - margin) * l_ab)


def flip(tri: Triangulation, e: int) -> Triangulation:
    """The triangulation with edge e flipped (Lemma 5.8); edge e keeps its index and gets the
    length of the other diagonal of the unfolded quadrilateral.

    **Raises:** `MeshError` naming e if it is a boundary edge, lies twice on one triangle, or its
    unfolded quadrilateral is not convex.
    """
    if not is_flippable(tri, e):
        raise MeshError(
            f"edge {e} cannot be flipped (Lemma 5.8): it is a boundary edge, lies twice on one "
            "triangle, or its two triangles unfold to a non-convex quadrilateral"
        )
    F, edge, halfedges, lengths = tri.F.reshape(-1).copy(), tri.edge.copy(), tri.halfedges.copy(), tri.lengths.copy()
    flip_batch(F, edge, halfedges, lengths, np.array([e]))
    return of_arrays(F, edge, halfedges, lengths, tri.n_vertices)
