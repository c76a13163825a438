"""Piecewise flat surfaces as glued Euclidean triangles (Sec 5.3, Def 5.5, 5.6).

A geodesic triangulation is stored as a gluing map plus edge lengths, not as vertex triples, so
that it admits the non-regular triangulations the edge-flip algorithm produces (Remark 5.9,
Example 7.2): a triangle glued to itself, loops, two edges between the same pair of vertices,
vertices of valence one.

Side `i` of face `f` is the halfedge `h = 3 f + i`, running from corner `i` to corner `i + 1`
of the face (indices mod 3).  The faces are oriented consistently: two glued halfedges run in
opposite directions.  Arrays:

- `F` (nf, 3) int: the vertex at each corner (vertex labels; after flips a face may repeat one);
- `edge` (3 nf,) int: the edge each halfedge lies on;
- `halfedges` (ne, 2) int: the two halfedges of each edge, `[e, 1] = -1` on the boundary;
- `lengths` (ne,) float: the edge lengths, satisfying every triangle inequality strictly.

The angle at corner k of a face lies opposite its side k + 1.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import (
    GluingError,
    MeshError,
    NonFiniteError,
    NonManifoldError,
    OrientationError,
    ShapeError,
    TriangleInequalityError,
)
from .geometry import apex, cotangent, triangle_area

__all__ = [
    "Triangulation",
    "angle_defects",
    "boundary_vertices",
    "cone_angles",
    "corner_angles",
    "corner_cotangents",
    "from_checked_mesh",
    "from_faces",
    "from_gluing",
    "from_mesh",
    "next_halfedge",
    "side_lengths",
    "unfold",
]


@dataclass(frozen=True, eq=False)
class Triangulation:
    """A geodesic triangulation of a piecewise flat surface (Def 5.6); see the module docstring
    for the meaning of the arrays.  Immutable: operations return new triangulations.
    """

    F: np.ndarray
    edge: np.ndarray
    halfedges: np.ndarray
    lengths: np.ndarray
    n_vertices: int

    @property
    def n_faces(self) -> int:
        return int(self.F.shape[0])

    @property
    def n_edges(self) -> int:
        return int(self.halfedges.shape[0])

    @property
    def twin(self) -> np.ndarray:
        """(3 nf,) the halfedge glued to each halfedge, -1 on the boundary."""
        pair = self.halfedges[self.edge]
        return np.where(pair[:, 0] == np.arange(self.edge.size), pair[:, 1], pair[:, 0])

    @property
    def edges(self) -> np.ndarray:
        """(ne, 2) the endpoints (tail, head) of each edge's first halfedge."""
        h = self.halfedges[:, 0]
        return np.stack([self.F.reshape(-1)[h], self.F.reshape(-1)[next_halfedge(h)]], axis=1)

    def with_lengths(self, lengths) -> Triangulation:
        """The same gluing with other edge lengths (validated)."""
        return _validated(replace(self, lengths=np.array(lengths, dtype=np.float64)))


def next_halfedge(h):
    """The next halfedge in the same face: 3 f + (i + 1 mod 3)."""
    h = np.asarray(h)
    return np.where(h - 3 * (h // 3) == 2, h - 2, h + 1)


def side_lengths(tri: Triangulation) -> np.ndarray:
    """(nf, 3): entry [f, i] is the length of side i (from corner i to corner i + 1) of face f."""
    return tri.lengths[tri.edge].reshape(-1, 3)


def _check_lengths(tri: Triangulation) -> None:
    l = tri.lengths
    if l.shape != (tri.n_edges,):
        raise ShapeError(f"lengths must have shape ({tri.n_edges},) (one per edge), got {l.shape}")
    bad = np.flatnonzero(~np.isfinite(l))
    if bad.size:
        raise NonFiniteError(f"edge {bad[0]} has the non-finite length {l[bad[0]]}")
    bad = np.flatnonzero(l <= 0)
    if bad.size:
        raise TriangleInequalityError(f"edge {bad[0]} has the non-positive length {l[bad[0]]}")
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


def _glue_by_keys(keys: np.ndarray):
    """Group halfedges with equal keys into edges, with one sort.

    Returns `(edge, halfedges, unique_keys, count)`: the edge of each halfedge, numbered in
    increasing key order (for keys lo · nv + hi this is the lexicographic order of
    `ddgjax.mesh.edges(F)`); the (ne, 2) halfedges of each edge (-1 in column 1 where there is
    one; only the first two are kept); the sorted distinct keys and their multiplicities.
    """
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    n = keys.size
    if n % 2 == 0 and n and np.array_equal(sorted_keys[0::2], sorted_keys[1::2]) and np.all(sorted_keys[2::2] != sorted_keys[1:-1:2]):
        # every key exactly twice (a closed surface): the pairs are consecutive
        edge = np.empty(n, dtype=np.int64)
        edge[order] = np.arange(n) >> 1
        return edge, order.reshape(-1, 2), sorted_keys[0::2], np.full(n // 2, 2)
    is_start = np.empty(keys.size, dtype=bool)
    is_start[:1] = True
    np.not_equal(sorted_keys[1:], sorted_keys[:-1], out=is_start[1:])
    starts = np.flatnonzero(is_start)
    count = np.diff(np.append(starts, keys.size))
    edge = np.empty(keys.size, dtype=np.int64)
    edge[order] = np.cumsum(is_start) - 1
    halfedges = np.full((starts.size, 2), -1, dtype=np.int64)
    halfedges[:, 0] = order[starts]
    two = count >= 2
    halfedges[:, 1][two] = order[starts[two] + 1]  # column view: row-wise masks are slow
    return edge, halfedges, sorted_keys[starts], count


def _faces_array(F) -> np.ndarray:
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ShapeError(f"F must be an (nf, 3) array of triangles, got shape {F.shape}")
    if F.size and not np.issubdtype(F.dtype, np.integer) and not np.all(F == np.round(F)):
        f = int(np.argwhere(F != np.round(F))[0, 0])
        raise MeshError(f"face {f} has a non-integer vertex index {F[f].tolist()}")
    F = F.astype(np.int64)
    if F.size and F.min() < 0:
        raise MeshError(f"face {int(np.argwhere(F < 0)[0, 0])} has a negative vertex index")
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if repeated.any():
        f = int(np.argmax(repeated))
        raise MeshError(f"face {f} repeats a vertex: {F[f].tolist()}")
    return F


def checked_faces(F, n_vertices: int | None = None):
    """`(F, nv)`: F as an (nf, 3) int64 array of labels < nv (default max + 1); raises `ShapeError`
    / `MeshError` naming the face."""
    F = _faces_array(F)
    nv = int(F.max()) + 1 if n_vertices is None else int(n_vertices)
    if F.size and F.max() >= nv:
        raise MeshError(f"face {int(np.argwhere(F >= nv)[0, 0])} has a vertex index >= n_vertices = {nv}")
    return F, nv


def _glue_faces(F: np.ndarray, nv: int):
    """(edge, halfedges, keys) of faces given by vertex triples; keys = i · nv + j, i < j."""
    tail = F.reshape(-1)
    head = np.empty_like(F)
    head[:, :2] = F[:, 1:]
    head[:, 2] = F[:, 0]
    head = head.reshape(-1)
    lo = np.minimum(tail, head)
    lo *= np.int64(nv)
    lo += np.maximum(tail, head)
    edge, halfedges, keys, count = _glue_by_keys(lo)
    if np.any(count > 2):
        e = int(np.argmax(count > 2))
        raise NonManifoldError(
            f"edge {e} with vertices ({keys[e] // nv}, {keys[e] % nv}) lies in {count[e]} faces; "
            "a surface edge lies in at most two"
        )
    h, t = halfedges[:, 0], halfedges[:, 1]  # column views (row gathers are slow)
    same = (t >= 0) & (tail[h] == tail[t])
    if same.any():
        e = int(np.argmax(same))
        raise OrientationError(
            f"edge {e} with vertices ({keys[e] // nv}, {keys[e] % nv}) is traversed in the same "
            "direction by its two faces; orient the faces consistently (ddgjax.mesh.orient)"
        )
    return edge, halfedges, keys


def from_faces(F, lengths, n_vertices: int | None = None) -> Triangulation:
    """The triangulation of a simplicial surface given by vertex triples, with edge `lengths`
    ordered like `ddgjax.mesh.edges(F)` (lexicographic vertex pairs i < j).

    **Raises:** `ShapeError` for F not (nf, 3) or lengths of the wrong shape; `MeshError` for a
    bad vertex index or a face repeating a vertex; `NonManifoldError` for an edge in more than two
    faces; `OrientationError` for two faces traversing an edge in the same direction;
    `NonFiniteError` / `TriangleInequalityError` for bad lengths (naming the edge or face).
    """
    F, nv = checked_faces(F, n_vertices)
    edge, halfedges, _ = _glue_faces(F, nv)
    return _validated(Triangulation(F, edge, halfedges, np.array(lengths, dtype=np.float64), nv))


def checked_positions(V) -> np.ndarray:
    """V as an (nv, n) float64 array; `NonFiniteError` naming the first vertex with NaN / inf."""
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2:
        raise ShapeError(f"V must be an (nv, n) array of positions, got shape {V.shape}")
    bad = np.argwhere(~np.isfinite(V))
    if bad.size:
        raise NonFiniteError(f"V has the non-finite value {V[tuple(bad[0])]} at vertex {bad[0, 0]}")
    return V


def from_mesh(V, F) -> Triangulation:
    """The piecewise flat surface of a simplicial surface in R^n: lengths |v_j − v_i| (Sec 5.3).
    Raises as `from_faces`, and `NonFiniteError` for NaN / inf coordinates (naming the vertex).
    """
    V = checked_positions(V)
    F, _ = checked_faces(F, V.shape[0])
    return from_checked_mesh(V, F)


def from_checked_mesh(V: np.ndarray, F: np.ndarray) -> Triangulation:
    """`from_mesh` for V, F already passed through `checked_positions` / `checked_faces`."""
    nv = V.shape[0]
    edge, halfedges, keys = _glue_faces(F, nv)
    lo = keys // nv
    d = np.take(V, keys - lo * nv, axis=0) - np.take(V, lo, axis=0)  # take: fancy row indexing is slow
    lengths = np.sqrt(np.einsum("ij,ij->i", d, d))
    return _validated(Triangulation(F, edge, halfedges, lengths, nv))


def _check_gluing(twin: np.ndarray) -> None:
    n = twin.size
    if n % 3:
        raise ShapeError(f"twin must have 3 entries per triangle, got {n}")
    bad = np.flatnonzero((twin < -1) | (twin >= n))
    if bad.size:
        raise GluingError(f"halfedge {bad[0]} is glued to {twin[bad[0]]}, outside 0..{n - 1}")
    bad = np.flatnonzero(twin == np.arange(n))
    if bad.size:
        raise GluingError(f"halfedge {bad[0]} (side {bad[0] % 3} of face {bad[0] // 3}) is glued to itself")
    glued = np.flatnonzero(twin >= 0)
    bad = glued[twin[twin[glued]] != glued]
    if bad.size:
        h = int(bad[0])
        raise GluingError(
            f"halfedge {h} (side {h % 3} of face {h // 3}) is glued to {twin[h]}, which is glued to "
            f"{twin[twin[h]]}; a gluing must pair sides"
        )


def from_gluing(twin, side_lengths) -> Triangulation:
    """The piecewise flat surface of triangles glued along sides (Sec 5.3): halfedge `h` (side
    h mod 3 of face h // 3) is glued to `twin[h]` (-1: boundary), reversing direction, and side i
    of face f has length `side_lengths[f, i]`.  Vertices are the classes of corners that the
    gluing identifies; a face may be glued to itself, and loops and multiple edges are allowed.
    Edges are numbered in order of their first halfedge.

    **Raises:** `GluingError` for an index out of range, a side glued to itself, a gluing that is
    not an involution, or glued sides of different lengths (naming the halfedge);
    `TriangleInequalityError` / `NonFiniteError` for bad lengths (naming the face or edge).
    Glued sides must agree to a relative 1e-12; the edge takes the length of its first side.
    """
    twin = np.asarray(twin, dtype=np.int64).reshape(-1)
    _check_gluing(twin)
    L = np.asarray(side_lengths, dtype=np.float64)
    if L.shape != (twin.size // 3, 3):
        raise ShapeError(f"side_lengths must have shape ({twin.size // 3}, 3), got {L.shape}")
    h = np.arange(twin.size)
    flat = L.reshape(-1)
    glued = twin >= 0
    mismatch = glued & ~np.isclose(flat, flat[np.where(glued, twin, h)], rtol=1e-12, atol=0) & np.isfinite(flat)
    if mismatch.any():
        b = int(np.argmax(mismatch))
        raise GluingError(f"halfedge {b} has length {flat[b]} but is glued to halfedge {twin[b]} of length {flat[twin[b]]}")
    first = np.where(glued, np.minimum(h, twin), h)
    owners, edge = np.unique(first, return_inverse=True)
    halfedges = np.stack([owners, np.where(twin[owners] >= 0, twin[owners], -1)], axis=1)
    # the tail of h is the head of its twin, i.e. the tail of next(twin)
    a = h[glued]
    graph = sp.coo_matrix((np.ones(a.size), (a, next_halfedge(twin[a]))), shape=(h.size, h.size))
    n_vertices, vertex = connected_components(graph, directed=False)
    return _validated(Triangulation(vertex.reshape(-1, 3).astype(np.int64), edge.reshape(-1), halfedges,
                                    flat[owners].copy(), int(n_vertices)))


def _opposite_and_adjacent(tri: Triangulation):
    """Per corner k: (a, b, c, A) with a the opposite side k + 1, b and c the sides k + 2 and k
    at the corner, A the face area; each (nf, 3)."""
    L = side_lengths(tri)
    A = triangle_area(L[:, 0], L[:, 1], L[:, 2])[:, None]
    return np.roll(L, -1, axis=1), np.roll(L, -2, axis=1), L, A


def corner_cotangents(tri: Triangulation) -> np.ndarray:
    """(nf, 3): cot of the angle at corner k, (b² + c² − a²) / 4A with a the opposite side."""
    a, b, c, A = _opposite_and_adjacent(tri)
    return cotangent(a, b, c, A)


def corner_angles(tri: Triangulation) -> np.ndarray:
    """(nf, 3): the angle at corner k from the lengths alone, atan2(4A, b² + c² − a²) with a the
    opposite side (the law of cosines; stable near 0 and π).
    """
    a, b, c, A = _opposite_and_adjacent(tri)
    return np.arctan2(4.0 * A, b * b + c * c - a * a)


def cone_angles(tri: Triangulation) -> np.ndarray:
    """(nv,) the total angle around each vertex: the sum of its corner angles (Def 5.5)."""
    return np.bincount(tri.F.reshape(-1), corner_angles(tri).reshape(-1), minlength=tri.n_vertices)


def boundary_vertices(tri: Triangulation) -> np.ndarray:
    """(nv,) bool: vertices on a boundary edge."""
    h = tri.halfedges[tri.halfedges[:, 1] < 0, 0]
    mask = np.zeros(tri.n_vertices, dtype=bool)
    mask[tri.F.reshape(-1)[h]] = True
    mask[tri.F.reshape(-1)[next_halfedge(h)]] = True
    return mask


def angle_defects(tri: Triangulation) -> np.ndarray:
    """(nv,) K(p) = 2π − θ(p) at interior vertices, π − θ(p) at boundary vertices, θ the cone
    angle (Def 5.2, Remark 5.4, Thm 5.5); a function of the lengths alone.
    """
    return np.where(boundary_vertices(tri), np.pi, 2 * np.pi) - cone_angles(tri)


def unfold(tri: Triangulation, e: int) -> np.ndarray:
    """(4, 2): the two triangles of the interior edge e laid out in the plane (Lemma 5.8): rows
    a, b, c, d with e = ab from a = (0, 0) to b = (l_ab, 0), the face of the first halfedge
    (a, b, c) above and the other face (b, a, d) below the x-axis.

    **Raises:** `MeshError` for a boundary edge (naming it).
    """
    h, t = (int(x) for x in tri.halfedges[e])
    if t < 0:
        raise MeshError(f"edge {e} is a boundary edge: it has one triangle, nothing to unfold")
    h1, t1 = next_halfedge(h), next_halfedge(t)
    l_ab, l_bc, l_ca, l_ad, l_db = tri.lengths[[e, tri.edge[h1], tri.edge[next_halfedge(h1)],
                                                tri.edge[t1], tri.edge[next_halfedge(t1)]]]
    c = apex(l_ab, l_ca, l_bc, triangle_area(l_ab, l_bc, l_ca), +1.0)
    d = apex(l_ab, l_ad, l_db, triangle_area(l_ab, l_ad, l_db), -1.0)
    return np.array([[0.0, 0.0], [l_ab, 0.0], c, d])
