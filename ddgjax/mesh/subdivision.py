"""Subdivision of triangle meshes: the 1 → 4 split, with midpoint or Loop positions.

Every triangle (a, b, c) is split at its edges into four, (a, ab, ca), (b, bc, ab), (c, ca, bc),
(ab, bc, ca), each with the orientation of its parent (the four blocks stacked in this order,
block k holding the children of the faces 0..nf−1 in order).  Vertex numbering of the result:

- vertices 0..nv−1 are the old vertices, in their order (old vertex i is new vertex i, so index
  sets and fixed-vertex masks carry over unchanged);
- vertex nv + e is the new vertex on edge e, the edges in the order of `dg.mesh.edges(F)`
  (lexicographic in (i, j), i < j).

So nv' = nv + ne, nf' = 4 nf, ne' = 2 ne + 3 nf and χ = nv − ne + nf is preserved.  The positions
of the new mesh are linear in the old ones, V' = S V with the sparse prolongation matrix
S = `subdivision_matrix(F, nv, scheme)`, (nv + ne, nv), whose rows are the stencils below (each
sums to 1: affine maps commute with subdivision).  The same S carries any per-vertex data (a
warm start, a displacement field) to the refined mesh.

Schemes (Loop 1987; Warren's weights, Warren & Weimer, *Subdivision Methods for Geometric
Design*, 2002):

- `"midpoint"`: the edge vertex of edge (i, j) is (v_i + v_j)/2, old vertices stay.  The
  subdivided polyhedron is the same point set as the old one (each face is cut into four coplanar
  triangles), so area and enclosed volume are unchanged and boundary curves stay where they were.
- `"loop"`: interior edge (i, j) with opposite vertices k, l: 3/8 (v_i + v_j) + 1/8 (v_k + v_l);
  interior vertex of valence n: (1 − n β) v + β Σ_{neighbours} v_j with β = 3/(8n) for n > 3 and
  β = 3/16 for n = 3.  Boundary edges and vertices follow the cubic B-spline rules of the
  boundary polygon alone (so the boundary curve is subdivided as a curve, independent of the
  interior): edge (i, j) → (v_i + v_j)/2, vertex → 1/8 v_prev + 3/4 v + 1/8 v_next with v_prev,
  v_next its two neighbours along the boundary; with `boundary="fixed"` the old boundary
  vertices keep their positions instead (their rows of S are rows of the identity), so a fixed
  boundary of a variational problem stays fixed.  Loop surfaces converge to C² limits except at
  extraordinary vertices (valence ≠ 6), where they are C¹.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._checks import check_finite
from ..errors import InvalidInputError, ShapeError
from .connectivity import checked_triangles, from_faces

__all__ = ["SCHEMES", "BOUNDARY_RULES", "subdivide", "subdivision_matrix"]

SCHEMES = ("midpoint", "loop")
BOUNDARY_RULES = ("curve", "fixed")


def _edges_of_faces(F, nv: int | None) -> tuple[np.ndarray, int, np.ndarray, np.ndarray, np.ndarray]:
    """`(F, nv, edges, edge_of, count)` of valid triangles (`from_faces`: indices in 0..nv−1, no
    face repeating a vertex, every edge in at most two faces, every vertex a single fan): F (nf, 3)
    int64; the (ne, 2) edges (i, j), i < j, in lexicographic order (`dg.mesh.edges`); the (nf, 3)
    edge of side corner k → corner k + 1 of each face; the number of faces at each edge."""
    F, nv = checked_triangles(F, nv)
    h = from_faces(F, nv)  # NonManifoldError naming the edge or the vertex
    return F, nv, h.edges, h.edge.reshape(-1, 3), 1 + (h.halfedges[:, 1] >= 0)


def _check_options(scheme: str, boundary: str) -> None:
    if scheme not in SCHEMES:
        raise InvalidInputError(f"scheme must be one of {SCHEMES}, got {scheme!r}")
    if boundary not in BOUNDARY_RULES:
        raise InvalidInputError(f"boundary must be one of {BOUNDARY_RULES}, got {boundary!r}")


def _split_faces(F: np.ndarray, nv: int, edge_of: np.ndarray) -> np.ndarray:
    """The (4 nf, 3) children of the faces (module docstring), edge e's vertex nv + e."""
    a, b, c = F.T
    ab, bc, ca = (edge_of + nv).T
    return np.concatenate([np.stack(t, axis=1) for t in ([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca])])


def _warren_beta(n: np.ndarray) -> np.ndarray:
    """Warren's β(n) = 3/(8n) for n > 3, 3/16 for n = 3 (0 for an isolated vertex)."""
    return np.where(n == 3, 3.0 / 16.0, 3.0 / (8.0 * np.maximum(n, 1)))


def _loop_edge_rows(F, nv, edges, edge_of, count):
    """Loop's edge stencils: each face adds 3/16 at the ends and 1/8 at the opposite corner of its
    three sides, so an interior edge gets 3/8, 3/8, 1/8, 1/8 from its two faces; a boundary edge
    gets 1/2 at its ends instead."""
    on_boundary = count == 1
    e = edge_of.reshape(-1)
    tail, head, opposite = (np.roll(F, -k, axis=1).reshape(-1) for k in range(3))
    inner = ~on_boundary[e]
    m, mb = int(inner.sum()), int(on_boundary.sum())
    rows = np.concatenate([np.tile(nv + e[inner], 3), np.tile(nv + np.flatnonzero(on_boundary), 2)])
    cols = np.concatenate([tail[inner], head[inner], opposite[inner], edges[on_boundary, 0], edges[on_boundary, 1]])
    vals = np.concatenate([np.full(2 * m, 3.0 / 16.0), np.full(m, 1.0 / 8.0), np.full(2 * mb, 0.5)])
    return rows, cols, vals


def _loop_vertex_rows(nv, edges, count, boundary: str):
    """Loop's vertex stencils: an interior vertex of valence n gets (1 − n β) at itself and β at
    each neighbour (Warren's β); a boundary vertex 3/4 at itself and 1/8 at its two neighbours
    along boundary edges (`"curve"`), or 1 at itself (`"fixed"`)."""
    on_boundary = count == 1
    valence = np.bincount(edges.reshape(-1), minlength=nv)
    is_boundary = np.zeros(nv, dtype=bool)
    is_boundary[edges[on_boundary].reshape(-1)] = True
    beta = np.where(is_boundary, 0.0, _warren_beta(valence))
    curve = boundary == "curve"
    centre = np.where(is_boundary, 0.75 if curve else 1.0, 1.0 - valence * beta)
    i, j = edges.T.reshape(-1), edges[:, ::-1].T.reshape(-1)  # each edge in both directions
    along = np.concatenate([on_boundary, on_boundary])
    weight = np.where(is_boundary[i], np.where(along & curve, 1.0 / 8.0, 0.0), beta[i])
    return np.concatenate([np.arange(nv), i]), np.concatenate([np.arange(nv), j]), np.concatenate([centre, weight])


def _midpoint_rows(nv, edges):
    ne = len(edges)
    rows = np.concatenate([np.arange(nv), nv + np.arange(ne), nv + np.arange(ne)])
    cols = np.concatenate([np.arange(nv), edges[:, 0], edges[:, 1]])
    vals = np.concatenate([np.ones(nv), np.full(2 * ne, 0.5)])
    return rows, cols, vals, nv + ne


def _matrix(F, nv, scheme, boundary, edges, edge_of, count) -> sp.csr_matrix:
    if scheme == "midpoint":
        rows, cols, vals, n = _midpoint_rows(nv, edges)
    else:
        parts = _loop_vertex_rows(nv, edges, count, boundary), _loop_edge_rows(F, nv, edges, edge_of, count)
        rows, cols, vals = (np.concatenate(p) for p in zip(*parts))
        n = nv + len(edges)
    S = sp.csr_matrix((vals, (rows, cols)), shape=(n, nv))
    S.eliminate_zeros()
    return S


def subdivision_matrix(F, nv: int | None = None, scheme: str = "midpoint", *, boundary: str = "curve") -> sp.csr_matrix:
    """The prolongation S, (nv + ne, nv) `scipy.sparse.csr_matrix`, of one subdivision step of the
    triangles F (module docstring): `subdivide(V, F, ...)` has positions S @ V, and S @ u carries
    any per-vertex data u (nv, ...) to the refined mesh.  Row i < nv is old vertex i's stencil, row
    nv + e the stencil of the new vertex on edge e (`dg.mesh.edges(F)` order); every row sums to 1
    and is nonnegative.

    **Arguments:** `F` (nf, 3) int; `nv` the number of vertices (default max(F) + 1; vertices in no
    face get identity rows); `scheme` `"midpoint"` or `"loop"`; `boundary` the rule at old boundary
    vertices for Loop, `"curve"` (1/8, 3/4, 1/8) or `"fixed"` (unmoved); midpoint ignores it.

    **Raises:** `ShapeError` (F not (nf, 3)), `MeshError` (no faces, an index negative or >= nv, a
    face repeating a vertex: naming the face), `NonManifoldError` (an edge in more than two faces,
    naming it and its faces; a vertex whose faces form several fans, naming it),
    `InvalidInputError` (unknown scheme or boundary rule).
    """
    _check_options(scheme, boundary)
    F, nv, edges, edge_of, count = _edges_of_faces(F, nv)
    return _matrix(F, nv, scheme, boundary, edges, edge_of, count)


def subdivide(V, F, *, scheme: str = "midpoint", boundary: str = "curve") -> tuple[np.ndarray, np.ndarray]:
    """One 1 → 4 subdivision step of the triangle mesh (V, F): `(V', F')`, V' = S V with
    S = `subdivision_matrix(F, len(V), scheme, boundary=boundary)` (module docstring: old vertices
    first and unchanged in index, then one vertex per edge in `dg.mesh.edges(F)` order; the
    children of each face oriented like it).

    **Arguments:** `V` (nv, d) float (positions, d = 3, or any per-vertex data); `F` (nf, 3) int
    with indices < nv; `scheme` `"midpoint"` (new vertices at edge midpoints, the polyhedron
    unchanged as a point set) or `"loop"` (Loop's smoothing stencils, Warren's β); `boundary`
    for Loop the rule at old boundary vertices, `"curve"` (the cubic B-spline rule of the
    boundary polygon) or `"fixed"`.

    **Returns:** V' (nv + ne, d) float64, F' (4 nf, 3) int64.

    **Raises:** `ShapeError` (V not 2-D), `NonFiniteError` (a NaN or inf entry of V, named), the
    errors of `subdivision_matrix`.
    """
    _check_options(scheme, boundary)
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2:
        raise ShapeError(f"V must be (nv, d), got shape {V.shape}")
    check_finite(V, "V")
    F, nv, edges, edge_of, count = _edges_of_faces(F, len(V))
    S = _matrix(F, nv, scheme, boundary, edges, edge_of, count)
    return np.asarray(S @ V), _split_faces(F, nv, edge_of)
