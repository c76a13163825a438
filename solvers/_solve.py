"""`solve`: critical points of a constrained energy, their multipliers, and their derivatives."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax._checks import check_positive, checked_count, is_concrete
from ddgjax._host import on_device
from ddgjax.errors import ConvergenceError, InvalidInputError, NonFiniteError
from ddgjax.problem import Problem, flatten_multipliers

from ._banded import chain_structure
from ._cache import LRU, cleared_by_jax, derived
from ._dense import DenseLU
from ._direct import SparseDirect, default_factoriser
from ._exported import Program
from ._first_order import augmented_lagrangian
from ._implicit import implicit_solution
from ._kkt import KKT, Spec, residual_weights, scaled_residual, spec_of
from ._klu import KLU
from ._krylov import Krylov
from ._linear import LinearSolver
from ._newton import CONVERGED, MAX_STEPS, NONFINITE, STALLED, STATUS_TEXT, newton
from ._sparse import cached_pattern

METHODS = ("auto", "dense", "sparse", "krylov", "lbfgs")
WARM_STARTS = ("auto", "lbfgs", None)
FIRST_ORDER_OUTER = 50


class Solution(NamedTuple):
    """The result of `solve`.

    - `x`: the critical point, a pytree like `x0` (fixed entries bit-for-bit from `x0`).
    - `multipliers`: `∇E(x) = Jg(x)ᵀ multipliers`; 1-D, ordered like the constraint vector, or
      for named constraints a pytree like the constraints' output (`multipliers["chord"]`).
    - `energy`: `E(x)`.
    - `residual`: max-norm of the (scaled) KKT residual at `x`.
    - `steps`: Newton steps taken (outer augmented-Lagrangian steps for `method="lbfgs"`).
    - `converged`: `residual <= tol` and the energy finite at `x`.
    - `history`: residual after each step (`history[0]` at the start of Newton).
    - `status`: 0 converged, 1 max_steps reached, 2 stalled, 3 non-finite.
    - `first_order_steps`: outer augmented-Lagrangian L-BFGS steps run before Newton
      (`warm_start="lbfgs"`, or the retry of `warm_start="auto"`: a positive count there says
      that the first Newton run stopped and this solution is the retry's; 0 otherwise).
    """

    x: object
    multipliers: object
    energy: jax.Array
    residual: jax.Array
    steps: jax.Array
    converged: jax.Array
    history: jax.Array
    status: jax.Array
    first_order_steps: jax.Array | int = 0


DENSE_MAX = 2000  # unknowns + multipliers: dense LU beyond this costs seconds and gigabytes


def choose_method(spec: Spec, backend: str) -> str:
    """The linear algebra `method="auto"` uses, by size and backend.

    - `"sparse"` for a problem declared local on the CPU: there it beats dense LU at every
      size we measured (N = 10²: 1.0 vs 2.6 ms, `benchmarks/solver.py`);
    - `"dense"` when N = n + m ≤ `DENSE_MAX` otherwise (one LU on an accelerator is fast);
    - `"krylov"` for larger problems that are not local-on-CPU (the sparse factorisations run on
      the CPU only, and dense LU does not fit): no factorisation, inside `jit` on any backend.
    """
    if spec.is_local and backend == "cpu":
        return "sparse"
    if spec.n + spec.m <= DENSE_MAX:
        return "dense"
    return "krylov"


def is_chain(problem: Problem, spec: Spec) -> bool:
    """Whether the local problem's KKT matrix is block tridiagonal up to a border (a curve)."""
    pattern = cached_pattern(spec, problem.x0, problem.params)
    shape = spec.layout.shapes[0]
    width = shape[1] if len(shape) == 2 else 1
    return derived(pattern, "chain", lambda: chain_structure(pattern, spec.layout.free, width)) is not None


KLU_MAX = 2500
"""Unknowns + multipliers up to which `method="sparse"` takes KLU on meshes too.  KLU's Newton
solvers are kept on disk (`_exported`); `SparseDirect`'s host callbacks are not, so every new
process traces and compiles them again.  Measured by `python benchmarks/klu_max.py` (the time to
a first solution in a new process with warm caches, KLU vs Pardiso, one run): 0.4–1.1 s vs
3.9–6.4 s on surfaces of N = 487–2,352 (5.7–11× faster), where a solve once compiled takes
0.6–4.3× Pardiso's time (closed surfaces: 1.5× on the double bubble of N = 1,019, 4.3× = 0.25 s
more on the bubble of N = 1,927: KLU is ahead for the first ~20 solves in a process).  At
N = 7,687 (bubble 4) Pardiso's fill-reducing factorisation wins outright (1.3 vs 4.7 s per
solve).  Newton's steps are alike on both (the bubble of N = 1,927 at tol 1e-12: 9 vs 8)."""


def sparse_direct_for(problem: Problem, spec: Spec) -> LinearSolver:
    """`method="sparse"`: KLU for chains (banded, no fill: KLU is fastest there) and for small
    problems (N = n + m ≤ `KLU_MAX`), the fill-reducing `SparseDirect` with Pardiso (or CHOLMOD)
    otherwise (meshes; KLU where neither is installed: SuperLU, the remaining factoriser, is
    slower than KLU there)."""
    if spec.n + spec.m <= KLU_MAX or default_factoriser() is None or is_chain(problem, spec):
        return KLU()
    return SparseDirect()


def krylov_for(problem: Problem, spec: Spec) -> LinearSolver:
    """`method="krylov"`: MINRES preconditioned by the multigrid cycle for an unconstrained
    problem declared local that is not a chain (a mesh: the cycle's iteration count barely grows
    with the mesh, where the Jacobi metric's grows with the condition number), `Krylov()`
    otherwise (GMRES with the block-tridiagonal preconditioner on chains; MINRES on the
    constraints' tangent space with the Jacobi metric).  On an accelerator this is what
    `method="auto"` runs for large meshes (`benchmarks/accelerator.py`)."""
    if spec.is_local and spec.m == 0 and not is_chain(problem, spec):
        return Krylov(preconditioner="amg")
    return Krylov()


def linear_solver_of(problem: Problem, spec: Spec, method: str, linear_solver: LinearSolver | None) -> LinearSolver:
    """The bound linear solver of a solve: `linear_solver` if given, else the one `method` names."""
    if linear_solver is None:
        if method == "auto":
            method = choose_method(spec, jax.default_backend())
        if method == "sparse" and not spec.is_local:
            raise InvalidInputError(
                "method='sparse' needs an energy declared with dg.local_sum (and constraints with "
                "dg.local_map / dg.local_sum / dg.concat) over a single array of unknowns"
            )
        linear_solver = {"dense": DenseLU, "krylov": lambda: krylov_for(problem, spec)}.get(
            method, lambda: sparse_direct_for(problem, spec))()
    elif not isinstance(linear_solver, LinearSolver):
        raise InvalidInputError(
            f"linear_solver must be a solvers.LinearSolver (DenseLU(), KLU(), SparseDirect(), Krylov()), "
            f"got {type(linear_solver).__name__}"
        )
    elif linear_solver.needs_locality and not spec.is_local:
        raise InvalidInputError(
            f"{linear_solver!r} assembles a sparse KKT matrix: it needs an energy declared with dg.local_sum "
            "(and constraints with dg.local_map / dg.local_sum / dg.concat) over a single array of unknowns"
        )
    return linear_solver.bind(problem, spec)


COMPILED_SOLVERS = 32
"""Compiled solvers kept by `solve`, one per problem declaration and options (least recently
used dropped first, with every trace and executable JAX keeps for it): a new `lambda` energy per
call costs a compilation each time but no longer grows memory without bound."""

JITTED = cleared_by_jax(LRU(COMPILED_SOLVERS), "solvers.solve compiled solvers")


def _solve_jit(spec, linear, z0, params, lam0, weights, *, tol, max_steps, first_order, newton_phase):
    """`_solve_impl` compiled once per (declaration, options), through the bounded `JITTED` (and
    across processes through the exported programs, `_exported.Program`)."""
    static = dict(tol=tol, max_steps=max_steps, first_order=first_order, newton_phase=newton_phase)
    program = JITTED.get((spec, tuple(static.items())),
                         lambda: Program(_solve_impl, spec, static))
    return program(linear, z0, params, lam0, weights)


def compiled_solver_count() -> int:
    """The number of executables `solve` holds (over every declaration in `JITTED`)."""
    return sum(jitted._cache_size() for jitted in JITTED._items.values())


def _solve_impl(spec, linear, z0, params, lam0, weights, *, tol, max_steps, first_order, newton_phase):
    z0_, params_ = jax.lax.stop_gradient((z0, params))
    kkt = KKT(spec, z0_, params_)
    u0 = z0_[spec.layout.free]
    if lam0 is None and spec.m == 0:
        lam0 = jnp.zeros((0,), u0.dtype)

    def iterate(linear):
        """The critical point from (u0, lam0): `(w, residual, steps, history, status, fo_steps)`."""
        lam = lam0
        if lam is None:
            # least-squares multipliers argmin |∇E − Jᵀλ|: the KKT system with ∇²L replaced by I
            grad_e = jax.grad(kkt.energy)(u0)
            w_probe = jnp.concatenate([u0, jnp.zeros((spec.m,), u0.dtype)])
            rhs = jnp.concatenate([grad_e, jnp.zeros((spec.m,), u0.dtype)])
            lam = -linear.solve(kkt, w_probe, 1e-12, rhs, identity_hessian=True)[spec.n :]
            lam = jnp.where(jnp.isfinite(lam), lam, 0.0)
        w = jnp.concatenate([u0, lam])
        fo_steps = jnp.asarray(0)
        if first_order:
            w, fo_steps, _ = augmented_lagrangian(kkt, w, weights, tol=tol, outer_steps=first_order)
        if newton_phase:
            state = newton(kkt, linear, w, weights, tol=tol, max_steps=max_steps)
            return state.w, state.residual, state.step, state.history, state.status, fo_steps
        residual = scaled_residual(kkt.residual(w), weights, spec.n)
        history = jnp.full((max_steps + 1,), jnp.nan).at[0].set(residual)
        finite = jnp.isfinite(residual) & jnp.isfinite(kkt.energy(kkt.split(w)[0]))
        return w, residual, fo_steps, history, jnp.where(residual <= tol, CONVERGED, jnp.where(finite, 1, NONFINITE)), fo_steps

    w, residual, steps, history, status, fo_steps = linear.analysed(iterate)
    converged = (residual <= tol) & jnp.isfinite(kkt.energy(kkt.split(w)[0]))
    status = jnp.where((status == CONVERGED) & ~converged, NONFINITE, status)
    w = implicit_solution(spec, jax.lax.stop_gradient(linear), w, z0, params, converged)
    kkt_diff = KKT(spec, z0, params)
    u, lam = kkt_diff.split(w)
    x = kkt_diff.x(u)
    energy = kkt_diff.energy(u)
    return Solution(x, spec.constraint_structure.unravel(lam), energy, residual, steps, converged, history, status,
                    fo_steps)


def solver_inputs(problem: Problem, method: str, linear_solver: LinearSolver | None, tol: float, max_steps: int):
    """`(spec, linear, z0, weights, max_steps)`: the declaration, the bound linear solver (its
    host-side analysis made now, outside any trace), the flat unknowns of x0, the residual's
    weights and the checked step count, from which `solve` and `solve_batch` call the solver.

    **Raises:** `InvalidInputError` for a non-positive `tol`, a negative `max_steps`, every
    entry of x0 fixed, or a linear solver that does not fit the problem."""
    check_positive(tol, "tol")
    max_steps = checked_count(max_steps, 0, "max_steps")
    spec = spec_of(problem)
    if spec.n == 0:
        raise InvalidInputError("every entry of x0 is fixed: there is nothing to solve for")
    linear = linear_solver_of(problem, spec, method, linear_solver)
    return spec, linear, spec.layout.ravel(problem.x0), residual_weights(problem, spec), max_steps


def solve(
    problem: Problem,
    *,
    tol: float = 1e-10,
    max_steps: int = 100,
    method: str = "auto",
    linear_solver: LinearSolver | None = None,
    throw: bool = True,
    multipliers0=None,
    warm_start: str | None = "auto",
) -> Solution:
    """Find a critical point of `problem.energy` on `problem.constraints == 0`.

    Newton's method on the KKT system `∇E − Jᵀλ = 0, g = 0` over the free unknowns and the
    multipliers, second derivatives by autodiff, globalised by a backtracking line search on
    `½|R|²` and regularised so that singular KKT matrices (continuous symmetries, redundant
    constraints) do not stop it.  Converges to saddle points as well as minima.

    **Arguments:**
    - `tol`: stop when the scaled max-norm KKT residual is `<= tol` (see `Problem.residual_scale`).
      The test is on the residual, not on x: where the reduced Hessian has an eigenvalue λ, x
      is determined to about `tol/λ` (the direct paths solve each Newton step exactly and return
      x to round-off also for λ ≈ 1e-14; the Krylov path resolves each step to its `rtol`, so
      give an energy with tiny curvatures its `residual_scale`, as for an energy of tiny scale).
    - `max_steps`: Newton steps (outer augmented-Lagrangian steps for `method="lbfgs"`).
    - `method`: `"dense"` (LU, n ≲ 2,000), `"sparse"` (a sparse direct solve of the KKT matrix
      assembled from a locality declaration, `dg.local_sum`, on the CPU: KLU for curves,
      `SparseDirect` for meshes), `"krylov"` (inside `jit` on any backend,
      `solvers/_krylov.py`: GMRES preconditioned by a block-tridiagonal solve for problems on
      curves, MINRES on the constraints' tangent space with a Jacobi metric otherwise),
      `"lbfgs"` (augmented Lagrangian with jaxopt L-BFGS inner solves: minimisation only,
      first-order), or `"auto"` (`choose_method`: sparse for a problem declared local on the
      CPU, else dense up to N = n + m = 2,000 unknowns and multipliers, else Krylov).
    - `linear_solver`: a `solvers.LinearSolver` object (`DenseLU()`, `KLU()`, `SparseDirect()`,
      `Krylov(rtol=…)`, or your own) for the Newton steps; overrides `method`'s choice.
    - `throw`: raise `ConvergenceError` when not converged; inside `jit`/`vmap` the compiled
      computation raises at run time instead (`equinox.error_if`; an `EqxRuntimeError` naming the
      problem). With `throw=False` check `Solution.converged`.
    - `multipliers0`: starting multipliers, flat or named like `Solution.multipliers` (default:
      least squares `argmin |∇E − Jᵀλ|` at x0).
    - `warm_start`: `"lbfgs"` runs up to 50 augmented-Lagrangian L-BFGS steps before Newton, for
      minimisation problems started far away; `"auto"` (default) runs Newton from x0 and, only if
      that stops without converging (max_steps reached or stalled, not a non-finite start),
      solves once more from x0 with the L-BFGS phase first and returns that solution if it
      converged (outside `jit`/`vmap`/`grad`, where values are concrete; Newton's merit |R|² has
      local minima that are not solutions, which the augmented Lagrangian escapes); `None`:
      Newton alone.  The retry finds minima, not saddles.

    **Returns:** a `Solution`. Derivatives of functions of `.x`, `.multipliers`, `.energy` with
    respect to `problem.params` (and `x0`'s fixed entries) are exact (implicit function theorem),
    in reverse mode (`grad`, `jacrev`, `vjp`) and forward mode (`jvp`, `jacfwd`, `hessian`); they
    are NaN when the solve did not converge. `jax.vmap` over `params` works (also under `jit`, on both the dense and
    the sparse path; `solve_batch` packages it and shards a batch over devices).

    **Raises:** `ConvergenceError` (with `.residual`, `.steps`, `.solution`), `NonFiniteError`
    when the energy or residual is NaN at `x0` (or in `multipliers0`), `ShapeError` for
    `multipliers0` of the wrong shape or structure, `InvalidInputError` for unknown options.
    """
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    if warm_start not in WARM_STARTS:
        raise InvalidInputError(f"warm_start must be one of {WARM_STARTS}, got {warm_start!r}")
    lam0 = None if multipliers0 is None else flatten_multipliers(problem, multipliers0)
    spec, linear, z0, weights, max_steps = solver_inputs(
        problem, "dense" if method == "lbfgs" else method, linear_solver, tol, max_steps)
    lam0 = None if lam0 is None else lam0.astype(z0.dtype)
    first_order = FIRST_ORDER_OUTER if warm_start == "lbfgs" else (int(max_steps) if method == "lbfgs" else 0)

    def run(first_order: int) -> Solution:
        return _solve_jit(spec, linear, z0, problem.params, lam0, weights, tol=float(tol), max_steps=int(max_steps),
                          first_order=first_order, newton_phase=method != "lbfgs")

    try:
        sol = run(first_order)
        if not is_concrete(sol):
            return _raise_if_not_converged(problem, sol) if throw else sol
        jax.block_until_ready(sol)  # a failure in the computation surfaces here, not later
        if warm_start == "auto" and method != "lbfgs" and int(sol.status) in (MAX_STEPS, STALLED):
            retry = run(FIRST_ORDER_OUTER)
            sol = retry if bool(retry.converged) else sol
    except jax.errors.JaxRuntimeError as err:  # KLU and the host factorisations report a singular matrix so
        raise ConvergenceError(
            f"{_label(problem)}the sparse linear solve failed ({_first_line(err)}); try method='dense' to diagnose",
            residual=float("nan"), steps=0,
        ) from None
    return _finish(problem, sol, throw, tol)


def _first_line(error: BaseException) -> str:
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__


def _raise_if_not_converged(problem: Problem, sol: Solution) -> Solution:
    """`sol` with a run-time check: the compiled computation raises unless every member of a
    (possibly batched) solve converged."""
    import equinox as eqx

    message = f"{_label(problem)}solve did not converge (throw=True inside jit/vmap; pass throw=False and check .converged)"
    x, multipliers, energy = eqx.error_if((sol.x, sol.multipliers, sol.energy), ~sol.converged, message)
    return sol._replace(x=x, multipliers=multipliers, energy=energy)


def _label(problem: Problem) -> str:
    return f"{problem.name}: " if problem.name else ""


def _finish(problem: Problem, sol: Solution, throw: bool, tol: float) -> Solution:
    steps = int(sol.steps)
    sol = sol._replace(history=on_device(np.asarray(sol.history)[: steps + 1]))
    status = int(sol.status)
    if status == NONFINITE and steps == 0:
        raise NonFiniteError(
            f"{_label(problem)}the energy or the KKT residual is not finite at x0 (residual "
            f"{float(sol.residual)}): check the energy's domain at the starting point"
        )
    if throw and not bool(sol.converged):
        where = (f"with energy {float(sol.energy)} at the last iterate (KKT residual {float(sol.residual):.3e})"
                 if status == NONFINITE else f"with KKT residual {float(sol.residual):.3e} > tol {tol:.1e}")
        raise ConvergenceError(
            f"{_label(problem)}solve did not converge: {STATUS_TEXT.get(status, status)} after {steps} "
            f"steps {where}. Try a better x0, a larger max_steps, or a looser tol.",
            residual=float(sol.residual), steps=steps, solution=sol,
        )
    return sol
