"""Array bookkeeping on concrete values in NumPy, on traced values in `jax.numpy`.

Outside `jit`, every `jax.numpy` operation on a shape not seen before compiles an XLA program
(about 10 ms each on a CPU, cached only for that shape).  The bookkeeping around a solve —
flattening `x0`, slicing and reshaping the result, the residual weights — runs once per call on
concrete values, where NumPy does the same in microseconds and compiles nothing; under a trace
(`jit`, `vmap`, `grad`) the same code must stay in `jax.numpy`.  Results go back to JAX arrays
with `jax.device_put`, which copies without compiling.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["namespace", "on_device", "with_set"]


def namespace(*trees):
    """`numpy` when no leaf of `trees` is a tracer, else `jax.numpy`."""
    leaves = jax.tree_util.tree_leaves(trees)
    return jnp if any(isinstance(leaf, jax.core.Tracer) for leaf in leaves) else np


def on_device(x):
    """A NumPy array as a JAX array (`jax.device_put`, no compilation); anything else as is."""
    return jax.device_put(x) if isinstance(x, (np.ndarray, np.generic)) else x


def with_set(x, index, values):
    """`x` with `x[index] = values`, `x` unchanged: a NumPy copy for concrete values,
    `x.at[index].set(values)` when either is traced (differentiable in `x` and `values`)."""
    if namespace(x, values) is np:
        out = np.array(x, dtype=np.result_type(np.asarray(x).dtype, np.asarray(values).dtype))
        out[index] = np.asarray(values)
        return out
    return jnp.asarray(x).at[index].set(values)
