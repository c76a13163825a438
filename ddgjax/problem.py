"""Declaring a variational problem: an energy, constraints, parameters and fixed entries.

A `Problem` is the whole declaration of a discrete object in ddgjax: everything else
(Euler–Lagrange equations, multipliers, the critical point, flows) is derived from it by
automatic differentiation.

Sign convention.  The critical points of `E` on `{g = 0}` are the zeros of

    ∇E(x) − Jg(x)ᵀ λ = 0,     g(x) = 0,

i.e. the critical points of the Lagrangian `L = E − λ·g`.  The reference (Sec 3.1, "Basic fact
from the calculus of variations") writes `S_λ = S + Σ λ_i F_i`; its multipliers are minus ours.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from ._checks import check_finite, check_same_structure, is_concrete, leaf_paths
from .errors import InvalidInputError, NotScalarError, OverconstrainedError, ShapeError
from .locality import Local

__all__ = ["Problem", "euler_lagrange", "lagrangian"]

PyTree = Any


@dataclass(frozen=True, eq=False)
class Problem:
    """A constrained variational problem: find critical points of `energy` on `constraints == 0`.

    **Arguments:**
    - `energy(x, params) -> scalar`: the functional. Declare it with `dg.local_sum` to give the
      solver its sparsity (needed for the sparse path at large sizes).
    - `x0`: pytree of float arrays, the unknowns' starting values (copied, never mutated).
    - `constraints(x, params) -> 1-D array` (optional): the constraint set is `constraints == 0`.
    - `params`: pytree passed to `energy` and `constraints`; `solve` is differentiable and
      `vmap`-able with respect to it.
    - `fixed`: pytree of bool arrays shaped like `x0`; True entries stay at their `x0` value.
    - `name`: used in messages.
    - `residual_scale`: `(s_E, s_g)`, floats or arrays shaped like the flattened free unknowns
      and the constraint vector; the reported KKT residual is
      `max(|s_E·(∇E − Jᵀλ)|∞, |s_g·g|∞)`.  Catalogue problems set it from the mesh size so
      that `tol` means the same at every resolution (`../shared/SOLVER-NOTES.md`).

    **Raises:** `NonFiniteError` (NaN/inf in `x0` or `params`, naming leaf and index),
    `ShapeError` (`fixed` or `x0` malformed, constraints not 1-D), `NotScalarError` (energy
    not a scalar), `OverconstrainedError` (more constraints than free unknowns).
    """

    energy: Callable
    x0: PyTree
    constraints: Callable | None = None
    params: PyTree = None
    fixed: PyTree = None
    name: str = ""
    residual_scale: tuple | None = None
    n_constraints: int = field(init=False, default=0)

    def __post_init__(self):
        label = f"Problem {self.name!r}: " if self.name else ""
        object.__setattr__(self, "x0", _as_float_tree(self.x0, label + "x0"))
        check_finite(self.params, label + "params")
        object.__setattr__(self, "fixed", _as_fixed(self.fixed, self.x0, label))
        _check_energy(self, label)
        object.__setattr__(self, "n_constraints", _count_constraints(self, label))
        n_free = int(sum(np.size(m) - np.count_nonzero(m) for m in jax.tree_util.tree_leaves(self.fixed)))
        if self.n_constraints > n_free:
            raise OverconstrainedError(
                f"{label}{self.n_constraints} constraints but only {n_free} free unknowns: "
                "the constraint set is generically empty; fix fewer entries or drop constraints"
            )

    @property
    def is_local(self) -> bool:
        """True when energy and constraints are declared local (`dg.local_sum`, `dg.local_map`)."""
        leaves = jax.tree_util.tree_leaves(self.x0)
        return (
            isinstance(self.energy, Local)
            and (self.constraints is None or isinstance(self.constraints, Local))
            and len(leaves) == 1
        )

    def with_params(self, params: PyTree) -> "Problem":
        """The same problem with other parameters (e.g. inside `jax.vmap`)."""
        return replace(self, params=params)

    def with_x0(self, x0: PyTree) -> "Problem":
        """The same problem started from (or with boundary values taken from) `x0`."""
        return replace(self, x0=x0)


def _as_float_tree(x0, name: str):
    leaves = jax.tree_util.tree_leaves(x0)
    if not leaves:
        raise ShapeError(f"{name} has no array leaves: there is nothing to solve for")
    check_finite(x0, name)

    def convert(leaf):
        if isinstance(leaf, jax.core.Tracer):
            return leaf.astype(jnp.result_type(float))
        arr = np.array(leaf, dtype=np.float64)  # a private copy
        return jnp.asarray(arr)

    return jax.tree_util.tree_map(convert, x0)


def _as_fixed(fixed, x0, label: str):
    if fixed is None:
        return jax.tree_util.tree_map(lambda leaf: np.zeros(np.shape(leaf), dtype=bool), x0)
    check_same_structure(x0, fixed, label + "fixed", "x0")
    for path, leaf in leaf_paths(fixed):
        if np.asarray(leaf).dtype != bool:
            raise ShapeError(f"{label}fixed{path} must be a bool array, got dtype {np.asarray(leaf).dtype}")
    return jax.tree_util.tree_map(lambda m: np.array(m, dtype=bool), fixed)


def _check_energy(problem: Problem, label: str) -> None:
    out = jax.eval_shape(problem.energy, problem.x0, problem.params)
    if not hasattr(out, "shape") or out.shape != ():
        shape = getattr(out, "shape", type(out).__name__)
        raise NotScalarError(f"{label}energy must return a scalar, got shape {shape}")


def _count_constraints(problem: Problem, label: str) -> int:
    if problem.constraints is None:
        return 0
    out = jax.eval_shape(problem.constraints, problem.x0, problem.params)
    if not hasattr(out, "shape") or len(out.shape) > 1:
        shape = getattr(out, "shape", type(out).__name__)
        raise ShapeError(f"{label}constraints must return a 1-D array, got shape {shape}")
    return int(np.prod(out.shape, dtype=int))


def constraint_values(problem: Problem, x, params) -> jax.Array:
    """`g(x)` as a 1-D array (empty when the problem is unconstrained)."""
    if problem.constraints is None:
        return jnp.zeros((0,))
    return jnp.ravel(problem.constraints(x, params))


def lagrangian(problem: Problem) -> Callable:
    """`L(x, λ, params) = E(x) − λ·g(x)`, whose critical points are the constrained ones."""

    def L(x, multipliers, params):
        return problem.energy(x, params) - jnp.dot(multipliers, constraint_values(problem, x, params))

    return L


def euler_lagrange(problem: Problem) -> Callable:
    """`f(x, multipliers) = ∇E(x) − Jg(x)ᵀ multipliers`, zero on fixed entries (pytree like x).

    The discrete Euler–Lagrange equations of the problem are `f = 0` together with `g = 0`.
    Uses `problem.params`.
    """
    L = lagrangian(problem)
    free = jax.tree_util.tree_map(lambda m: ~m, problem.fixed)

    def f(x, multipliers=None):
        lam = jnp.zeros((problem.n_constraints,)) if multipliers is None else jnp.asarray(multipliers)
        grad = jax.grad(L)(x, lam, problem.params)
        return jax.tree_util.tree_map(lambda gi, mi: jnp.where(mi, gi, 0.0), grad, free)

    return f


def validate_multipliers(problem: Problem, multipliers) -> None:
    if multipliers is not None and np.shape(multipliers) != (problem.n_constraints,):
        raise ShapeError(
            f"multipliers must have shape ({problem.n_constraints},), got {np.shape(multipliers)}"
        )
    if multipliers is not None and is_concrete(multipliers):
        check_finite(multipliers, "multipliers")
    if problem.n_constraints == 0 and multipliers is not None and np.size(multipliers):
        raise InvalidInputError("the problem has no constraints, so no multipliers")
