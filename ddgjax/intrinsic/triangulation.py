"""Piecewise flat surfaces as glued Euclidean triangles (Sec 5.3, Def 5.5, 5.6).

A geodesic triangulation is connectivity plus edge lengths: a `ddgjax.mesh.Halfedges` of
triangles (the one connectivity type of ddgjax) and one length per edge satisfying every triangle
inequality strictly.  The gluing admits the non-regular triangulations the edge-flip algorithm
produces (Remark 5.9, Example 7.2): a triangle glued to itself, loops, two edges between the same
pair of vertices, vertices of valence one.  All geometry comes from the lengths
(`ddgjax.mesh.lengths`).

Side `i` of face `f` is the halfedge `h = 3 f + i`, running from corner `i` to corner `i + 1`
of the face (indices mod 3).  The faces are oriented consistently: two glued halfedges run in
opposite directions.  Arrays:

- `F` (nf, 3) int: the vertex at each corner (vertex labels; after flips a face may repeat one);
- `edge` (3 nf,) int: the edge each halfedge lies on;
- `halfedges` (ne, 2) int: the two halfedges of each edge, `[e, 1] = -1` on the boundary;
- `lengths` (ne,) float: the edge lengths.

The angle at corner k of a face lies opposite its side k + 1.

Angles, cotangents and the Delaunay test are invariant under l ↦ s l; they are computed on the
lengths divided by a power of two (`ddgjax.mesh.lengths.normalised`: exact, and 1 at ordinary
sizes), so that squares and areas stay within float64 for lengths from 1e-300 to 1e300.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import (
    GluingError,
    MeshError,
    ShapeError,
    TriangleInequalityError,
)
from ..mesh.connectivity import (
    Halfedges,
    checked_triangles,
    from_twins,
    glue_triangles,
    next_halfedge,
)
from ..mesh.lengths import angle_defects as angle_defects_of_sides
from ..mesh.lengths import (
    check_edge_lengths,
    check_positions,
    corner_angles_of_sides,
    normalised,
    side_cotangents,
    triangle_area,
)
from ..mesh.lengths import corner_cotangents as cotangents_of_sides
from .geometry import apex

__all__ = [
    "Triangulation",
    "angle_defects",
    "boundary_vertices",
    "checked_faces",
    "cone_angles",
    "corner_angles",
    "corner_cotangents",
    "corner_weights",
    "cotan_weights",
    "halfedge_cotangents",
    "from_checked_mesh",
    "from_faces",
    "from_gluing",
    "from_mesh",
    "next_halfedge",
    "normalised_side_lengths",
    "opposite_side_lengths",
    "side_lengths",
    "unfold",
]

checked_faces = checked_triangles


@dataclass(frozen=True, eq=False)
class Triangulation:
    """A geodesic triangulation of a piecewise flat surface (Def 5.6): `connectivity` (triangles
    glued consistently oriented, h = 3 f + i) and `lengths` (ne,).  Immutable: operations return
    new triangulations.  The arrays `F`, `edge`, `halfedges`, `twin`, `edges` and the counts are
    those of the connectivity (module docstring).
    """

    connectivity: Halfedges
    lengths: np.ndarray

    @property
    def F(self) -> np.ndarray:
        return self.connectivity.F

    @property
    def edge(self) -> np.ndarray:
        return self.connectivity.edge

    @property
    def halfedges(self) -> np.ndarray:
        return self.connectivity.halfedges

    @property
    def n_vertices(self) -> int:
        return self.connectivity.n_vertices

    @property
    def n_faces(self) -> int:
        return self.connectivity.n_faces

    @property
    def n_edges(self) -> int:
        return self.connectivity.n_edges

    @property
    def twin(self) -> np.ndarray:
        """(3 nf,) the halfedge glued to each halfedge, -1 on the boundary."""
        return self.connectivity.twin

    @property
    def edges(self) -> np.ndarray:
        """(ne, 2) the endpoints of each edge in its canonical direction (`Halfedges.edges`)."""
        return self.connectivity.edges

    def with_lengths(self, lengths) -> Triangulation:
        """The same gluing with other edge lengths (validated)."""
        return _validated(Triangulation(self.connectivity, np.array(lengths, dtype=np.float64)))


def of_arrays(F, edge, halfedges, lengths, n_vertices: int) -> Triangulation:
    """The triangulation of the flat arrays of a consistently oriented triangle gluing (as the
    flip loop keeps them), not validated."""
    F = np.asarray(F).reshape(-1)
    return Triangulation(Halfedges(F, edge, halfedges, int(n_vertices), F.size // 3), lengths)


def side_lengths(tri: Triangulation) -> np.ndarray:
    """(nf, 3): entry [f, i] is the length of side i (from corner i to corner i + 1) of face f."""
    return tri.lengths[tri.edge].reshape(-1, 3)


def _check_lengths(tri: Triangulation) -> None:
    l = tri.lengths
    if l.shape != (tri.n_edges,):
        raise ShapeError(f"lengths must have shape ({tri.n_edges},) (one per edge), got {l.shape}")
    check_edge_lengths(l)
    L = side_lengths(tri)
    a, b, c = L[:, 0], L[:, 1], L[:, 2]
    longest = np.maximum(np.maximum(a, b), c)
    # the longest side is shorter than the other two together (the strict triangle inequality)
    bad = np.flatnonzero((a + b + c) - longest <= longest)
    if bad.size:
        f = int(bad[0])
        slack = L[f].sum() - 2 * L[f]
        i = int(np.argmax(slack <= 0)) if np.any(slack <= 0) else int(np.argmax(L[f]))
        raise TriangleInequalityError(
            f"face {f} has side lengths {tuple(float(x) for x in L[f])}: side {i} is not shorter "
            "than the other two together (the triangle inequality must hold strictly)"
        )


def _validated(tri: Triangulation) -> Triangulation:
    _check_lengths(tri)
    return tri


def from_faces(F, lengths, n_vertices: int | None = None) -> Triangulation:
    """The triangulation of a simplicial surface given by vertex triples, with edge `lengths`
    ordered like `ddgjax.mesh.edges(F)` (lexicographic vertex pairs i < j).

    **Raises:** `ShapeError` for F not (nf, 3) or lengths of the wrong shape; `MeshError` for a
    bad vertex index or a face repeating a vertex; `NonManifoldError` for an edge in more than two
    faces; `OrientationError` for two faces traversing an edge in the same direction;
    `NonFiniteError` / `TriangleInequalityError` for bad lengths (naming the edge or face).
    """
    F, nv = checked_triangles(F, n_vertices)
    connectivity, _ = glue_triangles(F, nv)
    return _validated(Triangulation(connectivity, np.array(lengths, dtype=np.float64)))


def normalised_side_lengths(tri: Triangulation) -> np.ndarray:
    """`side_lengths` divided by the power of two nearest the longest (`ddgjax.mesh.lengths.
    normalised`), for the scale-invariant quantities."""
    return normalised(side_lengths(tri))[0]


def checked_positions(V) -> np.ndarray:
    """V as an (nv, n) float64 array; `NonFiniteError` naming the first vertex with NaN / inf."""
    V = np.asarray(V, dtype=np.float64)
    check_positions(V, dims=None)
    return V


def from_mesh(V, F) -> Triangulation:
    """The piecewise flat surface of a simplicial surface in R^n: lengths |v_j − v_i| (Sec 5.3).
    Raises as `from_faces`, and `NonFiniteError` for NaN / inf coordinates (naming the vertex).
    """
    V = checked_positions(V)
    F, _ = checked_triangles(F, V.shape[0])
    return from_checked_mesh(V, F)


def from_checked_mesh(V: np.ndarray, F: np.ndarray) -> Triangulation:
    """`from_mesh` for V, F already passed through `checked_positions` / `checked_triangles`;
    the lengths of V / s times s (`ddgjax.mesh.lengths.normalised`), so that |v_j − v_i|² need
    not be a float."""
    nv = V.shape[0]
    connectivity, keys = glue_triangles(F, nv)
    V, s = normalised(V)
    lo = keys // nv
    d = np.take(V, keys - lo * nv, axis=0) - np.take(V, lo, axis=0)  # take: fancy row indexing is slow
    lengths = np.sqrt(np.einsum("ij,ij->i", d, d))
    return _validated(Triangulation(connectivity, lengths if s == 1.0 else lengths * s))


def from_gluing(twin, side_lengths) -> Triangulation:
    """The piecewise flat surface of triangles glued along sides (Sec 5.3): halfedge `h` (side
    h mod 3 of face h // 3) is glued to `twin[h]` (-1: boundary), reversing direction, and side i
    of face f has length `side_lengths[f, i]` (connectivity: `ddgjax.mesh.from_twins`).

    **Raises:** `GluingError` for an index out of range, a side glued to itself, a gluing that is
    not an involution, or glued sides of different lengths (naming the halfedge);
    `TriangleInequalityError` / `NonFiniteError` for bad lengths (naming the face or edge).
    Glued sides must agree to a relative 1e-12; the edge takes the length of its first side.
    """
    connectivity = from_twins(twin)
    twin = connectivity.twin
    L = np.asarray(side_lengths, dtype=np.float64)
    if L.shape != (connectivity.n_faces, 3):
        raise ShapeError(f"side_lengths must have shape ({connectivity.n_faces}, 3), got {L.shape}")
    flat = L.reshape(-1)
    glued = twin >= 0
    other = flat[np.where(glued, twin, np.arange(twin.size))]
    mismatch = glued & ~np.isclose(flat, other, rtol=1e-12, atol=0) & np.isfinite(flat)
    if mismatch.any():
        b = int(np.argmax(mismatch))
        raise GluingError(f"halfedge {b} has length {flat[b]} but is glued to halfedge {twin[b]} of length {flat[twin[b]]}")
    return _validated(Triangulation(connectivity, flat[connectivity.halfedges[:, 0]].copy()))


def _opposite_edges(tri: Triangulation) -> np.ndarray:
    """(nf, 3): the edge opposite corner k of each face (side k + 1)."""
    return tri.edge.reshape(-1, 3)[:, [1, 2, 0]]


def opposite_side_lengths(tri: Triangulation) -> np.ndarray:
    """(nf, 3): entry [f, k] is the length of the side opposite corner k (side k + 1), the
    layout of `ddgjax.mesh.lengths`."""
    return tri.lengths[_opposite_edges(tri)]


def corner_cotangents(tri: Triangulation) -> np.ndarray:
    """(nf, 3): cot of the angle at corner k (`ddgjax.mesh.lengths.corner_cotangents`), from
    the normalised lengths (scale-invariant)."""
    L = normalised(opposite_side_lengths(tri))[0]
    a, b, c = L[:, 0], L[:, 1], L[:, 2]
    return np.stack(cotangents_of_sides(a * a, b * b, c * c, triangle_area(a, b, c)), axis=1)


def halfedge_cotangents(tri: Triangulation) -> np.ndarray:
    """(3 nf,): cot of the angle opposite each halfedge (side i of a face is opposite its corner
    i + 2), derived as twice the off-diagonal of the Hessian of the Dirichlet energy on the
    squared lengths (`ddgjax.mesh.lengths.side_cotangents`, Thm 6.6), of the normalised
    lengths (scale-invariant)."""
    L = normalised_side_lengths(tri)
    return side_cotangents(L * L)[0].reshape(-1)


def corner_weights(tri: Triangulation) -> np.ndarray:
    """(nf, 3): ½ cot α_k, each face's contribution to the cotan weight of the side opposite its
    corner k (side k + 1), from the derived `halfedge_cotangents`."""
    return 0.5 * halfedge_cotangents(tri).reshape(-1, 3)[:, [1, 2, 0]]


def cotan_weights(tri: Triangulation, halfedge_cot: np.ndarray | None = None) -> np.ndarray:
    """(ne,) ν(e) = ½ (cot α + cot β), ½ cot α on the boundary (eq 6.2), in edge order of `tri`:
    the sum of `corner_weights` over the corners opposite each edge (`halfedge_cot`: the
    `halfedge_cotangents` of `tri`, if already known)."""
    cot = halfedge_cotangents(tri) if halfedge_cot is None else halfedge_cot
    return 0.5 * np.bincount(tri.edge, cot, minlength=tri.n_edges)


def corner_angles(tri: Triangulation) -> np.ndarray:
    """(nf, 3): the angle at corner k from the lengths alone (`ddgjax.mesh.lengths.corner_angles`)."""
    return corner_angles_of_sides(opposite_side_lengths(tri))


def cone_angles(tri: Triangulation) -> np.ndarray:
    """(nv,) the total angle around each vertex: the sum of its corner angles (Def 5.5)."""
    return np.bincount(tri.F.reshape(-1), corner_angles(tri).reshape(-1), minlength=tri.n_vertices)


def boundary_vertices(tri: Triangulation) -> np.ndarray:
    """(nv,) bool: vertices on a boundary edge."""
    return tri.connectivity.boundary_vertex_mask


def angle_defects(tri: Triangulation) -> np.ndarray:
    """(nv,) K(p) = 2π − θ(p) at interior vertices, π − θ(p) at boundary vertices, θ the cone
    angle (Def 5.2, Remark 5.4, Thm 5.5); a function of the lengths alone
    (`ddgjax.mesh.lengths.angle_defects`).
    """
    return np.asarray(angle_defects_of_sides(tri.connectivity, opposite_side_lengths(tri)))


def unfold(tri: Triangulation, e: int) -> np.ndarray:
    """(4, 2): the two triangles of the interior edge e laid out in the plane (Lemma 5.8): rows
    a, b, c, d with e = ab from a = (0, 0) to b = (l_ab, 0), the face of the first halfedge
    (a, b, c) above and the other face (b, a, d) below the x-axis.

    **Raises:** `MeshError` for a boundary edge (naming it).  Laid out on the lengths divided by
    a power of two s and scaled back (`ddgjax.mesh.lengths.normalised`).
    """
    h, t = (int(x) for x in tri.halfedges[e])
    if t < 0:
        raise MeshError(f"edge {e} is a boundary edge: it has one triangle, nothing to unfold")
    h1, t1 = next_halfedge(h), next_halfedge(t)
    l, s = normalised(tri.lengths[[e, tri.edge[h1], tri.edge[next_halfedge(h1)],
                                   tri.edge[t1], tri.edge[next_halfedge(t1)]]])
    l_ab, l_bc, l_ca, l_ad, l_db = l
    c = apex(l_ab, l_ca, l_bc, triangle_area(l_ab, l_bc, l_ca), +1.0)
    d = apex(l_ab, l_ad, l_db, triangle_area(l_ab, l_ad, l_db), -1.0)
    return np.array([[0.0, 0.0], [l_ab, 0.0], c, d]) * s
