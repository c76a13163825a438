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
LU factorisation of the interior block (`dg.laplace.dirichlet_solve`).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax._checks import check_finite
from ddgjax.errors import ShapeError
from ddgjax.laplace import (
    boundary_indices,
    check_unique,
    checked_graph,
    checked_triangle_mesh,
    triangle_dirichlet_energy,
)

__all__ = ["cotan", "cotan_sparse", "edge_energy", "graph", "graph_sparse"]


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


def _boundary_data(n: int, boundary, values) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`(V₀, c, x0)`: validated boundary indices and values and the start (c on V₀, the mean
    of c elsewhere)."""
    b = boundary_indices(boundary, n)
    c = np.array(values, dtype=np.float64).reshape(-1)
    if c.shape != (b.size,):
        raise ShapeError(f"values must have shape ({b.size},), one per boundary vertex, got {np.shape(values)}")
    check_finite(c, "values")
    x0 = np.full(n, c.mean() if c.size else 0.0)
    x0[b] = c
    return b, c, x0


def _problem(energy, params, L, n: int, boundary, values, name: str) -> dg.Problem:
    b, _, x0 = _boundary_data(n, boundary, values)
    check_unique(L, b)
    fixed = np.zeros(n, dtype=bool)
    fixed[b] = True
    return dg.Problem(energy, x0, params=params, fixed=fixed, name=name)


def graph(edges, weights, boundary, values, *, n_vertices: int | None = None) -> dg.Problem:
    """The Dirichlet energy of a weighted graph (Def 6.1) with f = c fixed on V₀ = `boundary`.

    **Arguments:** `edges` (ne, 2) int; `weights` ν (ne,); `boundary` vertex indices (or a bool
    mask); `values` c (nb,), ordered like `boundary`; `n_vertices` (default max index + 1).
    Unknowns: f (nv,); `params = {"weights": ν}` (so `solve` is differentiable in the weights).

    **Raises:** `NonUniqueSolutionError` when a connected component has no boundary vertex
    (naming a vertex of it); `InvalidInputError` for a boundary vertex that does not exist or a
    bad edge (naming it); `NonFiniteError` for NaN weights or values; `ShapeError`.
    """
    edges, weights, n = checked_graph(edges, weights, n_vertices)
    energy = dg.local_sum(_edge_term, edges, data=np.arange(len(edges)))
    L = dg.laplace.graph_laplacian(edges, weights, n)
    params = {"weights": jnp.asarray(weights)}
    return _problem(energy, params, L, n, boundary, values, f"graph Dirichlet energy (nv={n}, ne={len(edges)})")


def cotan(V, F, boundary, values) -> dg.Problem:
    """The Dirichlet energy of piecewise affine functions on the triangle mesh (V, F) (Thm 6.6)
    with f = c fixed on V₀ = `boundary`; unknowns f (nv,); `params = {"triangles": V[F]}` (nf, 3, 3),
    the positions, in which `solve` is differentiable.

    **Raises:** as `graph`, and `NonFiniteError` (NaN position, naming the vertex),
    `DegenerateFaceError` (zero-area face), `MeshError` / `NonManifoldError` (naming the face,
    edge or vertex).
    """
    V, F = checked_triangle_mesh(V, F, manifold=True)
    L = dg.laplace.cotan_laplacian(V, F)
    energy = dg.local_sum(_face_term, F, data=np.arange(len(F)))
    params = {"triangles": jnp.asarray(V[F])}
    name = f"cotan Dirichlet energy (nv={V.shape[0]}, nf={len(F)})"
    return _problem(energy, params, L, V.shape[0], boundary, values, name)


def graph_sparse(edges, weights, boundary, values, *, n_vertices: int | None = None) -> np.ndarray:
    """The solution f (nv,) of the problem `graph(...)` by one sparse LU solve (same arguments,
    same errors): the fast path for large graphs."""
    L = dg.laplace.graph_laplacian(edges, weights, n_vertices)
    b, c, _ = _boundary_data(L.shape[0], boundary, values)
    return dg.laplace.dirichlet_solve(L, b, c)


def cotan_sparse(V, F, boundary, values) -> np.ndarray:
    """The solution f (nv,) of the problem `cotan(...)` by one sparse LU solve (same arguments,
    same errors)."""
    V, F = checked_triangle_mesh(V, F, manifold=True)
    L = dg.laplace.cotan_laplacian(V, F)
    b, c, _ = _boundary_data(V.shape[0], boundary, values)
    return dg.laplace.dirichlet_solve(L, b, c)
