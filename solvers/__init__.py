"""ddgjax.solvers: the generic constrained critical-point solver.

`solve(problem)` runs globalised Newton on the KKT system of a `ddgjax.Problem` with dense or
sparse (declared locality) linear algebra, an optional first-order phase, and implicit
differentiation; `solve_batch(problem, params_batch, devices=...)` solves a batch of
parameters in one call, vectorised and sharded over devices.  This package knows nothing of curves or meshes.
"""

import ddgjax as _ddgjax  # noqa: F401  (switches on float64 before anything is traced)

from ._batch import solve_batch as solve_batch
from ._solve import Solution as Solution
from ._solve import solve as solve

__all__ = ["solve", "solve_batch", "Solution"]
