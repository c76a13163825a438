"""Caches of the solver: bounded, keyed by the declaration, held outside the objects they serve.

- `LRU`: a bounded map, least recently used entry evicted first (sparsity patterns by the
  problem's declaration: a new energy per call never grows memory without bound).
- `derived(obj, name, make)`: a value computed once from an immutable object (the symbolic
  analysis of a pattern, its device index arrays), kept in a weak map, so that it lives exactly
  as long as the object and never writes into it.
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from typing import Callable, Hashable

__all__ = ["LRU", "derived"]


class LRU:
    """At most `size` entries; `get(key, make)` returns the cached value or stores `make()`."""

    def __init__(self, size: int):
        self.size = int(size)
        self._items: OrderedDict = OrderedDict()

    def get(self, key: Hashable, make: Callable):
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key]
        value = make()
        self._items[key] = value
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return value


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
