"""Linear algebra of Newton–KKT: solve the regularised KKT system `(K + μ S) d = b`.

`S = diag(I_n, −I_m)`.  The regularisation makes the system solvable when the KKT matrix is
singular (a continuous symmetry of the energy, redundant constraints); with μ proportional to
the residual it leaves Newton's quadratic convergence intact.  `μ` is given relative to the
largest entry of `K`, so that it means the same whatever the scaling of the energy.

Two interchangeable back ends, static and hashable, with the methods
- `matrix(kkt, w, identity_hessian=False) -> K`: the KKT matrix at w (dense array, or the
  coalesced values of the sparse pattern), evaluated once per Newton step and shared by:
- `factor_matrix(kkt, K, mu_rel) -> fac`: `K + μS` (LU-factorised by the dense back end);
- `apply(fac, b)`: solve with it (Newton's damping test reuses one factorisation);
- `matvec(K, v)`: `K v`;
- `lm_solve_matrix(K, nu, R)`: the Levenberg–Marquardt step `−(KᵀK + ν I)⁻¹ KᵀR`;
- `factor(kkt, w, mu_rel, identity_hessian=False)`, `solve(...)`: the compositions.
Evaluating the second derivatives once per step (not again for the LM fallback and its model)
keeps the compiled Newton loop small: compile time is dominated by the size of the traced
graph, and the per-cell Hessians are its largest part.
The sparse back end's index arrays enter the compiled solver as constants (it is a static
argument of `jit`): XLA's gathers and scatters with constant indices are ~10× faster than
with traced ones.
- `DenseAlgebra`: `K` by forward-over-reverse autodiff, LU by `jax.scipy.linalg.lu_factor` (not
  lineax's LU, whose structure check fails inside `jax.shard_map`: `solve_batch`).  For n ≲ 2,000.
- `SparseAlgebra`: `K` assembled from the per-cell Hessian blocks of a problem declared with
  `dg.local_sum` / `dg.local_map`, factorised by KLU (klujax), inside `jit`, `vmap`-able.
  Its LM step solves the augmented system `[[I, K], [Kᵀ, −ν I]] (s, d) = (−R, 0)`, which
  keeps K's sparsity.

`identity_hessian=True` replaces `∇²L` by the identity: the system then gives the least-squares
multipliers `argmin_λ |∇E − Jᵀλ|` used to start Newton.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._kkt import KKT
from ._sparse import SparsePattern, cell_blocks

MU_FLOOR = 1e-300


def _regularisation(n: int, m: int, mu):
    return jnp.concatenate([jnp.full((n,), mu), jnp.full((m,), -mu)])


class _Algebra:
    """The compositions shared by both back ends."""

    def factor(self, kkt: KKT, w, mu_rel, identity_hessian=False):
        return self.factor_matrix(kkt, self.matrix(kkt, w, identity_hessian), mu_rel)

    def solve(self, kkt: KKT, w, mu_rel, b, identity_hessian=False):
        return self.apply(self.factor(kkt, w, mu_rel, identity_hessian), b)


class DenseAlgebra(_Algebra):
    """Dense KKT matrix by `jax.hessian` of the Lagrangian; LU solve."""

    def __hash__(self):
        return hash(DenseAlgebra)

    def __eq__(self, other):
        return isinstance(other, DenseAlgebra)

    def matrix(self, kkt: KKT, w, identity_hessian=False):
        n, m = kkt.spec.n, kkt.spec.m
        if identity_hessian:
            u, _ = kkt.split(w)
            J = jax.jacfwd(kkt.g)(u)
            return jnp.block([[jnp.eye(n), -J.T], [-J, jnp.zeros((m, m))]])
        return jax.hessian(kkt.lagrangian)(w)

    def factor_matrix(self, kkt: KKT, K, mu_rel):
        scale = jnp.maximum(jnp.max(jnp.abs(K)), 1.0)
        K = K + jnp.diag(_regularisation(kkt.spec.n, kkt.spec.m, jnp.maximum(mu_rel * scale, MU_FLOOR)))
        return jax.scipy.linalg.lu_factor(K)

    def apply(self, fac, b):
        return jax.scipy.linalg.lu_solve(fac, b)

    def matvec(self, K, v):
        return K @ v

    def lm_solve_matrix(self, K, nu, R):
        normal = K.T @ K + nu * jnp.eye(K.shape[0])
        return self.apply(jax.scipy.linalg.lu_factor(normal), -K.T @ R)



def _klu_solve(rows, cols, values, b, symbolic):
    """Solve with KLU, reusing a symbolic analysis, for COO indices already sorted by (row, col).

    `klujax.solve_with_symbol` lexsorts the indices on every call; our patterns are sorted
    when built (`np.unique`), so we bind its primitive directly: that sort cost ~30% of a
    sparse Newton step at 10⁴ unknowns, and constant-folding it made compiles take ~30 s.
    `tests/test_solve.py` checks this against `klujax.solve`.
    """
    import klujax

    handle = jnp.asarray(symbolic.raw, dtype=jnp.uint64)
    rhs = b.reshape(1, b.shape[0], -1)  # (n_lhs = 1, n_col, n_rhs)
    x = klujax.solve_with_symbol_f64.bind(
        jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32), values[None, :], rhs, handle
    )
    return x.reshape(b.shape)


def _bordered_solve(split, values, b):
    """Solve `[[A, B], [Bᵗ, C]] x = b` through the Schur complement of the border (`Bordered`)."""
    n_in, p = len(split.interior), len(split.border)
    B = jnp.zeros((n_in, p)).at[split.b_rows, split.b_cols].add(values[split.take_b])
    Bt = jnp.zeros((p, n_in)).at[split.bt_rows, split.bt_cols].add(values[split.take_bt])
    C = jnp.zeros((p, p)).at[split.c_rows, split.c_cols].add(values[split.take_c])
    rhs = jnp.concatenate([b[split.interior][:, None], B], axis=1)
    Y = _klu_solve(split.a_rows, split.a_cols, values[split.take_a], rhs, split.symbolic())
    schur = C - Bt @ Y[:, 1:]
    x_border = jnp.linalg.solve(schur, b[split.border] - Bt @ Y[:, 0])
    x_interior = Y[:, 0] - Y[:, 1:] @ x_border
    return jnp.zeros_like(b).at[split.interior].set(x_interior).at[split.border].set(x_border)


class SparseAlgebra(_Algebra):
    """Sparse KKT matrix assembled from local blocks; KLU solve (klujax)."""

    def __init__(self, pattern: SparsePattern):
        self.pattern = pattern
        # KLU's analyses, made here, outside any trace
        for augmented in (False, True):
            if pattern.split(augmented) is None:
                pattern.symbolic(augmented)

    # Equal by the problem structure the pattern was built from (functions, stencils, layout),
    # so that every problem declared alike (e.g. each `elastica.clamped(n, ...)` call) reuses
    # one compiled solver.  jit's cache keeps the first algebra, and with it the KLU analyses
    # its compiled code refers to, alive.
    def __hash__(self):
        return hash(self.pattern.key)

    def __eq__(self, other):
        return isinstance(other, SparseAlgebra) and other.pattern.key == self.pattern.key

    def matrix(self, kkt: KKT, w, identity_hessian=False):
        """Coalesced COO values of K (K's Hessian block replaced by I if asked)."""
        n, m, p = kkt.spec.n, kkt.spec.m, self.pattern
        hess, jac = cell_blocks(p, kkt, w, identity_hessian)
        raw = jnp.concatenate([hess, -jac])
        # a concatenation, not `zeros.at[:n].add`: XLA constant-folds that scatter (seconds at 10⁵)
        diag = jnp.concatenate([jnp.full((n,), 1.0 if identity_hessian else 0.0), jnp.zeros((m,))])
        values = jnp.concatenate([raw[p.source], diag])
        return jax.ops.segment_sum(values, p.target, num_segments=p.nnz)

    def factor_matrix(self, kkt: KKT, K, mu_rel):
        n, m, p = kkt.spec.n, kkt.spec.m, self.pattern
        scale = jnp.maximum(jnp.max(jnp.abs(K)), 1.0)
        diagonal = p.target[p.source.shape[0]:]  # where the n + m diagonal entries were summed
        return K.at[diagonal].add(_regularisation(n, m, jnp.maximum(mu_rel, MU_FLOOR) * scale))

    def apply(self, fac, b):
        split = self.pattern.split()
        if split is not None:
            return _bordered_solve(split, fac, b)
        return _klu_solve(self.pattern.rows, self.pattern.cols, fac, b, self.pattern.symbolic())

    def matvec(self, K, v):
        p = self.pattern
        return jax.ops.segment_sum(K * v[p.cols], p.rows, num_segments=v.shape[0])

    def lm_solve_matrix(self, K, nu, R):
        size = R.shape[0]
        aug = jnp.concatenate([jnp.ones((size,)), K, K, jnp.full((size,), -nu)])
        rhs = jnp.concatenate([-R, jnp.zeros_like(R)])
        rows, cols, order = self.pattern.augmented()
        split = self.pattern.split(augmented=True)
        if split is not None:
            return _bordered_solve(split, aug[order], rhs)[size:]
        return _klu_solve(rows, cols, aug[order], rhs, self.pattern.symbolic(augmented=True))[size:]
