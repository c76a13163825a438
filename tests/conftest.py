"""Shared test helpers. Importing ddgjax switches JAX to float64.

The tests solve small problems many times over: XLA's compile time, not run time, is most of
the suite's time, so they run with `compile_cache.fast_compile_xla_flags()` (about half the
compile time of a Newton solver; set before JAX starts its backend).  Set XLA_FLAGS to override.
The compiled programs are kept in the persistent compilation cache of the command line
(`ddgjax.compile_cache`, the user's cache folder; `DDGJAX_COMPILE_CACHE=DIR` or `=off`): the
pytest-xdist workers share it, and a second run of the suite loads what the first compiled.
"""

import os

from ddgjax import compile_cache  # imports JAX without starting its backend

os.environ.setdefault("XLA_FLAGS", compile_cache.fast_compile_xla_flags())

import jax  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

compile_cache.enable()


def tree_max_abs_diff(a, b) -> float:
    """max |a − b| over all leaves of two pytrees of the same structure."""
    diffs = jax.tree_util.tree_map(lambda x, y: float(np.max(np.abs(np.asarray(x) - np.asarray(y)))), a, b)
    return max(jax.tree_util.tree_leaves(diffs))


def lowered(fn):
    """`(fn(), names)`: the names of the XLA programs lowered while `fn` runs."""
    names = []

    def listener(event, duration, **kw):
        if event == "/jax/core/compile/jaxpr_to_mlir_module_duration":
            names.append(kw.get("fun_name"))

    jax.monitoring.register_event_duration_secs_listener(listener)
    try:
        return fn(), names
    finally:
        jax.monitoring.unregister_event_duration_listener(listener)


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop JAX's compiled programs after each test module.

    Every XLA CPU executable keeps its own memory mappings; a few thousand of them, held by the
    jit caches over the whole suite, reach the kernel's limit on mappings per process
    (vm.max_map_count, 65530), and the next compilation aborts the process.  Programs are rarely
    shared between modules, so releasing them costs little."""
    yield
    jax.clear_caches()


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


HEAVY_FIRST = ("test_docs.py", "test_verify_checks.py", "test_sweep.py", "test_willmore.py", "test_multiprocess.py",
               "test_rod.py", "test_subdivision.py", "test_named_constraints.py")
"""Modules holding the suite's longest tests (`--durations=15`), run first.  `make test` uses
pytest-xdist's worksteal: each worker starts on a contiguous part of the collection and one that
runs out takes half of the other's remaining queue, so long tests at the end would leave one
worker running alone while short ones at the end are easily shared.  Whole modules move, in
their own order, so that their module fixtures are built once per worker."""


def pytest_collection_modifyitems(items):
    def rank(item) -> int:
        name = item.path.name
        return HEAVY_FIRST.index(name) if name in HEAVY_FIRST else len(HEAVY_FIRST)

    items.sort(key=rank)  # stable: the order within a module and among the others is kept
