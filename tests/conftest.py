"""Shared test helpers. Importing ddgjax switches JAX to float64.

The tests solve small problems many times over: XLA's compile time, not run time, is most of
the suite's time, so they run with LLVM's backend optimisation off (about half the compile
time of a Newton solver; set before JAX starts its backend).  Set XLA_FLAGS to override.
"""

import os

os.environ.setdefault("XLA_FLAGS", "--xla_backend_optimization_level=0")

import jax  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ddgjax  # noqa: F401, E402


def tree_max_abs_diff(a, b) -> float:
    """max |a − b| over all leaves of two pytrees of the same structure."""
    diffs = jax.tree_util.tree_map(lambda x, y: float(np.max(np.abs(np.asarray(x) - np.asarray(y)))), a, b)
    return max(jax.tree_util.tree_leaves(diffs))


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
