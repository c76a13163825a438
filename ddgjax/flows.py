"""Flows derived from energies: gradient flows, Hamiltonian flows, Lie brackets, integration.

- `gradient_flow(problem)`: `ẋ = −P ∇E`, with `P` the orthogonal projection onto the tangent
  space `ker Jg(x)` of the constraint set (fixed entries do not move).
- `hamiltonian_flow(H, poisson)`: `ẋ = poisson(x, ∇H(x))`; `spin_poisson` is the Lie–Poisson
  structure of spin chains, `Ṡ_i = ∇_i H × S_i` (reference Appendix A, eq (A.2)).
- `lie_bracket(f, g)`: `[f, g](x) = Dg(x) f(x) − Df(x) g(x)` by two Jacobian-vector products.
  With this (standard) convention the rotation fields `R_a(x) = a × x` satisfy
  `[R_a, R_b] = −R_{a×b}`; the fields `x ↦ x × a` satisfy `[·,·]` = `+` (so(3)).
- `integrate(f, x0, t1)`: adaptive Dormand–Prince 8 (diffrax), or fixed-step Gauss–Legendre
  collocation, which keeps every quadratic invariant (|S_i|² of spins) to round-off, with an
  optional projection onto a constraint set after each step.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree
from jaxtyping import Array, Float

from ._checks import check_finite, check_positive, check_same_structure, checked_count, is_concrete
from ._flat import layout_of
from ._host import on_device
from .errors import ConvergenceError, InvalidInputError, ShapeError
from .problem import Problem, constraint_values

__all__ = ["gradient_flow", "hamiltonian_flow", "spin_poisson", "lie_bracket", "integrate"]


def gradient_flow(problem: Problem) -> Callable:
    """`f(x) = −(∇E − Jᵀμ)` with `μ = argmin |∇E − Jᵀμ|`: minus the projected gradient.

    The velocity is tangent to the constraint set (`Jg(x) f(x) = 0`) and zero on fixed
    entries; along it the energy decreases, `dE/dt = −|f|²`.  Uses `problem.params`.

    **Raises** (when `f` is called): `ShapeError` unless `x` has the structure and shapes of
    `problem.x0` (naming the leaf, the expected and the given shape); `NonFiniteError` for a
    concrete `x` with NaN or inf (naming the entry).
    """
    layout = layout_of(problem)

    def f(x):
        check_same_structure(problem.x0, x, "x", "problem.x0")
        check_finite(x, "x")
        z = layout.ravel(x)
        u = z[layout.free]

        def energy(u_):
            return problem.energy(layout.x_of(z, u_), problem.params)

        def g(u_):
            return constraint_values(problem, layout.x_of(z, u_), problem.params)

        grad = jax.grad(energy)(u)
        if problem.n_constraints:
            J = jax.jacrev(g)(u)
            mu = jnp.linalg.lstsq(J.T, grad)[0]
            grad = grad - J.T @ mu
        return layout.unravel(jnp.zeros_like(z).at[layout.free].set(-grad))

    return f


def hamiltonian_flow(H: Callable, poisson: Callable) -> Callable:
    """`f(x) = poisson(x, ∇H(x))` for a Poisson tensor given as `poisson(x, dH) -> ẋ`."""

    def f(x):
        return poisson(x, jax.grad(H)(x))

    return f


def spin_poisson(S: Float[Array, "n 3"], dH: Float[Array, "n 3"]) -> Float[Array, "n 3"]:
    """Lie–Poisson tensor of spin chains: `Ṡ_i = ∇_i H × S_i` (Appendix A, (A.2)).

    **Raises:** `ShapeError` unless S is (n, 3) and dH has its shape (naming both shapes).
    """
    if np.ndim(S) != 2 or np.shape(S)[1] != 3:
        raise ShapeError(f"spins S must have shape (n, 3), one spin in R³ per row, got {np.shape(S)}")
    if np.shape(dH) != np.shape(S):
        raise ShapeError(f"the gradient dH must have the shape of S, {np.shape(S)}, got {np.shape(dH)}")
    return jnp.cross(dH, S)


def lie_bracket(f: Callable, g: Callable) -> Callable:
    """`h(x) = Dg(x) f(x) − Df(x) g(x)`, by Jacobian-vector products (works on pytrees).

    **Raises:** `ShapeError` unless `f(x)` and `g(x)` have the structure and shapes of `x`.
    """

    def h(x):
        fx, gx = f(x), g(x)
        check_same_structure(x, fx, "f(x)", "x")
        check_same_structure(x, gx, "g(x)", "x")
        dg_f = jax.jvp(g, (x,), (fx,))[1]
        df_g = jax.jvp(f, (x,), (gx,))[1]
        return jax.tree_util.tree_map(jnp.subtract, dg_f, df_g)

    return h


_GAUSS = {
    1: (np.array([[0.5]]), np.array([1.0])),
    2: (
        np.array([[1 / 4, 1 / 4 - np.sqrt(3) / 6], [1 / 4 + np.sqrt(3) / 6, 1 / 4]]),
        np.array([0.5, 0.5]),
    ),
    3: (
        np.array(
            [
                [5 / 36, 2 / 9 - np.sqrt(15) / 15, 5 / 36 - np.sqrt(15) / 30],
                [5 / 36 + np.sqrt(15) / 24, 2 / 9, 5 / 36 - np.sqrt(15) / 24],
                [5 / 36 + np.sqrt(15) / 30, 2 / 9 + np.sqrt(15) / 15, 5 / 36],
            ]
        ),
        np.array([5 / 18, 4 / 9, 5 / 18]),
    ),
}
METHODS = {"gauss2": 1, "gauss4": 2, "gauss6": 3, "dopri8": None}


def gauss_legendre_step(f: Callable, y: jax.Array, h, stages: int = 3, iterations: int = 100):
    """One step of the s-stage Gauss–Legendre method (order 2s) by fixed-point iteration.

    Symplectic and exact on quadratic invariants; `stages=1` is the implicit midpoint rule.
    Iterates `K_i = f(y + h Σ_j a_ij K_j)` until the change is at round-off level or stops
    shrinking.  If it stopped shrinking well above round-off (h·Lipschitz too large: the
    iteration does not contract) the step returns NaN, which `integrate` reports as an error
    naming the step.
    """
    A, b = (jnp.asarray(t) for t in _GAUSS[stages])
    K0 = jnp.tile(f(y), (stages, 1))
    eps = jnp.finfo(y.dtype).eps

    def update(K):
        return jax.vmap(f)(y + h * (A @ K))

    def scale(K):
        return jnp.maximum(1.0, jnp.max(jnp.abs(K)))

    def cond(carry):
        K, change, previous, k = carry
        contracting = (change < previous) | (k < 3)
        return (change > 4 * eps * scale(K)) & contracting & (k < iterations)

    def body(carry):
        K, change, _, k = carry
        K_new = update(K)
        return K_new, jnp.max(jnp.abs(K_new - K)), change, k + 1

    inf = jnp.asarray(jnp.inf)
    K, change, _, _ = jax.lax.while_loop(cond, body, (K0, inf, inf, 0))
    converged = change <= 1e-9 * scale(K)
    return jnp.where(converged, y + h * (b @ K), jnp.nan)


def project(constraints: Callable, y: jax.Array, iterations: int = 4) -> jax.Array:
    """Nearest point of `{c = 0}` by Gauss–Newton minimum-norm corrections."""

    def body(_, y):
        c = constraints(y)
        J = jax.jacrev(constraints)(y)
        return y - J.T @ jnp.linalg.solve(J @ J.T, c)

    return jax.lax.fori_loop(0, iterations, body, y)


def integrate(
    f: Callable,
    x0,
    t1: float,
    *,
    steps: int | None = None,
    rtol: float = 1e-10,
    method: str | None = None,
    constraints: Callable | None = None,
    saves: int = 101,
):
    """Integrate `ẋ = f(x)` from `x0` at t = 0 to `t1`; returns `(ts, xs)` (xs stacked like x0).

    **Arguments:**
    - `steps`: number of fixed steps; then `method` defaults to `"gauss6"` (Gauss–Legendre,
      order 6) and every step is returned.  With `steps=None` the default is adaptive
      `"dopri8"` (diffrax) to `rtol` (atol = rtol·1e-2), returning `saves` equally spaced times.
    - `method`: `"gauss2"` (implicit midpoint), `"gauss4"`, `"gauss6"`, `"dopri8"`.
    - `constraints(x) -> 1-D`: keep the iterates on `{constraints = 0}` by projecting after
      every step (every saved time for `"dopri8"`).

    **Raises:** `NonFiniteError` for NaN in `x0` or a `t1` that is not finite, `ShapeError`
    unless `f(x0)` has the structure and shapes of `x0` (naming the expected and the given
    shape), `InvalidInputError` for bad options (`rtol` not finite and positive, `saves` < 2, an
    unknown `method`).
    """
    check_finite(x0, "x0")
    check_finite(t1, "t1")
    check_positive(rtol, "rtol")
    saves = checked_count(saves, 2, "saves (the number of saved times, t = 0 and t1 included)")
    check_same_structure(x0, jax.eval_shape(f, x0), "f(x0)", "x0")
    method = method or ("gauss6" if steps is not None else "dopri8")
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {tuple(METHODS)}, got {method!r}")
    if METHODS[method] is not None and steps is None:
        raise InvalidInputError(f"method={method!r} is fixed-step: give steps")
    y0, unravel = ravel_pytree(x0)
    fy = lambda y: ravel_pytree(f(unravel(y)))[0]  # noqa: E731
    cy = None if constraints is None else (lambda y: jnp.ravel(constraints(unravel(y))))  # noqa: E731
    if METHODS[method] is not None:
        ts, ys = _fixed_steps(fy, y0, float(t1), int(steps), METHODS[method], cy)
    else:
        ts, ys = _adaptive(fy, y0, float(t1), rtol, saves if steps is None else steps + 1, cy)
    _check_trajectory(ts, ys)
    return ts, jax.vmap(unravel)(ys)


def _check_trajectory(ts, ys) -> None:
    """Never hand back a silent NaN: name the first saved time where the state is not finite."""
    if not is_concrete(ys):
        return
    finite = np.all(np.isfinite(np.asarray(ys)), axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        raise ConvergenceError(
            f"integrate: the state became non-finite at saved step {k} (t = {float(ts[k]):.6g}); for "
            "the Gauss methods this means the implicit stage iteration diverged: the flow is too "
            "stiff for this step size, use more steps",
            residual=float("nan"), steps=k,
        )


def _fixed_steps(fy, y0, t1, steps, stages, cy):
    if steps < 1:
        raise InvalidInputError(f"steps must be >= 1, got {steps}")
    h = t1 / steps

    def step(y, _):
        y = gauss_legendre_step(fy, y, h, stages)
        y = y if cy is None else project(cy, y)
        return y, y

    _, ys = jax.lax.scan(step, y0, None, length=steps)
    return on_device(np.linspace(0.0, t1, steps + 1)), jnp.concatenate([y0[None], ys])


def _adaptive(fy, y0, t1, rtol, saves, cy):
    import diffrax  # here, not at module level: it costs half a second to import

    ts = jnp.linspace(0.0, t1, saves)
    term = diffrax.ODETerm(lambda t, y, args: fy(y))
    controller = diffrax.PIDController(rtol=rtol, atol=rtol * 1e-2)

    def segment(y, t_pair):
        sol = diffrax.diffeqsolve(
            term, diffrax.Dopri8(), t_pair[0], t_pair[1], None, y,
            stepsize_controller=controller, max_steps=100_000,
        )
        y = sol.ys[-1]
        y = y if cy is None else project(cy, y)
        return y, y

    _, ys = jax.lax.scan(segment, y0, jnp.stack([ts[:-1], ts[1:]], axis=1))
    return ts, jnp.concatenate([y0[None], ys])
