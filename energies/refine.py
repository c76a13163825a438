"""Solving on successively refined meshes: solve, subdivide the solution, solve again (Surface
Evolver's `r` and `g`).

`refine(problem_of, V, F)` solves `problem_of(V, F)` on the coarse mesh, carries the solution to
the subdivided mesh by the prolongation of `dg.mesh.subdivide` (V' = S V: the warm start of the
next solve), optionally moves the new positions by `project` (e.g. the boundary vertices back onto
the boundary curve, since midpoints of a circle's chords lie inside the circle), and solves
again, until the energy changes by less than `rtol` between two levels or `levels` subdivisions
are done.

Layering: it needs the meshes (`ddgjax.mesh`) and `solvers.solve`; `solvers` knows nothing of
meshes, and the `ddgjax` layers below the application do not import `solvers`, so the driver
lives with the catalogue, which sees both (as `area.minimal_surface` does).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from ddgjax.errors import InvalidInputError, ShapeError
from ddgjax.mesh.subdivision import subdivide

__all__ = ["Level", "refine"]


class Level(NamedTuple):
    """One level of `refine`: the mesh `(V, F)` it was solved on (V the start, after subdivision
    and `project`), the `solvers.Solution`, its `energy` and Newton `steps`."""

    V: np.ndarray
    F: np.ndarray
    solution: object
    energy: float
    steps: int


def _solve_level(problem_of, V, F, solve_options) -> Level:
    from solvers import solve

    problem = problem_of(V, F)
    if np.shape(problem.x0) != V.shape:
        raise ShapeError(f"refine: problem_of(V, F) must have the vertex positions {V.shape} as its unknowns, "
                         f"got x0 of shape {np.shape(problem.x0)}")
    sol = solve(problem, **solve_options)
    return Level(V, F, sol, float(sol.energy), int(sol.steps))


def refine(problem_of: Callable, V, F, *, levels: int = 3, rtol: float | None = None, scheme: str = "midpoint",
           boundary: str = "fixed", project: Callable | None = None, **solve_options) -> list[Level]:
    """Solve on (V, F), then on its subdivisions, each started from the last solution.

    Level 0 solves `problem_of(V, F)`; level k + 1 starts from `subdivide(x_k, F_k, scheme=scheme,
    boundary=boundary)` (old vertices keep their indices, so a fixed set given by indices or a
    mask over the old vertices carries over; `problem_of` rebuilds it for the new mesh), moved by
    `project` if given, and solves `problem_of` there.  It stops after level k ≥ 1 when
    |E_k − E_{k−1}| <= rtol |E_k|, or after `levels` subdivisions.

    **Arguments:** `problem_of(V, F) -> dg.Problem` whose unknowns are the positions V (nv, 3)
    (e.g. `lambda V, F: area.with_volume(V, F, 4 * np.pi / 3)`); `V`, `F` the coarse mesh;
    `levels` the most subdivisions (>= 0); `rtol` the relative energy change that ends the
    refinement (None: all `levels`); `scheme`, `boundary` as `dg.mesh.subdivide` (`"fixed"`:
    Loop keeps old boundary vertices, which are fixed in a Plateau problem); `project(V, F) -> V`
    applied to the subdivided positions before the solve (default: none; the solver moves the
    free vertices, but fixed ones stay where subdivision put them); `solve_options` go to
    `solvers.solve` (`tol`, `method`, `throw`, ...).

    **Returns:** a list of `Level` (V, F, solution, energy, steps), coarse first.

    **Raises:** `InvalidInputError` (`levels` < 0, `rtol` not positive), `ShapeError`
    (`project` or `problem_of` changing the shape of V), the errors of `subdivide` and `solve`.
    """
    if int(levels) < 0:
        raise InvalidInputError(f"refine: levels must be >= 0, got {levels}")
    if rtol is not None and not (np.isfinite(rtol) and rtol > 0):
        raise InvalidInputError(f"refine: rtol must be finite and > 0 (or None), got {rtol}")
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F)
    out = [_solve_level(problem_of, V, F, solve_options)]
    for _ in range(int(levels)):
        V, F = subdivide(np.asarray(out[-1].solution.x), out[-1].F, scheme=scheme, boundary=boundary)
        if project is not None:
            moved = np.asarray(project(V, F), dtype=np.float64)
            if moved.shape != V.shape:
                raise ShapeError(f"refine: project must return positions of shape {V.shape}, got {moved.shape}")
            V = moved
        out.append(_solve_level(problem_of, V, F, solve_options))
        if rtol is not None and abs(out[-1].energy - out[-2].energy) <= rtol * abs(out[-1].energy):
            break
    return out
