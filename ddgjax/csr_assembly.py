"""The graph Laplacian of weighted edges in compressed sparse row form, compiled by numba.

For edges e = (i_e, j_e) with weights w_e the Laplacian is

    L_ii = Σ_{e ∋ i, i_e ≠ j_e} w_e,    L_ij = −Σ_{e = (ij) or (ji)} w_e  (i ≠ j),

so that (L f)_i = Σ_j ν_ij (f_i − f_j) (eq 6.2, Def 6.2): several edges between two vertices add
their weights and loops drop out.  Written directly in CSR, row by row: a counting sort of the
entries by row, an insertion sort of each (short) row by column, duplicates merged.  This is
`ddgjax.laplace.laplacian_of_edge_weights` for a connectivity used once (an intrinsic
triangulation after flips), where no cached pattern pays off; the same matrix as scipy's COO → CSR
conversion of the entries, in canonical form (sorted, no duplicates), in one pass over memory
instead of a sort.  Plain integer and float arithmetic that nothing traces or differentiates;
numba caches the machine code on disk (`cache=True`) and this module is imported on first use
only, so `import ddgjax` does not load numba.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _rows(i, j, w, n):
    """Unsorted rows: `(indptr, indices, data)` with the diagonal first in each row, then one
    entry −w per end of each edge that is not a loop."""
    count = np.ones(n + 1, np.int64)
    count[0] = 0
    diagonal = np.zeros(n)
    for e in range(i.size):
        a, b = i[e], j[e]
        if a != b:
            count[a + 1] += 1
            count[b + 1] += 1
            diagonal[a] += w[e]
            diagonal[b] += w[e]
    indptr = np.cumsum(count)
    indices = np.empty(indptr[n], i.dtype)
    data = np.empty(indptr[n])
    fill = indptr[:n].copy()
    for v in range(n):
        indices[fill[v]] = v
        data[fill[v]] = diagonal[v]
        fill[v] += 1
    for e in range(i.size):
        a, b = i[e], j[e]
        if a != b:
            indices[fill[a]], data[fill[a]] = b, -w[e]
            fill[a] += 1
            indices[fill[b]], data[fill[b]] = a, -w[e]
            fill[b] += 1
    return indptr, indices, data


@numba.njit(cache=True)
def _canonical(indptr, indices, data):
    """Sort each row by column and add up repeated columns, in place; the new row pointers
    (the arrays are valid up to `new_indptr[-1]`)."""
    n = indptr.size - 1
    new_indptr = np.empty(n + 1, indptr.dtype)
    new_indptr[0] = 0
    out = 0
    for v in range(n):
        start, end = indptr[v], indptr[v + 1]
        for k in range(start + 1, end):  # insertion sort: rows have a handful of entries
            c, x = indices[k], data[k]
            m = k - 1
            while m >= start and indices[m] > c:
                indices[m + 1], data[m + 1] = indices[m], data[m]
                m -= 1
            indices[m + 1], data[m + 1] = c, x
        k = start
        while k < end:  # out <= k: the compacted row never overtakes the one being read
            c, x = indices[k], data[k]
            k += 1
            while k < end and indices[k] == c:
                x += data[k]
                k += 1
            indices[out], data[out] = c, x
            out += 1
        new_indptr[v + 1] = out
    return new_indptr


def edge_laplacian_csr(i: np.ndarray, j: np.ndarray, w: np.ndarray, n: int):
    """`(data, indices, indptr)` of the (n, n) Laplacian of the edges (i[e], j[e]) with weights
    w[e] (module docstring), canonical CSR; `indices`, `indptr` of the dtype of i (int32 or
    int64, scipy's index types)."""
    indptr, indices, data = _rows(i, j, np.ascontiguousarray(w, dtype=np.float64), n)
    indptr = _canonical(indptr, indices, data)
    nnz = int(indptr[-1])
    index = i.dtype if nnz < np.iinfo(np.int32).max else np.int64
    return data[:nnz], indices[:nnz].astype(index, copy=False), indptr.astype(index)
