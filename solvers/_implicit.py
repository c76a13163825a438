"""Implicit differentiation of a KKT point with respect to `params` and the fixed data `z0`.

At a solution `R(w*(p), p) = 0`, so `K dw*/dp = −∂R/∂p`.  Reverse mode: for a cotangent `w̄`,
solve `Kᵀ v = w̄` and return `p̄ = −vᵀ ∂R/∂p`, one linear solve with the
same back end (dense, sparse or Krylov) that Newton used; the back end is an argument
(a pytree of index arrays) with no derivative.  The solver loop itself is never
differentiated.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

from ._kkt import KKT

ADJOINT_MU = 1e-13  # relative regularisation of the adjoint solve (singular K under symmetry)


@partial(jax.custom_vjp, nondiff_argnums=(0,))
def implicit_solution(spec, linear, w_star, z0, params):
    """Identity on `w_star`; its derivative is that of the KKT point as a function of (z0, params)."""
    return w_star


def _fwd(spec, linear, w_star, z0, params):
    return w_star, (linear, w_star, z0, params)


def _bwd(spec, residuals, w_bar):
    linear, w_star, z0, params = residuals
    kkt = KKT(spec, z0, params)
    v = linear.apply_transpose(linear.factor(kkt, w_star, ADJOINT_MU), w_bar)

    def R_of(z0_, params_):
        return KKT(spec, z0_, params_).residual(w_star)

    _, vjp = jax.vjp(R_of, z0, params)
    z0_bar, params_bar = vjp(-v)
    return None, jnp.zeros_like(w_star), z0_bar, params_bar


implicit_solution.defvjp(_fwd, _bwd)
