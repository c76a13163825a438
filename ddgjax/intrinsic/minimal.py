"""Simplicial minimal surfaces in the narrow sense (Sec 7.5, Def 7.9, Fig 7.23).

S is minimal in the narrow sense if Δf = 0 for the discrete Laplace–Beltrami operator and its
triangulation T is Delaunay; then Δ is the cotan Laplacian of T, S is a critical point of the
area (Thm 6.7, Remark 7.10), and with all weights ≥ 0 every interior vertex lies in the convex
hull of its neighbours (maximum principle, Prop 6.8).

`harmonic_iteration` runs the fixed-point iterations of Fig 6.5 (`flip=False`: the cotan
Laplacian of the current simplicial surface, Pinkall–Polthier) and Fig 7.23 (`flip=True`: first
make the current triangulation intrinsically Delaunay by edge flips, then solve with its
Laplace–Beltrami operator and keep the new combinatorics).  The surface is carried as a gluing
(`Triangulation`), so that the flipped triangulations may be Δ-complexes.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from ..errors import ConvergenceError, DDGError, InvalidInputError, MeshError
from ..mesh.builtin import tall_dome
from .delaunay import DELAUNAY_TOL, flip_to_delaunay
from .geometry import triangle_area
from .laplace_beltrami import cotan_laplacian
from .triangulation import Triangulation, boundary_vertices, from_mesh, side_lengths

__all__ = ["fig_7_26", "harmonic_iteration", "interior_residual", "minimal_surface_delaunay"]


def _boundary_mask(boundary, n: int) -> np.ndarray:
    b = np.asarray(boundary)
    if b.dtype == bool:
        if b.shape != (n,):
            raise InvalidInputError(f"a boolean boundary mask must have shape ({n},), got {b.shape}")
        return b.copy()
    mask = np.zeros(n, dtype=bool)
    if b.size and (b.min() < 0 or b.max() >= n):
        raise MeshError(f"boundary vertex index {int(b[(b < 0) | (b >= n)][0])} is outside 0..{n - 1}")
    mask[b.astype(np.int64)] = True
    return mask


def _with_positions(tri: Triangulation, V: np.ndarray) -> Triangulation:
    """The same gluing with the extrinsic lengths |v_j − v_i| of the positions V."""
    i, j = tri.edges.T
    return tri.with_lengths(np.linalg.norm(V[j] - V[i], axis=1))


def interior_residual(L, V, fixed: np.ndarray) -> float:
    """max over free vertices of |(Δ f)(i)|, the area gradient ∇_{f(i)} A (Thm 6.7)."""
    return float(np.max(np.abs((L @ V)[~fixed]), initial=0.0))


def _harmonic_extension(L, V: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """Solve Δ f̃ = 0 at the free vertices with f̃ = f at the fixed ones."""
    free = ~fixed
    L = L.tocsr()
    rhs = -(L[free][:, fixed] @ V[fixed])
    out = V.copy()
    out[free] = spla.splu(L[free][:, free].tocsc()).solve(rhs)
    return out


def harmonic_iteration(V, F, boundary=None, *, flip: bool, tol: float = 1e-10, max_iter: int = 1000,
                       delaunay_tol: float = DELAUNAY_TOL, throw: bool = False):
    """Iterate S ← S̃ with Δ_{S,T} f̃ = 0, the boundary vertices fixed (Fig 6.5 for flip=False,
    Fig 7.23 for flip=True, where T is first made Delaunay by edge flips).

    **Arguments:** `V` (nv, n), `F` (nf, 3) or a `Triangulation` carrying the gluing; `boundary`
    fixed vertex indices or an (nv,) bool mask (default: the vertices on boundary edges); `tol`
    on the interior residual max |Δf(i)| = |∇_{f(i)} A| (Thm 6.7); `max_iter` the iteration
    budget; `throw` raise `ConvergenceError` when not converged.

    **Returns:** `(V, F, info)`, info with `method`, `converged`, `iterations`, `history` (the
    residual at each iterate, measured before its step), `residual` (the last), `flips` (per
    iterate), `area` (of each iterate, the simplicial surface before flipping),
    `triangulation` (the final gluing).  An iterate with a
    degenerate triangle (the iteration broke down) ends the run, not converged.

    **Raises:** the errors of `triangulation.from_mesh`; `ConvergenceError` (with `throw`).
    """
    V = np.array(V, dtype=np.float64)
    tri = F if isinstance(F, Triangulation) else from_mesh(V, F)
    fixed = boundary_vertices(tri) if boundary is None else _boundary_mask(boundary, V.shape[0])
    history, flips, areas, breakdown = [], [], [], None
    for k in range(max_iter + 1):
        try:
            tri = _with_positions(tri, V)
        except DDGError as error:
            breakdown = error
            break
        L_side = side_lengths(tri)
        areas.append(float(triangle_area(L_side[:, 0], L_side[:, 1], L_side[:, 2]).sum()))
        n_flips = 0
        if flip:
            result = flip_to_delaunay(tri, tol=delaunay_tol, record_history=False)
            tri, n_flips = result.triangulation, result.n_flips
        L = cotan_laplacian(tri)
        history.append(interior_residual(L, V, fixed))
        flips.append(n_flips)
        if (n_flips == 0 and history[-1] <= tol) or k == max_iter:
            break
        V = _harmonic_extension(L, V, fixed)
    converged = breakdown is None and flips[-1] == 0 and history[-1] <= tol
    info = {"method": "delaunay" if flip else "cotan", "converged": converged, "iterations": len(history) - 1,
            "history": np.array(history), "residual": history[-1] if history else np.inf,
            "flips": np.array(flips, dtype=np.int64), "area": np.array(areas), "triangulation": tri}
    if throw and not converged:
        reason = f"the iteration broke down ({breakdown})" if breakdown else (
            f"residual {info['residual']:.3e} > tol {tol:.1e} or still flipping after {info['iterations']} iterations")
        raise ConvergenceError(f"harmonic iteration (Fig {'7.23' if flip else '6.5'}) did not converge: {reason}",
                               residual=float(info["residual"]), steps=info["iterations"])
    return V, tri.F, info


def minimal_surface_delaunay(V, F, boundary=None, *, tol: float = 1e-10, max_iter: int = 1000,
                             delaunay_tol: float = DELAUNAY_TOL, throw: bool = True):
    """Minimal surface in the narrow sense by the algorithm of Fig 7.23 (Def 7.9): each step
    makes the triangulation intrinsically Delaunay by edge flips and solves Δf̃ = 0 with its
    Laplace–Beltrami operator, the boundary fixed; it stops when the triangulation is Delaunay
    for the current surface and max |Δf(i)| ≤ tol at the free vertices.  Returns `(V, F, info)`
    as `harmonic_iteration`; the returned F is the final (Delaunay) triangulation, possibly with
    other combinatorics than the input (a face may repeat a vertex if the surface degenerates).
    """
    return harmonic_iteration(V, F, boundary, flip=True, tol=tol, max_iter=max_iter,
                              delaunay_tol=delaunay_tol, throw=throw)


def fig_7_26(seed: int = 0, budget: int = 30, **dome):
    """Fig 7.26 on `mesh.tall_dome(seed, **dome)`: `(V, F, boundary, cotan, narrow)` with `cotan` and
    `narrow` the `(V, F, info)` of `intrinsic.minimal.harmonic_iteration` without flips (Fig 6.5,
    which ends a run whose iterate degenerates) and with flips (Fig 7.23), `budget` iterations."""
    V, F, boundary = tall_dome(seed, **dome)
    cotan = harmonic_iteration(V, F, boundary, flip=False, tol=1e-9, max_iter=budget)
    narrow = harmonic_iteration(V, F, boundary, flip=True, tol=1e-9, max_iter=budget)
    return V, F, boundary, cotan, narrow
