"""ddgjax.solvers: the generic constrained critical-point solver.

`solve(problem)` runs globalised Newton on the KKT system of a `ddgjax.Problem` with a
`LinearSolver` (dense LU, KLU, a fill-reducing sparse direct solver, Krylov), an optional first-order phase, and implicit
differentiation; `solve_batch(problem, params_batch, devices=...)` solves a batch of
parameters in one call, vectorised and sharded over devices.  This package knows nothing of curves or meshes.
"""

import ddgjax as _ddgjax  # noqa: F401  (switches on float64 before anything is traced)

from ._batch import solve_batch as solve_batch
from ._continuation import Bifurcation as Bifurcation
from ._continuation import Branch as Branch
from ._continuation import continuation as continuation
from ._dense import DenseLU as DenseLU
from ._direct import SparseDirect as SparseDirect
from ._klu import KLU as KLU
from ._krylov import Krylov as Krylov
from ._linear import LinearSolver as LinearSolver
from ._minimize import minimize as minimize
from ._newton import STATUS_TEXT as STATUS_TEXT
from ._solve import Solution as Solution
from ._solve import solve as solve
from ._stability import Stability as Stability
from ._stability import stability as stability

__all__ = ["solve", "minimize", "solve_batch", "Solution", "LinearSolver", "DenseLU", "KLU", "SparseDirect", "Krylov",
           "stability", "Stability", "continuation", "Branch", "Bifurcation", "STATUS_TEXT"]
