"""`DenseLU`: the KKT matrix by forward-over-reverse autodiff, LU-factorised.

`jax.hessian` of the Lagrangian, then `jax.scipy.linalg.lu_factor` (not lineax's LU, whose
structure check fails inside `jax.shard_map`: `solve_batch`).  Any backend, inside `jit`,
`vmap` and `grad`; for N = n + m ≲ 2,000 (beyond that one LU costs seconds and gigabytes).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._kkt import KKT
from ._linear import LinearSolver, row_regularisation


@jax.tree_util.register_pytree_node_class
class DenseLU(LinearSolver):
    """Dense KKT matrix by `jax.hessian` of the Lagrangian; LU solve.  A pytree without leaves."""

    iterative_refinement = True

    def tree_flatten(self):
        return (), None

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls()

    def __repr__(self):
        return "DenseLU()"

    def matrix(self, kkt: KKT, w, identity_hessian=False):
        n, m = kkt.spec.n, kkt.spec.m
        if identity_hessian:
            u, _ = kkt.split(w)
            J = jax.jacfwd(kkt.g)(u)
            return jnp.block([[jnp.eye(n), -J.T], [-J, jnp.zeros((m, m))]])
        return jax.hessian(kkt.lagrangian)(w)

    def factor_matrix(self, kkt: KKT, K, mu_rel):
        """`lu_factor(K + μS)`, μ scaled row by row (`row_regularisation`)."""
        mu_s = row_regularisation(kkt.spec.n, kkt.spec.m, mu_rel, jnp.max(jnp.abs(K), axis=1))
        return jax.scipy.linalg.lu_factor(K + jnp.diag(mu_s))

    def apply(self, fac, b):
        return jax.scipy.linalg.lu_solve(fac, b)

    def apply_transpose(self, fac, b):
        return jax.scipy.linalg.lu_solve(fac, b, trans=1)

    def matvec(self, K, v):
        return K @ v

    def solve_once(self, kkt, w, mu_rel, b):
        """The LU solve itself: JAX transposes it and differentiates it again (`jax.hessian`)."""
        return self.solve(kkt, w, mu_rel, b)

    def lm_solve_matrix(self, K, nu, R):
        normal = K.T @ K + nu * jnp.eye(K.shape[0])
        return jax.scipy.linalg.lu_solve(jax.scipy.linalg.lu_factor(normal), -K.T @ R)
