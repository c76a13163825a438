"""The discrete spherical pendulum (Def 3.3, Thm 3.10): the Kirchhoff analogy, discretely.

A trajectory T_0 … T_{n−1} on S² is a critical point of the action

    S = Σ_k L_k,    L_k = log(1 + <T_k, T_{k−1}>) − <a, T_k>,

with gravity a ∈ R³ (Remark 3.9: kinetic term log(1 + <T_k, T_{k−1}>) ≈ log 2 − κ_k²/4, potential
<a, T_k>).  With fixed T_0 and T_{n−1} this is `action`.  The discrete Lagrangian map `step`
takes (T_{k−1}, T_k) to the T_{k+1} that makes S critical with respect to T_k:

    ∇_{T_k}[log(1 + <T_k, T_{k−1}>) + log(1 + <T_{k+1}, T_k>)] − a  ∥  T_k,   |T_{k+1}| = 1.

By Thm 3.10 these are the tangents of discrete elastica: the pendulum with gravity a and the
clamped elastica with chord multipliers λ are the same when a = (h²/2) λ
(`elastica.pendulum_gravity`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax._checks import check_finite, checked_count, checked_shape
from solvers import solve

from .elastica import bending_density, clamp_ends, great_circle, start_data, starting_array, unit_vector

__all__ = ["action", "step", "shoot", "kinetic"]


def kinetic(T_prev: Float[Array, "3"], T_next: Float[Array, "3"]) -> Float[Array, ""]:
    """`log(1 + <T_k, T_{k−1}>)` (Remark 3.9), evaluated as `log 2 − log(1 + κ_k²/4)`."""
    return jnp.log(2.0) - bending_density(T_prev, T_next)


def _kinetic_term(T2, _):
    return kinetic(T2[0], T2[1])


def _potential_term(T1, p):
    return -jnp.dot(p["a"], T1[0])


def _unit(T1, _):
    return jnp.dot(T1[0], T1[0]) - 1.0


def action(n: int, *, a, T_first, T_last, x0=None) -> dg.Problem:
    """The action S of Def 3.3 over n tangents with T_0 = T_first and T_{n−1} = T_last fixed.

    Unknowns: `T` (n, 3); constraints `{"unit": |T_k|² − 1 for the free k}` (n − 2,).  The
    default start is the great-circle interpolation of the end tangents.  Differentiable in the
    gravity `a` (in `params`) and the end tangents (the fixed rows of `x0`).

    **Raises:** `InvalidInputError` for n < 3 or end tangents that are zero or not finite,
    `NonFiniteError` for NaN in `a` or `x0`, `ShapeError` (values are checked when concrete).
    """
    n = checked_count(n, 3, "n, the number of tangents of the pendulum,")
    a = jnp.asarray(a, dtype=float)
    checked_shape(a, (3,), "a")
    check_finite(a, "a")
    first, last = unit_vector(T_first, "T_first"), unit_vector(T_last, "T_last")
    T0, fixed = clamp_ends(starting_array(x0, lambda: _great_circle_start(first, last, n), (n, 3)), first, last)
    k = np.arange(n)
    energy = dg.local_sum(_kinetic_term, np.stack([k[:-1], k[1:]], axis=1)) + dg.local_sum(_potential_term, k[:, None])
    return dg.Problem(
        energy, T0, constraints=dg.concat(unit=dg.local_map(_unit, k[1:-1, None])), params={"a": a},
        fixed=fixed, name=f"discrete spherical pendulum (n={n})",
    )


def _great_circle_start(first, last, n: int):
    """The great-circle interpolation of the end tangents, with no derivative (`start_data`)."""
    xp, (first, last) = start_data(first, last)
    return great_circle(first, last, xp.linspace(0.0, 1.0, n), xp)


def _tangent_basis(T):
    """Two unit vectors spanning T^⊥."""
    helper = jnp.where(jnp.abs(T[0]) < 0.9, jnp.array([1.0, 0.0, 0.0]), jnp.array([0.0, 1.0, 0.0]))
    e1 = helper - jnp.dot(helper, T) * T
    e1 = e1 / jnp.linalg.norm(e1)
    return e1, jnp.cross(T, e1)


def _lagrangian_map_equations(T_next, p):
    """`{"unit": |T_{k+1}|² − 1, "stationary": the tangential part (2,) of ∇_{T_k} S}` (Def 3.3),
    by autodiff."""
    def S_k(T_curr):
        return kinetic(p["T_prev"], T_curr) + kinetic(T_curr, T_next) - jnp.dot(p["a"], T_curr)

    force = jax.grad(S_k)(p["T_curr"])
    e1, e2 = _tangent_basis(p["T_curr"])
    return {"unit": jnp.dot(T_next, T_next) - 1.0, "stationary": jnp.stack([jnp.dot(force, e1), jnp.dot(force, e2)])}


def _no_energy(T_next, p):
    return 0.0 * jnp.sum(T_next)


def step(T_prev: Float[Array, "3"], T_curr: Float[Array, "3"], a: Float[Array, "3"], *, tol: float = 1e-13):
    """The discrete Lagrangian map (T_{k−1}, T_k) ↦ T_{k+1} of the pendulum (Def 3.3).

    Solved by the generic solver as the constraint set of a problem with zero energy (three
    equations, three unknowns), started from the linear extrapolation 2T_k − T_{k−1}.

    **Raises:** `ConvergenceError` if no T_{k+1} exists nearby (e.g. too large a gravity);
    `ShapeError` unless the three vectors have shape (3,); `NonFiniteError` for NaN.
    """
    T_prev, T_curr, a = (jnp.asarray(v, dtype=float) for v in (T_prev, T_curr, a))
    for v, name in ((T_prev, "T_prev"), (T_curr, "T_curr"), (a, "a")):
        checked_shape(v, (3,), name)
    guess = 2.0 * T_curr - T_prev
    guess = guess / jnp.linalg.norm(guess)
    params = {"T_prev": T_prev, "T_curr": T_curr, "a": a}
    problem = dg.Problem(_no_energy, guess, constraints=_lagrangian_map_equations, params=params, name="pendulum step")
    return solve(problem, tol=tol).x


def shoot(T_first, T_second, a, n: int) -> Float[Array, "n 3"]:
    """The pendulum trajectory T_0 … T_{n−1} from its first two tangents by iterating `step`."""
    n = checked_count(n, 2, "n, the number of tangents of the trajectory,")
    T = [jnp.asarray(T_first, dtype=float), jnp.asarray(T_second, dtype=float)]
    for _ in range(n - 2):
        T.append(step(T[-2], T[-1], a))
    return jnp.stack(T)
