"""Globalised Newton's method on the KKT system `R(w) = 0` (Newton / Levenberg–Marquardt hybrid).

Each step first tries the Newton step `Δ = −K⁻¹R` (with a regularisation μ = 1e-14 relative to
each row of K, enough to factorise an exactly singular K, and one step of iterative refinement
with the unregularised K: `LinearSolver.refined`), damped `αΔ` with
α = 1, ½, … until Deuflhard's natural monotonicity test holds (`_step`); near a
solution the full step is taken, so convergence is quadratic, and a quadratic program takes
one step.

If even α = 2⁻¹⁰ fails, the step is a Levenberg–Marquardt step on the merit `φ = ½|R|²`, `d = −(KᵀK + ν I)⁻¹ KᵀR`, a descent direction
of `φ` for every ν > 0, with `ν = θ|R|` and θ adapted like a trust region radius by the ratio
of actual to predicted decrease of `φ` (Fan–Yuan).  LM steps are well defined when K is
singular (continuous symmetries, where the solutions form a manifold), and converge there too.

The iteration stops as stalled when the residual has not halved in `STAGNATION_STEPS` steps
(`_stagnant`): `solve`'s `warm_start="auto"` then retries from an L-BFGS minimisation.

The merit is the size of the residual, not the energy, so saddle points (Euler's figure-eight
elastica) are found as readily as minima.  A minimisation problem started very far away is
better served by `warm_start="lbfgs"`.  The iteration is one `lax.while_loop` and the trials
of a step another, with one evaluation of the residual in it: compile time grows with the
traced graph.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from ._kkt import KKT, scaled_residual

CONVERGED, MAX_STEPS, STALLED, NONFINITE, RUNNING = 0, 1, 2, 3, -1
STAGNATION_STEPS = 20
"""Steps in which the residual must fall below half its smallest value before them (`_stagnant`)."""
STATUS_TEXT = {
    CONVERGED: "converged",
    MAX_STEPS: "reached max_steps",
    STALLED: f"stalled: no step decreases the residual, or it has not halved in {STAGNATION_STEPS} steps (if the "
    "residual is tiny, it is at the round-off level of float64 for this problem: loosen tol)",
    NONFINITE: "the energy or its derivatives became non-finite",
}
"""What `Solution.status` means, by its value (`solvers.STATUS_TEXT`)."""

ARMIJO = 1e-4
NEWTON_MU = 1e-14
MIN_NEWTON_STEP = 2.0**-10
ROUNDOFF = 1e-13
THETA_START, THETA_MIN, THETA_MAX = 1e-3, 1e-10, 1e12


class NewtonState(NamedTuple):
    w: jax.Array
    R: jax.Array
    residual: jax.Array
    theta: jax.Array
    step: jax.Array
    history: jax.Array
    status: jax.Array


def _merit(R):
    return 0.5 * jnp.dot(R, R)


class Trial(NamedTuple):
    """The state of the trials of one step: the last damping tried (2 before the first), whether
    the trial was the Levenberg–Marquardt one, the step, the residual there, acceptance, θ."""

    alpha: jax.Array
    lm: jax.Array
    d: jax.Array
    R_new: jax.Array
    ok: jax.Array
    theta: jax.Array


def _lm_direction(linear, K, R, theta, wanted):
    """The Levenberg–Marquardt step `d = −(KᵀK + ν I)⁻¹ KᵀR`, `ν = θ|R|`, and `K d` (for the
    predicted decrease), if `wanted`, else zeros: the Newton trials pay neither.

    A loop that runs 0 or 1 times rather than `lax.cond`: under `vmap` a cond with a batched
    predicate batches all its operands, incl. the sparse index arrays, which KLU cannot take
    batched; a while_loop keeps them unbatched.  The loop consumes R from its state (the
    state's R is zero after the step): a body computed from loop-invariant values only would be
    hoisted out of the loop by XLA, and run whether wanted or not."""
    nu = theta * jnp.linalg.norm(R)

    def body(carry):
        _, _, rhs, _ = carry
        d = linear.lm_solve_matrix(K, nu, rhs)
        return d, linear.matvec(K, d), jnp.zeros_like(rhs), jnp.asarray(False)

    zeros = jnp.zeros_like(R)
    d, Kd, _, _ = jax.lax.while_loop(lambda carry: carry[3], body, (zeros, zeros, R, wanted))
    return d, Kd


def _step(kkt: KKT, linear, K, w, R, theta, active=True):
    """One globalised step from `w`: damped Newton trials, then at most one LM trial.

    Newton: with the correction `Δ = −K(w)⁻¹R(w)` and, for a trial `w + αΔ`, the simplified
    correction `Δ̄ = −K(w)⁻¹R(w + αΔ)` (same factorisation), the step is accepted when
    `|Δ̄| ≤ (1 − α/4)|Δ|` (Deuflhard's natural monotonicity test), for the largest α in
    {1, ½, …, 2⁻¹⁰}.  Unlike a test on |R| this does not depend on how the equations are
    scaled, so a start with a small residual but far from the answer (a field acting on a long
    chain) still takes long steps.  Near a solution `|Δ̄| = O(|Δ|²)` and α = 1: quadratic
    convergence.

    If no α passes, one Levenberg–Marquardt trial `d = −(KᵀK + ν I)⁻¹ KᵀR` on the merit
    `φ = ½|R|²`, accepted when the ratio ρ of actual to predicted decrease of φ exceeds
    `ARMIJO`; θ grows when ρ < ¼ and shrinks when ρ > ¾ (Fan–Yuan) and after a Newton step.
    No LM trial when the Newton correction is at the round-off level of w: the residual cannot
    be reduced further in float64 (`stuck`).

    All trials are one loop with one evaluation of the residual, so the compiled program holds
    the residual once.  Returns `(d, R(w + d), accepted, θ, stuck)`; `K = linear.matrix(kkt, w)`.
    With `active` False no trial is made (nothing accepted): under `vmap` the members that
    have finished still run the step, and their trials, discarded, would keep the loop going.
    """
    fac = linear.factor_matrix(kkt, K, NEWTON_MU)
    return linear.factorised(fac, lambda solve: _trials(kkt, linear, solve, K, w, R, theta, active))


def _trials(kkt: KKT, linear, solve, K, w, R, theta, active):
    """The trials of `_step`, `solve` applying the factorised `(K + μS)⁻¹`."""
    delta = linear.refined(solve, K, -R)
    size = jnp.linalg.norm(delta)
    at_roundoff = jnp.max(jnp.abs(delta)) <= ROUNDOFF * jnp.maximum(1.0, jnp.max(jnp.abs(w)))

    def cond(t: Trial):
        newton_left = (t.alpha > MIN_NEWTON_STEP) | ~at_roundoff
        return active & ~t.ok & ~t.lm & newton_left

    def body(t: Trial) -> Trial:
        alpha = 0.5 * t.alpha  # the first trial is α = 1; after 2⁻¹⁰, the LM trial
        lm = alpha < MIN_NEWTON_STEP
        d_lm, Kd_lm = _lm_direction(linear, K, R, t.theta, lm)
        d = jnp.where(lm, d_lm, alpha * delta)
        R_new = kkt.residual(w + d)
        simplified = jnp.linalg.norm(solve(-R_new))
        newton_ok = jnp.isfinite(_merit(R_new)) & jnp.isfinite(simplified) & jnp.isfinite(size)
        newton_ok = newton_ok & (simplified <= (1 - alpha / 4) * size)
        predicted = _merit(R) - _merit(R + Kd_lm)  # meaningful in the LM trial only
        rho = jnp.where(predicted > 0, (_merit(R) - _merit(R_new)) / predicted, -1.0)
        rho = jnp.where(jnp.isfinite(rho) & jnp.all(jnp.isfinite(d)), rho, -1.0)
        theta_lm = jnp.where(rho < 0.25, 4.0 * t.theta, jnp.where(rho > 0.75, jnp.maximum(t.theta / 4, THETA_MIN), t.theta))
        ok = jnp.where(lm, rho > ARMIJO, newton_ok)
        theta = jnp.where(lm, theta_lm, jnp.where(ok, jnp.maximum(t.theta / 4, THETA_MIN), t.theta))
        return Trial(alpha, lm, d, R_new, ok, theta)

    false = jnp.asarray(False)
    t = jax.lax.while_loop(cond, body, Trial(jnp.asarray(2.0, w.dtype), false, jnp.zeros_like(w), R, false, theta))
    return t.d, t.R_new, t.ok, t.theta, ~t.ok & ~t.lm & at_roundoff


def _stagnant(history, step):
    """Whether the residuals of the last `STAGNATION_STEPS` steps all exceed half the smallest
    residual before them: Newton makes no progress (e.g. it has reached a singular critical point,
    which it approaches at the rate ½ and then cannot resolve: a mesh whose triangles collapse).
    `history[k]` is the residual after step k; no verdict in the first `STAGNATION_STEPS` steps."""
    k = jnp.arange(history.shape[0])
    before = jnp.min(jnp.where(k <= step - STAGNATION_STEPS, history, jnp.inf))
    recent = jnp.min(jnp.where((k > step - STAGNATION_STEPS) & (k <= step), history, jnp.inf))
    return recent > 0.5 * before


def newton(kkt: KKT, linear, w0, weights, *, tol: float, max_steps: int) -> NewtonState:
    n = kkt.spec.n
    R0 = kkt.residual(w0)
    res0 = scaled_residual(R0, weights, n)
    history = jnp.full((max_steps + 1,), jnp.nan).at[0].set(res0)
    go_on = RUNNING if max_steps > 0 else MAX_STEPS
    finite = jnp.isfinite(res0) & jnp.isfinite(kkt.energy(kkt.split(w0)[0]))
    status0 = jnp.where(finite, jnp.where(res0 <= tol, CONVERGED, go_on), NONFINITE)
    state = NewtonState(w0, R0, res0, jnp.asarray(THETA_START), jnp.asarray(0), history, status0)
    if max_steps == 0:  # the KKT residual at w0 only: no second derivatives, no linear solver in the program
        return state

    def cond(s: NewtonState):
        return s.status == RUNNING

    def body(s: NewtonState) -> NewtonState:
        K = linear.matrix(kkt, s.w)  # the second derivatives, once per step
        d, R_new, ok, theta, stuck = _step(kkt, linear, K, s.w, s.R, s.theta, s.status == RUNNING)
        w = jnp.where(ok, s.w + d, s.w)
        R = jnp.where(ok, R_new, s.R)
        residual = scaled_residual(R, weights, n)
        step = s.step + 1
        history = s.history.at[step].set(residual)
        status = jnp.where(
            residual <= tol,
            CONVERGED,
            jnp.where(
                ~jnp.isfinite(residual),
                NONFINITE,
                jnp.where(
                    (theta >= THETA_MAX) | stuck | _stagnant(history, step),
                    STALLED,
                    jnp.where(step >= max_steps, MAX_STEPS, RUNNING),
                ),
            ),
        )
        return NewtonState(w, R, residual, theta, step, history, status)

    return jax.lax.while_loop(cond, body, state)
