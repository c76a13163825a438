"""The area of simplicial surfaces and simplicial minimal surfaces (Sec 6.4, Thm 6.7, Fig 6.5).

**Energy.**  A(S) = Σ_F ½ |(v1 − v0) × (v2 − v0)|, declared with `dg.local_sum` over the faces;
the unknowns are the vertex positions (nv, 3), the boundary vertices are fixed.  Thm 6.7: A is the
sum of the Dirichlet energies of the three coordinate functions, and its gradient is the cotan
Laplacian of the surface applied to its own positions, ∇_{f(i)} A = (L f)(i).  So S is critical
for the area (a simplicial minimal surface in the wide sense, [PP93]) iff its coordinates are
harmonic for its own cotan Laplacian, L f = 0 at the interior vertices.

**Algorithms** (`minimal_surface`), all but Newton one loop, `harmonic_iteration`:
- `method="cotan"`: Fig 6.5, the Pinkall–Polthier iteration: solve the Dirichlet problem of the
  cotan Laplacian of the current surface with the boundary fixed (one sparse LU, three right-hand
  sides, `dirichlet.dirichlet_solve`) and replace the surface by the solution, until the area
  gradient at the interior vertices is below `tol` (max-norm, the KKT residual of `simplicial`).
- `method="delaunay"`: Fig 7.23, minimal surfaces in the narrow sense (Def 7.9): the same
  iteration, but each step first makes the triangulation intrinsically Delaunay by edge flips
  and solves with its Laplace–Beltrami operator, keeping the new combinatorics; it stops when the
  triangulation is Delaunay for the current surface and the residual is below `tol`.  Run to a
  loose tolerance, then accelerated by Newton's method on the area of the current triangulation
  (its fixed points are exactly the critical points of A_T with T Delaunay), with re-flips until
  the triangulation is Delaunay for Newton's solution (`minimal_surface_delaunay`).  Then S is
  critical for the area (Thm 6.7, Remark 7.10) and, all weights being ≥ 0, every interior vertex
  lies in the convex hull of its neighbours (maximum principle, Prop 6.8).  The surface is
  carried as a gluing (`ddgjax.intrinsic.Triangulation`), so the flipped triangulations may be
  Δ-complexes.
- `method="newton"`: `solvers.solve` on `simplicial(...)`: Newton on ∇A = 0 with the Hessian by
  autodiff (quadratic convergence from a start close enough).

In practice Fig 6.5 brings the area gradient down fast to ~1e-5 (for O(1) surfaces) and then
creeps: the remaining motion is mostly tangential and contracts by ~1 % per step on the catenoid
of `tests/test_area.py`.  Newton started from such an iterate converges in two or three steps;
started from a coarse guess (the cylinder) it does not (area is not convex).  From a start with
skinny triangles Fig 6.5 may degenerate where Fig 7.23 converges (Fig 7.26), and the area on a
fixed triangulation can decrease by degenerating triangles tangentially (on polar disks of
Enneper's surface Newton's minimisation collapses the central fan's slivers).  So `"auto"`:
Fig 7.23 to a loose `tol`, then a minimisation on that triangulation, re-made Delaunay when a
triangle degenerates.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax import intrinsic
from ddgjax._checks import check_positive
from ddgjax.errors import ConvergenceError, DDGError, DegenerateFaceError, InvalidInputError, NonFiniteError, ShapeError
from ddgjax.laplace import (
    check_nondegenerate,
    checked_triangle_mesh,
    cotan_laplacian,
    face_areas,
)
from ddgjax.mesh import boundary_indices, boundary_vertices
from ddgjax.mesh.lengths import squared_side_lengths, triangle_area

from .dirichlet import dirichlet_solve

__all__ = ["METHODS", "between_circles", "cap_volume", "cone_volume", "enclosed_volume", "face_area", "face_volume",
           "harmonic_iteration", "interior_residual", "minimal_surface", "minimal_surface_delaunay",
           "pinkall_polthier_step", "simplicial", "surface_between_circles", "with_volume", "with_volumes",
           "chamber_volumes"]

METHODS = ("auto", "cotan", "newton", "delaunay")
LOOSE_TOL = 1e-4  # the "auto" method's switch from Fig 6.5 to Newton, relative to the boundary's size
LOOSE_ITER = 200
NEWTON_ROUND = 20  # "auto": Newton steps between two Delaunay retriangulations
FLIP_ROUNDS = 4  # "auto": retriangulations when Newton's minimisation degenerates


def face_area(P: Float[Array, "3 3"], params=None) -> Float[Array, ""]:
    """A(F) of one face from its side lengths (Kahan's Heron, `ddgjax.mesh.lengths`): the density
    of `simplicial`."""
    l = squared_side_lengths(P) ** 0.5
    return triangle_area(l[0], l[1], l[2])


def _checked(V, F, boundary) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    V, F = checked_triangle_mesh(V, F, manifold=True)
    check_nondegenerate(V, F)
    b = boundary_vertices(F, V.shape[0]) if boundary is None else boundary_indices(boundary, V.shape[0])
    return V, F, b


def simplicial(V, F, boundary=None) -> dg.Problem:
    """The area A(S) = Σ_F A(F) of the triangle mesh (V, F) as a functional of the vertex
    positions (nv, 3), with the vertices `boundary` fixed (default: the vertices on boundary
    edges of F).  Its critical points are simplicial minimal surfaces (Thm 6.7).

    **Raises:** `NonFiniteError` (NaN position, naming the vertex), `DegenerateFaceError` (a
    zero-area face, where the area is not differentiable), `MeshError` / `NonManifoldError`
    (naming the face, edge or vertex), `InvalidInputError` (a boundary vertex that does not exist).
    """
    V, F, b = _checked(V, F, boundary)
    fixed = np.zeros(V.shape, dtype=bool)
    fixed[b] = True
    return dg.Problem(dg.local_sum(face_area, F), V, fixed=fixed, name=f"simplicial area (nv={len(V)}, nf={len(F)})")


def between_circles(n: int, height: float = 0.45) -> dg.Problem:
    """The catenoid's problem (Sec 6.4, Thm 6.7): the area of the triangulated cylinder
    `dg.mesh.builtin.cylinder(n, 1, 1)` spanned between the unit circles at z = ±H, with the
    half-distance H a parameter, `params={"height": H}`.

    The unknowns are `(x, y, ζ)` per vertex and the surface is `X = (x, y, H ζ)`: ζ = ±1 on the
    fixed circles, so every H shares one declaration (`with_params`, `solve_batch`, sweeps) and
    `surface_between_circles(x, H)` gives the positions.  `x0` is the cylinder of radius 1, from
    which `solve` finds the stable catenoid (at n = 8 for H up to 0.65); the smooth catenoid
    r = c cosh(z/c) exists while c cosh(H/c) = 1 has a root, up to H* ≈ 0.6627 (the fold), and
    beyond it the solve does not converge.

    **Raises:** `InvalidInputError` for n < 1 or a height that is not finite and positive.
    """
    if int(n) < 1:
        raise InvalidInputError(f"between_circles needs n >= 1 (rings of the cylinder), got {n}")
    check_positive(height, "between_circles: height")
    V, F = dg.mesh.builtin.cylinder(int(n), 1.0, 1.0)
    fixed = np.zeros(V.shape, dtype=bool)
    fixed[np.abs(np.abs(V[:, 2]) - 1.0) < 1e-12] = True
    energy = dg.local_sum(_face_area_between_circles, F)
    return dg.Problem(energy, V, params={"height": float(height)}, fixed=fixed,
                      name=f"catenoid between circles (cylinder({int(n)}), {len(F)} faces)")


def _face_area_between_circles(P: Float[Array, "3 3"], params) -> Float[Array, ""]:
    """The area of the face with corners `(x, y, H ζ)` (`between_circles`)."""
    return face_area(surface_between_circles(P, params["height"]))


def surface_between_circles(x: Float[Array, "*n 3"], height) -> Float[Array, "*n 3"]:
    """The positions `(x, y, H ζ)` of `between_circles`' unknowns `(x, y, ζ)`."""
    return x * jnp.array([1.0, 1.0, height])


def interior_residual(L, V, fixed: np.ndarray) -> float:
    """max over the free vertices of |(Δ f)(i)|, the area gradient ∇_{f(i)} A (Thm 6.7)."""
    return float(np.max(np.abs((L @ V)[~fixed]), initial=0.0))


def _harmonic_step(L, V: np.ndarray, boundary: np.ndarray, fixed: np.ndarray) -> tuple[np.ndarray, float]:
    """`(Ṽ, r)`: Ṽ harmonic for L with Ṽ = V on `boundary` (`dirichlet_solve`), and r the area
    gradient at V (`interior_residual`)."""
    return dirichlet_solve(L, boundary, V[boundary]), interior_residual(L, V, fixed)


def _mask(boundary: np.ndarray, n: int) -> np.ndarray:
    fixed = np.zeros(n, dtype=bool)
    fixed[boundary] = True
    return fixed


def pinkall_polthier_step(V, F, boundary) -> tuple[np.ndarray, float]:
    """One step of Fig 6.5: `(Ṽ, r)` with Ṽ harmonic for the cotan Laplacian L of (V, F), Ṽ = V on
    `boundary`, and r = max |(L V)_i| over the interior vertices, the area gradient at V (Thm 6.7).

    **Raises:** `DegenerateFaceError` when a face of (V, F) has zero area.
    """
    V = np.asarray(V, dtype=np.float64)
    b = boundary_indices(boundary, len(V))
    return _harmonic_step(cotan_laplacian(V, F), V, b, _mask(b, len(V)))


def _surface_laplacian(V, F, delaunay_tol):
    """Fig 6.5: the cotan Laplacian of the simplicial surface (V, F), its area, no flips."""
    return cotan_laplacian(V, F), F, float(face_areas(V, F).sum()), 0


def _delaunay_laplacian(V, tri, delaunay_tol):
    """Fig 7.23: the gluing `tri` with the lengths of V, made Delaunay by flips; its cotan
    Laplacian (the Laplace–Beltrami operator), the area, the number of flips."""
    i, j = tri.edges.T
    tri = tri.with_lengths(np.linalg.norm(V[j] - V[i], axis=1))
    L = intrinsic.triangulation.side_lengths(tri)
    area = float(triangle_area(L[:, 0], L[:, 1], L[:, 2]).sum())
    result = intrinsic.flip_to_delaunay(tri, tol=delaunay_tol, record_history=False)
    return intrinsic.cotan_laplacian(result.triangulation), result.triangulation, area, result.n_flips


def harmonic_iteration(V, F, boundary=None, *, flip: bool, tol: float = 1e-10, max_iter: int = 1000,
                       delaunay_tol: float = intrinsic.delaunay.DELAUNAY_TOL, throw: bool = False):
    """Iterate S ← S̃ with Δ_{S,T} f̃ = 0, the boundary vertices fixed: Fig 6.5 for `flip=False`
    (Δ the cotan Laplacian of the surface S), Fig 7.23 for `flip=True` (T first made
    intrinsically Delaunay by edge flips, Δ its Laplace–Beltrami operator, Def 7.9).

    **Arguments:** `V` (nv, 3), `F` (nf, 3) (or, with `flip=True`, a `Triangulation` carrying the
    gluing); `boundary` fixed vertex indices or an (nv,) bool mask (default: the vertices on
    boundary edges); `tol` on the interior residual max |Δf(i)| = |∇_{f(i)} A| (Thm 6.7);
    `max_iter` the iteration budget; `delaunay_tol` the tie tolerance of the flips; `throw`
    raise `ConvergenceError` when not converged.

    **Returns:** `(V, F, info)`, info with `method`, `converged`, `iterations`, `history` (the
    residual at each iterate, measured before its step), `residual` (the last), `flips` (per
    iterate), `area` (of each iterate, the simplicial surface before flipping), `triangulation`
    (the final gluing; None for `flip=False`).  An iterate with a degenerate triangle (the
    iteration broke down) ends the run, not converged.

    **Raises:** the errors of `intrinsic.from_mesh` (`flip=True`) or `simplicial`;
    `ConvergenceError` (with `throw`).
    """
    V = np.array(V, dtype=np.float64)
    if flip:
        carrier = F if isinstance(F, intrinsic.Triangulation) else intrinsic.from_mesh(V, F)
        laplacian = _delaunay_laplacian
        default = np.flatnonzero(carrier.connectivity.boundary_vertex_mask)
    else:
        V, carrier, default = _checked(V, F, None)
        laplacian = _surface_laplacian
    b = default if boundary is None else boundary_indices(boundary, len(V))
    fixed = _mask(b, len(V))
    history, flips, areas, breakdown = [], [], [], None
    for k in range(max_iter + 1):
        try:
            L, carrier, area, n_flips = laplacian(V, carrier, delaunay_tol)
        except DDGError as error:
            breakdown = error
            break
        V_next, residual = _harmonic_step(L, V, b, fixed)
        areas.append(area)
        history.append(residual)
        flips.append(n_flips)
        if (n_flips == 0 and residual <= tol) or k == max_iter:
            break
        V = V_next
    info = _report(flip, history, flips, areas, breakdown, tol)
    info["triangulation"] = carrier if flip else None
    if throw and not info["converged"]:
        reason = f"the iteration broke down ({breakdown})" if breakdown else (
            f"residual {info['residual']:.3e} > tol {tol:.1e} or still flipping after {info['iterations']} iterations")
        raise ConvergenceError(f"harmonic iteration (Fig {'7.23' if flip else '6.5'}) did not converge: {reason}; "
                               "raise max_iter or tol, or start closer",
                               residual=float(info["residual"]), steps=info["iterations"])
    return V, carrier.F if flip else carrier, info


def _report(flip, history, flips, areas, breakdown, tol) -> dict:
    residual = history[-1] if history else np.inf
    converged = breakdown is None and bool(flips) and flips[-1] == 0 and residual <= tol
    return {"method": "delaunay" if flip else "cotan", "converged": converged, "iterations": max(len(history) - 1, 0),
            "history": np.array(history), "residual": float(residual), "flips": np.array(flips, dtype=np.int64),
            "area": np.array(areas), "breakdown": breakdown}


def minimal_surface_delaunay(V, F, boundary=None, *, tol: float = 1e-10, max_iter: int = 1000,
                             delaunay_tol: float = intrinsic.delaunay.DELAUNAY_TOL, throw: bool = True,
                             newton: bool = True):
    """Minimal surface in the narrow sense (Def 7.9) by the algorithm of Fig 7.23,
    `harmonic_iteration(..., flip=True)`, accelerated by Newton's method.

    Fig 7.23 contracts linearly, slowly where the surface moves tangentially (on a non-planar
    boundary it is still at ~1e-5 after thousands of iterations).  Its fixed points are the
    surfaces S with a triangulation T that is Delaunay for S and ∇A_T(S) = L_T f = 0 (Thm 6.7,
    Remark 7.10: L_T is then the Laplace–Beltrami operator).  So with `newton=True` (default)
    the iteration runs to a loose tolerance (`LOOSE_TOL` of the boundary's size), then Newton's
    method (`solvers.solve`, a critical point of any index) solves ∇A_T = 0 on the current
    triangulation T; if T is Delaunay for the solution, it is a fixed point of Fig 7.23 to `tol`;
    otherwise a few Fig 7.23 steps re-flip T and Newton runs again (at most `NARROW_ROUNDS`
    times).  `newton=False` is the plain iteration.  `max_iter` bounds the iterations and Newton
    steps together.

    **Returns:** `(V, F, info)` as `harmonic_iteration`; F is the final (Delaunay) triangulation,
    possibly with other combinatorics than the input (a face may repeat a vertex if the surface
    degenerates); info also `newton_iterations` (0 without Newton).
    """
    if newton:
        V1, F1, info = _narrow(V, F, boundary, float(tol), int(max_iter), delaunay_tol)
    else:
        V1, F1, info = harmonic_iteration(V, F, boundary, flip=True, tol=tol, max_iter=max_iter,
                                          delaunay_tol=delaunay_tol)
    if throw and not info["converged"]:
        reason = f"the iteration broke down ({info['breakdown']})" if info["breakdown"] else (
            f"residual {info['residual']:.3e} > tol {tol:.1e} or still flipping after {info['iterations']} iterations")
        raise ConvergenceError(f"minimal surface in the narrow sense (Fig 7.23) did not converge: {reason}; "
                               "raise max_iter or tol, or start closer",
                               residual=float(info["residual"]), steps=info["iterations"])
    return V1, F1, info


NARROW_ROUNDS = 8  # Newton solves between Fig 7.23 re-flips (minimal_surface_delaunay)
NARROW_STEPS = 10  # Fig 7.23 steps after a Newton solve whose triangulation is not Delaunay
NARROW_NEWTON = 20  # Newton steps per round (far from converging, Newton wanders along tangential directions)


def _narrow(V, F, boundary, tol, max_iter, delaunay_tol):
    """`minimal_surface_delaunay` with Newton's method: Fig 7.23 to a loose tolerance, then
    rounds of (Newton on ∇A_T = 0, then Fig 7.23 from its solution: converged when that finds T
    Delaunay and the residual within `tol`, else `NARROW_STEPS` re-flipping steps)."""
    from solvers import solve

    V = np.array(V, dtype=np.float64)
    b0 = boundary_vertices(np.asarray(F.F if isinstance(F, intrinsic.Triangulation) else F), len(V)) \
        if boundary is None else boundary_indices(boundary, len(V))
    scale = float(np.ptp(V[b0], axis=0).max()) if b0.size else 1.0
    loose = max(tol, LOOSE_TOL * scale)
    V1, F1, info = harmonic_iteration(V, F, b0, flip=True, tol=loose, max_iter=min(LOOSE_ITER, max_iter),
                                      delaunay_tol=delaunay_tol)
    parts, budget, newton_steps = [info], max_iter - info["iterations"], 0
    for _ in range(NARROW_ROUNDS):
        if parts[-1]["converged"] and parts[-1]["residual"] <= tol or parts[-1]["breakdown"] is not None or budget <= 0:
            break
        try:
            sol = solve(simplicial(V1, F1, b0), tol=tol, max_steps=min(NARROW_NEWTON, budget), throw=False)
        except DDGError:  # the gluing is not a simplicial surface (a Δ-complex): Fig 7.23 alone
            break
        steps = int(sol.steps)
        newton_steps, budget = newton_steps + steps, budget - steps
        if not np.all(np.isfinite(np.asarray(sol.x))):
            break
        V1, F1, info = harmonic_iteration(np.asarray(sol.x), F1, b0, flip=True, tol=tol,
                                          max_iter=min(NARROW_STEPS, max(budget, 0)), delaunay_tol=delaunay_tol)
        budget -= info["iterations"]
        parts.append(info)
    return V1, F1, _joined(parts, newton_steps, tol)


def _joined(parts: list[dict], newton_steps: int, tol: float) -> dict:
    """The info of consecutive `harmonic_iteration` runs as one run, with `newton_iterations`;
    converged when the last run ended Delaunay within `tol` (the first ran to a looser one)."""
    last = parts[-1]
    info = dict(last, converged=bool(last["converged"] and last["residual"] <= tol))
    for key in ("history", "flips", "area"):
        info[key] = np.concatenate([p[key] for p in parts])
    info["iterations"] = sum(p["iterations"] for p in parts) + newton_steps
    info["newton_iterations"] = newton_steps
    return info


def _newton(V, F, b, tol, max_iter, solve_method="auto", **kwargs):
    from solvers import solve

    sol = solve(simplicial(V, F, b), tol=tol, max_steps=max_iter, throw=False, method=solve_method, **kwargs)
    info = {"iterations": int(sol.steps), "history": np.asarray(sol.history), "area": np.array([float(sol.energy)])}
    info.update(method="newton", residual=float(info["history"][-1]))
    info["converged"] = info["residual"] <= tol
    return np.asarray(sol.x), F, info


PINCH = 1e-8  # a face whose area falls below this fraction of the mean has collapsed


def _pinched(V, F) -> int | None:
    """The first face of (V, F) whose area collapsed (below `PINCH` × the mean), or None."""
    with np.errstate(invalid="ignore"):  # Heron's formula is NaN (collapsed) past a triangle inequality
        areas = np.asarray(face_areas(V, F)) if np.all(np.isfinite(V)) else np.zeros(len(F))
    small = np.flatnonzero(~(areas > PINCH * max(float(np.mean(areas)), 1e-300)))
    return int(small[0]) if small.size else None


def _pinch_error(V, F, where: str, cause=None) -> ConvergenceError:
    face = _pinched(V, F)
    what = f"face {face} collapsed" if face is not None else f"the next iterate degenerated: {cause}"
    return ConvergenceError(
        f"minimal_surface: the surface pinched during {where} ({what}): there is no minimal "
        "surface of this topology near the start spanning this boundary (e.g. two coaxial circles too far "
        "apart for a catenoid); the input mesh is not at fault", residual=float("nan"), steps=0)


def _degenerate_error(V, F, flips: int, cause: str) -> ConvergenceError:
    face = _pinched(V, F)
    what = f"face {face} degenerated" if face is not None else cause
    return ConvergenceError(
        f"minimal_surface: Newton's minimisation of the area found no minimum ({what}, after {flips} "
        "Delaunay flips of the triangulation): the simplicial area has no nondegenerate local minimum on "
        "this triangulation near the start (its tangential directions are nearly flat and degenerate "
        "triangles lower it); method='delaunay' gives a minimal surface in the narrow sense (Def 7.9), "
        "method='newton' a critical point of any index", residual=float("nan"), steps=0)


def _auto(V, F, boundary, tol, max_iter):
    """Fig 7.23 to a loose tolerance (the Pinkall–Polthier iteration on a triangulation kept
    intrinsically Delaunay by flips), then minimisation of the area on that triangulation by
    Newton with inertia correction (`solvers.minimize`), `NEWTON_ROUND` steps at a time; when a
    round ends unconverged (a triangle degenerating), the triangulation is made Delaunay again
    for the current surface and the minimisation goes on, at most `FLIP_ROUNDS` times.  The result
    is a local minimum of the area on the returned triangulation, to `tol`."""
    from solvers import minimize

    V0, F, b = _checked(V, F, boundary)
    loose = max(tol, LOOSE_TOL * float(np.ptp(V0[b], axis=0).max() if b.size else 1.0))
    V1, F, pp = harmonic_iteration(V0, F, b, flip=True, tol=loose, max_iter=min(LOOSE_ITER, max_iter))
    if pp["breakdown"] is not None or _pinched(V1, F) is not None:
        raise _pinch_error(V1, F, f"the Pinkall–Polthier iteration (step {pp['iterations']})", pp["breakdown"])
    history, flips, budget = [pp["history"][:-1]], int(pp["flips"].sum()), max(max_iter - pp["iterations"], 0)
    for round_ in range(FLIP_ROUNDS + 1):
        steps = budget if round_ == FLIP_ROUNDS else min(NEWTON_ROUND, budget)
        try:
            sol = minimize(simplicial(V1, F, b), tol=tol, max_steps=steps, throw=False)
        except (DegenerateFaceError, NonFiniteError) as error:  # a re-flip made a face flat in space
            raise _degenerate_error(V1, F, flips, "a triangle degenerated") from error
        V1, budget = np.asarray(sol.x), budget - int(sol.steps)
        history.append(np.asarray(sol.history) if round_ == 0 else np.asarray(sol.history)[1:])
        if sol.converged or budget == 0 or round_ == FLIP_ROUNDS or _pinched(V1, F) is not None:
            break
        V1, F, retriangulated = harmonic_iteration(V1, F, b, flip=True, max_iter=0)
        flips += int(retriangulated["flips"].sum())
    if not sol.converged and (_pinched(V1, F) is not None or not np.isfinite(float(sol.residual))):
        raise _degenerate_error(V1, F, flips, f"gradient {float(sol.residual):.1e}")
    history = np.concatenate(history)
    info = {"method": "auto", "iterations": len(history) - 1, "history": history, "residual": float(history[-1]),
            "area": np.concatenate([pp["area"], [float(sol.energy)]]), "converged": bool(sol.converged),
            "cotan_iterations": pp["iterations"], "newton_iterations": len(history) - 1 - pp["iterations"],
            "flips": flips, "minimum": bool(sol.converged)}
    return V1, F, info


def minimal_surface(V, F, boundary=None, *, method: str = "auto", tol: float = 1e-10,
                    max_iter: int = 1000, throw: bool = True, **kwargs):
    """A simplicial minimal surface spanned by the fixed `boundary` vertices of (V, F), started
    from V: `(V_min, F, info)`.

    **Arguments:** `method` `"auto"` (default: Fig 7.23 to a loose tolerance, 1e-4 of the
    boundary's size, then Newton's method with inertia correction, `solvers.minimize`, on that
    triangulation, made intrinsically Delaunay again when a triangle degenerates on the way: a
    local *minimum* of the area on the returned triangulation, never a saddle, converged to
    `tol`), `"cotan"` (Fig 6.5,
    Pinkall–Polthier alone: fast to ~1e-5, then creeping), `"delaunay"` (Fig 7.23, a minimal
    surface in the narrow sense, accelerated by Newton: `minimal_surface_delaunay`;
    `delaunay_tol=` the flips' tie tolerance, `newton=False` the plain iteration) or `"newton"`
    (`solvers.solve` on `simplicial`, a critical point of any index; `solve_method=` is solve's
    `method`, other `kwargs` go to `solve`); `tol`: stop when the max-norm of the area gradient
    at the interior vertices is `<= tol`; `max_iter`: iterations (both phases of `"auto"`
    together); `throw`: raise `ConvergenceError` if not converged.

    **Returns:** `V_min` (nv, 3), `F` (for `"delaunay"` and `"auto"` the final triangulation:
    the input's where no edge was flipped), and `info` as `harmonic_iteration` (Newton and auto:
    `method`, `iterations`, `history`, `area`, `residual`, `converged`; auto also
    `cotan_iterations`, `newton_iterations`, `flips` and `minimum`: no negative eigenvalue of the
    area Hessian on the free vertices).

    **Raises:** `InvalidInputError` (unknown method or option), the errors of `simplicial`,
    `ConvergenceError` (not converged, an iterate degenerated, or, for `"auto"`, the surface
    pinched during the first phase: no minimal surface near the start; or a triangle
    degenerated during the minimisation: no nondegenerate minimum of the area on this
    triangulation near the start, which happens on fine meshes whose tangential directions are
    nearly flat, e.g. polar disks of 12 or more rings).
    """
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    if method == "auto":
        if kwargs:
            raise InvalidInputError(f"method='auto' takes no further options, got {sorted(kwargs)}")
        V_min, F, info = _auto(V, F, boundary, float(tol), int(max_iter))
    elif method == "newton":
        V, F, b = _checked(V, F, boundary)
        V_min, F, info = _newton(V, F, b, float(tol), int(max_iter), **kwargs)
    else:
        if set(kwargs) - {"delaunay_tol", "newton"} or (kwargs and method == "cotan"):
            raise InvalidInputError(f"method={method!r} takes no further options, got {sorted(kwargs)}")
        if method == "delaunay":
            return minimal_surface_delaunay(V, F, boundary, tol=float(tol), max_iter=int(max_iter), throw=throw,
                                            **kwargs)
        return harmonic_iteration(V, F, boundary, flip=False, tol=float(tol), max_iter=int(max_iter), throw=throw)
    if throw and not info["converged"]:
        raise ConvergenceError(
            f"minimal_surface(method={method!r}) did not converge: area-gradient residual "
            f"{info['residual']:.3e} > tol {tol:.1e} after {info['iterations']} iterations; raise max_iter "
            "or tol, or start closer",
            residual=info["residual"], steps=info["iterations"],
        )
    return V_min, F, info


# ---------------------------------------------------------------------------------------------
# Soap bubbles: the area with prescribed enclosed volume (constant mean curvature, Laplace–Young)


def face_volume(P: Float[Array, "3 3"], params=None) -> Float[Array, ""]:
    """det(v0, v1, v2)/6: the signed volume of the cone from the origin over the face."""
    import jax.numpy as jnp

    return jnp.linalg.det(P) / 6.0


def cone_volume(P: Float[Array, "3 3"], share, params) -> Float[Array, "1"]:
    """The density of the named constraint `"volume"` of `with_volume`, one face's share of
    vol(S) − volume: `face_volume`, plus the face's `share` (1/nf) of `cap − params["volume"]`
    (shape (1,))."""
    return (face_volume(P) + share["weight"] * (share["cap"] - params["volume"]))[None]


def _boundary_halfedges(F: np.ndarray) -> np.ndarray:
    """(k, 2): the halfedges (a, b), as the faces of F run through them, without a twin
    (`glue_triangles`; `OrientationError` for an inconsistently oriented F)."""
    from ddgjax.mesh.connectivity import glue_triangles

    halfedges, _ = glue_triangles(np.asarray(F), int(np.max(F)) + 1)
    h = np.flatnonzero(halfedges.twin < 0)
    return np.stack([halfedges.vertex[h], halfedges.head[h]], axis=1)


def cap_volume(V, F) -> float:
    """The signed volume of the cones from the origin over the flat caps that close the boundary
    loops of (V, F): each loop is coned off from its centroid c, by the triangles (c, b, a) for its
    boundary halfedges (a, b) (reversed, so surface and caps are consistently oriented); 0 for a
    closed mesh.  With it, Σ_F det/6 + cap is the volume enclosed by the surface closed by its caps,
    independent of the origin."""
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F)
    edges = _boundary_halfedges(F)
    if not edges.size:
        return 0.0
    centroid = np.zeros_like(V)
    for loop in dg.mesh.boundary_loops(F):
        centroid[loop] = V[loop].mean(axis=0)
    a, b = V[edges[:, 0]], V[edges[:, 1]]
    return float(np.einsum("ij,ij->i", centroid[edges[:, 0]], np.cross(b, a)).sum() / 6.0)


def enclosed_volume(V, F) -> float:
    """vol(S) = Σ_F det(v0, v1, v2)/6 + `cap_volume(V, F)`: the volume enclosed by the oriented
    surface (V, F) (closed by flat caps over its boundary loops), positive when the normals
    (v1 − v0) × (v2 − v0) point out of it."""
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F)
    return float(np.linalg.det(V[F]).sum() / 6.0) + cap_volume(V, F)


def _check_bubble(V: np.ndarray, F: np.ndarray, fixed: np.ndarray) -> None:
    """The checks `with_volume` adds to `simplicial`'s: F consistently oriented, the boundary
    loops fixed, the normals pointing out of the enclosed volume."""
    from ddgjax.errors import OrientationError
    from ddgjax.mesh.connectivity import glue_triangles

    glue_triangles(F, len(V))  # OrientationError naming an edge two faces run through alike
    loop_vertices = np.unique(_boundary_halfedges(F))
    loose = loop_vertices[~fixed[loop_vertices]]
    if loose.size:
        raise InvalidInputError(
            f"with_volume: vertex {loose[0]} lies on a boundary loop of F but is not fixed: the volume enclosed by "
            "a surface with boundary is measured with flat caps over its boundary loops, which must stay put")
    vol0 = enclosed_volume(V, F)
    if vol0 < 0:
        raise OrientationError(
            f"with_volume: the enclosed volume of the start is {vol0:.6g} < 0: the faces of F are oriented "
            "inward; the volume is measured with the normals (v1 − v0) × (v2 − v0) pointing out of it, so "
            "reverse the faces (F[:, ::-1])")


def with_volume(V, F, volume, boundary=None) -> dg.Problem:
    """Soap bubbles: the area A(S) = Σ_F A(F) of the triangle mesh (V, F) as a functional of the
    vertex positions (nv, 3), with the enclosed volume prescribed, the named constraint

        "volume":  vol(S) − volume = 0,   vol(S) = (1/6) Σ_F det(v0, v1, v2) + cap,

    (F oriented, normals (v1 − v0) × (v2 − v0) pointing out of the volume).  For a closed mesh
    cap = 0 and vol(S) is the enclosed volume (divergence theorem: the cones from the origin over
    the faces).  For a mesh with boundary (vertices `boundary` fixed; default: the vertices on
    boundary edges, which must all be fixed) Σ_F det/6 alone is the signed volume of the cone
    from the origin over S; `cap = cap_volume(V, F)`, a constant since the boundary is fixed,
    adds the cones over flat caps closing each boundary loop from its centroid, so vol(S) is
    the volume enclosed by S and its caps, independent of the origin (a liquid bridge between
    two coaxial circles: the volume between the surface and the two disks).

    Critical points: ∇A = p ∇vol with the multiplier p = `solve(problem).multipliers["volume"]`
    (`dg.Problem`'s sign: critical points of A − p (vol − volume)).  Thm 6.7: ∇_{f(i)} A = (L f)(i),
    the cotan Laplacian of the surface applied to its positions, the discrete mean curvature
    normal, 2H N times the vertex area as h → 0, while ∇_{f(i)} vol is the vertex area times N
    (⅓ of the area-weighted normals of the faces at i).  So the critical points are the discrete
    surfaces of constant mean curvature 2H = κ1 + κ2 = p, and p is the pressure difference across
    the film of the Laplace–Young law Δp = σ(κ1 + κ2) (surface tension σ = 1): round sphere of
    radius r, p = 2/r (area 4πr², volume 4πr³/3, dA/dvol = 2/r); cylinder of radius R, p = 1/R.
    On a convex bubble both gradients point out, so p > 0.  p is also the derivative of the
    critical area in the prescribed volume, dA/d(volume) = p (the envelope theorem).

    A closed bubble is free to translate and rotate (area and volume are invariant): its KKT
    matrix has a 6-dimensional kernel.  Nothing pins it: `solve`'s regularised Newton steps
    (μ = 1e-14 and LM, `solvers/_newton.py`) converge on such a family of solutions, to one member
    near the start.  As for `simplicial`, the tangential motions of the vertices are nearly flat
    for the area: start close (a sphere with a few percent of smooth perturbation converges in a
    few steps; a coarse start far away may stall, where the default `warm_start` retries).

    **Arguments:** `V` (nv, 3), `F` (nf, 3) consistently oriented; `volume` the enclosed volume
    (finite, > 0; `params={"volume": volume}`, so `jax.grad` of `solve(...).energy` in it is the
    pressure); `boundary` fixed vertex indices or an (nv,) bool mask.

    **Raises:** the errors of `simplicial`; `OrientationError` (two faces running through an edge
    alike, naming it, or the normals pointing into the volume: reverse F); `InvalidInputError`
    (`volume` not finite and positive, or a boundary-loop vertex not fixed, naming it).
    """
    V, F, b = _checked(V, F, boundary)
    check_positive(volume, "with_volume: volume")
    fixed = _mask(b, len(V))
    _check_bubble(V, F, fixed)
    share = {"weight": np.full(len(F), 1.0 / len(F)), "cap": np.full(len(F), cap_volume(V, F))}
    return dg.Problem(dg.local_sum(face_area, F), V,
                      constraints=dg.concat(volume=dg.local_sum(cone_volume, F, data=share)),
                      params={"volume": float(volume)}, fixed=np.repeat(fixed[:, None], 3, axis=1),
                      name=f"area with volume {float(volume):.6g} (nv={len(V)}, nf={len(F)})")


def chamber_volumes(P: Float[Array, "3 3"], share, params) -> Float[Array, "c"]:
    """The density of the named constraint `"volumes"` of `with_volumes`: one face's share of
    vol_c − volumes_c for every chamber c, `share["sign"][c]` det(P)/6 (`face_volume`) minus
    the face's `share["weight"]` (1/nf) of the prescribed volumes."""
    return share["sign"] * face_volume(P) - share["weight"] * params["volumes"]


def with_volumes(V, F, chambers, volumes) -> dg.Problem:
    """Foams of a few chambers (a double bubble): the area A = Σ_F A(F) of a closed triangle
    complex (V, F), whose edges may lie in three faces (where films meet), with the volume of
    each chamber prescribed, the named constraint

        "volumes":  vol_c − volumes_c = 0,   vol_c = (1/6) Σ_F chambers[F, c] det(v0, v1, v2),

    `chambers` (nf, c) the faces' incidence with the chambers: ±1 where the normal (v1 − v0) ×
    (v2 − v0) points out of / into chamber c, 0 where the face does not bound it (a shared wall
    bounds two chambers with opposite signs).  Each chamber's faces must close up (the
    divergence theorem then makes vol_c the volume it encloses, independent of the origin).

    Critical points: ∇A = Σ_c p_c ∇vol_c with the multipliers p = `multipliers["volumes"]`, the
    chambers' pressures over the outside: on a film bounding chamber c alone its mean curvature
    is 2H = p_c, on a wall between chambers c and d it is p_c − p_d (Laplace–Young, as
    `with_volume`), and where three films meet, the vertex gradient of the area balances at
    120° (Plateau's laws; Taylor 1976).  The standard double bubble of two equal chambers of
    volume 9πr³/8 (`ddgjax.mesh.builtin.double_bubble`) has caps of radius r (p = 2/r) and a flat
    wall, area 27πr²/4, and is the least-area enclosure of two equal volumes (Hutchings, Morgan,
    Ritoré & Ros 2002).

    **Arguments:** `V` (nv, 3); `F` (nf, 3); `chambers` (nf, c) of −1, 0, 1 with every chamber
    enclosing a positive volume at the start; `volumes` (c,) finite and positive
    (`params={"volumes": volumes}`).

    **Raises:** the mesh errors of `simplicial` (without the manifold check: films meet along
    edges); `ShapeError` (`chambers` not (nf, c), `volumes` not (c,)); `InvalidInputError`
    (entries of `chambers` other than −1, 0, 1, a chamber with no face or enclosing a
    non-positive volume at the start — reverse its faces' signs —, `volumes` not finite and
    positive, naming the chamber).
    """
    V, F = checked_triangle_mesh(V, F)
    check_nondegenerate(V, F)
    C = np.asarray(chambers, dtype=np.float64)
    target = np.asarray(volumes, dtype=np.float64)
    if C.ndim != 2 or C.shape[0] != len(F):
        raise ShapeError(f"with_volumes: chambers must be (nf, c) = ({len(F)}, c), got shape {C.shape}")
    if target.shape != (C.shape[1],):
        raise ShapeError(f"with_volumes: volumes must be ({C.shape[1]},), one per chamber, got shape {target.shape}")
    if not np.all(np.isin(C, (-1.0, 0.0, 1.0))):
        f, c = np.argwhere(~np.isin(C, (-1.0, 0.0, 1.0)))[0]
        raise InvalidInputError(f"with_volumes: chambers[{f}, {c}] = {C[f, c]!r}; the entries are -1, 0 or 1")
    start = (C * (np.linalg.det(V[F]) / 6.0)[:, None]).sum(axis=0)
    for c in range(C.shape[1]):
        if not (np.isfinite(target[c]) and target[c] > 0):
            raise InvalidInputError(f"with_volumes: volumes[{c}] = {target[c]!r}; a chamber's volume is finite and positive")
        if not np.any(C[:, c]) or start[c] <= 0:
            raise InvalidInputError(
                f"with_volumes: chamber {c} encloses the volume {start[c]:.6g} <= 0 at the start: its faces do not "
                "bound it with outward normals (reverse the signs of chambers[:, c])")
    share = {"sign": C, "weight": np.full(len(F), 1.0 / len(F))}
    return dg.Problem(dg.local_sum(face_area, F), V,
                      constraints=dg.concat(volumes=dg.local_sum(chamber_volumes, F, data=share)),
                      params={"volumes": target}, name=f"area with {C.shape[1]} chamber volumes (nv={len(V)}, nf={len(F)})")
