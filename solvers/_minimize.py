"""`minimize`: a local minimum, never a saddle: Newton with inertia correction and a line search.

`solve` finds critical points of every index (Euler's figure-eight elastica is a saddle), so it
may also settle on a saddle when a minimum is wanted.  For the unconstrained problem
`min E(u)` (fixed entries allowed) each step here factorises the shifted Hessian `H + δI` by a
factorisation that reports its inertia (`SparseDirect`'s `LDLᵀ` by Pardiso or CHOLMOD, Sylvester's law; the
eigenvalues for a dense Hessian) and raises δ until the matrix is positive definite, as
interior-point codes do (Wächter & Biegler 2006, Sec 3.1):

    δ = 0 first;  else δ = max(δ_min, δ_last / 3), then δ ← 8δ until no eigenvalue is negative,

with δ_min = 1e-8 max|H|.  The step `d = −(H + δI)⁻¹ ∇E` is then a descent direction, and a
backtracking line search takes the largest α in {1, ½, …} with Armijo's decrease
`E(u + αd) ≤ E(u) + 10⁻⁴ α ∇E·d` (at the round-off level of E, a decrease of |∇E| instead).
Near a nondegenerate minimum δ = 0 and α = 1: Newton's quadratic convergence.  The run ends
when the scaled gradient is below `tol` *and* the Hessian there has no eigenvalue below
−10⁻¹⁰ max|H| (the second-order condition, flat directions of a symmetry allowed); a point with a small gradient and a negative eigenvalue is a saddle and is left
along the corrected direction.

The result is handed to `solve` from the minimum (zero Newton steps), so it is a `Solution`
whose derivatives with respect to the parameters are exact (implicit function theorem).
"""

from __future__ import annotations


import jax
import jax.numpy as jnp
import numpy as np

from ddgjax._host import on_device
from ddgjax.errors import ConvergenceError, InvalidInputError
from ddgjax.problem import Problem

from ._dense import DenseLU
from ._direct import SparseDirect, default_factoriser
from ._exported import programs
from ._kkt import KKT, residual_weights, scaled_residual, spec_of
from ._solve import Solution, linear_solver_of, solve

ARMIJO = 1e-4
DELTA_MIN, DELTA_GROWTH, DELTA_DECAY, DELTA_MAX = 1e-8, 8.0, 3.0, 1e20
MAX_BACKTRACK = 40
ROUNDOFF = 1e-14
FLAT = 1e-10  # eigenvalues of H above −FLAT·max|H| count as zero (symmetries, flat directions)


@programs
def _energy_gradient(spec, z0, params, u):
    return jax.value_and_grad(KKT(spec, z0, params).energy)(u)


@programs
def _hessian(spec, linear, z0, params, u):
    return linear.matrix(KKT(spec, z0, params), u)


@jax.jit
def _shifted_ldl(linear: SparseDirect, K, delta):
    return linear.factor_with_inertia(K.at[linear.index["diagonal"]].add(delta), 0.0)


@jax.jit
def _apply(linear: SparseDirect, token, b):
    return linear.apply(token, b)


def _host_energy_gradient(spec, z0, params, u) -> tuple[float, np.ndarray]:
    """`(E(u), ∇E(u))` as a float and a NumPy array."""
    energy, grad = _energy_gradient(spec, z0, params, u)
    return float(energy), np.asarray(grad)


def _scale(linear, K) -> float:
    return max(float(np.max(np.abs(np.asarray(K)))), 1.0) if K.size else 1.0


def _convexified(linear, K, delta: float):
    """`(solve, negative)`: a solver with `H + δI` and its number of negative eigenvalues
    (−1 if unknown: the `LDLᵀ` met a tiny pivot and fell back to LU)."""
    if isinstance(linear, SparseDirect):
        token, negative = _shifted_ldl(linear, K, delta)
        return (lambda b: _apply(linear, token, b)), int(negative)
    H = np.asarray(K) + delta * np.eye(K.shape[0])
    eigenvalues, vectors = np.linalg.eigh(H)
    negative = int(np.sum(eigenvalues < 0))
    return (lambda b: vectors @ ((vectors.T @ np.asarray(b)) / eigenvalues)), negative


def _positive_definite(linear, K, delta_last: float):
    """`(solve, δ)` with `H + δI` positive definite, δ chosen as in the module docstring; `(None, δ)`
    when no δ ≤ 10²⁰ max|H| does (non-finite entries)."""
    scale = _scale(linear, K)
    delta = 0.0
    while True:
        solve_with, negative = _convexified(linear, K, delta)
        if negative == 0:
            return solve_with, delta
        if delta > DELTA_MAX * scale:
            return None, delta
        delta = max(DELTA_MIN * scale, delta_last / DELTA_DECAY) if delta == 0.0 else DELTA_GROWTH * delta


def minimize(problem: Problem, *, tol: float = 1e-10, max_steps: int = 200, linear_solver=None,
             throw: bool = True) -> Solution:
    """A local minimum of `problem.energy` (no constraints; fixed entries allowed) by Newton's
    method with inertia correction and an Armijo line search (module docstring): it cannot
    converge to a saddle.

    **Arguments:** `tol` on the scaled max-norm gradient (as `solve`); `max_steps` Newton steps;
    `linear_solver` `SparseDirect()` (default for a problem declared local, with Pardiso or CHOLMOD) or
    `DenseLU()` (otherwise; inertia from the eigenvalues, for small problems); `throw` raise
    `ConvergenceError` when not converged.

    **Returns:** a `Solution` (`steps` and `history` of this minimisation; differentiable in the
    parameters like `solve`'s).

    **Raises:** `InvalidInputError` (constraints, or a linear solver without inertia),
    `ConvergenceError` (with `throw`: not converged within `max_steps`, the line search
    failed, or the Hessian has non-finite entries).
    """
    spec = spec_of(problem)
    if spec.m:
        raise InvalidInputError(
            "minimize handles problems without constraints (fixed entries are fine); for constrained "
            "problems use solve and check the index of the solution"
        )
    if linear_solver is None:
        linear_solver = SparseDirect() if spec.is_local and default_factoriser() else DenseLU()
    if isinstance(linear_solver, SparseDirect) and linear_solver.factoriser == "superlu":
        raise InvalidInputError("minimize needs the inertia of an LDLᵀ: SparseDirect() with Pardiso (pip install "
                                "pypardiso) or CHOLMOD, or DenseLU()")
    if not isinstance(linear_solver, (SparseDirect, DenseLU)):
        raise InvalidInputError(f"minimize needs the inertia of the Hessian: SparseDirect() or DenseLU(), got {linear_solver!r}")
    linear = linear_solver_of(problem, spec, "auto", linear_solver)
    z0 = spec.layout.ravel(problem.x0)
    params = problem.params
    weights = residual_weights(problem, spec)
    u = np.asarray(z0)[spec.layout.free]  # the loop runs on the host in NumPy: no program per operation
    energy, grad = _host_energy_gradient(spec, z0, params, u)
    history = [float(scaled_residual(grad, weights, spec.n))]
    delta, status = 0.0, "reached max_steps"
    for step in range(max_steps + 1):
        K = _hessian(spec, linear, z0, params, u)
        if history[-1] <= tol:
            # second-order condition: no eigenvalue of H below −ε max|H| (flat directions pass)
            if _convexified(linear, K, FLAT * _scale(linear, K))[1] == 0:
                status = "converged"
                break
        if step == max_steps:
            break
        solve_with, delta = _positive_definite(linear, K, delta)
        if solve_with is None:
            status = "no shift makes the Hessian positive definite (non-finite entries: a degenerate configuration)"
            break
        d = np.asarray(solve_with(-grad))
        slope = float(np.dot(grad, d))
        alpha, accepted = 1.0, False
        for _ in range(MAX_BACKTRACK):
            e_new, g_new = _host_energy_gradient(spec, z0, params, u + alpha * d)
            decrease = float(energy - e_new)
            if np.isfinite(float(e_new)) and (
                decrease >= -ARMIJO * alpha * slope
                or (abs(decrease) <= ROUNDOFF * abs(float(energy)) and float(np.max(np.abs(g_new))) < float(np.max(np.abs(grad))))
            ):
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            status = "stalled: the line search found no decrease (at the round-off level of the energy: loosen tol)"
            break
        u, energy, grad = u + alpha * d, e_new, g_new
        history.append(float(scaled_residual(grad, weights, spec.n)))
    sol = solve(problem.with_x0(spec.layout.x_of(z0, u)), linear_solver=linear_solver, tol=max(tol, history[-1]), max_steps=0, throw=False)
    sol = sol._replace(steps=jnp.asarray(len(history) - 1), history=on_device(np.asarray(history)),
                       converged=jnp.asarray(status == "converged"), residual=jnp.asarray(history[-1]))
    if throw and status != "converged":
        raise ConvergenceError(
            f"{problem.name + ': ' if problem.name else ''}minimize did not converge: {status} after "
            f"{len(history) - 1} steps with gradient {history[-1]:.3e} (tol {tol:.1e})",
            residual=history[-1], steps=len(history) - 1, solution=sol,
        )
    return sol
