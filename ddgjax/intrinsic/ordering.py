"""A spatially coherent numbering of mesh elements (Z-order / Morton curve).

The flip loop gathers and scatters edge-, face- and halfedge-indexed arrays at random places; on
meshes whose vertex labels jump around (an icosphere's subdivision levels, say) those accesses
miss the cache.  Relabelling the vertices along a Morton curve and sorting the faces by their
smallest vertex label makes neighbouring elements neighbours in memory too, which halves the flip
time on 10⁶ faces.  Nothing here changes any result; `laplace_beltrami` maps the labels back.
"""

from __future__ import annotations

import numpy as np

__all__ = ["is_local", "local_numbering", "morton_order", "radix_argsort"]

_BITS = 10  # cells per axis: 2^10


def _spread(x: np.ndarray) -> np.ndarray:
    """Insert two zero bits between consecutive bits of 10-bit integers."""
    x = x & 0x3FF
    x = (x | (x << 16)) & 0x30000FF
    x = (x | (x << 8)) & 0x300F00F
    x = (x | (x << 4)) & 0x30C30C3
    return (x | (x << 2)) & 0x9249249


def radix_argsort(keys: np.ndarray) -> np.ndarray:
    """`np.argsort(keys, kind="stable")` for nonnegative integer keys, as a least-significant-digit
    radix sort: one stable argsort per 16-bit digit (numpy radix-sorts 16-bit integers in linear
    time; its sort of int64 is a comparison sort, several times slower)."""
    keys = np.asarray(keys)
    top = int(keys.max()) if keys.size else 0
    order = None
    shift = 0
    while True:
        digits = ((keys if order is None else keys[order]) >> shift).astype(np.uint16)  # low 16 bits
        step = np.argsort(digits, kind="stable")
        order = step if order is None else order[step]
        shift += 16
        if top >> shift == 0:
            return order


def morton_order(P) -> np.ndarray:
    """The permutation sorting the points P (n, 2 or 3) along a Z-order curve on a 2^10 grid
    over their bounding box."""
    P = np.asarray(P, dtype=np.float64)
    P = np.column_stack([P, np.zeros((len(P), 3 - P.shape[1]))]) if P.shape[1] < 3 else P[:, :3]
    lo = np.array([P[:, k].min() for k in range(3)])  # per column: reductions over axis 0 are slow
    span = np.array([P[:, k].max() for k in range(3)]) - lo
    q = ((P - lo) / np.where(span > 0, span, 1.0) * ((1 << _BITS) - 1)).astype(np.int64)
    code = _spread(q[:, 0]) | (_spread(q[:, 1]) << 1) | (_spread(q[:, 2]) << 2)
    return radix_argsort(code)


def local_numbering(V, F) -> tuple[np.ndarray, np.ndarray]:
    """`(order, F_local)`: vertex i of the new numbering is `order[i]` of the old one, and
    `F_local` are the faces in new labels, sorted by their smallest label."""
    order = morton_order(V)
    label = np.empty_like(order)
    label[order] = np.arange(order.size)
    F_local = label[np.asarray(F)]
    smallest = np.minimum(np.minimum(F_local[:, 0], F_local[:, 1]), F_local[:, 2])
    return order, np.take(F_local, radix_argsort(smallest), axis=0)  # take: fancy row indexing is slow


def is_local(F, n_vertices: int) -> bool:
    """Heuristic: the labels are already spatially coherent if the median label difference along
    the faces' sides is below 4 √nv (a row-major grid has √nv, a Morton numbering less); on at
    most about 10⁵ faces spread over the mesh."""
    F = np.asarray(F)
    F = F[:: max(1, len(F) // 100_000)]
    return bool(np.median(np.abs(F - np.roll(F, 1, axis=1))) <= 4.0 * np.sqrt(n_vertices))
