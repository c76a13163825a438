"""Topological invariants and the classification of compact surfaces (Sec 4.2).

Every function takes `F` as an (nf, k) int array, a list of polygons, a gluing word such as
"abAB" (`gluing.from_word`), or `Halfedges`.  Vertex labels that no face uses do
not count.  `classify` and `genus` describe one connected surface (Def 4.1) and raise
`MeshError` for several components (split first with `connected_components`) or for none (an
empty face list).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components as _components

from ..errors import MeshError, OrientationError
from .connectivity import Halfedges, as_halfedges, check_has_faces

__all__ = [
    "euler_characteristic",
    "connected_components",
    "is_orientable",
    "orient",
    "boundary_loops",
    "genus",
    "crosscaps",
    "Classification",
    "classification",
    "classify",
    "is_regular",
    "is_strongly_regular",
]


def _n_used_vertices(h: Halfedges) -> int:
    return int(np.unique(h.vertex).size)


def euler_characteristic(F) -> int:
    """χ = |V| − |E| + |F| (Def 4.6), counting the vertices used by some face."""
    h = as_halfedges(F)
    return _n_used_vertices(h) - h.n_edges + h.n_faces


def _face_components(h: Halfedges) -> tuple[int, np.ndarray]:
    inner = h.twin >= 0
    a, b = h.face[inner], h.face[h.twin[inner]]
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(h.n_faces, h.n_faces))
    return _components(graph, directed=False)


def connected_components(F) -> list[np.ndarray]:
    """Face indices of each connected component (faces joined through edges), in order of their
    smallest face.
    """
    n, labels = _face_components(as_halfedges(F))
    return [np.flatnonzero(labels == c) for c in range(n)]


def _orientation_cover(h: Halfedges) -> np.ndarray:
    """Component labels of the orientation double cover: node f = face f as given, node f + nf =
    face f reversed.  Two faces at an edge are consistently oriented when they traverse it in
    opposite directions, so equal signs join f1 to reversed f2, opposite signs f1 to f2.
    """
    nf = h.n_faces
    h1 = np.flatnonzero(h.twin > np.arange(h.twin.size))
    f1, f2 = h.face[h1], h.face[h.twin[h1]]
    flip = (h.sign[h1] == h.sign[h.twin[h1]]).astype(np.int64) * nf
    a = np.concatenate([f1, f1 + nf])
    b = np.concatenate([f2 + flip, (f2 + nf - flip)])
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(2 * nf, 2 * nf))
    return _components(graph, directed=False)[1]


def is_orientable(F) -> bool:
    """True when every component can be oriented consistently: no face is joined to its own
    reverse in the orientation double cover (parity union-find over the edge–face incidence).
    """
    h = as_halfedges(F)
    labels = _orientation_cover(h)
    return not np.any(labels[: h.n_faces] == labels[h.n_faces:])


def orient(F) -> list | np.ndarray:
    """The faces of an orientable `F` reordered so that every interior edge is traversed in
    opposite directions by its two faces; the first face of each component keeps its order.
    Returns an array for array input, a list of lists otherwise.  Raises `OrientationError` for a
    non-orientable component (naming a face of it).
    """
    h = as_halfedges(F)
    nf = h.n_faces
    labels = _orientation_cover(h)
    bad = np.flatnonzero(labels[:nf] == labels[nf:])
    if bad.size:
        raise OrientationError(f"face {bad[0]} lies on a non-orientable component; it cannot be oriented")
    _, comp = _face_components(h)
    _, root = np.unique(comp, return_index=True)
    reverse = labels[:nf] != labels[root[comp]]
    if isinstance(F, np.ndarray):
        return np.where(reverse[:, None], F[:, ::-1], F)
    return [list(f)[::-1] if r else list(f) for f, r in zip(F, reverse)]


def _boundary_edges(h: Halfedges) -> np.ndarray:
    return np.flatnonzero(h.twin < 0)


def boundary_loops(F) -> list[np.ndarray]:
    """The boundary components as cycles of vertex indices (Remark 4.6).

    The boundary halfedges form a 2-regular graph on the boundary vertices (each vertex of a
    manifold carries one fan); each loop is walked from its smallest vertex in the direction of
    the boundary halfedge leaving it.  For a `Halfedges` from a gluing, vertices are its corner
    classes.
    """
    h = as_halfedges(F)
    hb = _boundary_edges(h)
    tail, head = h.vertex[hb], h.head[hb]
    neighbours: dict[int, list[int]] = {}
    for a, b in zip(tail.tolist(), head.tolist()):
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    out_of = dict(zip(tail.tolist(), head.tolist()))
    loops, seen = [], set()
    for start in sorted(neighbours):
        if start in seen:
            continue
        loop, prev, cur = [start], start, out_of.get(start, neighbours[start][0])
        seen.add(start)
        while cur != start:
            loop.append(cur)
            seen.add(cur)
            nb = neighbours[cur]
            prev, cur = cur, (nb[1] if nb[0] == prev and len(nb) > 1 else nb[0])
        loops.append(np.array(loop, dtype=np.int64))
    return loops


def _single_component(h: Halfedges) -> None:
    check_has_faces(h.n_faces)
    n, labels = _face_components(h)
    if n > 1:
        first = [int(np.argmax(labels == c)) for c in range(n)]
        raise MeshError(
            f"F has {n} connected components (first faces {first}); a surface is connected "
            "(Def 4.1): classify each of mesh.connected_components(F) separately"
        )


@dataclass(frozen=True)
class Classification:
    """A compact connected surface up to homeomorphism (Thm 4.1, Cor 4.2, Remark 4.6).

    `genus` is the number of handles g when orientable (χ = 2 − 2g − b) and the number of
    cross-caps k otherwise (χ = 2 − k − b); `name` is the common name or "".
    """

    orientable: bool
    genus: int
    boundary_components: int
    euler_characteristic: int
    name: str

    def __str__(self) -> str:
        b = _plural(self.boundary_components, "boundary component")
        name = f" ({self.name})" if self.name else ""
        if self.orientable:
            return f"orientable surface of genus {self.genus} with {b}{name}"
        return f"non-orientable surface with {_plural(self.genus, 'cross-cap')} and {b}{name}"


def _plural(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


_ORIENTABLE_NAMES = {(0, 0): "sphere", (1, 0): "torus", (2, 0): "double torus", (3, 0): "triple torus",
                     (0, 1): "disk", (0, 2): "annulus", (0, 3): "pair of pants", (1, 1): "punctured torus"}
_NONORIENTABLE_NAMES = {(1, 0): "projective plane", (2, 0): "Klein bottle", (3, 0): "Dyck's surface",
                        (1, 1): "Möbius strip"}


def classification(F) -> Classification:
    """Orientability, genus or cross-caps, boundary count and χ of one connected surface.

    **Raises:** `MeshError` for several components or none (no faces).
    """
    h = as_halfedges(F)
    _single_component(h)
    chi = euler_characteristic(h)
    b = len(boundary_loops(h))
    orientable = is_orientable(h)
    if orientable:
        g, names = (2 - chi - b) // 2, _ORIENTABLE_NAMES
    else:
        g, names = 2 - chi - b, _NONORIENTABLE_NAMES
    return Classification(orientable, int(g), b, chi, names.get((int(g), b), ""))


def classify(F) -> str:
    """A readable classification, e.g. "orientable surface of genus 1 with 0 boundary components
    (torus)" or "non-orientable surface with 2 cross-caps and 0 boundary components (Klein bottle)".
    """
    return str(classification(F))


def genus(F) -> int:
    """g with χ = 2 − 2g − b for an orientable surface; for a non-orientable one the
    non-orientable genus, i.e. the number k of cross-caps with χ = 2 − k − b (Thm 4.1).
    """
    return classification(F).genus


def crosscaps(F) -> int:
    """The number k of projective planes in M = (RP²)#k (Thm 4.1); 0 for an orientable surface."""
    c = classification(F)
    return 0 if c.orientable else c.genus


def _regularity_violation(h: Halfedges) -> str | None:
    loops = np.flatnonzero(h.edges[:, 0] == h.edges[:, 1])
    if loops.size:
        return f"edge {loops[0]} is a loop at vertex {h.edges[loops[0], 0]}"
    pairs = np.unique(np.stack([h.face, h.vertex], axis=1), axis=0)
    counts = np.bincount(h.face, minlength=h.n_faces)
    distinct = np.bincount(pairs[:, 0], minlength=h.n_faces)
    bad = np.flatnonzero(distinct < counts)
    if bad.size:
        return f"face {bad[0]} touches itself at a vertex"
    return None


def is_regular(F) -> bool:
    """Def 4.4: every cell's characteristic map is a homeomorphism, i.e. no edge is a loop and
    no face meets a vertex (hence an edge) twice.  Always true for faces of vertex indices.
    """
    return _regularity_violation(as_halfedges(F)) is None


def is_strongly_regular(F) -> bool:
    """Def 4.4: regular, and the closures of any two cells meet in ∅ or in the closure of one cell.

    For a regular decomposition this means: no two edges with the same endpoints; an edge whose
    endpoints both lie on a face is an edge of it; two faces share no vertex, one vertex, or one
    edge with its two endpoints, and nothing else.
    """
    h = as_halfedges(F)
    if _regularity_violation(h) is not None:
        return False
    lo, hi = np.sort(h.edges, axis=1).T
    if np.unique(np.stack([lo, hi], axis=1), axis=0).shape[0] < h.n_edges:
        return False
    ones = np.ones(h.vertex.size)
    fv = sp.csr_matrix((ones, (h.face, h.vertex)), shape=(h.n_faces, h.n_vertices))
    fe = sp.csr_matrix((ones, (h.face, h.edge)), shape=(h.n_faces, h.n_edges))
    ev = sp.csr_matrix((np.ones(2 * h.n_edges), (np.repeat(np.arange(h.n_edges), 2), h.edges.reshape(-1))),
                       shape=(h.n_edges, h.n_vertices))
    if _has_chord(ev, fv, fe):
        return False
    shared_v = (fv @ fv.T).tocoo()
    shared_e = (fe @ fe.T).tocsr()
    off = shared_v.row != shared_v.col
    sv = shared_v.data[off]
    se = np.asarray(shared_e[shared_v.row[off], shared_v.col[off]]).reshape(-1)
    ok = ((sv <= 1) & (se == 0)) | ((sv == 2) & (se == 1))
    return bool(np.all(ok))


def _has_chord(ev, fv, fe) -> bool:
    """Some edge has both endpoints on a face without being one of its edges."""
    both = (ev @ fv.T).tocsr()
    both.data = (both.data == 2).astype(float)
    chords = both - both.multiply((fe.T > 0).astype(float))
    chords.eliminate_zeros()
    return chords.nnz > 0
