"""Halfedge arrays of a cell decomposition (Def 4.3), orientable or not.

A face with k corners contributes k halfedges; halfedge `h` leaves the vertex of corner `h` and
ends at the vertex of corner `next[h]` of the same face, so halfedges and corners share one index.
Each halfedge lies on an undirected edge `edge[h]` and runs along that edge's canonical direction
(`sign[h] = +1`, from `edges[e, 0]` to `edges[e, 1]`) or against it (`sign[h] = -1`).  `twin[h]` is
the other halfedge of the same edge, `-1` on the boundary.

Nothing here assumes a consistent orientation: at an edge the two faces may traverse it in the
same direction (a Möbius strip or a projective plane given face by face).  Orientability is a
property computed from the signs (`topology.is_orientable`), not a precondition.

Two constructors: `from_faces(F)` for faces given by vertex indices (an (nf, k) array or a list of
polygons), where vertices are labels and the surface must be a manifold; and `from_gluing(...)`
for polygons whose edges are glued by labels (`gluing.py`), where vertices are the classes of
corners that the gluing identifies and faces may touch themselves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import MeshError, NonManifoldError, ShapeError

__all__ = ["Halfedges", "from_faces", "from_gluing", "as_halfedges", "edges", "faces_as_corners"]


@dataclass(frozen=True, eq=False)
class Halfedges:
    """Halfedge arrays of a cell decomposition; every array has shape (nh,) unless stated.

    **Fields:**
    - `vertex`: the vertex the halfedge leaves (= the vertex of corner h).
    - `face`, `next`, `prev`: the face of h and the following / preceding halfedge in that face.
    - `edge`, `sign`: the undirected edge and the direction (±1) in which h runs along it.
    - `twin`: the other halfedge on the same edge, -1 on a boundary edge.
    - `edges`: (ne, 2) endpoints of each edge in its canonical direction.
    - `n_vertices`, `n_faces`: counts (vertex labels are 0..n_vertices-1; a label that no face
      uses is not counted by `topology.euler_characteristic`).
    """

    vertex: np.ndarray
    face: np.ndarray
    next: np.ndarray
    prev: np.ndarray
    edge: np.ndarray
    sign: np.ndarray
    twin: np.ndarray
    edges: np.ndarray
    n_vertices: int
    n_faces: int

    @property
    def n_edges(self) -> int:
        return int(self.edges.shape[0])

    @property
    def head(self) -> np.ndarray:
        """The vertex each halfedge ends at."""
        return self.vertex[self.next]


def faces_as_corners(F) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flatten faces to corners: `(vertex, face, next)`, each (n_corners,) int.

    `F` is an (nf, k) integer array (vectorised) or a sequence of polygons (vertex index lists of
    any lengths ≥ 2).  Raises `ShapeError` for a face with fewer than two corners and `MeshError`
    for a non-integer or negative index (naming the face).
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


def _face_of(sizes: np.ndarray, corner: int) -> int:
    return int(np.searchsorted(np.cumsum(sizes), corner, side="right"))


def _inverse_permutation(p: np.ndarray) -> np.ndarray:
    inv = np.empty_like(p)
    inv[p] = np.arange(p.size)
    return inv


def _twins(edge: np.ndarray, n_edges: int) -> np.ndarray:
    """Pair the (at most two) halfedges of each edge; -1 where an edge has one halfedge."""
    order = np.argsort(edge, kind="stable")
    count = np.bincount(edge, minlength=n_edges)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    twin = np.full(edge.size, -1, dtype=np.int64)
    pair = start[count == 2]
    twin[order[pair]] = order[pair + 1]
    twin[order[pair + 1]] = order[pair]
    return twin


def _check_multiplicity(edge, face, edges, n_edges) -> None:
    count = np.bincount(edge, minlength=n_edges)
    bad = np.flatnonzero(count > 2)
    if bad.size:
        e = int(bad[0])
        faces = sorted(set(face[edge == e].tolist()))
        raise NonManifoldError(
            f"edge {e} with vertices ({edges[e, 0]}, {edges[e, 1]}) lies in {count[e]} faces {faces}; "
            "a surface edge lies in at most two"
        )


def _corner_identification(h_next, edge, sign, twin, n_corners) -> tuple[int, np.ndarray]:
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


def _check_vertex_fans(vertex, h_next, edge, sign, twin) -> None:
    """Each vertex must carry exactly one fan of corners (its neighbourhood is a disk)."""
    n, labels = _corner_identification(h_next, edge, sign, twin, vertex.size)
    pairs = np.unique(np.stack([vertex, labels], axis=1), axis=0)
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
    """Halfedges of a surface given by faces of vertex indices; vectorised (sort / unique).

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
    lo, hi = np.minimum(vertex, head), np.maximum(vertex, head)
    edges_, edge = np.unique(np.stack([lo, hi], axis=1), axis=0, return_inverse=True)
    edge = edge.reshape(-1)
    sign = np.where(vertex < head, 1, -1)
    _check_multiplicity(edge, face, edges_, edges_.shape[0])
    twin = _twins(edge, edges_.shape[0])
    _check_vertex_fans(vertex, h_next, edge, sign, twin)
    n_faces = int(face.max()) + 1 if face.size else 0
    return Halfedges(vertex, face, h_next, _inverse_permutation(h_next), edge, sign, twin,
                     edges_, nv, n_faces)


def from_gluing(face, h_next, edge, sign) -> Halfedges:
    """Halfedges of polygons glued along labelled edges (each label on one or two sides).

    **Arguments:** per side of the polygons: `face`, `next` (the following side), `edge` (label
    0..ne-1) and `sign` (±1, the side runs along or against the label's direction).  Vertices
    are the classes of corners the gluing identifies.

    **Raises:** `NonManifoldError` for a label used more than twice.
    """
    face, h_next, edge, sign = (np.asarray(a, dtype=np.int64) for a in (face, h_next, edge, sign))
    n_edges = int(edge.max()) + 1
    count = np.bincount(edge, minlength=n_edges)
    if np.any(count > 2):
        e = int(np.argmax(count > 2))
        raise NonManifoldError(f"edge label {e} is used {count[e]} times; a surface edge lies on at most two sides")
    twin = _twins(edge, n_edges)
    _, vertex = _corner_identification(h_next, edge, sign, twin, edge.size)
    head = vertex[h_next]
    order = np.argsort(edge, kind="stable")
    first = order[np.concatenate([[0], np.cumsum(count)[:-1]])]
    tail0 = np.where(sign[first] > 0, vertex[first], head[first])
    head0 = np.where(sign[first] > 0, head[first], vertex[first])
    edges_ = np.stack([tail0, head0], axis=1)
    return Halfedges(vertex.astype(np.int64), face, h_next, _inverse_permutation(h_next), edge, sign,
                     twin, edges_, int(vertex.max()) + 1, int(face.max()) + 1)


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
