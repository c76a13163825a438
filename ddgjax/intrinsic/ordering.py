"""A spatially coherent numbering of mesh elements (Z-order / Morton curve).

The flip loop gathers and scatters edge-, face- and halfedge-indexed arrays at random places; on
meshes whose vertex labels jump around (an icosphere's subdivision levels, say) those accesses
miss the cache.  Relabelling the vertices along a Morton curve and sorting the faces by their
smallest vertex label makes neighbouring elements neighbours in memory too, which halves the flip
time on 10⁶ faces.  Nothing here changes any result; `laplace_beltrami` maps the labels back.
"""

from __future__ import annotations

import numpy as np

__all__ = ["is_local", "local_numbering", "morton_order"]

_BITS = 10  # cells per axis: 2^10


def _spread(x: np.ndarray) -> np.ndarray:
    """Insert two zero bits between consecutive bits of 10-bit integers."""
    x = x & 0x3FF
    x = (x | (x << 16)) & 0x30000FF
    x = (x | (x << 8)) & 0x300F00F
    x = (x | (x << 4)) & 0x30C30C3
    return (x | (x << 2)) & 0x9249249


def morton_order(P) -> np.ndarray:
    """The permutation sorting the points P (n, 2 or 3) along a Z-order curve on a 2^10 grid
    over their bounding box."""
    P = np.asarray(P, dtype=np.float64)
    P = np.column_stack([P, np.zeros((len(P), 3 - P.shape[1]))]) if P.shape[1] < 3 else P[:, :3]
    lo, span = P.min(axis=0), np.ptp(P, axis=0)
    q = ((P - lo) / np.where(span > 0, span, 1.0) * ((1 << _BITS) - 1)).astype(np.int64)
    code = _spread(q[:, 0]) | (_spread(q[:, 1]) << 1) | (_spread(q[:, 2]) << 2)
    return np.argsort(code, kind="stable")


def local_numbering(V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(order, F_local)`: vertex i of the new numbering is `order[i]` of the old one, and
    `F_local` are the faces in new labels, sorted by their smallest label."""
    order = morton_order(V)
    label = np.empty_like(order)
    label[order] = np.arange(order.size)
    F_local = label[np.asarray(F)]
    return order, F_local[np.argsort(F_local.min(axis=1), kind="stable")]


def is_local(F, n_vertices: int) -> bool:
    """Heuristic: the labels are already spatially coherent if the median label difference along
    the faces' sides is below 4 √nv (a row-major grid has √nv, a Morton numbering less)."""
    F = np.asarray(F)
    return bool(np.median(np.abs(F - np.roll(F, 1, axis=1))) <= 4.0 * np.sqrt(n_vertices))
