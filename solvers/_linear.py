"""The linear-solver interface of Newton–KKT: solve the regularised KKT system `(K + μ S) d = b`.

`S = diag(I_n, −I_m)`.  The regularisation makes the system solvable when the KKT matrix is
singular (a continuous symmetry of the energy, redundant constraints); with μ proportional to
the residual it leaves Newton's quadratic convergence intact.  `μ` is given relative to the
largest entry of `K`, so that it means the same whatever the scaling of the energy.

A back end is a `LinearSolver`: a pytree (its array data are arguments of the compiled solver,
its static data the jit cache key) with
- `bind(problem, spec) -> LinearSolver`: made once per `solve` call, outside any trace: a
  solver ready for this problem's structure (a sparse back end builds or fetches its pattern and
  symbolic analysis here);
- `matrix(kkt, w, identity_hessian=False) -> K`: the KKT matrix at w in the back end's own form
  (dense array, coalesced sparse values, or products), evaluated once per Newton step;
- `factor_matrix(kkt, K, mu_rel) -> fac`: `K + μS` made ready to solve with (factorised);
- `apply(fac, b)`: solve with it (Newton's damping test reuses one factorisation);
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

import jax.numpy as jnp

MU_FLOOR = 1e-300


def regularisation(n: int, m: int, mu):
    """The diagonal of `μS = μ diag(I_n, −I_m)`."""
    return jnp.concatenate([jnp.full((n,), mu), jnp.full((m,), -mu)])


class LinearSolver(abc.ABC):
    """A linear-algebra back end of `solve` (module docstring); subclasses are pytrees."""

    #: True if the back end needs a problem declared local (`dg.local_sum`): it assembles K sparsely
    needs_locality: bool = False

    def bind(self, problem, spec) -> LinearSolver:
        """This solver prepared for `problem` (called once per solve, outside any trace)."""
        return self

    @abc.abstractmethod
    def matrix(self, kkt, w, identity_hessian: bool = False): ...

    @abc.abstractmethod
    def factor_matrix(self, kkt, K, mu_rel): ...

    @abc.abstractmethod
    def apply(self, fac, b): ...

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
