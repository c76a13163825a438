"""Validation at the API boundary: messages that name the offending leaf and index.

Values are validated when they are *concrete*: NumPy or JAX arrays, Python numbers, and the
tracers of `jax.grad` / `jax.jvp` outside `jit`, whose primal value is known
(`concrete_value`).  Under `jit` or `vmap` a value is abstract and its checks are skipped
(`when_concrete`); shapes are always checked.
"""

from __future__ import annotations

import functools
from typing import Callable

import jax
import numpy as np

from .errors import InvalidInputError, NonFiniteError, ShapeError

try:  # the primal of a JVP tracer (JAX >= 0.4.36); without it every tracer counts as abstract
    from jax._src.core import to_concrete_value as _to_concrete_value
except ImportError:  # pragma: no cover
    def _to_concrete_value(x):
        return None

try:  # whether a jit's trace is under way (JAX >= 0.4.36); without it every call counts as staged
    from jax._src.core import unsafe_am_i_under_a_jit as _under_a_jit
except ImportError:  # pragma: no cover
    def _under_a_jit():
        return True


def is_concrete(tree) -> bool:
    """True when no leaf of `tree` is a tracer (so values can be inspected in Python)."""
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(tree))


def is_staged() -> bool:
    """True while `jax.jit` traces a program here (also under `grad` or `vmap` inside it): an
    array made now becomes a constant of that program, written into its text.  False outside
    `jit`, under `grad` or `vmap` alone included."""
    return bool(_under_a_jit())


def concrete_value(x) -> np.ndarray | None:
    """`x` as a NumPy array if its value is known now, else None.

    A tracer of `jax.grad` or `jax.jvp` (outside `jit`) carries a concrete primal, which is
    returned; a tracer of `jit` or `vmap` has no value yet (None).
    """
    if not isinstance(x, jax.core.Tracer):
        return np.asarray(x)
    value = _to_concrete_value(x)
    return None if value is None else np.asarray(value)


_ABSTRACT = object()


def when_concrete(check: Callable[..., None]) -> Callable[..., None]:
    """`check` run on concrete values only: validate if concrete.

    The wrapped check receives every traced argument as its `concrete_value` (a NumPy array),
    other arguments unchanged; it is skipped when an argument is traced abstractly (under `jit`
    or `vmap`), where its value cannot be inspected.  Use it for checks of *values* (finite,
    positive, feasible); check shapes unconditionally.
    """

    @functools.wraps(check)
    def checked(*args, **kwargs):
        def concrete(leaf):
            if not isinstance(leaf, jax.core.Tracer):
                return leaf
            value = concrete_value(leaf)
            return _ABSTRACT if value is None else value

        args, kwargs = jax.tree_util.tree_map(concrete, (args, kwargs))
        if not any(leaf is _ABSTRACT for leaf in jax.tree_util.tree_leaves((args, kwargs))):
            check(*args, **kwargs)

    return checked


def checked_count(n, minimum: int, name: str) -> int:
    """`n` as a Python int, or `InvalidInputError` unless it is an integer `>= minimum`.

    Counts (edges, spins, steps) fix array shapes, so they are never traced.
    """
    if isinstance(n, jax.core.Tracer):
        raise InvalidInputError(f"{name} sets array shapes and must be a Python integer, not a traced value")
    try:
        count = int(n)
    except (TypeError, ValueError, OverflowError):
        count = None
    if count is None or count != n or isinstance(n, bool):
        raise InvalidInputError(f"{name} must be an integer, got {n!r}")
    if count < minimum:
        raise InvalidInputError(f"{name} must be at least {minimum}, got {count}")
    return count


def checked_shape(x, shape: tuple, name: str) -> None:
    """Raise `ShapeError` naming the expected and the given shape unless `np.shape(x) == shape`."""
    if np.shape(x) != tuple(shape):
        raise ShapeError(f"{name} must have shape {tuple(shape)}, got {np.shape(x)}")


@when_concrete
def check_positive(value, name: str) -> None:
    """Raise `InvalidInputError` unless the concrete scalar `value` is finite and `> 0`."""
    try:
        value = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a finite positive number, got {value!r}") from None
    if value.ndim != 0:
        raise InvalidInputError(f"{name} must be a scalar, got an array of shape {value.shape}")
    if not (np.isfinite(value) and value > 0):
        raise InvalidInputError(f"{name} must be finite and positive, got {value}")


def leaf_paths(tree) -> list[tuple[str, object]]:
    """`[(path string, leaf)]` in flattening order; the path reads like `['T']` or `[0]`."""
    flat, _ = jax.tree_util.tree_flatten_with_path(tree)
    return [(jax.tree_util.keystr(path), leaf) for path, leaf in flat]


def check_finite(tree, name: str) -> None:
    """Raise `NonFiniteError` naming the first NaN/inf entry of a concrete pytree.

    Leaves are inspected when concrete (`concrete_value`; abstract tracers are skipped), 0-d ones
    included; non-float leaves cannot be NaN.
    """
    for path, leaf in leaf_paths(tree):
        arr = concrete_value(leaf)
        if arr is None or not np.issubdtype(arr.dtype, np.inexact):
            continue
        bad = np.argwhere(~np.isfinite(arr))
        if len(bad):
            index = tuple(int(i) for i in bad[0])
            value = arr[index] if arr.ndim else arr
            more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
            raise NonFiniteError(
                f"{name}{path} has the non-finite value {value} at index {index}{more}"
            )


def check_same_structure(reference, other, name: str, reference_name: str) -> None:
    """Raise `ShapeError` unless `other` has the tree structure and leaf shapes of `reference`."""
    ref_def = jax.tree_util.tree_structure(reference)
    other_def = jax.tree_util.tree_structure(other)
    if ref_def != other_def:
        raise ShapeError(
            f"{name} must have the pytree structure of {reference_name}: "
            f"got {other_def}, expected {ref_def}"
        )
    for (path, ref_leaf), (_, leaf) in zip(leaf_paths(reference), leaf_paths(other)):
        if np.shape(ref_leaf) != np.shape(leaf):
            raise ShapeError(
                f"{name}{path} has shape {np.shape(leaf)}, expected {np.shape(ref_leaf)} "
                f"(the shape of {reference_name}{path})"
            )
