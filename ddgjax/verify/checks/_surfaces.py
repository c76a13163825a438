"""Graphs shared by the Sec 6 checks."""

from __future__ import annotations

import numpy as np


def random_graph(seed: int, n: int = 14, extra: int = 12):
    """`(edges, weights, rng)`: a connected graph on n vertices (a random tree plus `extra` random
    chords, loops dropped) with weights uniform in [0.1, 2]."""
    rng = np.random.default_rng(seed)
    parent = np.array([rng.integers(0, i) for i in range(1, n)])
    chords = rng.integers(0, n, size=(extra, 2))
    edges = np.vstack([np.stack([np.arange(1, n), parent], 1), chords[chords[:, 0] != chords[:, 1]]])
    return edges, rng.uniform(0.1, 2.0, len(edges)), rng
