"""The area of simplicial surfaces and simplicial minimal surfaces (Sec 6.4, Thm 6.7, Fig 6.5).

**Energy.**  A(S) = Σ_F ½ |(v1 − v0) × (v2 − v0)|, declared with `dg.local_sum` over the faces;
the unknowns are the vertex positions (nv, 3), the boundary vertices are fixed.  Thm 6.7: A is the
sum of the Dirichlet energies of the three coordinate functions, and its gradient is the cotan
Laplacian of the surface applied to its own positions, ∇_{f(i)} A = (L f)(i).  So S is critical
for the area (a simplicial minimal surface in the wide sense, [PP93]) iff its coordinates are
harmonic for its own cotan Laplacian, L f = 0 at the interior vertices.

**Algorithms** (`minimal_surface`):
- `method="cotan"`: Fig 6.5, the Pinkall–Polthier iteration: solve the Dirichlet problem of the
  cotan Laplacian of the current surface with the boundary fixed (one sparse LU, three right-hand
  sides) and replace the surface by the solution, until the area gradient at the interior
  vertices is below `tol` (max-norm, the KKT residual of `simplicial`).
- `method="newton"`: `solvers.solve` on `simplicial(...)`: Newton on ∇A = 0 with the Hessian by
  autodiff (quadratic convergence from a start close enough).

In practice Fig 6.5 brings the area gradient down fast to ~1e-5 (for O(1) surfaces) and then
creeps: the remaining motion is mostly tangential and contracts by ~1 % per step on the catenoid
of `tests/test_area.py`.  Newton started from such an iterate converges in two or three steps;
started from a coarse guess (the cylinder) it does not (area is not convex).  So: `"cotan"` to a
loose `tol`, then `"newton"` from its result.
- `method="delaunay"`: Fig 7.23, the same iteration with the intrinsic Laplace–Beltrami operator
  and edge flips, `ddgjax.intrinsic.minimal.minimal_surface_delaunay` (issue 7).
"""

from __future__ import annotations

import numpy as np
from jaxtyping import Array, Float
from scipy.optimize import brentq

import ddgjax as dg
from ddgjax.errors import ConvergenceError, InvalidInputError
from ddgjax.laplace import (
    barycentric_areas,
    boundary_indices,
    check_nondegenerate,
    checked_triangle_mesh,
    cotan_laplacian,
    dirichlet_solve,
    triangle_area,
)

__all__ = ["METHODS", "catenoid_neck", "face_area", "mesh_boundary", "minimal_surface", "neck_radius", "pinkall_polthier_step", "simplicial"]

METHODS = ("cotan", "newton", "delaunay")


def face_area(P: Float[Array, "3 3"], params=None) -> Float[Array, ""]:
    """½ |(v1 − v0) × (v2 − v0)|: one face's area (the density of `simplicial`)."""
    return triangle_area(P)


def mesh_boundary(F, n_vertices: int) -> np.ndarray:
    """Indices of the vertices on boundary edges of F (the default fixed set)."""
    from ddgjax.mesh.connectivity import from_faces
    from ddgjax.mesh.curvature import boundary_vertex_mask

    return np.flatnonzero(boundary_vertex_mask(from_faces(F, n_vertices=n_vertices)))


def _checked(V, F, boundary) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    V, F = checked_triangle_mesh(V, F, manifold=True)
    check_nondegenerate(V, F)
    b = mesh_boundary(F, V.shape[0]) if boundary is None else boundary_indices(boundary, V.shape[0])
    return V, F, b


def simplicial(V, F, boundary=None) -> dg.Problem:
    """The area A(S) = Σ_F ½|(v1 − v0) × (v2 − v0)| of the triangle mesh (V, F) as a functional
    of the vertex positions (nv, 3), with the vertices `boundary` fixed (default: the vertices on
    boundary edges of F).  Its critical points are simplicial minimal surfaces (Thm 6.7).

    **Raises:** `NonFiniteError` (NaN position, naming the vertex), `DegenerateFaceError` (a
    zero-area face, where the area is not differentiable), `MeshError` / `NonManifoldError`
    (naming the face, edge or vertex), `InvalidInputError` (a boundary vertex that does not exist).
    """
    V, F, b = _checked(V, F, boundary)
    fixed = np.zeros(V.shape, dtype=bool)
    fixed[b] = True
    return dg.Problem(dg.local_sum(face_area, F), V, fixed=fixed, name=f"simplicial area (nv={len(V)}, nf={len(F)})")


def pinkall_polthier_step(V, F, boundary) -> tuple[np.ndarray, float]:
    """One step of Fig 6.5: `(Ṽ, r)` with Ṽ harmonic for the cotan Laplacian L of (V, F), Ṽ = V on
    `boundary`, and r = max |(L V)_i| over the interior vertices, the area gradient at V (Thm 6.7).

    **Raises:** `DegenerateFaceError` when a face of (V, F) has zero area.
    """
    V = np.asarray(V, dtype=np.float64)
    L = cotan_laplacian(V, F)
    interior = np.ones(len(V), dtype=bool)
    interior[boundary] = False
    gradient = L @ V
    residual = float(np.max(np.abs(gradient[interior]))) if interior.any() else 0.0
    return dirichlet_solve(L, boundary, V[boundary]), residual


def _cotan_iteration(V, F, b, tol, max_iter):
    residuals, areas = [], []
    for _ in range(max_iter + 1):
        V_next, residual = pinkall_polthier_step(V, F, b)
        residuals.append(residual)
        areas.append(float(barycentric_areas(V, F).sum()))
        if residual <= tol:
            break
        V = V_next
    return V, {"iterations": len(residuals) - 1, "history": np.array(residuals), "area": np.array(areas)}


def _newton(V, F, b, tol, max_iter, solve_method="auto", **kwargs):
    from solvers import solve

    sol = solve(simplicial(V, F, b), tol=tol, max_steps=max_iter, throw=False, method=solve_method, **kwargs)
    info = {"iterations": int(sol.steps), "history": np.asarray(sol.history), "area": np.array([float(sol.energy)])}
    return np.asarray(sol.x), info


def _delaunay(V, F, boundary, tol, max_iter, throw, **kwargs):
    try:
        from ddgjax.intrinsic.minimal import minimal_surface_delaunay
    except ImportError:
        raise NotImplementedError(
            "method='delaunay' (Fig 7.23) needs ddgjax.intrinsic.minimal.minimal_surface_delaunay "
            "(issue 7), which this installation does not have yet; use method='cotan' or 'newton'"
        ) from None
    return minimal_surface_delaunay(V, F, boundary, tol=tol, max_iter=max_iter, throw=throw, **kwargs)


def minimal_surface(V, F, boundary=None, *, method: str = "cotan", tol: float = 1e-10,
                    max_iter: int = 1000, throw: bool = True, **kwargs):
    """A simplicial minimal surface spanned by the fixed `boundary` vertices of (V, F), started
    from V: `(V_min, F, info)`.

    **Arguments:** `method` `"cotan"` (Fig 6.5, Pinkall–Polthier), `"newton"` (`solvers.solve`
    on `simplicial`; `solve_method=` is solve's `method`, other `kwargs` go to `solve`) or
    `"delaunay"` (Fig 7.23; `kwargs` go to `ddgjax.intrinsic.minimal.minimal_surface_delaunay`,
    which returns the result); `tol`: stop when the max-norm of the area gradient at the
    interior vertices is `<= tol` (Fig 6.5 gets to ~1e-5 fast and then creeps: module docstring);
    `max_iter`: iterations (Newton steps); `throw`: raise `ConvergenceError` if not converged.

    **Returns:** `V_min` (nv, 3), `F`, and `info` with `method`, `iterations`, `history` (the
    area-gradient residual at each iterate), `area` (at each iterate, or the final one),
    `residual` (the last), `converged`.

    **Raises:** `InvalidInputError` (unknown method), the errors of `simplicial`,
    `DegenerateFaceError` when an iterate has a zero-area face, `ConvergenceError`,
    `NotImplementedError` for `"delaunay"` while issue 7's function is missing.
    """
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    if method == "delaunay":
        return _delaunay(V, F, boundary, tol, max_iter, throw, **kwargs)
    if kwargs and method == "cotan":
        raise InvalidInputError(f"method='cotan' takes no further options, got {sorted(kwargs)}")
    V, F, b = _checked(V, F, boundary)
    run = _cotan_iteration if method == "cotan" else _newton
    V_min, info = run(V, F, b, float(tol), int(max_iter), **kwargs)
    info.update(method=method, residual=float(info["history"][-1]))
    info["converged"] = info["residual"] <= tol
    if throw and not info["converged"]:
        raise ConvergenceError(
            f"minimal_surface(method={method!r}) did not converge: area-gradient residual "
            f"{info['residual']:.3e} > tol {tol:.1e} after {info['iterations']} iterations; raise max_iter "
            "or tol, or start closer",
            residual=info["residual"], steps=info["iterations"],
        )
    return V_min, F, info


def catenoid_neck(R: float = 1.0, H: float = 0.5) -> float:
    """The neck radius c of the stable catenoid r(z) = c cosh(z/c) through the circles of radius R
    at z = ±H: the larger root of c cosh(H/c) = R (the smaller one is the unstable catenoid)."""
    fold = brentq(lambda c: np.tanh(H / c) - c / H, 1e-3 * H, H)  # c cosh(H/c) is least here
    return brentq(lambda c: c * np.cosh(H / c) - R, fold, R)


def neck_radius(V) -> float:
    """min over the vertices of the distance to the z-axis."""
    return float(np.min(np.linalg.norm(np.asarray(V)[:, :2], axis=1)))
