"""Caches of the solver: bounded, keyed by the declaration, held outside the objects they serve.

- `LRU`: a bounded map, least recently used entry evicted first, with hit and miss counts.
  Its instances: `_sparse.PATTERNS` (sparsity patterns by the problem's declaration, at most
  8) and `_batch.COMPILED` (`solve_batch`'s executables by structure, at most
  `_batch.COMPILED_BATCH_SOLVERS`).  A new energy per call never grows memory without bound.
- `cleared_by_jax(cache)`: the cache is also emptied by `jax.clear_caches()`, so that an
  executable held here does not outlive JAX's own.
- `derived(obj, name, make)`: a value computed once from an immutable object (the symbolic
  analysis of a pattern, its device index arrays), kept in a weak map, so that it lives exactly
  as long as the object and never writes into it.
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from typing import Callable, Hashable, NamedTuple

__all__ = ["LRU", "CacheInfo", "cleared_by_jax", "derived"]


class CacheInfo(NamedTuple):
    """Lookups that found an entry (`hits`) or made one (`misses`); the bound and the count held."""

    hits: int
    misses: int
    maxsize: int
    currsize: int


class LRU:
    """At most `size` entries; `get(key, make)` returns the cached value or stores `make()`.

    The entry used longest ago is evicted when an insertion exceeds `size` (`size` may be
    changed; the new bound applies from the next insertion).  `make()` raising stores nothing.
    """

    def __init__(self, size: int):
        self.size = int(size)
        self.hits = 0
        self.misses = 0
        self._items: OrderedDict = OrderedDict()

    def __len__(self) -> int:
        return len(self._items)

    def get(self, key: Hashable, make: Callable):
        if key in self._items:
            self.hits += 1
            self._items.move_to_end(key)
            return self._items[key]
        self.misses += 1
        value = make()
        self._items[key] = value
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return value

    def cache_info(self) -> CacheInfo:
        return CacheInfo(self.hits, self.misses, self.size, len(self._items))

    def cache_keys(self) -> list:
        return list(self._items)

    def cache_clear(self) -> None:
        """Drop every entry and reset the counts."""
        self._items.clear()
        self.hits = self.misses = 0


def cleared_by_jax(cache: LRU, what: str = "ddgjax solvers") -> LRU:
    """`cache`, registered so that `jax.clear_caches()` empties it too; returned unchanged
    (and emptied only by `cache.cache_clear()`) on a JAX without the registration hook."""
    try:
        from jax._src.util import register_cache
    except ImportError:
        return cache
    register_cache(cache, what)
    return cache


_DERIVED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def derived(obj, name: str, make: Callable | None = None):
    """`make()` computed once per (object, name) and kept while `obj` lives; without `make`,
    the value computed before (KeyError if there is none)."""
    table = _DERIVED.setdefault(obj, {})
    if name not in table:
        if make is None:
            raise KeyError(f"{name} of {type(obj).__name__} was never computed")
        table[name] = make()
    return table[name]
