"""First-order phase: the augmented Lagrangian method with L-BFGS inner solves (jaxopt).

For a *minimisation* problem this needs only gradients, so it is cheap per step and robust far
from the solution; it either solves the problem alone (`method="lbfgs"`) or warm-starts Newton
(`warm_start="lbfgs"`).  With `L_ρ(u; λ) = E(u) − λ·g(u) + ½ρ|g(u)|²`:

    u ← argmin_u L_ρ(u; λ)          (L-BFGS, jaxopt)
    λ ← λ − ρ g(u)                   (first-order multiplier update, our sign: ∇E = Jᵀλ)
    ρ ← 10ρ  if |g| did not shrink by a factor 4

It stops at the tolerance, after `outer_steps`, or when the residual has stagnated: no outer
step in the last `STALL_OUTER` lowered the best residual by `STALL_FACTOR` (where no critical
point is near, e.g. a catenoid beyond its fold, the penalty ρ reaches its cap and each further
outer step costs a full L-BFGS run without progress).

It cannot find saddle points; Newton can.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import jax
import jax.numpy as jnp

from ._kkt import KKT, scaled_residual


STALL_OUTER = 5  # outer steps without progress after which the phase stops
STALL_FACTOR = 0.9  # progress: the best residual lowered by this factor at least


class FirstOrderState(NamedTuple):
    u: jax.Array
    lam: jax.Array
    rho: jax.Array
    g_norm: jax.Array
    residual: jax.Array
    step: jax.Array
    best: jax.Array  # the least residual reached
    stalled: jax.Array  # outer steps since the best residual last fell by STALL_FACTOR


def augmented_lagrangian(kkt: KKT, w0, weights, *, tol: float, outer_steps: int, inner_steps: int = 500):
    """Run at most `outer_steps` outer iterations; returns `(w, outer steps taken, residual)`."""
    with warnings.catch_warnings():  # imported here: jaxopt pulls in scipy.optimize and numba
        warnings.simplefilter("ignore", DeprecationWarning)
        import jaxopt

    n = kkt.spec.n

    def L_rho(u, lam, rho):
        g = kkt.g(u)
        return kkt.energy(u) - jnp.dot(lam, g) + 0.5 * rho * jnp.dot(g, g)

    lbfgs = jaxopt.LBFGS(fun=L_rho, maxiter=inner_steps, tol=0.1 * tol, implicit_diff=False)

    def residual_of(u, lam):
        return scaled_residual(kkt.residual(jnp.concatenate([u, lam])), weights, n)

    def cond(s: FirstOrderState):
        return (s.residual > tol) & (s.step < outer_steps) & (s.stalled < STALL_OUTER)

    def body(s: FirstOrderState) -> FirstOrderState:
        u = lbfgs.run(s.u, s.lam, s.rho).params
        g = kkt.g(u)
        lam = s.lam - s.rho * g
        g_norm = jnp.max(jnp.abs(g)) if g.size else jnp.zeros(())
        rho = jnp.where(g_norm > 0.25 * s.g_norm, 10.0 * s.rho, s.rho)
        residual = residual_of(u, lam)
        progress = residual <= STALL_FACTOR * s.best
        return FirstOrderState(u, lam, jnp.minimum(rho, 1e8), g_norm, residual, s.step + 1,
                               jnp.where(progress, residual, s.best), jnp.where(progress, 0, s.stalled + 1))

    u0, lam0 = kkt.split(w0)
    inf = jnp.asarray(jnp.inf)  # the best residual counts from the first outer step: ρ starts small
    s0 = FirstOrderState(u0, lam0, jnp.asarray(10.0), inf, residual_of(u0, lam0), jnp.asarray(0), inf, jnp.asarray(0))
    s = jax.lax.while_loop(cond, body, s0)
    return jnp.concatenate([s.u, s.lam]), s.step, s.residual
