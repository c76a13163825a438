"""Shared test helpers. Importing ddgjax switches JAX to float64."""

import jax
import numpy as np
import pytest

import ddgjax  # noqa: F401


def tree_max_abs_diff(a, b) -> float:
    """max |a − b| over all leaves of two pytrees of the same structure."""
    diffs = jax.tree_util.tree_map(lambda x, y: float(np.max(np.abs(np.asarray(x) - np.asarray(y)))), a, b)
    return max(jax.tree_util.tree_leaves(diffs))


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
