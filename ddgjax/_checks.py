"""Validation at the API boundary: messages that name the offending leaf and index."""

from __future__ import annotations

import jax
import numpy as np

from .errors import NonFiniteError, ShapeError


def is_concrete(tree) -> bool:
    """True when no leaf of `tree` is a tracer (so values can be inspected in Python)."""
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(tree))


def leaf_paths(tree) -> list[tuple[str, object]]:
    """`[(path string, leaf)]` in flattening order; the path reads like `['T']` or `[0]`."""
    flat, _ = jax.tree_util.tree_flatten_with_path(tree)
    return [(jax.tree_util.keystr(path), leaf) for path, leaf in flat]


def check_finite(tree, name: str) -> None:
    """Raise `NonFiniteError` naming the first NaN/inf entry of a concrete pytree.

    Tracers and non-float leaves are skipped (they cannot be inspected or cannot be NaN).
    """
    for path, leaf in leaf_paths(tree):
        if isinstance(leaf, jax.core.Tracer):
            continue
        arr = np.asarray(leaf)
        if not np.issubdtype(arr.dtype, np.inexact):
            continue
        bad = np.argwhere(~np.isfinite(arr))
        if bad.size:
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
