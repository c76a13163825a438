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
The back ends are pytrees: the sparse one's index arrays are arguments of the compiled solver
(`_sparse.index_arrays`), its pattern and KLU analysis static data.
- `DenseAlgebra`: `K` by forward-over-reverse autodiff, LU by `jax.scipy.linalg.lu_factor` (not
  lineax's LU, whose structure check fails inside `jax.shard_map`: `solve_batch`).  For n ≲ 2,000.
- `SparseAlgebra`: `K` assembled from the per-cell Hessian blocks of a problem declared with
  `dg.local_sum` / `dg.local_map`, factorised by KLU (klujax), inside `jit`, `vmap`-able.
  Its LM step is one complex solve with `K + i√ν I`, on K's own pattern and KLU analysis.

`identity_hessian=True` replaces `∇²L` by the identity: the system then gives the least-squares
multipliers `argmin_λ |∇E − Jᵀλ|` used to start Newton.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._kkt import KKT
from ._sparse import SPLIT_ARRAYS, PatternKey, SparsePattern, index_arrays, kkt_values

MU_FLOOR = 1e-300


def _regularisation(n: int, m: int, mu):
    return jnp.concatenate([jnp.full((n,), mu), jnp.full((m,), -mu)])


class _Algebra:
    """The compositions shared by both back ends."""

    def factor(self, kkt: KKT, w, mu_rel, identity_hessian=False):
        return self.factor_matrix(kkt, self.matrix(kkt, w, identity_hessian), mu_rel)

    def solve(self, kkt: KKT, w, mu_rel, b, identity_hessian=False):
        return self.apply(self.factor(kkt, w, mu_rel, identity_hessian), b)


@jax.tree_util.register_pytree_node_class
class DenseAlgebra(_Algebra):
    """Dense KKT matrix by `jax.hessian` of the Lagrangian; LU solve.  A pytree without leaves."""

    def tree_flatten(self):
        return (), None

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls()

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
    solve = klujax.solve_with_symbol_c128 if jnp.iscomplexobj(values) else klujax.solve_with_symbol_f64
    x = solve.bind(
        jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32), values[None, :], rhs, handle
    )
    return x.reshape(b.shape)


def _bordered_solve(split, index: dict, values, b):
    """Solve `[[A, B], [Bᵗ, C]] x = b` through the Schur complement of the border (`Bordered`);
    `index` holds its arrays (`split_*`), `split` the sizes and KLU's analysis of A."""
    ix = {name: index[f"split_{name}"] for name in SPLIT_ARRAYS}
    n_in, p = len(split.interior), len(split.border)
    B = jnp.zeros((n_in, p), values.dtype).at[ix["b_rows"], ix["b_cols"]].add(values[ix["take_b"]])
    Bt = jnp.zeros((p, n_in), values.dtype).at[ix["bt_rows"], ix["bt_cols"]].add(values[ix["take_bt"]])
    C = jnp.zeros((p, p), values.dtype).at[ix["c_rows"], ix["c_cols"]].add(values[ix["take_c"]])
    rhs = jnp.concatenate([b[ix["interior"]][:, None], B], axis=1)
    Y = _klu_solve(ix["a_rows"], ix["a_cols"], values[ix["take_a"]], rhs, split.symbolic())
    schur = C - Bt @ Y[:, 1:]
    x_border = jnp.linalg.solve(schur, b[ix["border"]] - Bt @ Y[:, 0])
    x_interior = Y[:, 0] - Y[:, 1:] @ x_border
    return jnp.zeros(b.shape, values.dtype).at[ix["interior"]].set(x_interior).at[ix["border"]].set(x_border)


@jax.tree_util.register_pytree_node_class
class SparseAlgebra(_Algebra):
    """Sparse KKT matrix assembled from local blocks; KLU solve (klujax).

    A pytree whose leaves are the pattern's index arrays (`index_arrays`) and whose static
    part is the pattern (compared by structure, `PatternKey`): the compiled solver takes the
    arrays as arguments.
    """

    def __init__(self, pattern: SparsePattern, index: dict | None = None):
        self.pattern = pattern
        if index is None:
            # KLU's analysis, made here, outside any trace
            if pattern.split() is None:
                pattern.symbolic()
            index = index_arrays(pattern)
        self.index = index

    def tree_flatten(self):
        names = tuple(sorted(self.index))
        return tuple(self.index[k] for k in names), (PatternKey(self.pattern), names)

    @classmethod
    def tree_unflatten(cls, aux, children):
        key, names = aux
        return cls(key.pattern, dict(zip(names, children)))

    def matrix(self, kkt: KKT, w, identity_hessian=False):
        """Coalesced COO values of K (K's Hessian block replaced by I if asked)."""
        return kkt_values(self.pattern, self.index, kkt, w, identity_hessian)

    def factor_matrix(self, kkt: KKT, K, mu_rel):
        n, m = kkt.spec.n, kkt.spec.m
        scale = jnp.maximum(jnp.max(jnp.abs(K)), 1.0)
        return K.at[self.index["diagonal"]].add(_regularisation(n, m, jnp.maximum(mu_rel, MU_FLOOR) * scale))

    def apply(self, fac, b):
        split = self.pattern.split()
        if split is not None:
            return _bordered_solve(split, self.index, fac, b)
        return _klu_solve(self.index["rows"], self.index["cols"], fac, b, self.pattern.symbolic())

    def matvec(self, K, v):
        return jax.ops.segment_sum(K * v[self.index["cols"]], self.index["rows"], num_segments=v.shape[0])

    def lm_solve_matrix(self, K, nu, R):
        """`−(K² + ν I)⁻¹ K R = −Re[(K + i√ν I)⁻¹ R]` (K symmetric: `(K + isI)⁻¹ = (K − isI)(K² + s²I)⁻¹`),
        one complex KLU solve on K's own pattern and analysis, with smallest singular value ≥ √ν."""
        shifted = K.astype(jnp.complex128).at[self.index["diagonal"]].add(1j * jnp.sqrt(nu))
        return -jnp.real(self.apply(shifted, R.astype(jnp.complex128)))
