"""The free entries of a pytree of unknowns as one flat vector.

Solvers and flows work on `u`, the vector of free entries; `x = unravel(z0.at[free].set(u))`
rebuilds the pytree with the fixed entries copied bit for bit from `z0`, the flattened `x0`.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ._host import namespace, on_device, with_set


@dataclass(frozen=True, eq=False)
class Layout:
    """Static description of the unknowns: tree structure, leaf shapes, free positions."""

    treedef: object
    shapes: tuple
    free: np.ndarray  # (n_free,) int64, positions of free entries in the flat vector

    @property
    def n_total(self) -> int:
        return int(sum(int(np.prod(s, dtype=int)) for s in self.shapes))

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    def key(self):
        return (self.treedef, self.shapes, self.free.tobytes())

    def __hash__(self):
        return hash(self.key())

    def __eq__(self, other):
        return isinstance(other, Layout) and self.key() == other.key()

    def ravel(self, x) -> jax.Array:
        """Flatten a pytree shaped like x0 into one vector (leaf by leaf, C order)."""
        xp = namespace(x)
        return on_device(xp.concatenate([xp.ravel(leaf) for leaf in jax.tree_util.tree_leaves(x)]))

    def unravel(self, z: jax.Array):
        xp = namespace(z)
        z = xp.asarray(z)
        leaves, start = [], 0
        for shape in self.shapes:
            size = int(np.prod(shape, dtype=int))
            leaves.append(on_device(z[start : start + size].reshape(shape)))
            start += size
        return jax.tree_util.tree_unflatten(self.treedef, leaves)

    def embed(self, z0: jax.Array, u: jax.Array) -> jax.Array:
        """The full flat vector: fixed entries from `z0`, free entries from `u`."""
        return on_device(with_set(z0, self.free, u))

    def x_of(self, z0: jax.Array, u: jax.Array):
        return self.unravel(with_set(z0, self.free, u))  # unravel puts the leaves on the device


def layout_of(problem) -> Layout:
    leaves, treedef = jax.tree_util.tree_flatten(problem.x0)
    fixed = np.concatenate([np.ravel(m) for m in jax.tree_util.tree_leaves(problem.fixed)])
    shapes = tuple(tuple(np.shape(leaf)) for leaf in leaves)
    return Layout(treedef, shapes, np.flatnonzero(~fixed).astype(np.int64))
