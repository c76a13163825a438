"""Implicit differentiation of a KKT point with respect to `params` and the fixed data `z0`.

At a solution `R(w*(p), p) = 0`, so `K dw*/dp = −∂R/∂p` (implicit function theorem).  The rule
is a `custom_jvp`: the tangent of `w*` along `(ż0, ṗ)` is `ẇ = −K⁻¹ (∂R/∂z0 ż0 + ∂R/∂p ṗ)`, one
linear solve with the back end (dense, sparse or Krylov) that Newton used (`solve_once`),
linear in the right-hand side, so that JAX transposes it: reverse mode (`grad`, `jacrev`)
solves with `Kᵀ = K` on cotangents, forward mode (`jvp`, `jacfwd`) with `K` on tangents, and
`hessian` differentiates the solve once more.
The back end is an argument (a pytree of index arrays) with no derivative, and the solver loop
itself is never differentiated.

A solve that did not converge has no derivative: its tangents (and so its cotangents) are NaN.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

from ._kkt import KKT

ADJOINT_MU = 1e-13  # relative regularisation of the derivative's solve (singular K under symmetry)


@partial(jax.custom_jvp, nondiff_argnums=(0,))
def implicit_solution(spec, linear, w_star, z0, params, converged):
    """Identity on `w_star`; its derivative is that of the KKT point as a function of (z0, params)
    where `converged`, NaN elsewhere."""
    return w_star


@implicit_solution.defjvp
def _tangent(spec, primals, tangents):
    linear, w_star, z0, params, converged = primals
    _, _, dz0, dparams, _ = tangents
    kkt = KKT(spec, z0, params)
    # w* as a function of (z0, params) again, so that differentiating this rule (second
    # derivatives: `hessian`, `jacfwd(grad)`) sees how K and ∂R/∂p move with the solution
    w_of_p = implicit_solution(spec, linear, w_star, z0, params, converged)

    def R_of(z0_, params_):
        return KKT(spec, z0_, params_).residual(w_of_p)

    _, dR = jax.jvp(R_of, (z0, params), (dz0, dparams))
    dw = -linear.solve_once(kkt, w_of_p, ADJOINT_MU, dR)
    no_derivative = jnp.where(converged, 1.0, jnp.nan)  # a factor, so the tangent stays linear
    return w_of_p, dw * no_derivative
