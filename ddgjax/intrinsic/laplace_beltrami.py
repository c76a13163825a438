"""The discrete Laplace–Beltrami operator of a piecewise flat surface (Sec 7.4, Def 7.8) and the
Delaunay tessellation (Def 7.3, Remark 7.7).

The cotan weights ν(e) = ½ (cot α + cot β) (eq 6.2) of any Delaunay triangulation are ≥ 0
(Prop 7.10); they vanish exactly on the edges that triangulate a cocircular polygon of the
Delaunay tessellation, and the others do not depend on how the polygons were triangulated
(Fig 7.20).  So the operator

    (Δ f)(i) = Σ_{e = (ij)} ν(e) (f(i) − f(j))

is a property of the metric alone (Remark 7.9): the same for every Delaunay triangulation and for
every isometric deformation of a polyhedral surface (Example 5.3) [Bobenko–Springborn 2007].
It is `ddgjax.laplace`'s derived cotan Laplacian (the autodiff Hessian of the Dirichlet energy on
squared lengths, Thm 6.6) composed with the flip algorithm: `cotan_laplacian(tri)` on the
lengths of `tri`, `laplace_beltrami(V, F)` on those of the intrinsic Delaunay triangulation.
Sign convention as `ddgjax.laplace.cotan_laplacian`: positive semidefinite, L·1 = 0, L_ij = −ν
off the diagonal; the negative of libigl's `cotmatrix`, equal to geometry-central's / robust-
laplacian's `L`.  Multiple edges between two vertices add their weights; loops drop out.

Surfaces with boundary: only interior edges are flipped (`delaunay.flip_to_delaunay`), boundary
edges keep their single cotangent ν = ½ cot α (eq 6.2), as in libigl.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .._checks import check_positive
from ..errors import DDGError
from ..laplace import laplacian_of_edge_weights
from ..mesh.lengths import face_harmonic_index, triangle_area
from .delaunay import (
    DELAUNAY_TOL,
    as_triangulation,
    edge_cotangent_sums,
    flip_owned,
)
from .ordering import is_local, local_numbering
from .triangulation import (
    Triangulation,
    checked_faces,
    checked_positions,
    cotan_weights,
    from_checked_mesh,
    from_mesh,
    next_halfedge,
    normalised_side_lengths,
)

__all__ = [
    "Tessellation",
    "cotan_laplacian",
    "cotan_weights",
    "delaunay_tessellation",
    "laplace_beltrami",
    "laplace_beltrami_from_lengths",
]


def cotan_laplacian(tri: Triangulation, labels=None, weights=None) -> sp.csr_matrix:
    """The cotan Laplace operator of the geodesic triangulation `tri` (Def 6.2) as an
    (nv, nv) `csr_matrix` L with (L f)_i = Σ_j ν_ij (f_i − f_j), ν the derived weights
    `cotan_weights(tri)` (the autodiff Hessian of the Dirichlet energy on the lengths of `tri`),
    assembled by `ddgjax.laplace.laplacian_of_edge_weights` (multiple edges add their weights,
    loops drop out); `labels` (nv,) the row of each vertex of `tri` (default the identity);
    `weights` the ν (ne,) if already known.
    """
    F = tri.F.reshape(-1)
    h = tri.halfedges[:, 0]
    i, j = F[h], F[next_halfedge(h)]
    if labels is not None:
        i, j = labels[i], labels[j]
    w = cotan_weights(tri) if weights is None else weights
    return laplacian_of_edge_weights(i, j, w, tri.n_vertices)


def _delaunay_laplacian(tri: Triangulation, tol: float, labels=None, owned: bool = False) -> sp.csr_matrix:
    """`owned`: `tri` was built here, its arrays may be flipped in place."""
    result = flip_owned(tri, tol, copy=not owned)
    return cotan_laplacian(result.triangulation, labels, result.cotan_weights())


def laplace_beltrami_from_lengths(F, lengths=None, *, tol: float = DELAUNAY_TOL) -> sp.csr_matrix:
    """Def 7.8 for a piecewise flat surface given by faces and edge lengths (ordered like
    `ddgjax.mesh.edges(F)`) or by a `Triangulation`: the cotan Laplacian of its intrinsic
    Delaunay triangulation.  Invariant under l ↦ s l (2-D cotan weights).

    **Raises:** the errors of `triangulation.from_faces`; `InvalidInputError` unless `tol` is
    finite and positive.
    """
    check_positive(tol, "tol")
    return _delaunay_laplacian(as_triangulation(F, lengths), tol)


def laplace_beltrami(V, F, *, tol: float = DELAUNAY_TOL) -> sp.csr_matrix:
    """The discrete Laplace–Beltrami operator (Def 7.8) of the simplicial surface (V, F):
    (nv, nv) `csr_matrix`, (L f)_i = Σ_j ν_ij (f_i − f_j), ν the cotan weights of the intrinsic
    Delaunay triangulation of its piecewise flat metric (Bobenko–Springborn).  Boundary edges are
    kept and only interior edges flipped (module docstring).  A mesh whose labels are not
    spatially coherent is renumbered internally along a Morton curve (`ordering`, for cache
    locality); the result is in the caller's labels.

    Invariant under V ↦ sV (2-D cotan weights; lengths from V / s, `triangulation.from_mesh`).

    **Raises:** the errors of `triangulation.from_mesh` (bad faces, non-manifold edges,
    inconsistent orientation, degenerate triangles, NaN coordinates), naming the caller's
    indices; `InvalidInputError` unless `tol` is finite and positive.
    """
    check_positive(tol, "tol")
    V = checked_positions(V)
    F, _ = checked_faces(F, V.shape[0])
    if is_local(F, V.shape[0]):
        return _delaunay_laplacian(from_checked_mesh(V, F), tol, owned=True)
    order, F_local = local_numbering(V, F)
    try:
        tri = from_checked_mesh(np.take(V, order, axis=0), F_local)
    except DDGError:
        from_mesh(V, F)  # the same error, with the caller's indices
        raise
    return _delaunay_laplacian(tri, tol, labels=order, owned=True)


@dataclass(frozen=True, eq=False)
class Tessellation:
    """The Delaunay tessellation (Def 7.3) obtained from a Delaunay triangulation by deleting the
    edges of zero weight (Remark 7.7).

    **Fields:** `triangulation` (the Delaunay triangulation it was built from); `edge_mask` (ne,)
    bool, True for the edges of the tessellation; `cell` (nf,) the cell (cocircular polygon) of
    each triangle; `n_cells`; `cell_size` (n_cells,) the number of triangles in each cell (a
    cocircular k-gon has k − 2).
    """

    triangulation: Triangulation
    edge_mask: np.ndarray
    cell: np.ndarray
    n_cells: int
    cell_size: np.ndarray


def delaunay_tessellation(tri: Triangulation, *, zero_tol: float = 1e-9) -> Tessellation:
    """Merge the triangles of the Delaunay triangulation `tri` across the interior edges with
    |cot α + cot β| ≤ zero_tol · (h(Δ₁) + h(Δ₂))/4 (zero weight up to rounding, the scale of
    `delaunay`'s tie test) into cocircular polygons (Remark 7.7, Fig 7.20); scale-invariant.

    **Raises:** `InvalidInputError` unless `zero_tol` is finite and positive.
    """
    check_positive(zero_tol, "zero_tol")
    L = normalised_side_lengths(tri)
    a, b, c = L.T
    per_face = 0.25 * face_harmonic_index(a, b, c, triangle_area(a, b, c))
    scale = np.bincount(tri.edge, np.repeat(per_face, 3), minlength=tri.n_edges)
    interior = tri.halfedges[:, 1] >= 0
    zero = interior & (np.abs(edge_cotangent_sums(tri)) <= zero_tol * scale)
    h = tri.halfedges[zero]
    graph = sp.coo_matrix((np.ones(len(h)), (h[:, 0] // 3, h[:, 1] // 3)), shape=(tri.n_faces,) * 2)
    n_cells, cell = connected_components(graph, directed=False)
    return Tessellation(tri, ~zero, cell, int(n_cells), np.bincount(cell, minlength=n_cells))
