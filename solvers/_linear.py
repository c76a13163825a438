"""The linear-solver interface of Newton–KKT: solve the regularised KKT system `(K + μS) d = b`.

`S = diag(I_n, −I_m)`, μ a diagonal.  The regularisation makes the system solvable when the KKT
matrix is singular (a continuous symmetry of the energy, redundant constraints).  It is scaled
to the problem row by row (`row_regularisation`): `μ_i = mu_rel · max_j |K_ij|`, a relative
perturbation of each row of the size of the round-off a factorisation commits anyway, so that
it means the same whatever the scaling of the energy, of the constraints or of single unknowns,
and does not swamp a small eigenvalue that belongs to a small row (a diagonal quadratic with
condition number 10¹⁶ is solved exactly).  The direct back ends then correct the regularised
solve once with the unregularised K (`apply_refined`): the Newton step is K's own to
`O(μ²/λ²)` in an eigendirection with eigenvalue λ, where the plain regularised step is off by
`μ/λ`.

A back end is a `LinearSolver`: a pytree (its array data are arguments of the compiled solver,
its static data the jit cache key) with
- `bind(problem, spec) -> LinearSolver`: made once per `solve` call, outside any trace: a
  solver ready for this problem's structure (a sparse back end builds or fetches its pattern and
  symbolic analysis here);
- `matrix(kkt, w, identity_hessian=False) -> K`: the KKT matrix at w in the back end's own form
  (dense array, coalesced sparse values, or products), evaluated once per Newton step;
- `factor_matrix(kkt, K, mu_rel) -> fac`: `K + μS` made ready to solve with (factorised);
- `apply(fac, b)`: solve with it (Newton's damping test reuses one factorisation);
- `apply_refined(fac, K, b)`: the same, refined once with K when `iterative_refinement`;
- `factorised(fac, use)`: `use(solve)` with one factorisation for all its solves;
- `apply_transpose(fac, b)`: solve with the transpose, for the adjoint of implicit
  differentiation (`K + μS` is symmetric, so by default the same solve);
- `matvec(K, v)`: `K v`;
- `lm_solve_matrix(K, nu, R)`: the Levenberg–Marquardt step `−(KᵀK + ν I)⁻¹ KᵀR`;
- `factor(kkt, w, mu_rel, identity_hessian=False)`, `solve(...)`: the compositions.
Evaluating the second derivatives once per step (not again for the LM fallback and its model)
keeps the compiled Newton loop small: compile time is dominated by the size of the traced
graph, and the per-cell Hessians are its largest part.

`identity_hessian=True` replaces `∇²L` by the identity: the system then gives the least-squares
multipliers `argmin_λ |∇E − Jᵀλ|` used to start Newton.

The back ends, one file each: `DenseLU` (`_dense.py`), `KLU` (`_klu.py`), `SparseLDL`
(`_ldl.py`, a fill-reducing sparse direct solver on the host) and `Krylov` (`_krylov.py`).
"""

from __future__ import annotations

import abc

import jax
import jax.numpy as jnp

MU_FLOOR = 1e-300
ROW_FLOOR = float(jnp.finfo(jnp.float64).eps)  # rows below this, relative to the largest, are round-off


def regularisation(n: int, m: int, mu):
    """The diagonal of `μS = μ diag(I_n, −I_m)` (μ a scalar or an (n + m,) array)."""
    sign = jnp.concatenate([jnp.ones((n,)), -jnp.ones((m,))])
    return sign * jnp.broadcast_to(mu, (n + m,))


def row_regularisation(n: int, m: int, mu_rel, row_max):
    """The diagonal of `μS` scaled row by row: `μ_i = mu_rel · max(r_i, ε r_max)` with the row
    sizes `r_i = max_j |K_ij|` (`row_max`, (n + m,)), at least `MU_FLOOR`.

    A zero row (an unknown on which nothing depends, a constraint with a vanishing gradient)
    gets `mu_rel · ε · r_max`: rows below `ε r_max` are at the round-off level of the largest.
    """
    scale = jnp.maximum(row_max, ROW_FLOOR * jnp.max(row_max, initial=0.0))
    return regularisation(n, m, jnp.maximum(mu_rel * scale, MU_FLOOR))


class LinearSolver(abc.ABC):
    """A linear-algebra back end of `solve` (module docstring); subclasses are pytrees."""

    #: True if the back end needs a problem declared local (`dg.local_sum`): it assembles K sparsely
    needs_locality: bool = False
    #: True if `apply_refined` refines (a factorisation: one more back substitution is cheap)
    iterative_refinement: bool = False

    def bind(self, problem, spec) -> LinearSolver:
        """This solver prepared for `problem` (called once per solve, outside any trace)."""
        return self

    @abc.abstractmethod
    def matrix(self, kkt, w, identity_hessian: bool = False): ...

    @abc.abstractmethod
    def factor_matrix(self, kkt, K, mu_rel): ...

    @abc.abstractmethod
    def apply(self, fac, b): ...

    def apply_refined(self, fac, K, b):
        """`d = (K + μS)⁻¹ b`, then, if `iterative_refinement`, one step of iterative refinement
        with the unregularised K (`refined`)."""
        return self.refined(lambda r: self.apply(fac, r), K, b)

    def refined(self, solve, K, b):
        """`d = solve(b)`, `solve` applying `(K + μS)⁻¹`, then, if `iterative_refinement`, one
        step of iterative refinement with the unregularised K: `d + (K + μS)⁻¹ (b − K d)`.

        In an eigendirection of K with eigenvalue λ the regularised solve is off by the factor
        `λ/(λ + μ)` and the refined one by `1 − μ²/(λ + μ)²`; in a null direction (λ = 0,
        where b has only round-off) the refined step is twice the regularised one.
        """
        d = solve(b)
        if not self.iterative_refinement:
            return d
        return d + solve(b - self.matvec(K, d))

    def factorised(self, fac, use):
        """`use(solve)`, `solve(b) = (K + μS)⁻¹ b` with `fac = factor_matrix(...)`: for a
        computation that solves several times with one matrix (a Newton step, its refinement and
        its damping tests).  A back end whose `apply` factorises anew (KLU) factorises once here
        and frees the factorisation once `use`'s result is computed."""
        return use(lambda b: self.apply(fac, b))

    def analysed(self, run):
        """`run(self)`, for a computation that factorises and solves many times (Newton's
        iteration).  A back end that has not analysed its matrix's pattern in advance (KLU bound
        while `jit` traces) analyses it here once for all of them, and frees the analysis after."""
        return run(self)

    def apply_transpose(self, fac, b):
        """`(K + μS)ᵀ⁻¹ b`; K and S are symmetric."""
        return self.apply(fac, b)

    @abc.abstractmethod
    def matvec(self, K, v): ...

    @abc.abstractmethod
    def lm_solve_matrix(self, K, nu, R): ...

    def factor(self, kkt, w, mu_rel, identity_hessian: bool = False):
        return self.factor_matrix(kkt, self.matrix(kkt, w, identity_hessian), mu_rel)

    def solve(self, kkt, w, mu_rel, b, identity_hessian: bool = False):
        return self.apply(self.factor(kkt, w, mu_rel, identity_hessian), b)

    def solve_once(self, kkt, w, mu_rel, b):
        """`(K + μS)⁻¹ b` as one self-contained operation, linear in `b` and transposable (the
        derivative's solve): declared to JAX as a linear solve of the symmetric `K + μS`, so
        that reverse mode transposes it as the same solve.  A back end whose solve JAX can
        transpose and differentiate itself (dense LU) returns `solve` directly."""
        K = self.matrix(kkt, w)
        fac = self.factor_matrix(kkt, K, mu_rel)  # K assembled once, for the product and the factorisation
        return jax.lax.custom_linear_solve(lambda v: self.matvec(K, v), b, lambda _, rhs: self.apply(fac, rhs), symmetric=True)
