"""Halfedge arrays of a cell decomposition (Def 4.3): the one connectivity type of ddgjax.

A face with k corners contributes k halfedges; halfedge `h` leaves the vertex of corner `h` and
ends at the vertex of corner `next[h]` of the same face, so halfedges and corners share one index
(for triangles given as an (nf, 3) array, h = 3 f + i).  Each halfedge lies on an undirected edge
`edge[h]` and runs along that edge's canonical direction (`sign[h] = +1`, from `edges[e, 0]` to
`edges[e, 1]`) or against it (`sign[h] = -1`).  `halfedges[e]` are the (at most two) halfedges of
edge e, `-1` in column 1 on the boundary; `twin[h]` is the other halfedge of the same edge.

Nothing here assumes a consistent orientation, nor that vertices are distinct: at an edge the two
faces may traverse it in the same direction (a Möbius strip or a projective plane given face by
face); in a gluing a face may touch itself, an edge may be a loop and two edges may join the same
two vertices (the Δ-complexes of the flip algorithm, Remark 5.9).  Orientability is computed from
the signs (`topology.is_orientable`), not a precondition.  Edges are indexed by halfedge, never by
vertex pair.

Constructors: `from_faces(F)` for faces given by vertex labels (manifold checks), `glue_triangles`
for consistently oriented triangles (the fast path of the intrinsic triangulations), `from_gluing`
for polygons glued along labelled sides, `from_twins` for triangles glued by an involution of
their sides; in the last two, vertices are the classes of corners that the gluing identifies.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import (
    GluingError,
    InvalidInputError,
    MeshError,
    NonManifoldError,
    OrientationError,
    ShapeError,
)

__all__ = [
    "Halfedges",
    "as_halfedges",
    "boundary_indices",
    "boundary_vertices",
    "check_has_faces",
    "edges",
    "faces_as_corners",
    "from_faces",
    "from_gluing",
    "from_twins",
    "glue_triangles",
    "next_halfedge",
]


def next_halfedge(h):
    """The next halfedge in the same triangle: 3 f + (i + 1 mod 3)."""
    h = np.asarray(h)
    return np.where(h - 3 * (h // 3) == 2, h - 2, h + 1)


@dataclass(frozen=True, eq=False)
class Halfedges:
    """Halfedge arrays of a cell decomposition (module docstring).

    **Fields:** `vertex` (nh,) the vertex each halfedge leaves (= the vertex of corner h);
    `edge` (nh,) its edge; `halfedges` (ne, 2) the halfedges of each edge (-1 in column 1 on the
    boundary); `n_vertices`, `n_faces`.  Optional, for polygons or non-oriented gluings (default:
    triangles h = 3 f + i, consistently oriented): `face_of`, `next_of` (nh,), `sign_of` (nh,) and
    `edge_ends` (ne, 2).

    **Properties** (computed on first use): `face`, `next`, `prev`, `head`, `twin`, `sign`,
    `edges` (the endpoints of each edge in its canonical direction: `edge_ends`, or the tail and
    head of `halfedges[e, 0]`), `F` (nf, 3) for triangles, `n_edges`, `boundary_vertex_mask`.
    """

    vertex: np.ndarray
    edge: np.ndarray
    halfedges: np.ndarray
    n_vertices: int
    n_faces: int
    face_of: np.ndarray | None = field(default=None, repr=False)
    next_of: np.ndarray | None = field(default=None, repr=False)
    sign_of: np.ndarray | None = field(default=None, repr=False)
    edge_ends: np.ndarray | None = field(default=None, repr=False)

    @property
    def n_edges(self) -> int:
        return int(self.halfedges.shape[0])

    @property
    def is_triangles(self) -> bool:
        """True when halfedge h is side h mod 3 of triangle h // 3."""
        return self.next_of is None

    @property
    def F(self) -> np.ndarray:
        """(nf, 3) the vertex at each corner of each triangle (a view of `vertex`)."""
        if not self.is_triangles:
            raise ShapeError("F (nf, 3) exists for triangles only; this cell decomposition has polygons")
        return self.vertex.reshape(-1, 3)

    @cached_property
    def face(self) -> np.ndarray:
        return np.arange(self.vertex.size) // 3 if self.face_of is None else self.face_of

    @cached_property
    def next(self) -> np.ndarray:
        return next_halfedge(np.arange(self.vertex.size)) if self.next_of is None else self.next_of

    @cached_property
    def prev(self) -> np.ndarray:
        prev = np.empty_like(self.next)
        prev[self.next] = np.arange(self.next.size)
        return prev

    @cached_property
    def head(self) -> np.ndarray:
        """The vertex each halfedge ends at."""
        return self.vertex[self.next]

    @cached_property
    def twin(self) -> np.ndarray:
        """(nh,) the other halfedge of the same edge, -1 on a boundary edge."""
        return _twins(self.halfedges, self.vertex.size)

    @cached_property
    def sign(self) -> np.ndarray:
        """(nh,) +1 where h runs along its edge's canonical direction, -1 against it."""
        if self.sign_of is not None:
            return self.sign_of
        sign = np.ones(self.vertex.size, dtype=np.int64)
        second = self.halfedges[:, 1]
        sign[second[second >= 0]] = -1
        return sign

    @cached_property
    def edges(self) -> np.ndarray:
        """(ne, 2) the endpoints of each edge in its canonical direction (loops and repeated
        pairs possible)."""
        if self.edge_ends is not None:
            return self.edge_ends
        h = self.halfedges[:, 0]
        return np.stack([self.vertex[h], self.vertex[self.next[h]]], axis=1)

    @cached_property
    def boundary_vertex_mask(self) -> np.ndarray:
        """(n_vertices,) bool: the vertex lies on a boundary edge."""
        h = self.halfedges[self.halfedges[:, 1] < 0, 0]
        mask = np.zeros(self.n_vertices, dtype=bool)
        mask[self.vertex[h]] = True
        mask[self.vertex[self.next[h]]] = True
        return mask


def _twins(halfedges: np.ndarray, n_halfedges: int) -> np.ndarray:
    twin = np.full(n_halfedges, -1, dtype=np.int64)
    h, t = halfedges[:, 0], halfedges[:, 1]
    glued = t >= 0
    twin[h[glued]] = t[glued]
    twin[t[glued]] = h[glued]
    return twin


def faces_as_corners(F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flatten faces to corners: `(vertex, face, next)`, each (n_corners,) int.

    `F` is an (nf, k) integer array (vectorised) or a sequence of polygons (vertex index lists of
    any lengths ≥ 2).  Raises `ShapeError` for a face with fewer than two corners and `MeshError`
    for indices that are not numbers, a non-integer or negative index (naming the face).
    """
    if isinstance(F, np.ndarray) or (hasattr(F, "shape") and hasattr(F, "dtype")):
        arr = np.asarray(F)
        if arr.ndim != 2 or arr.shape[1] < 2:
            raise ShapeError(f"F must be (nf, k) with k >= 2 or a list of polygons, got shape {arr.shape}")
        nf, k = arr.shape
        sizes = np.full(nf, k)
        flat = arr.reshape(-1)
    else:
        polys = [np.asarray(f).reshape(-1) for f in F]
        sizes = np.array([p.size for p in polys], dtype=np.int64)
        short = np.flatnonzero(sizes < 2)
        if short.size:
            raise ShapeError(f"face {short[0]} has {sizes[short[0]]} corners; a face needs at least 2")
        flat = np.concatenate(polys) if polys else np.zeros(0, np.int64)
    if flat.size and not (np.issubdtype(flat.dtype, np.number) or flat.dtype == bool):
        raise MeshError(f"F must hold integer vertex indices, got values of type {flat.dtype} (face 0: {flat[:3].tolist()})")
    if flat.size and not np.issubdtype(flat.dtype, np.integer):
        if not np.all(flat == np.round(flat)):
            bad = int(np.argmax(flat != np.round(flat)))
            raise MeshError(f"face {_face_of(sizes, bad)} has the non-integer vertex index {flat[bad]}")
    vertex = flat.astype(np.int64)
    face = np.repeat(np.arange(sizes.size), sizes)
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    nxt = np.arange(vertex.size) + 1
    last = start + sizes - 1
    nxt[last] = start
    if vertex.size and vertex.min() < 0:
        bad = int(np.argmin(vertex))
        raise MeshError(f"face {face[bad]} has the negative vertex index {vertex[bad]}")
    return vertex, face, nxt


def checked_corners(F, n_vertices: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`faces_as_corners(F)` of at least one polygon, each with at least three corners, labels
    of vertices `0 … n_vertices − 1` and no repeated vertex.  **Raises:** as `faces_as_corners`
    and `check_has_faces`; `ShapeError` for a face with two corners, `MeshError` naming the face
    with an index ≥ `n_vertices` or a repeated vertex."""
    vertex, face, nxt = faces_as_corners(F)
    sizes = np.bincount(face)
    check_has_faces(sizes.size)
    if sizes.min() < 3:
        raise ShapeError(f"face {int(np.argmin(sizes))} has {sizes.min()} corners; a polygon needs at least 3")
    if vertex.size and vertex.max() >= n_vertices:
        bad = int(np.argmax(vertex))
        raise MeshError(f"face {face[bad]} has the vertex index {vertex[bad]} >= n_vertices = {n_vertices}")
    _check_repeated_vertices(vertex, face)
    return vertex, face, nxt


def _face_of(sizes: np.ndarray, corner: int) -> int:
    return int(np.searchsorted(np.cumsum(sizes), corner, side="right"))


def glue_by_keys(keys: np.ndarray):
    """Group halfedges with equal keys into edges, with one sort.

    Returns `(edge, halfedges, unique_keys, count)`: the edge of each halfedge, numbered in
    increasing key order (for keys lo · nv + hi the lexicographic order of vertex pairs); the
    (ne, 2) halfedges of each edge, lowest index first (-1 in column 1 where there is one; only
    the first two are kept); the sorted distinct keys and their multiplicities.
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


def _glue_by_vertices(tail, head, nv: int, face):
    """`(edge, halfedges, keys)` of halfedges glued where they join the same two vertex labels
    (keys lo · nv + hi); `face` (a callable h -> face) names the faces of an edge in more than two.

    **Raises:** `NonManifoldError` for an edge in more than two faces.
    """
    keys = np.minimum(tail, head)
    keys *= np.int64(nv)
    keys += np.maximum(tail, head)
    edge, halfedges, keys, count = glue_by_keys(keys)
    bad = np.flatnonzero(count > 2)
    if bad.size:
        e = int(bad[0])
        faces = sorted(set(face(np.flatnonzero(edge == e)).tolist()))
        raise NonManifoldError(
            f"edge {e} with vertices ({keys[e] // nv}, {keys[e] % nv}) lies in {count[e]} faces {faces}; "
            "a surface edge lies in at most two"
        )
    return edge, halfedges, keys


def _corner_identification(h_next, sign, twin, n_corners) -> tuple[int, np.ndarray]:
    """Classes of corners identified across glued edges: `(n_classes, label per corner)`.

    Across an edge with halfedges h1, h2: tails match tails when they run the same way
    (sign equal), tails match heads when they run opposite ways.
    """
    h1 = np.flatnonzero(twin > np.arange(twin.size))
    h2 = twin[h1]
    same = sign[h1] == sign[h2]
    a = np.concatenate([h1, h_next[h1]])
    b = np.concatenate([np.where(same, h2, h_next[h2]), np.where(same, h_next[h2], h2)])
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(n_corners, n_corners))
    return connected_components(graph, directed=False)


def _check_vertex_fans(h: Halfedges) -> None:
    """Each vertex must carry exactly one fan of corners (its neighbourhood is a disk)."""
    _, labels = _corner_identification(h.next, h.sign, h.twin, h.vertex.size)
    pairs = np.unique(np.stack([h.vertex, labels], axis=1), axis=0)
    fans = np.bincount(pairs[:, 0])
    bad = np.flatnonzero(fans > 1)
    if bad.size:
        v = int(bad[0])
        raise NonManifoldError(
            f"vertex {v} is non-manifold: its faces form {fans[v]} fans joined only at the vertex"
        )


def _check_repeated_vertices(vertex, face) -> None:
    order = np.lexsort((vertex, face))
    v, f = vertex[order], face[order]
    dup = np.flatnonzero((v[1:] == v[:-1]) & (f[1:] == f[:-1]))
    if dup.size:
        i = dup[0]
        raise MeshError(f"face {f[i]} repeats the vertex {v[i]}")


def from_faces(F, n_vertices: int | None = None) -> Halfedges:
    """Halfedges of a surface given by faces of vertex labels; vectorised (one sort of the
    halfedges by vertex pair).  Edges are numbered in lexicographic order of their vertex pairs
    (i, j), i < j, which is also their canonical direction.

    **Arguments:** `F`, (nf, k) int array or list of polygons; `n_vertices`, the number of vertex
    labels (default `max(F) + 1`).

    **Raises:** `MeshError` for an out-of-range or negative index or a face repeating a vertex
    (naming the face); `NonManifoldError` for an edge in more than two faces (naming its
    vertices and faces) or a vertex whose faces form several fans (naming the vertex).
    """
    vertex, face, h_next = faces_as_corners(F)
    nv = int(vertex.max()) + 1 if n_vertices is None and vertex.size else int(n_vertices or 0)
    if vertex.size and vertex.max() >= nv:
        bad = int(np.argmax(vertex))
        raise MeshError(f"face {face[bad]} has the vertex index {vertex[bad]} >= n_vertices = {nv}")
    _check_repeated_vertices(vertex, face)
    head = vertex[h_next]
    edge, halfedges, keys = _glue_by_vertices(vertex, head, nv, lambda h: face[h])
    n_faces = int(face.max()) + 1 if face.size else 0
    ends = np.stack([keys // nv, keys % nv], axis=1) if nv else np.zeros((0, 2), np.int64)
    h = Halfedges(vertex, edge, halfedges, nv, n_faces, face_of=face, next_of=h_next,
                  sign_of=np.where(vertex < head, 1, -1), edge_ends=ends)
    _check_vertex_fans(h)
    return h


def check_has_faces(n_faces: int) -> None:
    """Raise `MeshError` for a face list without faces: the empty set is not a surface (Def
    4.1), and its invariants (χ = 0 would read as a torus) describe nothing."""
    if n_faces == 0:
        raise MeshError("F has no faces: a surface needs at least one face (Def 4.1)")


def checked_triangles(F, n_vertices: int | None = None) -> tuple[np.ndarray, int]:
    """`(F, nv)`: F as an (nf, 3) int64 array of labels < nv (default max + 1), no face repeating
    a vertex.  **Raises:** `ShapeError` (not (nf, 3)) or `MeshError` (no faces, a non-integer,
    negative or too large index, a repeated vertex), naming the face."""
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ShapeError(f"F must be an (nf, 3) array of triangles, got shape {F.shape}")
    check_has_faces(F.shape[0])
    if not (np.issubdtype(F.dtype, np.number) or F.dtype == bool):
        raise MeshError(f"F must hold integer vertex indices, got values of type {F.dtype} (face 0: {F[0].tolist()})")
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
    nv = int(F.max()) + 1 if n_vertices is None else int(n_vertices)
    if F.size and F.max() >= nv:
        raise MeshError(f"face {int(np.argwhere(F >= nv)[0, 0])} has a vertex index >= n_vertices = {nv}")
    return F, nv


def glue_triangles(F: np.ndarray, nv: int) -> tuple[Halfedges, np.ndarray]:
    """`(Halfedges, keys)` of consistently oriented triangles F (already `checked_triangles`),
    halfedge h = 3 f + i; keys (ne,) = i · nv + j, i < j, the vertex pair of each edge (edges
    numbered in their lexicographic order).  No fan check: the fast path of the intrinsic
    triangulations.

    **Raises:** `NonManifoldError` for an edge in more than two faces; `OrientationError` for
    two faces traversing an edge in the same direction (naming the edge's vertices).
    """
    tail = F.reshape(-1)
    head = np.empty_like(F)
    head[:, :2] = F[:, 1:]
    head[:, 2] = F[:, 0]
    edge, halfedges, keys = _glue_by_vertices(tail, head.reshape(-1), nv, lambda h: h // 3)
    h, t = halfedges[:, 0], halfedges[:, 1]  # column views (row gathers are slow)
    same = (t >= 0) & (tail[h] == tail[t])
    if same.any():
        e = int(np.argmax(same))
        raise OrientationError(
            f"edge {e} with vertices ({keys[e] // nv}, {keys[e] % nv}) is traversed in the same "
            "direction by its two faces; orient the faces consistently (ddgjax.mesh.orient)"
        )
    return Halfedges(tail, edge, halfedges, nv, F.shape[0]), keys


def from_gluing(face, h_next, edge, sign) -> Halfedges:
    """Halfedges of polygons glued along labelled edges (each label on one or two sides).

    **Arguments:** per side of the polygons: `face`, `next` (the following side), `edge` (label
    0..ne-1) and `sign` (±1, the side runs along or against the label's direction).  Vertices
    are the classes of corners the gluing identifies.

    **Raises:** `NonManifoldError` for a label used more than twice.
    """
    face, h_next, edge, sign = (np.asarray(a, dtype=np.int64) for a in (face, h_next, edge, sign))
    edge, halfedges, _, count = glue_by_keys(edge)
    if np.any(count > 2):
        e = int(np.argmax(count > 2))
        raise NonManifoldError(f"edge label {e} is used {count[e]} times; a surface edge lies on at most two sides")
    _, vertex = _corner_identification(h_next, sign, _twins(halfedges, edge.size), edge.size)
    first = halfedges[:, 0]
    tail, head = vertex[first], vertex[h_next[first]]
    ends = np.stack([np.where(sign[first] > 0, tail, head), np.where(sign[first] > 0, head, tail)], axis=1)
    return Halfedges(vertex.astype(np.int64), edge, halfedges, int(vertex.max()) + 1, int(face.max()) + 1,
                     face_of=face, next_of=h_next, sign_of=sign, edge_ends=ends)


def _check_twins(twin: np.ndarray) -> None:
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


def from_twins(twin) -> Halfedges:
    """Triangles glued along sides, reversing direction: halfedge h (side h mod 3 of face h // 3)
    is glued to `twin[h]` (-1: boundary).  Vertices are the classes of corners the gluing
    identifies; a face may be glued to itself, loops and multiple edges are allowed.  Edges are
    numbered in order of their first halfedge.

    **Raises:** `ShapeError` unless there are 3 sides per face; `GluingError` for an index out of
    range, a side glued to itself or a gluing that is not an involution (naming the halfedge).
    """
    twin = np.asarray(twin, dtype=np.int64).reshape(-1)
    _check_twins(twin)
    h = np.arange(twin.size)
    first = np.where(twin >= 0, np.minimum(h, twin), h)
    owners, edge = np.unique(first, return_inverse=True)
    halfedges = np.stack([owners, np.where(twin[owners] >= 0, twin[owners], -1)], axis=1)
    sign = np.where(h == owners[edge], 1, -1)
    n_vertices, vertex = _corner_identification(next_halfedge(h), sign, twin, h.size)
    return Halfedges(vertex.astype(np.int64), edge.reshape(-1), halfedges, int(n_vertices), twin.size // 3)


def as_halfedges(F) -> Halfedges:
    """`F` itself if it already is `Halfedges`, `gluing.from_word(F)` for a word (a string), else
    `from_faces(F)`.
    """
    if isinstance(F, Halfedges):
        return F
    if isinstance(F, str):
        from .gluing import from_word

        return from_word(F)
    return from_faces(F)


def edges(F) -> np.ndarray:
    """(ne, 2) int: the undirected edges of `F`, sorted lexicographically, each as (i, j), i < j.

    This is the edge order of every per-edge array in `ddgjax.mesh` (`edge_mean_curvature`,
    `edge_lengths`).
    """
    return as_halfedges(F).edges


def boundary_indices(boundary, n_vertices: int) -> np.ndarray:
    """The vertex set V₀ (e.g. the fixed boundary of a Dirichlet problem) as int64 indices, in
    the given order (a mask: increasing); `boundary` is an index array or a bool mask of length
    n_vertices.

    **Raises:** `InvalidInputError` naming an index outside 0..n_vertices−1 or a repeated index,
    `ShapeError` for a mask of the wrong length or non-integer indices.
    """
    b = np.array(boundary)
    if b.dtype == bool:
        if b.shape != (n_vertices,):
            raise ShapeError(f"a boundary mask needs shape ({n_vertices},), got {b.shape}")
        return np.flatnonzero(b).astype(np.int64)
    b = b.reshape(-1)
    if b.size and not np.issubdtype(b.dtype, np.integer):
        raise ShapeError(f"boundary must be vertex indices (integers) or a bool mask, got dtype {b.dtype}")
    out = np.flatnonzero((b < 0) | (b >= n_vertices))
    if out.size:
        raise InvalidInputError(
            f"boundary vertex {b[out[0]]} (entry {out[0]}) does not exist: vertices are 0..{n_vertices - 1}"
        )
    unique, counts = np.unique(b, return_counts=True)
    if np.any(counts > 1):
        raise InvalidInputError(f"boundary vertex {unique[counts > 1][0]} is listed more than once")
    return b.astype(np.int64)


def boundary_vertices(F, n_vertices: int | None = None) -> np.ndarray:
    """Sorted indices of the vertices on boundary edges of F (faces or `Halfedges`): the default
    fixed set of the Dirichlet and Plateau problems."""
    h = F if isinstance(F, Halfedges) else from_faces(F, n_vertices=n_vertices)
    return np.flatnonzero(h.boundary_vertex_mask)
