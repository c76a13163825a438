"""Graph and cotan Laplacians (Sec 6.2, 6.3 of the reference), assembled as scipy sparse matrices.

**Sign.**  We follow the reference (Def 6.1, Def 6.2): the Laplacian is positive semidefinite,

    (L f)_i = Σ_{j:(ij)∈E} ν(ij) (f_i − f_j),        E(f) = ½ Σ_{(ij)∈E} ν(ij) (f_i − f_j)² = ½ fᵀ L f,

so `L = ∇²E` and `L·1 = 0`.  libigl's `cotmatrix` is the negative semidefinite `−L`; the smooth
Laplacian is `Δf(x_i) ≈ −(L f)_i / M_i` with `M_i` the vertex area (`barycentric_areas`).

**Where the cotan weights come from.**  The Dirichlet energy of the affine interpolant on one
triangle (Sec 6.3) is declared from the triangle's squared side lengths alone
(`ddgjax.mesh.lengths.dirichlet_energy`: `½ A |∇f|²`, the Gram matrix of two edges written in
squared lengths, no angles).  Its 3×3 Hessian in the vertex values, taken by autodiff
(`ddgjax.mesh.lengths.stiffness`), is the local stiffness matrix whose off-diagonal entry at the
edge opposite corner k is `−½ cot α_k` (Thm 6.6); the sparse Laplacian is the sum of these blocks
(finite-element assembly, `laplacian_of_corner_weights`: a `bincount` into the csr structure of F,
which is built once per connectivity and cached), i.e. the cotan weights (6.2)

    ν(ij) = ½ (cot α_ij + cot α_ji) on interior edges,   ν(ij) = ½ cot α_ij on boundary edges.

The same derivation serves every Laplacian of ddgjax: here composed with the squared side lengths
of a mesh (V, F); in `ddgjax.intrinsic` with the lengths of an intrinsic triangulation (after
edge flips: the Laplace–Beltrami operator).  The autodiff Hessian is jit-compiled (XLA fuses it
into one pass over the faces).

**Scale.**  The cotan weights of a triangle mesh are invariant under V ↦ sV (in 2-D the Dirichlet
energy is), areas scale by s².  The positions are divided by a power of two first
(`mesh.lengths.normalised`, exact, and 1 at ordinary sizes), so that nothing overflows or
underflows for coordinates of any size; areas are scaled back (`mesh.lengths.scaled_back`).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np
import scipy.sparse as sp
from jaxtyping import Array, Float, Int

from .errors import (
    InvalidInputError,
    NonFiniteError,
    ShapeError,
)
from .mesh.connectivity import boundary_indices, checked_triangles, from_faces
from .mesh.lengths import (
    check_face_areas,
    corner_weights,
    dirichlet_energy,
    normalised,
    on_padded_rows,
    scaled_back,
    squared_side_lengths,
    stiffness,
    triangle_area,
)

__all__ = [
    "barycentric_areas",
    "boundary_indices",
    "check_nondegenerate",
    "checked_triangle_mesh",
    "cotan_laplacian",
    "cotan_weights",
    "edge_cotan_weights",
    "face_areas",
    "graph_laplacian",
    "laplacian_of_corner_weights",
    "laplacian_of_edge_weights",
    "triangle_dirichlet_energy",
    "triangle_stiffness",
]

def triangle_dirichlet_energy(f: Float[Array, "3"], P: Float[Array, "3 n"]) -> Float[Array, ""]:
    """Dirichlet energy ½ ∫ |∇f|² dA of the affine interpolant of the values f on the triangle P
    (Sec 6.3): `ddgjax.mesh.lengths.dirichlet_energy` of its squared side lengths, those of
    P / s (`normalised`; the energy is scale-invariant)."""
    return dirichlet_energy(f, squared_side_lengths(normalised(P)[0]))


@jax.jit
def _corner_weights_of_squares(l2):
    """(nf, 3) ½ cot α_k derived by autodiff (`mesh.lengths.corner_weights`) and sin² of each
    face's angle at corner 0, for the triangles with squared sides l2 (nf, 3)."""
    return corner_weights(l2)


@jax.jit
def _stiffness_of_squares(l2):
    """(nf, 3, 3) `mesh.lengths.stiffness` and sin² of each face's angle at corner 0."""
    return stiffness(l2), corner_weights(l2)[1]


def _as_positions(V) -> np.ndarray:
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] not in (2, 3):
        raise ShapeError(f"V must have shape (nv, 3) (or (nv, 2) for planar meshes), got {V.shape}")
    if V.shape[1] == 2:
        V = np.hstack([V, np.zeros((V.shape[0], 1))])
    bad = np.flatnonzero(~np.all(np.isfinite(V), axis=1))
    if bad.size:
        raise NonFiniteError(f"vertex {bad[0]} has the non-finite position {V[bad[0]].tolist()}")
    return V


def checked_triangle_mesh(V, F, *, manifold: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """`(V, F)` as float64 (nv, 3) and int64 (nf, 3) arrays, validated (the inputs are not changed).

    **Raises:** `ShapeError` (shapes), `NonFiniteError` (NaN/inf position, naming the vertex),
    `MeshError` (an index out of range or a repeated vertex, naming the face: `mesh.checked_triangles`); with `manifold=True` also the checks of
    `mesh.from_faces` (`NonManifoldError` naming the edge or vertex, a face repeating a vertex).
    Zero-area faces are detected where the geometry is computed (`DegenerateFaceError`).
    """
    V = _as_positions(V)
    F, _ = checked_triangles(F, V.shape[0])
    if manifold:
        from_faces(F, n_vertices=V.shape[0])
    return V, F


def triangle_stiffness(V, F) -> np.ndarray:
    """(nf, 3, 3): the Hessian of `triangle_dirichlet_energy` in the vertex values, per face, by
    autodiff; entry [k+1, k+2] (indices mod 3) is −½ cot α_k (Sec 6.3).

    **Raises:** as `checked_triangle_mesh`, and `DegenerateFaceError` naming a zero-area face.
    """
    return _per_face(_stiffness_of_squares, V, F)[0]


def _per_face(kernel, V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(kernel's per-face output, F)` for a validated mesh whose faces all have non-zero area.

    The kernel maps the faces' squared side lengths (nf, 3), those of V / s (`normalised`; its
    output must be invariant under V ↦ sV), to (per-face output, sin² of each face's angle at
    corner 0); it runs on the rows padded to `padded_size(nf)` (`on_padded_rows`), so that
    meshes of nearby sizes share its compiled program."""
    V, F = checked_triangle_mesh(V, F)
    out, sin2 = on_padded_rows(kernel, squared_side_lengths(normalised(V)[0][F]))
    check_face_areas(sin2, F)
    return out, F


def check_nondegenerate(V, F) -> None:
    """Raise `DegenerateFaceError` naming the first face of zero area (sin of its angle at
    corner 0 below ~1e-7), after the checks of `checked_triangle_mesh`."""
    _per_face(_corner_weights_of_squares, V, F)


def _corner_weights(V, F) -> tuple[np.ndarray, np.ndarray]:
    """Each face's contribution ½ cot α_k to the edge opposite corner k, (nf, 3), and F."""
    return _per_face(_corner_weights_of_squares, V, F)


@dataclass(frozen=True, eq=False)
class _Pattern:
    """The csr structure of L for edge entries (i_k, j_k) and where each entry lands in it.

    `slot[k]`: the position of (i_k, j_k) in `indices`; `transpose[s]`: the position of (c, r)
    for the entry (r, c) at s; `diagonal[v]`: the position of (v, v).
    """

    key: np.ndarray
    i: np.ndarray
    j: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    slot: np.ndarray
    transpose: np.ndarray
    diagonal: np.ndarray


_PATTERNS: list[_Pattern] = []  # the few most recent, newest last (a minimal-surface iteration reuses one)
_PATTERN_CACHE_SIZE = 4


def _build_pattern(key, i, j, n: int) -> _Pattern:
    k = np.arange(n, dtype=i.dtype)
    rows, cols = np.concatenate([i, j, k]), np.concatenate([j, i, k])
    structure = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    structure.sum_duplicates()
    row_of = np.repeat(np.arange(n, dtype=np.int64), np.diff(structure.indptr))
    flat = row_of * n + structure.indices  # sorted: rows ascending, columns sorted within rows
    position = lambda r, c: np.searchsorted(flat, r.astype(np.int64) * n + c)
    return _Pattern(key.copy(), i, j, structure.indptr, structure.indices, position(i, j),
                    position(structure.indices, row_of), position(k, k))


def _pattern(key: np.ndarray, n: int, entries) -> _Pattern:
    """The cached `_Pattern` of this connectivity (`key`: F or the edge list); `entries()` gives
    the edge entries `(i, j)` when it has to be built."""
    for pattern in _PATTERNS:
        if pattern.indptr.size == n + 1 and pattern.key.shape == key.shape and np.array_equal(pattern.key, key):
            return pattern
    pattern = _build_pattern(key, *entries(), n)
    _PATTERNS.append(pattern)
    del _PATTERNS[:-_PATTERN_CACHE_SIZE]
    return pattern


def _laplacian(pattern: _Pattern, w) -> sp.csr_matrix:
    """L = diag(Σ_j ν_ij) − W from the entries w at (pattern.i, pattern.j) (several entries of one
    edge are summed: one per face), assembled into the cached csr structure."""
    n = pattern.indptr.size - 1
    oriented = np.bincount(pattern.slot, w, pattern.indices.size)
    data = -(oriented + oriented[pattern.transpose])
    data[pattern.diagonal] = np.bincount(pattern.i, w, n) + np.bincount(pattern.j, w, n)
    # copies: scipy methods such as eliminate_zeros change a matrix's index arrays in place
    return sp.csr_matrix((data, pattern.indices.copy(), pattern.indptr.copy()), shape=(n, n))


def _face_edges(F):
    """`(i, j)`, (3 nf,): the edge opposite each corner k, (F[k+1], F[k+2])."""
    F = F.astype(np.int32) if F.size and F.max() < 2**31 - 1 else F
    return F[:, [1, 2, 0]].reshape(-1), F[:, [2, 0, 1]].reshape(-1)


def laplacian_of_corner_weights(F, w, n_vertices: int) -> sp.csr_matrix:
    """L = Σ_faces of the stiffness blocks: the Laplacian (nv, nv) csr with the weight w[f, k]
    (nf, 3) on the side opposite corner k of face f, (L f)_i = Σ_j ν_ij (f_i − f_j) (an
    interior edge's two faces add up).  The csr structure of F is cached (the last few), for
    repeated assembly on one connectivity."""
    return _laplacian(_pattern(F, n_vertices, lambda: _face_edges(F)), np.asarray(w).reshape(-1))


def laplacian_of_edge_weights(i, j, w, n_vertices: int) -> sp.csr_matrix:
    """The Laplacian (nv, nv) csr with the weight w[e] on the edge (i[e], j[e]),
    (L f)_i = Σ_j ν_ij (f_i − f_j): several edges between two vertices add their weights, loops
    (i = j) drop out.  Assembled directly in canonical CSR (`ddgjax.csr_assembly`, no cache): for
    a connectivity used once, such as an intrinsic triangulation after flips."""
    from .csr_assembly import edge_laplacian_csr

    n = n_vertices
    index = np.int32 if n < np.iinfo(np.int32).max else np.int64  # scipy's own index type
    data, indices, indptr = edge_laplacian_csr(np.asarray(i).astype(index), np.asarray(j).astype(index), w, n)
    L = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    L.has_sorted_indices = True
    L.has_canonical_format = True
    return L


def cotan_laplacian(V, F) -> sp.csr_matrix:
    """The cotan Laplacian (Def 6.2), (nv, nv) csr, positive semidefinite:
    (L f)_i = Σ_j ν(ij) (f_i − f_j), the autodiff Hessian of the Dirichlet energy on the squared
    side lengths of (V, F) (Thm 6.6), assembled by `laplacian_of_corner_weights`.

    libigl's `cotmatrix(V, F)` is `−L`.  `V` (nv, 3) or (nv, 2), `F` (nf, 3) int.  The csr
    structure of a connectivity F is computed on first use and cached (the last few F), so that
    repeated assembly on one mesh (Fig 6.5) costs a jit call and a `bincount`.
    **Raises:** as `triangle_stiffness` (manifoldness is not checked here: the Laplacian of any
    triangle soup is defined; the problem constructors of `energies` check it).
    """
    w, F = _corner_weights(V, F)
    return laplacian_of_corner_weights(F, w, np.shape(V)[0])


def cotan_weights(V, F) -> sp.csr_matrix:
    """The symmetric (nv, nv) matrix W of cotan weights (6.2): W_ij = ν(ij) on edges, 0 elsewhere.

    ν(ij) = ½ (cot α_ij + cot α_ji) on interior edges, ½ cot α_ij on boundary edges (Thm 6.6);
    negative where α_ij + α_ji > π (eq 6.3).  **Raises:** as `triangle_stiffness`.
    """
    L = cotan_laplacian(V, F)
    W = sp.diags(L.diagonal()) - L
    W.eliminate_zeros()
    return W.tocsr()


def edge_cotan_weights(V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(edges, ν)`: the edges of F as in `mesh.edges(F)` (sorted, i < j) and their cotan weights
    (edges of weight exactly 0, such as the diagonals of a square grid, included)."""
    L = cotan_laplacian(V, F).tocoo()  # the cached structure holds every edge, zero or not
    upper = L.row < L.col
    edges_ = np.stack([L.row[upper], L.col[upper]], axis=1).astype(np.int64)
    order = np.lexsort((edges_[:, 1], edges_[:, 0]))
    return edges_[order], -L.data[upper][order]


def graph_laplacian(edges: Int[np.ndarray, "ne 2"], weights: np.ndarray, n_vertices: int | None = None) -> sp.csr_matrix:
    """The Laplacian of a weighted graph (Def 6.1): (L f)_i = Σ_{j:(ij)∈E} ν(ij) (f_i − f_j).

    **Raises:** `ShapeError` for edges not (ne, 2) int or weights not (ne,), `InvalidInputError`
    for a negative index, a loop (i, i) or a vertex index ≥ n_vertices (naming the edge),
    `NonFiniteError` for a NaN weight (naming the edge).
    """
    edges, weights, n = checked_graph(edges, weights, n_vertices)
    return _laplacian(_pattern(edges, n, lambda: (edges[:, 0], edges[:, 1])), weights)


def checked_graph(edges, weights, n_vertices=None) -> tuple[np.ndarray, np.ndarray, int]:
    """`(edges, weights, n_vertices)` validated copies (see `graph_laplacian`)."""
    edges = np.array(edges)
    if edges.ndim != 2 or edges.shape[1] != 2 or not np.issubdtype(edges.dtype, np.integer):
        raise ShapeError(f"edges must be an (ne, 2) integer array, got {edges.dtype} {edges.shape}")
    weights = np.array(weights, dtype=np.float64)
    if weights.shape != (edges.shape[0],):
        raise ShapeError(f"weights must have shape ({edges.shape[0]},), one per edge, got {weights.shape}")
    bad = np.flatnonzero(~np.isfinite(weights))
    if bad.size:
        raise NonFiniteError(f"edge {bad[0]} {edges[bad[0]].tolist()} has the non-finite weight {weights[bad[0]]}")
    n = int(edges.max()) + 1 if n_vertices is None and edges.size else int(n_vertices or 0)
    for k, reason in ((np.flatnonzero((edges < 0).any(1)), "a negative vertex index"),
                      (np.flatnonzero((edges >= n).any(1)), f"a vertex index >= n_vertices = {n}"),
                      (np.flatnonzero(edges[:, 0] == edges[:, 1]), "a loop (both ends equal)")):
        if k.size:
            raise InvalidInputError(f"edge {k[0]} {edges[k[0]].tolist()} has {reason}")
    return edges.astype(np.int64), weights, n


def face_areas(V, F) -> np.ndarray:
    """(nf,) A(F) of each triangle from its side lengths (Kahan's Heron, `mesh.lengths`), those
    of V / s scaled back by s².

    **Raises:** as `checked_triangle_mesh`, and `InvalidInputError` where an area is not a
    float64 (`mesh.lengths.scaled_back`: coordinates beyond ~1e±154)."""
    V, F = checked_triangle_mesh(V, F)
    V, s = normalised(V)
    L = np.sqrt(squared_side_lengths(V[F]))
    return scaled_back(triangle_area(L[:, 0], L[:, 1], L[:, 2]), s, 2, "a face area")


def barycentric_areas(V, F) -> np.ndarray:
    """(nv,): M_i = ⅓ Σ_{F ∋ i} A(F), the lumped (barycentric) vertex area; −(L f)_i / M_i → Δf."""
    V, F = checked_triangle_mesh(V, F)
    return np.bincount(F.reshape(-1), np.repeat(face_areas(V, F) / 3.0, 3), V.shape[0])
