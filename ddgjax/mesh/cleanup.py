"""Clean-up of the usual defects of downloaded meshes, each a pure function `(V, F) -> (V, F, report)`.

- `remove_unreferenced_vertices`: vertices in no face;
- `weld_vertices`: vertices closer than a tolerance (duplicates of a file that stores each face's
  corners apart, as STL does, or of a seam);
- `split_nonmanifold_vertices`: a vertex whose faces form several fans (its neighbourhood is not a
  disk or half-disk, Def 4.3) becomes one vertex a fan;
- `drop_degenerate_faces`: faces that repeat a vertex or have zero area up to round-off.

`F` is an (nf, k) int array or a list of polygons; each function returns its faces in the same
form, and a `CleanupReport` of what it changed (all counts 0 on a clean mesh).  Inputs are never
modified.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from jaxtyping import Float, Int
from scipy.sparse.csgraph import connected_components

from ..errors import InvalidInputError, MeshError, NonFiniteError, ShapeError
from .connectivity import faces_as_corners
from .lengths import DEGENERATE

__all__ = [
    "CleanupReport",
    "remove_unreferenced_vertices",
    "weld_vertices",
    "split_nonmanifold_vertices",
    "drop_degenerate_faces",
]


@dataclass(frozen=True, eq=False)
class CleanupReport:
    """What a clean-up function changed.

    - `count`: the vertices removed, merged into another or added, or the faces dropped; 0 when
      there was nothing to do.
    - `vertex_map` (nv_old,): the new index of each old vertex, -1 for a removed one.
    - `vertex_origin` (nv_new,): the old index of each new vertex (the copies of a split vertex
      share it).
    - `face_origin` (nf_new,): the old index of each new face.
    - `vertices`, `faces`: the old vertices (removed, merged away, split) or faces (dropped)
      concerned, in increasing order.
    - `kinds`: counts by kind where there are several (`drop_degenerate_faces`:
      `repeated_vertex`, `zero_area`; `weld_vertices`: `faces_repeating_a_vertex` afterwards).
    """

    count: int
    vertex_map: Int[np.ndarray, "nv_old"]
    vertex_origin: Int[np.ndarray, "nv_new"]
    face_origin: Int[np.ndarray, "nf_new"]
    vertices: tuple[int, ...] = ()
    faces: tuple[int, ...] = ()
    kinds: dict = field(default_factory=dict)


def remove_unreferenced_vertices(V: Float[np.ndarray, "nv 3"], F):
    """`(V', F', report)`: V without the vertices that lie in no face, F renumbered (the remaining
    vertices keep their order).  `report.count` is the number removed.

    **Raises:** `ShapeError` (V not (nv, 3)), `MeshError` (a face index out of range).
    """
    V, sizes, corners = _mesh(V, F)
    used = np.zeros(len(V), dtype=bool)
    used[corners] = True
    vertex_map = np.where(used, np.cumsum(used) - 1, -1)
    removed = np.flatnonzero(~used)
    report = CleanupReport(int(removed.size), vertex_map, np.flatnonzero(used), np.arange(sizes.size),
                           vertices=tuple(removed.tolist()))
    return V[used], _faces_like(F, sizes, vertex_map[corners]), report


def weld_vertices(V: Float[np.ndarray, "nv 3"], F, tol: float):
    """`(V', F', report)`: vertices joined by a chain of pairs at distance `<= tol` become one, the
    one of lowest index (its position kept); F renumbered.  `tol = 0` welds exact duplicates.
    `report.count` is the number of vertices merged away; faces that now repeat a vertex are
    kept and counted in `report.kinds["faces_repeating_a_vertex"]` (`drop_degenerate_faces`
    removes them).

    **Raises:** `InvalidInputError` (tol negative, NaN or infinite), `NonFiniteError` (a vertex
    not finite), `ShapeError`, `MeshError` (as `remove_unreferenced_vertices`).
    """
    if not (np.isfinite(tol) and tol >= 0):
        raise InvalidInputError(f"tol must be finite and >= 0, got {tol}")
    V, sizes, corners = _mesh(V, F, finite=True)
    from scipy.spatial import cKDTree

    pairs = cKDTree(V).query_pairs(float(tol), output_type="ndarray")
    _, label = connected_components(_graph(len(V), pairs), directed=False)
    representative = np.full(label.max(initial=-1) + 1, len(V))
    np.minimum.at(representative, label, np.arange(len(V)))
    keep = np.sort(representative)
    rank = np.empty(len(V), dtype=np.int64)
    rank[keep] = np.arange(keep.size)
    vertex_map = rank[representative[label]]
    merged = np.flatnonzero(representative[label] != np.arange(len(V)))
    new_corners = vertex_map[corners]
    report = CleanupReport(int(merged.size), vertex_map, keep, np.arange(sizes.size), vertices=tuple(merged.tolist()),
                           kinds={"faces_repeating_a_vertex": int(_repeating(sizes, new_corners).sum())})
    return V[keep], _faces_like(F, sizes, new_corners), report


def split_nonmanifold_vertices(V: Float[np.ndarray, "nv 3"], F):
    """`(V', F', report)`: each vertex whose faces form k > 1 fans (faces around it joined
    through the edges at it) becomes k vertices, one a fan (Def 4.3: afterwards every vertex has
    a disk or half-disk neighbourhood, unless an edge lies in more than two faces, which this
    does not change).  The fan holding the vertex's first corner keeps its index, the others get
    copies appended to V (`report.vertex_origin`); `report.count` is the number of copies.

    **Raises:** `ShapeError`, `MeshError` (as `remove_unreferenced_vertices`).
    """
    V, sizes, corners = _mesh(V, F)
    fan = _fans(sizes, corners)
    first = np.unique(fan, return_index=True)[1]  # the first corner of each fan
    fan_vertex = corners[first]
    order = np.lexsort((first, fan_vertex))
    is_copy = np.zeros(first.size, dtype=bool)
    is_copy[order[1:]] = fan_vertex[order[1:]] == fan_vertex[order[:-1]]
    copies = np.flatnonzero(is_copy)
    copies = copies[np.argsort(first[copies], kind="stable")]
    fan_index = fan_vertex.copy()
    fan_index[copies] = len(V) + np.arange(copies.size)
    origin = np.concatenate([np.arange(len(V)), fan_vertex[copies]])
    report = CleanupReport(int(copies.size), np.arange(len(V)), origin, np.arange(sizes.size),
                           vertices=tuple(np.unique(fan_vertex[copies]).tolist()))
    return V[origin], _faces_like(F, sizes, fan_index[fan]), report


def drop_degenerate_faces(V: Float[np.ndarray, "nv 3"], F):
    """`(V, F', report)`: F without the faces that repeat a vertex or have zero area up to
    round-off: every corner lies on a line through the first, `sin² ∠(p_i − p_0, p_{i+1} − p_0)
    <= DEGENERATE` for all i (for a triangle the test of `lengths.check_face_areas`, scale-free).
    Vertices are kept (`remove_unreferenced_vertices` removes those left in no face).
    `report.kinds` counts `repeated_vertex` and `zero_area` faces.

    **Raises:** `NonFiniteError` (a vertex of a face not finite), `ShapeError`, `MeshError`.
    """
    V, sizes, corners = _mesh(V, F, finite=True)
    repeated = _repeating(sizes, corners)
    flat = ~repeated & _zero_area(V, sizes, corners)
    keep = ~(repeated | flat)
    kept_corners = corners[np.repeat(keep, sizes)]
    report = CleanupReport(int(np.sum(~keep)), np.arange(len(V)), np.arange(len(V)), np.flatnonzero(keep),
                           faces=tuple(np.flatnonzero(~keep).tolist()),
                           kinds={"repeated_vertex": int(repeated.sum()), "zero_area": int(flat.sum())})
    return V.copy(), _faces_like(F, sizes[keep], kept_corners), report


# --- helpers ---------------------------------------------------------------------------------


def _mesh(V, F, finite: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(V, sizes, corners)`: V a float64 copy, (nv, 3); the corner count of each face and the
    vertex of each corner, face after face.  Raises for a bad shape, an index out of range or
    (`finite`) a non-finite vertex."""
    V = np.array(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ShapeError(f"V must be (nv, 3), got shape {V.shape}")
    corners, face, _ = faces_as_corners(F)
    sizes = np.bincount(face, minlength=len(F)).astype(np.int64)
    out = np.flatnonzero(corners >= len(V))
    if out.size:
        raise MeshError(f"face {face[out[0]]} refers to vertex {corners[out[0]]}, but V has {len(V)} vertices")
    if finite:
        bad = np.flatnonzero(~np.all(np.isfinite(V), axis=1))
        if bad.size:
            raise NonFiniteError(f"vertex {bad[0]} has the non-finite coordinates {V[bad[0]].tolist()}")
    return V, sizes, corners


def _faces_like(F, sizes: np.ndarray, corners: np.ndarray):
    """Faces of the given corner counts and vertices, in the form of F: an (nf, k) array or a
    list of lists."""
    if isinstance(F, np.ndarray) or (hasattr(F, "shape") and hasattr(F, "dtype")):
        return corners.reshape(-1, np.shape(F)[1]).astype(np.int64)
    return [f.tolist() for f in np.split(corners, np.cumsum(sizes)[:-1])] if sizes.size else []


def _graph(n: int, pairs: np.ndarray) -> sp.csr_matrix:
    """The (n, n) adjacency matrix of the graph with the given (m, 2) edges."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return sp.csr_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))


def _repeating(sizes: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(nf,) bool: the faces in which some vertex appears twice."""
    face = np.repeat(np.arange(sizes.size), sizes)
    order = np.lexsort((corners, face))
    twice = (face[order][1:] == face[order][:-1]) & (corners[order][1:] == corners[order][:-1])
    out = np.zeros(sizes.size, dtype=bool)
    out[face[order][1:][twice]] = True
    return out


def _fans(sizes: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(n_corners,) the fan of each corner: corners at the same vertex whose faces share an edge
    at that vertex are in one fan (the connected components of this relation)."""
    n = corners.size
    start = np.repeat(np.cumsum(sizes) - sizes, sizes)
    position = np.arange(n) - start
    size = np.repeat(sizes, sizes)
    nxt = corners[start + (position + 1) % size]
    prv = corners[start + (position - 1) % size]
    corner = np.concatenate([np.arange(n), np.arange(n)])
    keys = np.stack([np.concatenate([corners, corners]), np.concatenate([nxt, prv])], axis=1)
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    same = np.all(keys[order][1:] == keys[order][:-1], axis=1)
    links = np.stack([corner[order][:-1][same], corner[order][1:][same]], axis=1)
    return connected_components(_graph(n, links), directed=False)[1]


def _zero_area(V: np.ndarray, sizes: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(nf,) bool: every fan triangle (p_0, p_i, p_{i+1}) of the face has sin² of its angle at p_0
    <= DEGENERATE (or undefined: coincident corners).  The differences p_i − p_0 are divided by
    their largest entry on each face first, so the test does not depend on the scale."""
    start = np.cumsum(sizes) - sizes
    face = np.repeat(np.arange(sizes.size), sizes)
    d = V[corners] - V[corners[start[face]]]
    scale = np.maximum.reduceat(np.max(np.abs(d), axis=1), start) if sizes.size else np.zeros(0)
    d = d / np.where(scale > 0, scale, 1.0)[face, None]
    position = np.arange(corners.size) - start[face]
    fan = np.flatnonzero((position >= 1) & (position <= sizes[face] - 2))  # the corner p_i of each fan triangle
    a, b = d[fan], d[fan + 1]
    with np.errstate(invalid="ignore", divide="ignore"):  # 0/0 at coincident corners: no area
        sin2 = np.sum(np.cross(a, b) ** 2, axis=1) / (np.sum(a * a, axis=1) * np.sum(b * b, axis=1))
    has_area = np.zeros(sizes.size, dtype=bool)
    np.logical_or.at(has_area, face[fan], sin2 > DEGENERATE)
    return ~has_area
