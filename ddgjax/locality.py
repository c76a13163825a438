"""Declared locality: energies and constraints written as sums of local densities.

A discrete energy is almost always a sum over the cells of a complex (edges of a curve, faces
of a mesh) of a density that reads a few rows of the unknown array:

    E(x) = Σ_k  density(x[stencil[k]], params)            (`local_sum`)

and constraints are either one small vector per cell (`local_map`, e.g. |T_k|² − 1 = 0) or a
global sum of local terms (`local_sum` with vector output, e.g. the chord Σ_k T_k − c = 0).

Declaring this, rather than writing the same sum as an opaque function, tells the solver the
sparsity of the Hessian and of the constraint Jacobian *without detection*
(`../shared/SOLVER-NOTES.md`: detection takes 41 s at 10⁵ unknowns, the declared pattern
0.3 s): each cell contributes a dense (s·d)×(s·d) block at known rows and columns, exactly as
finite-element assembly.  A `Local` object is itself a valid `energy(x, params)` or
`constraints(x, params)` callable, so the dense path and every flow work on it unchanged.

Constraints may be named, `concat(unit=local_map(...), chord=local_sum(...))`: the declaration
then returns a dict and `solve` returns the multipliers under the same names.

The unknown `x` of a local problem is a single array of shape (N, d) or (N,).
"""

from __future__ import annotations

import weakref
from functools import partial
from dataclasses import dataclass, field
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Int

from ._checks import is_concrete
from .errors import InvalidInputError, ShapeError

__all__ = ["Term", "Local", "local_sum", "local_map", "concat"]


_PER_FUNCTION: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _per_function(fn: Callable, kind: str, make: Callable[[], Callable]) -> Callable:
    """`make()`, made once per density function `fn` and `kind` (kept while `fn` lives; made
    anew each time for a callable without weak references)."""
    try:
        made = _PER_FUNCTION.setdefault(fn, {})
    except TypeError:
        return make()
    if kind not in made:
        made[kind] = make()
    return made[kind]


def _density(fn: Callable, x_local, data_k, params):
    """`fn(x_local, params)`, or `fn(x_local, data_k, params)` for a term with data."""
    return fn(x_local, params) if data_k is None else fn(x_local, data_k, params)


def _cell_value(fn: Callable, x_local, data_k, params, weights_k):
    """The density of one cell flattened, or the scalar `−w_k · g_k` when weights `w_k` are given."""
    value = jnp.ravel(_density(fn, x_local, data_k, params))
    return value if weights_k is None else -jnp.dot(weights_k, value)


def _cell_scalar(fn: Callable, x_local, data_k, params, weights_k):
    """`e_k`: a scalar density's value, or `−w_k · g_k` for a vector one with weights `w_k`."""
    value = _cell_value(fn, x_local, data_k, params, weights_k)
    return value[0] if weights_k is None else value


def _per_cell(fn: Callable, kind: str) -> Callable:
    """Of one cell of density `fn`, as a function of `(x_local, data_k, params, weights_k)`: its
    value (`kind="value"`), the Hessian ∇²e_k of `e_k` (`"hessian"`, `_cell_scalar`) or the
    Jacobian of its flattened value (`"jacobian"`), with respect to `x_local`."""
    if kind == "value":
        return lambda xl, dk, p, wk: _density(fn, xl, dk, p)
    if kind == "hessian":
        return jax.hessian(lambda xl, dk, p, wk: _cell_scalar(fn, xl, dk, p, wk))
    jacobian = jax.jacfwd(lambda xl, dk, p: _cell_value(fn, xl, dk, p, None))
    return lambda xl, dk, p, wk: jacobian(xl, dk, p)


def _batched(fn: Callable, kind: str) -> Callable:
    """`jax.jit(vmap(per-cell kind))` over a leading axis of cells, one per density function and
    kind (`_per_cell`): traced, differentiated and batched once per process and bucket of cells
    (`cell_bucket`), and reused by every compiled program that evaluates the term."""
    return _per_function(fn, kind, lambda: jax.jit(jax.vmap(_per_cell(fn, kind), in_axes=(0, 0, None, 0))))


CELL_BUCKETS = (32, 128)
"""Numbers of cells a density is evaluated on at once: a term of K cells is padded (with copies
of its first cell, whose values are dropped) to the first bucket ≥ K, so that small problems of
nearby sizes (a convergence study's curves of n = 8, 16, 32 edges; a torus of revolution's 12,
16, 24 profile points) share the traced and batched derivatives of the density.  Beyond the
last bucket K itself is used: a larger problem compiles its own program anyway, and padding
would multiply the density's evaluations in every Newton step (up to 4×)."""


def cell_bucket(cells: int) -> int:
    """The first of `CELL_BUCKETS` ≥ `cells`, or `cells` beyond the last."""
    return next((b for b in CELL_BUCKETS if b >= cells), cells)


def _padded(tree, cells: int):
    """Every leaf's leading axis padded from its length K to `cells` with copies of its row 0."""
    def pad(a):
        extra = cells - a.shape[0]
        if extra == 0:
            return a
        xp = np if isinstance(a, np.ndarray) else jnp
        return xp.concatenate([a, xp.repeat(a[:1], extra, axis=0)])

    return jax.tree_util.tree_map(pad, tree)


def _on_cells(fn: Callable, kind: str, x_cells, data, params, weights=None) -> Array:
    """The batched `kind` of density `fn` on K cells (`x_cells` (K, ...), `data` and `weights`
    with K rows), evaluated on the cells padded to `cell_bucket(K)`; K rows out."""
    cells = x_cells.shape[0]
    bucket = cell_bucket(cells)
    out = _batched(fn, kind)(*_padded((x_cells, data), bucket), params, _padded(weights, bucket))
    return jax.tree_util.tree_map(lambda a: a[:cells], out) if bucket != cells else out


@dataclass(frozen=True, eq=False)
class Term:
    """One local density `fn` evaluated on every row `k` of `stencil`.

    `fn(x_local, params)` or, when `data` is given, `fn(x_local, data_k, params)`, where
    `x_local = x[stencil[k]]` has shape (s, d) (or (s,) for a 1-D `x`) and `data_k` is the
    k-th slice of every leaf of `data`.  `reduce="sum"` adds the outputs over k,
    `reduce="map"` keeps one output per k (flattened, cell-major).
    """

    fn: Callable
    stencil: np.ndarray  # (K, s) int
    data: object = None
    reduce: str = "sum"

    def cell(self, x_local, k_data, params) -> Array:
        """The density of one cell."""
        return _density(self.fn, x_local, None if self.data is None else k_data, params)

    def hessians(self, x_cells, data, params, weights=None) -> Array:
        """∇²e_k with respect to `x_local` for every cell k of a chunk: `x_cells` (K, s, d),
        `data` the cells' data (K, ...), `weights` None for a scalar density (`e_k` its value) or
        (K, c) for a vector one (`e_k = −w_k · g_k`, the constraint part of the Lagrangian's
        Hessian).  Shape (K, s, d, s, d)."""
        return _on_cells(self.fn, "hessian", x_cells, data, params, weights)

    def jacobians(self, x_cells, data, params) -> Array:
        """∂g_k/∂x_local for every cell k: shape (K, c, s, d) for `x_cells` (K, s, d)."""
        return _on_cells(self.fn, "jacobian", x_cells, data, params)

    def __call__(self, x, params) -> Array:
        vals = _on_cells(self.fn, "value", x[self.stencil], self.data, params)
        return vals.sum(axis=0) if self.reduce == "sum" else vals.reshape(-1)

    def __repr__(self) -> str:
        """The density's name and the stencil's shape (not its entries: JAX formats the functions
        it traces, and a printed stencil costs milliseconds per trace)."""
        return f"Term({getattr(self.fn, '__name__', type(self.fn).__name__)}, stencil {self.stencil.shape}, {self.reduce})"

    def key(self) -> tuple:
        """Hashable description of the sparsity (the function by identity, the stencil by value)."""
        data_leaves = tuple(np.asarray(leaf).tobytes() for leaf in jax.tree_util.tree_leaves(self.data))
        return (self.fn, self.reduce, self.stencil.shape, self.stencil.tobytes(), data_leaves)


@dataclass(frozen=True, eq=False)
class Local:
    """Groups of `Term`s: terms within a group are summed, groups are concatenated.

    An energy is one group (`local_sum(a) + local_sum(b)`); constraints may be several
    (`concat(local_map(unit_length, cells), local_sum(chord, cells))`).  With `names` (one per
    group, sorted; consecutive groups may share a name) the call returns a dict `{name: output}`
    and the groups are stored in sorted-name order, which is JAX's order of the dict's leaves:
    the flat constraint vector is the groups' outputs concatenated in that order either way.
    """

    groups: tuple[tuple[Term, ...], ...]
    names: tuple[str, ...] | None = None
    hash_value: int = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        # the declaration is immutable: its hash (over the stencils' bytes) is computed once
        object.__setattr__(self, "hash_value", hash(self.key()))

    def __repr__(self) -> str:
        return f"Local({', '.join('[' + ', '.join(map(repr, g)) + ']' for g in self.groups)}, names={self.names})"

    def __call__(self, x, params=None):
        if is_concrete((x, params)):  # called eagerly (not by a solver): one program per shape
            return _evaluated(self, x, params)
        return self.evaluate(x, params)

    def evaluate(self, x, params=None):
        """The groups' outputs at `x`: summed over each group's terms, joined or named."""
        x = jnp.asarray(x)
        outs = [sum(term(x, params) for term in group) for group in self.groups]
        if self.names is None:
            return _joined(outs)
        return {name: _joined([o for o, n in zip(outs, self.names) if n == name]) for name in dict.fromkeys(self.names)}

    def __add__(self, other: "Local") -> "Local":
        if not isinstance(other, Local) or len(self.groups) != 1 or len(other.groups) != 1:
            return NotImplemented
        if self.names is not None or other.names is not None:
            return NotImplemented
        return Local((self.groups[0] + other.groups[0],))

    def key(self) -> tuple:
        return (tuple(tuple(term.key() for term in group) for group in self.groups), self.names)

    def __hash__(self):
        return self.hash_value

    def __eq__(self, other):
        return isinstance(other, Local) and self.key() == other.key()


@partial(jax.jit, static_argnums=0)
def _evaluated(local: Local, x, params):
    """`local.evaluate(x, params)` compiled once per declaration and shape."""
    return local.evaluate(x, params)


def _joined(outs: list) -> Array:
    """One group's output as it is; several groups' outputs raveled and concatenated."""
    if len(outs) == 1:
        return outs[0]
    return jnp.concatenate([jnp.ravel(o) for o in outs])


def _as_stencil(stencil, name: str) -> np.ndarray:
    s = np.array(stencil)  # a copy: the caller's array is never kept or changed
    if s.ndim == 1:
        s = s[:, None]
    if s.ndim != 2 or not np.issubdtype(s.dtype, np.integer):
        raise ShapeError(f"{name}: stencil must be an integer array of shape (K, s), got {s.dtype} {s.shape}")
    if s.size and s.min() < 0:
        k = int(np.argwhere(s < 0)[0][0])
        raise InvalidInputError(f"{name}: stencil row {k} has a negative index {s[k].tolist()}")
    return s.astype(np.int64)


def _as_data(data, n_cells: int, name: str):
    if data is None:
        return None
    data = jax.tree_util.tree_map(lambda a: np.array(a), data)
    for leaf in jax.tree_util.tree_leaves(data):
        if leaf.shape[:1] != (n_cells,):
            raise ShapeError(f"{name}: every data leaf needs a leading axis of length {n_cells}, got {leaf.shape}")
    return data


def local_sum(density: Callable, stencil: Int[np.ndarray, "K s"], data=None) -> Local:
    """`E(x, params) = Σ_k density(x[stencil[k]], params)` (or `density(x_local, data[k], params)`).

    `density` may return a scalar (an energy) or a vector of c entries (c global constraints,
    each a sum of local terms, such as a prescribed chord Σ_k T_k = c).

    **Raises:** `ShapeError` for a stencil that is not (K, s) integers, `InvalidInputError` for a
    negative index (naming the stencil row).
    """
    s = _as_stencil(stencil, "local_sum")
    return Local(((Term(density, s, _as_data(data, len(s), "local_sum"), "sum"),),))


def local_map(fn: Callable, stencil: Int[np.ndarray, "K s"], data=None) -> Local:
    """`g(x, params) = concat_k fn(x[stencil[k]], params)`: one small constraint vector per cell.

    Used for pointwise constraints such as unit tangents, `|T_k|² − 1 = 0` for every edge k.
    """
    s = _as_stencil(stencil, "local_map")
    return Local(((Term(fn, s, _as_data(data, len(s), "local_map"), "map"),),))


def concat(*parts: Local, **named: Local) -> Local:
    """Concatenate several local constraint declarations: positionally, in order, into one
    1-D constraint vector; or by keyword, `concat(unit=local_map(...), chord=local_sum(...))`,
    into named constraints, a dict `{"chord": ..., "unit": ...}` whose multipliers
    `solve(...).multipliers` carries under the same names.

    The constraint vector of a named declaration is its leaves concatenated in sorted-name
    order (JAX's order of a dict's leaves), and the groups are stored in that order, so the
    solvers see the same flat vector as for the positional declaration in sorted order.

    **Raises:** `InvalidInputError` for an argument that is not a local declaration, for
    positional and keyword arguments together, or for a keyword argument that is itself named.
    """
    if parts and named:
        raise InvalidInputError("concat: give the parts either all by position or all by name, not both")
    for label, part in [(f"argument {i}", p) for i, p in enumerate(parts)] + [(f"{k}=", p) for k, p in named.items()]:
        if not isinstance(part, Local):
            raise InvalidInputError(f"concat: {label} is {type(part).__name__}, not a local declaration")
    if not named:
        if any(part.names is not None for part in parts):
            raise InvalidInputError("concat: a named declaration cannot be concatenated by position; name every part")
        return Local(tuple(group for part in parts for group in part.groups))
    for name, part in named.items():
        if part.names is not None:
            raise InvalidInputError(f"concat: {name}= is itself named ({list(dict.fromkeys(part.names))}); nest no names")
    ordered = sorted(named)
    groups = tuple(group for name in ordered for group in named[name].groups)
    names = tuple(name for name in ordered for _ in named[name].groups)
    return Local(groups, names)
