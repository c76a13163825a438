"""The Dirichlet energy on graphs and on simplicial surfaces (Sec 6.2, 6.3).

**Graphs (Def 6.1).**  For a graph with edge weights ν and a function f on its vertices,

    E(f) = ½ Σ_{(ij)∈E} ν(ij) (f_i − f_j)²,       ∇E = L f,   (L f)_i = Σ_j ν(ij)(f_i − f_j),

declared with `dg.local_sum` over the edges.  With the values on V₀ fixed (`fixed=`), the
critical points are the solutions of the discrete Dirichlet boundary value problem (Thm 6.1); for
positive weights on a connected graph it is the unique minimum (Thm 6.5, Cor 6.4).

**Piecewise affine functions (Sec 6.3, Thm 6.6).**  On a simplicial surface the energy is the
sum over the faces of `½ ∫_F |∇f|² dA` of the affine interpolant, computed from the triangle's
positions (`dg.laplace.triangle_dirichlet_energy`); its Hessian is the cotan Laplacian.

Both problems are quadratic, so `solvers.solve` finishes in one Newton step; `graph_sparse` and
`cotan_sparse` take the same arguments and solve the same linear system directly with one sparse
LU factorisation of the interior block (`dirichlet_solve`, for any Laplacian: also the harmonic
iterations of `energies.area`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from jaxtyping import Array, Float
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

import ddgjax as dg
from ddgjax._checks import check_finite, concrete_value
from ddgjax._host import namespace
from ddgjax._host import namespace, with_set
from ddgjax.errors import NonUniqueSolutionError, ShapeError
from ddgjax.laplace import (
    checked_graph,
    checked_triangle_mesh,
    triangle_dirichlet_energy,
)
from ddgjax.mesh import boundary_indices
from ddgjax.mesh.connectivity import checked_triangles, from_faces

__all__ = ["check_unique", "cotan", "cotan_sparse", "dirichlet_solve", "edge_energy", "graph", "graph_sparse"]


def edge_energy(f2: Float[Array, "2"], weight: Float[Array, ""]) -> Float[Array, ""]:
    """½ ν(ij) (f_i − f_j)²: one edge's term of the graph Dirichlet energy (Def 6.1)."""
    return 0.5 * weight * (f2[0] - f2[1]) ** 2


# Densities of the declarations: module-level, and the weights and the triangles' positions are
# `params` indexed by the cell number (the terms' `data`), so that problems of one structure share
# a compiled solver whatever their weights or geometry, and `solve` is differentiable in them.


def _edge_term(f2, k, params):
    return edge_energy(f2, params["weights"][k])


def _face_term(f3, k, params):
    return triangle_dirichlet_energy(f3, params["triangles"][k])


def _boundary_data(n: int, boundary, values) -> tuple[np.ndarray, jax.Array]:
    """`(V₀, c)`: validated boundary indices and values (c traceable; NumPy when concrete)."""
    b = boundary_indices(boundary, n)
    c = namespace(values).asarray(values, dtype=float).reshape(-1)
    if c.shape != (b.size,):
        raise ShapeError(f"values must have shape ({b.size},), one per boundary vertex, got {np.shape(values)}")
    check_finite(c, "values")
    return b, c


def _start(n: int, b: np.ndarray, c: jax.Array) -> jax.Array:
    """c on V₀ (traced: the solution is differentiable in c through these fixed entries) and the
    mean of c elsewhere (no derivative: the solution's does not depend on the start)."""
    xp = namespace(c)
    fill = 0.0 if not c.size else np.mean(c) if xp is np else jax.lax.stop_gradient(c.mean())
    return with_set(xp.full(n, fill), b, c)


def _problem(energy, params, L, n: int, boundary, values, name: str) -> dg.Problem:
    b, c = _boundary_data(n, boundary, values)
    x0 = _start(n, b, c)
    check_unique(L, b)
    fixed = np.zeros(n, dtype=bool)
    fixed[b] = True
    return dg.Problem(energy, x0, params=params, fixed=fixed, name=name)


def _known_or(value: jax.Array, stand_in: np.ndarray) -> np.ndarray:
    """The concrete value of a parameter, or `stand_in` when it is traced abstractly (under `jit`
    or `vmap`): the structure is then checked with the stand-in, the values are not."""
    known = concrete_value(value)
    return stand_in if known is None else known


def graph(edges, weights, boundary, values, *, n_vertices: int | None = None) -> dg.Problem:
    """The Dirichlet energy of a weighted graph (Def 6.1) with f = c fixed on V₀ = `boundary`.

    **Arguments:** `edges` (ne, 2) int; `weights` ν (ne,); `boundary` vertex indices (or a bool
    mask); `values` c (nb,), ordered like `boundary`; `n_vertices` (default max index + 1).
    Unknowns: f (nv,); `params = {"weights": ν}`.  Differentiable in ν and c (traced values
    enter `params` and the fixed entries of `x0`).

    **Raises:** `NonUniqueSolutionError` when a connected component has no boundary vertex
    (naming a vertex of it); `InvalidInputError` for a boundary vertex that does not exist or a
    bad edge (naming it); `NonFiniteError` for NaN weights or values; `ShapeError`.  Weights and
    values are checked when concrete; under `jit`/`vmap` every edge counts as connecting.
    """
    weights = jnp.asarray(weights, dtype=float)
    edges, known, n = checked_graph(edges, _known_or(weights, np.ones(np.shape(weights))), n_vertices)
    energy = dg.local_sum(_edge_term, edges, data=np.arange(len(edges)))
    L = dg.laplace.graph_laplacian(edges, known, n)
    return _problem(energy, {"weights": weights}, L, n, boundary, values, f"graph Dirichlet energy (nv={n}, ne={len(edges)})")


def _mesh_laplacian(V: jax.Array, F) -> tuple[np.ndarray, sp.spmatrix]:
    """`(F, L)`: the checked faces and the cotan Laplacian of concrete positions V, or the mesh
    graph's Laplacian (same connectivity) when V is traced abstractly (under `jit`/`vmap`)."""
    known = concrete_value(V)
    if known is not None:
        V, F = checked_triangle_mesh(known, F, manifold=True)
        return F, dg.laplace.cotan_laplacian(V, F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ShapeError(f"V must be an (nv, 3) array of positions, got shape {V.shape}")
    F, n = checked_triangles(F, V.shape[0])
    E = from_faces(F, n_vertices=n).edges
    return F, dg.laplace.graph_laplacian(E, np.ones(len(E)), n)


def cotan(V, F, boundary, values) -> dg.Problem:
    """The Dirichlet energy of piecewise affine functions on the triangle mesh (V, F) (Thm 6.6)
    with f = c fixed on V₀ = `boundary`; unknowns f (nv,); `params = {"triangles": V[F]}` (nf, 3, 3),
    the positions.  Differentiable in V and c (traced values enter `params` and `x0`).

    **Raises:** as `graph`, and `NonFiniteError` (NaN position, naming the vertex),
    `DegenerateFaceError` (zero-area face), `MeshError` / `NonManifoldError` (naming the face,
    edge or vertex).  Positions are checked when concrete.
    """
    V = namespace(V).asarray(V, dtype=float)  # NumPy when concrete: V[F] gathers without compiling
    F, L = _mesh_laplacian(V, F)
    energy = dg.local_sum(_face_term, F, data=np.arange(len(F)))
    name = f"cotan Dirichlet energy (nv={V.shape[0]}, nf={len(F)})"
    return _problem(energy, {"triangles": V[F]}, L, V.shape[0], boundary, values, name)


def check_unique(L: sp.spmatrix, boundary: np.ndarray) -> None:
    """Raise `NonUniqueSolutionError` unless every connected component of the graph of L holds a
    boundary vertex (otherwise constants can be added on it: Cor 6.3), naming a vertex of it."""
    n_comp, label = connected_components(abs(L) > 0, directed=False)
    has_boundary = np.zeros(n_comp, dtype=bool)
    has_boundary[label[boundary]] = True
    if not has_boundary.all():
        c = int(np.argmin(has_boundary))
        v = int(np.argmax(label == c))
        raise NonUniqueSolutionError(
            f"the component containing vertex {v} has no boundary vertex: the Dirichlet problem's "
            "solution is not unique there (any constant can be added, Cor 6.3); add a boundary vertex to it"
        )


def dirichlet_solve(L: sp.spmatrix, boundary, values) -> np.ndarray:
    """The solution of the discrete Dirichlet boundary value problem (dDBVP, Cor 6.4, Thm 6.5):

        (L f)_i = 0 for i ∉ V₀,   f_i = c_i for i ∈ V₀,

    by one sparse LU factorisation of the interior block, `L_II f_I = −L_IB c`.

    **Arguments:** `L` (nv, nv) sparse (any Laplacian: a graph's, the cotan Laplacian of a mesh,
    the Laplace–Beltrami operator); `boundary` V₀ (indices, or a bool mask); `values` c, (nb,) or
    (nb, k) for k right-hand sides (e.g. the coordinates of a surface, Fig 6.5), ordered like
    `boundary` (like its True entries for a mask).
    **Returns:** f, (nv,) or (nv, k).
    **Raises:** `InvalidInputError` for a boundary index that does not exist, `NonFiniteError`
    for NaN values, `NonUniqueSolutionError` when a component has no boundary vertex or the
    interior block is singular (possible with negative weights).
    """
    L = sp.csr_matrix(L)
    n = L.shape[0]
    b = boundary_indices(boundary, n)
    c = np.array(values, dtype=np.float64)
    if c.shape[:1] != (b.size,) or c.ndim > 2:
        raise ShapeError(f"values must have shape ({b.size},) or ({b.size}, k), one row per boundary vertex, got {c.shape}")
    check_finite(c, "values")
    check_unique(L, b)
    interior = np.ones(n, dtype=bool)
    interior[b] = False
    inner = np.flatnonzero(interior)
    f = np.zeros((n,) + c.shape[1:])
    f[b] = c
    if inner.size == 0:
        return f
    rows = L[inner]
    try:
        lu = splu(rows[:, inner].tocsc(), permc_spec="MMD_AT_PLUS_A")
    except RuntimeError as err:
        raise NonUniqueSolutionError(
            f"the interior block of the Laplacian is singular ({err}): the Dirichlet problem has no unique "
            "solution (possible with negative weights, eq 6.3)"
        ) from None
    f[inner] = lu.solve(-(rows[:, b] @ c))
    return f


def graph_sparse(edges, weights, boundary, values, *, n_vertices: int | None = None) -> np.ndarray:
    """The solution f (nv,) of the problem `graph(...)` by one sparse LU solve (same arguments,
    same errors): the fast path for large graphs."""
    L = dg.laplace.graph_laplacian(edges, weights, n_vertices)
    b, c = _boundary_data(L.shape[0], boundary, values)
    return dirichlet_solve(L, b, c)


def cotan_sparse(V, F, boundary, values) -> np.ndarray:
    """The solution f (nv,) of the problem `cotan(...)` by one sparse LU solve (same arguments,
    same errors)."""
    V, F = checked_triangle_mesh(V, F, manifold=True)
    L = dg.laplace.cotan_laplacian(V, F)
    b, c = _boundary_data(V.shape[0], boundary, values)
    return dirichlet_solve(L, b, c)
