"""The KKT system of a problem, on the vector `w = (u, λ)` of free unknowns and multipliers.

With the Lagrangian `L(u, λ) = E(x(u)) − λ·g(x(u))`, the KKT residual used throughout is

    R(w) = ∇_w L = (∇E − Jᵀλ,  −g),

whose Jacobian is the symmetric (indefinite) KKT matrix `K = [[∇²L, −Jᵀ], [−J, 0]]`.
Newton's method for critical points is Newton's method for `R = 0`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax._flat import Layout, layout_of
from ddgjax._host import namespace, on_device
from ddgjax.locality import Local
from ddgjax.problem import ConstraintStructure


def _function_key(fn):
    return fn if isinstance(fn, Local) else ("fn", id(fn), fn)


@dataclass(frozen=True, eq=False)
class Spec:
    """Everything static about a problem: its functions and the layout of its unknowns.

    Hashable, so that `jax.jit` reuses the compiled solver for every problem with the same
    functions and shapes (values of `x0` and `params` are traced).
    """

    energy: Callable
    constraints: Callable | None
    layout: Layout
    constraint_structure: ConstraintStructure
    is_local: bool
    has_scale: bool

    def key(self):
        cons = None if self.constraints is None else _function_key(self.constraints)
        return (_function_key(self.energy), cons, self.layout, self.constraint_structure, self.is_local, self.has_scale)

    def __hash__(self):
        return hash(self.key())

    def __eq__(self, other):
        return isinstance(other, Spec) and self.key() == other.key()

    @property
    def n(self) -> int:
        return self.layout.n_free

    @property
    def m(self) -> int:
        return self.constraint_structure.size


def spec_of(problem) -> Spec:
    return Spec(
        problem.energy,
        problem.constraints,
        layout_of(problem),
        problem.constraint_structure,
        problem.is_local,
        problem.residual_scale is not None,
    )


@dataclass(frozen=True)
class KKT:
    """The problem's functions of `u` and `w`, with `z0` (flattened x0) and `params` bound."""

    spec: Spec
    z0: jax.Array
    params: object

    def x(self, u):
        return self.spec.layout.x_of(self.z0, u)

    def energy(self, u):
        return self.spec.energy(self.x(u), self.params)

    def g(self, u):
        if self.spec.constraints is None:
            return jnp.zeros((0,), dtype=u.dtype)
        return self.spec.constraint_structure.ravel(self.spec.constraints(self.x(u), self.params))

    def split(self, w):
        return w[: self.spec.n], w[self.spec.n :]

    def lagrangian(self, w):
        u, lam = self.split(w)
        return self.energy(u) - jnp.dot(lam, self.g(u))

    def residual(self, w):
        """`R(w) = (∇E − Jᵀλ, −g)`."""
        return jax.grad(self.lagrangian)(w)



def residual_weights(problem, spec: Spec):
    """`(s_E, s_g)` arrays for the scaled residual; see `Problem.residual_scale`."""
    if problem.residual_scale is None:
        return on_device(np.ones((spec.n,))), on_device(np.ones((spec.m,)))
    s_e, s_g = problem.residual_scale
    xp = namespace(problem.residual_scale)
    s_e = xp.broadcast_to(xp.asarray(s_e, dtype=float), (spec.n,))
    s_g = xp.broadcast_to(xp.asarray(s_g, dtype=float), (spec.m,))
    return on_device(s_e), on_device(s_g)


def scaled_residual(R, weights, n: int):
    """`max(|s_E·(∇E − Jᵀλ)|∞, |s_g·g|∞)`."""
    s_e, s_g = weights
    xp = namespace(R, weights)
    R, s_e, s_g = xp.asarray(R), xp.asarray(s_e), xp.asarray(s_g)
    scaled = xp.concatenate([s_e * R[:n], s_g * R[n:]])
    return xp.max(xp.abs(scaled)) if scaled.size else xp.zeros(())

