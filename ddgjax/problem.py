"""Declaring a variational problem: an energy, constraints, parameters and fixed entries.

A `Problem` is the whole declaration of a discrete object in ddgjax: everything else
(Euler–Lagrange equations, multipliers, the critical point, flows) is derived from it by
automatic differentiation.

Sign convention.  The critical points of `E` on `{g = 0}` are the zeros of

    ∇E(x) − Jg(x)ᵀ λ = 0,     g(x) = 0,

i.e. the critical points of the Lagrangian `L = E − λ·g`.  The reference (Sec 3.1, "Basic fact
from the calculus of variations") writes `S_λ = S + Σ λ_i F_i`; its multipliers are minus ours.

Named constraints.  `constraints(x, params)` may return a pytree, e.g. a dict
`{"unit": (n,), "chord": (3,)}`; the multipliers then have the same structure, one λ per
constraint, under the constraint's name.  *The constraint vector* `g` of such a problem is its
leaves raveled and concatenated in JAX's flattening order (a dict's keys sorted), and a flat
multiplier vector is ordered likewise; `ConstraintStructure` converts between the two.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from ._checks import check_finite, check_same_structure, is_concrete, leaf_paths
from ._host import namespace, on_device
from .errors import NotScalarError, OverconstrainedError, ShapeError
from .locality import Local

__all__ = ["ConstraintStructure", "Problem", "euler_lagrange", "flatten_multipliers", "lagrangian", "unflatten_multipliers"]

PyTree = Any


@dataclass(frozen=True, eq=False)
class Problem:
    """A constrained variational problem: find critical points of `energy` on `constraints == 0`.

    **Arguments:**
    - `energy(x, params) -> scalar`: the functional. Declare it with `dg.local_sum` to give the
      solver its sparsity (needed for the sparse path at large sizes).
    - `x0`: pytree of float arrays, the unknowns' starting values (copied, never mutated).
    - `constraints(x, params) -> 1-D array or pytree of arrays` (optional): the constraint set
      is `constraints == 0`; a pytree (a dict of named constraints) gives multipliers of the
      same structure (module docstring).
    - `params`: pytree passed to `energy` and `constraints`; `solve` is differentiable and
      `vmap`-able with respect to it.
    - `fixed`: pytree of bool arrays shaped like `x0`; True entries stay at their `x0` value.
    - `name`: used in messages.
    - `residual_scale`: `(s_E, s_g)`, floats or arrays shaped like the flattened free unknowns
      and the constraint vector (the flat one, for named constraints); the reported KKT residual is
      `max(|s_E·(∇E − Jᵀλ)|∞, |s_g·g|∞)`.  Catalogue problems set it from the mesh size so
      that `tol` means the same at every resolution (`../shared/SOLVER-NOTES.md`).

    **Derived:** `constraint_structure` (a `ConstraintStructure`: names, shapes, the flat
    order) and `n_constraints` (m, the length of the constraint vector).

    **Raises:** `NonFiniteError` (NaN/inf in `x0` or `params`, naming leaf and index),
    `ShapeError` (`fixed` or `x0` malformed, unnamed constraints not 1-D), `NotScalarError` (energy
    not a scalar), `OverconstrainedError` (more constraints than free unknowns).
    """

    energy: Callable
    x0: PyTree
    constraints: Callable | None = None
    params: PyTree = None
    fixed: PyTree = None
    name: str = ""
    residual_scale: tuple | None = None
    constraint_structure: ConstraintStructure = field(init=False, default=None)
    n_constraints: int = field(init=False, default=0)

    def __post_init__(self):
        label = self._label()
        object.__setattr__(self, "x0", _as_float_tree(self.x0, label + "x0"))
        check_finite(self.params, label + "params")
        object.__setattr__(self, "fixed", _as_fixed(self.fixed, self.x0, label))
        _check_energy(self, label)
        object.__setattr__(self, "constraint_structure", _constraint_structure(self, label))
        object.__setattr__(self, "n_constraints", self.constraint_structure.size)
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
        if not _same_types(params, self.params):
            return replace(self, params=params)
        check_finite(params, self._label() + "params")
        return self._with(params=params)

    def with_x0(self, x0: PyTree) -> "Problem":
        """The same problem started from (or with boundary values taken from) `x0`."""
        if not _same_types(x0, self.x0):
            return replace(self, x0=x0)
        return self._with(x0=_as_float_tree(x0, self._label() + "x0"))

    def _label(self) -> str:
        return f"Problem {self.name!r}: " if self.name else ""

    def _with(self, **checked) -> "Problem":
        """A copy with the fields `checked` replaced by values already validated, whose trees,
        shapes and dtypes are those of the fields they replace: the energy's and constraints'
        output shapes, which the declaration's checks trace the functions to find, are the same
        (a continuation or a parameter sweep makes one problem per point)."""
        other = object.__new__(type(self))
        other.__dict__.update(self.__dict__)
        other.__dict__.update(checked)
        return other


def _same_types(tree, other) -> bool:
    """Whether two pytrees have one structure and leaves of the same shapes, dtypes and weak
    types (`jax.typeof`; traced leaves included)."""
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    other_leaves, other_treedef = jax.tree_util.tree_flatten(other)
    if treedef != other_treedef:
        return False
    try:
        return all(jax.typeof(a) == jax.typeof(b) for a, b in zip(leaves, other_leaves, strict=True))
    except TypeError:  # a leaf JAX does not type (a string): compare by the full checks
        return False


def _as_float_tree(x0, name: str):
    leaves = jax.tree_util.tree_leaves(x0)
    if not leaves:
        raise ShapeError(f"{name} has no array leaves: there is nothing to solve for")
    check_finite(x0, name)

    def convert(leaf):
        if isinstance(leaf, jax.core.Tracer):
            return leaf.astype(jnp.result_type(float))
        return on_device(np.array(leaf, dtype=np.float64))  # a private copy

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


@dataclass(frozen=True, eq=False)
class ConstraintStructure:
    """The names and shapes of a problem's constraints, and the flat constraint vector's order.

    `treedef` and `shapes` describe what `constraints(x, params)` returns; `named` is False for
    a plain 1-D (or scalar) output, whose multipliers stay one 1-D vector.  `ravel` maps a
    pytree of that structure to the flat vector (leaves raveled, in flattening order),
    `unravel` maps back.  Hashable: part of the compiled solver's cache key.
    """

    treedef: object
    shapes: tuple
    named: bool

    @property
    def sizes(self) -> tuple[int, ...]:
        return tuple(int(np.prod(shape, dtype=int)) for shape in self.shapes)

    @property
    def size(self) -> int:
        return sum(self.sizes)

    def key(self):
        return (self.treedef, self.shapes, self.named)

    def __hash__(self):
        return hash(self.key())

    def __eq__(self, other):
        return isinstance(other, ConstraintStructure) and self.key() == other.key()

    def ravel(self, tree) -> jax.Array:
        xp = namespace(tree)
        leaves = [xp.ravel(leaf) for leaf in jax.tree_util.tree_leaves(tree)]
        return on_device(xp.concatenate(leaves) if leaves else xp.zeros((0,)))

    def unravel(self, flat: jax.Array):
        if not self.named:
            return flat
        offsets = np.cumsum((0,) + self.sizes)
        leaves = [flat[a:b].reshape(shape) for a, b, shape in zip(offsets[:-1], offsets[1:], self.shapes)]
        return jax.tree_util.tree_unflatten(self.treedef, leaves)

    def describe(self) -> str:
        """The structure with shapes for leaves, as in an error message: `{'chord': (3,), ...}`."""
        if not self.named:
            return f"({self.size},)"
        return str(jax.tree_util.tree_unflatten(self.treedef, list(self.shapes)))


UNCONSTRAINED = ConstraintStructure(jax.tree_util.tree_structure(0), ((0,),), False)


def _constraint_structure(problem: Problem, label: str) -> ConstraintStructure:
    if problem.constraints is None:
        return UNCONSTRAINED
    out = jax.eval_shape(problem.constraints, problem.x0, problem.params)
    leaves, treedef = jax.tree_util.tree_flatten(out)
    named = not jax.tree_util.treedef_is_leaf(treedef)
    for path, leaf in leaf_paths(out):
        if not hasattr(leaf, "shape"):
            raise ShapeError(f"{label}constraints{path} must be an array, got {type(leaf).__name__}")
        if not named and len(leaf.shape) > 1:
            raise ShapeError(
                f"{label}constraints must return a 1-D array, got shape {leaf.shape} (or a pytree, "
                "e.g. a dict of named constraints)"
            )
    return ConstraintStructure(treedef, tuple(tuple(leaf.shape) for leaf in leaves), named)


def constraint_values(problem: Problem, x, params) -> jax.Array:
    """`g(x)`, the constraint vector (empty when the problem is unconstrained; the leaves of
    named constraints concatenated in flattening order)."""
    if problem.constraints is None:
        return jnp.zeros((0,))
    return problem.constraint_structure.ravel(problem.constraints(x, params))


def flatten_multipliers(problem: Problem, multipliers) -> jax.Array:
    """The multipliers as one vector ordered like the constraint vector.

    Accepts the flat vector (m,) or, for named constraints, a pytree of the constraints'
    structure (e.g. `{"chord": (3,), "unit": (n,)}`).

    **Raises:** `ShapeError` naming the leaf (or the structure) that does not match,
    `NonFiniteError` for NaN/inf.
    """
    structure = problem.constraint_structure
    if structure.named and jax.tree_util.tree_structure(multipliers) == structure.treedef:
        for (path, leaf), shape in zip(leaf_paths(multipliers), structure.shapes):
            if np.shape(leaf) != shape:
                raise ShapeError(f"multipliers{path} has shape {np.shape(leaf)}, expected {shape} (constraints{path})")
        flat = structure.ravel(multipliers)
    elif isinstance(multipliers, (dict, tuple, list)) and not _is_numeric_sequence(multipliers):
        raise ShapeError(
            f"multipliers must have the structure of the constraints, {structure.describe()}, or be the "
            f"flat vector of shape ({structure.size},); got {jax.tree_util.tree_structure(multipliers)}"
        )
    else:
        if np.shape(multipliers) != (structure.size,):
            raise ShapeError(f"multipliers must have shape ({structure.size},), got {np.shape(multipliers)}")
        flat = on_device(namespace(multipliers).asarray(multipliers))
    if is_concrete(multipliers):
        check_finite(multipliers, "multipliers")
    return flat


def _is_numeric_sequence(tree) -> bool:
    return isinstance(tree, (tuple, list)) and all(np.ndim(leaf) == 0 for leaf in jax.tree_util.tree_leaves(tree))


def unflatten_multipliers(problem: Problem, flat: jax.Array):
    """The flat multiplier vector (m,) in the constraints' structure (itself when unnamed)."""
    return problem.constraint_structure.unravel(flat)


def lagrangian(problem: Problem) -> Callable:
    """`L(x, λ, params) = E(x) − λ·g(x)`, whose critical points are the constrained ones.

    `λ` is the flat vector or, for named constraints, a pytree like the constraints' output.
    """

    def L(x, multipliers, params):
        return _lagrangian_of_flat(problem, x, flatten_multipliers(problem, multipliers), params)

    return L


def _lagrangian_of_flat(problem: Problem, x, lam, params):
    """`E(x) − λ·g(x)` with λ the flat multiplier vector."""
    return problem.energy(x, params) - jnp.dot(lam, constraint_values(problem, x, params))


def euler_lagrange(problem: Problem) -> Callable:
    """`f(x, multipliers) = ∇E(x) − Jg(x)ᵀ multipliers`, zero on fixed entries (pytree like x).

    The discrete Euler–Lagrange equations of the problem are `f = 0` together with `g = 0`
    (Sec 3.1).  `multipliers`: the flat vector or, for named constraints, a pytree like the
    constraints' output (`flatten_multipliers`; default zero).  Uses `problem.params`.
    """
    free = jax.tree_util.tree_map(lambda m: ~m, problem.fixed)

    def f(x, multipliers=None):
        lam = jnp.zeros((problem.n_constraints,)) if multipliers is None else flatten_multipliers(problem, multipliers)
        grad = jax.grad(_lagrangian_of_flat, argnums=1)(problem, x, lam, problem.params)
        return jax.tree_util.tree_map(lambda gi, mi: jnp.where(mi, gi, 0.0), grad, free)

    return f
