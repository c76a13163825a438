"""Linear algebra of Newton–KKT: solve the regularised KKT system `(K + μ S) d = b`.

`S = diag(I_n, −I_m)`.  The regularisation makes the system solvable when the KKT matrix is
singular (a continuous symmetry of the energy, redundant constraints); with μ proportional to
the residual it leaves Newton's quadratic convergence intact.  `μ` is given relative to the
largest entry of `K`, so that it means the same whatever the scaling of the energy.

Two interchangeable back ends with one method, `solve(kkt, arrays, w, mu_rel, b, identity_hessian)`
(`arrays`: the back end's index arrays, passed explicitly so that they are ordinary traced
arguments of the jitted solver; `None` for the dense back end).  The back ends themselves are
static and hashable:
- `DenseAlgebra`: `K` by forward-over-reverse autodiff, LU through lineax.  For n ≲ 2,000.
- `SparseAlgebra`: `K` assembled from the per-cell Hessian blocks of a problem declared with
  `dg.local_sum` / `dg.local_map`, factorised by KLU (klujax), inside `jit`, `vmap`-able.

`lm_solve(kkt, arrays, w, nu, R)` returns the Levenberg–Marquardt step
`d = −(KᵀK + ν I)⁻¹ KᵀR` (dense: normal equations; sparse: the augmented system
`[[I, K], [Kᵀ, −ν I]] (s, d) = (−R, 0)`, which keeps K's sparsity).

`identity_hessian=True` replaces `∇²L` by the identity: the system then gives the least-squares
multipliers `argmin_λ |∇E − Jᵀλ|` used to start Newton.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import lineax as lx

from ._kkt import KKT
from ._sparse import SparsePattern, cell_blocks

MU_FLOOR = 1e-300


def _regularisation(n: int, m: int, mu):
    return jnp.concatenate([jnp.full((n,), mu), jnp.full((m,), -mu)])


class DenseAlgebra:
    """Dense KKT matrix by `jax.hessian` of the Lagrangian; LU solve."""

    def __hash__(self):
        return hash(DenseAlgebra)

    def __eq__(self, other):
        return isinstance(other, DenseAlgebra)

    def arrays(self):
        return None

    def solve(self, kkt: KKT, arrays, w, mu_rel, b, identity_hessian=False):
        n, m = kkt.spec.n, kkt.spec.m
        if identity_hessian:
            u, _ = kkt.split(w)
            J = jax.jacfwd(kkt.g)(u)
            K = jnp.block([[jnp.eye(n), -J.T], [-J, jnp.zeros((m, m))]])
        else:
            K = jax.hessian(kkt.lagrangian)(w)
        scale = jnp.maximum(jnp.max(jnp.abs(K)), 1.0)
        K = K + jnp.diag(_regularisation(n, m, jnp.maximum(mu_rel * scale, MU_FLOOR)))
        return _lu_solve(K, b)

    def lm_solve(self, kkt: KKT, arrays, w, nu, R):
        K = jax.hessian(kkt.lagrangian)(w)
        normal = K.T @ K + nu * jnp.eye(K.shape[0])
        return _lu_solve(normal, -K.T @ R)


def _lu_solve(A, b):
    return lx.linear_solve(lx.MatrixLinearOperator(A), b, lx.LU(), throw=False).value


class SparseAlgebra:
    """Sparse KKT matrix assembled from local blocks; KLU solve (klujax)."""

    def __init__(self, pattern: SparsePattern):
        self.pattern = pattern

    def __hash__(self):
        return id(self.pattern)

    def __eq__(self, other):
        return isinstance(other, SparseAlgebra) and other.pattern is self.pattern

    def arrays(self):
        return self.pattern.arrays()

    def _values(self, kkt: KKT, arrays, w, mu_rel, identity_hessian):
        """Coalesced COO values of `K + μS` (K's Hessian block replaced by I if asked)."""
        n, m = kkt.spec.n, kkt.spec.m
        hess, jac = cell_blocks(self.pattern, kkt, w, identity_hessian)
        raw = jnp.concatenate([hess, -jac])
        scale = jnp.maximum(jnp.max(jnp.abs(raw)) if raw.size else 1.0, 1.0)
        diag = _regularisation(n, m, mu_rel * scale)
        if identity_hessian:
            diag = diag.at[:n].add(1.0)
        values = jnp.concatenate([raw[arrays["source"]], diag])
        return jax.ops.segment_sum(values, arrays["target"], num_segments=self.pattern.nnz)

    def solve(self, kkt: KKT, arrays, w, mu_rel, b, identity_hessian=False):
        import klujax

        mu_rel = jnp.maximum(mu_rel, MU_FLOOR)
        values = self._values(kkt, arrays, w, mu_rel, identity_hessian)
        return klujax.solve(arrays["rows"], arrays["cols"], values, b)

    def lm_solve(self, kkt: KKT, arrays, w, nu, R):
        import klujax

        size = R.shape[0]
        values = self._values(kkt, arrays, w, 0.0, False)
        aug = jnp.concatenate([jnp.ones((size,)), values, values, jnp.full((size,), -nu)])
        rhs = jnp.concatenate([-R, jnp.zeros_like(R)])
        return klujax.solve(arrays["aug_rows"], arrays["aug_cols"], aug, rhs)[size:]
