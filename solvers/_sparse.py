"""Sparse KKT matrices from declared locality (finite-element style assembly).

For `E = Σ_k e(x[stencil_k])` the Hessian is `Σ_k P_kᵀ ∇²e P_k`: each cell adds a dense
(s·d)×(s·d) block at the rows and columns of the entries it reads.  The same holds for
`−λ·g` and, row by row, for the constraint Jacobian.  The pattern (which raw block entry goes
to which coalesced matrix entry) is computed once with NumPy from the stencils and the fixed
mask, and cached on the energy declaration; every Newton step then evaluates the blocks with
`vmap`ed `jax.hessian` / `jax.jacfwd` and adds each block value in place to its entry.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax._host import on_device
from ddgjax.errors import InvalidInputError
from ddgjax.locality import Local, Term

from ._cache import LRU, derived
from ._kkt import KKT, Spec


def _analyze(rows: np.ndarray, cols: np.ndarray, size: int):
    """`klujax.analyze`, run now even when called under an outer `jit` (e.g. `jit(vmap(solve))`),
    where it would otherwise return a tracer instead of the KLU symbolic object."""
    import klujax

    with jax.ensure_compile_time_eval():
        return klujax.analyze(on_device(rows), on_device(cols), size)


@dataclass(frozen=True, eq=False)
class TermPattern:
    term: Term
    columns: np.ndarray  # (K, s·d) flat indices of the entries the cell reads
    rows: np.ndarray | None  # (K, c) constraint rows the cell writes (constraints only)


@dataclass(frozen=True, eq=False)
class SparsePattern:
    n: int
    m: int
    energy_terms: tuple[TermPattern, ...]
    constraint_terms: tuple[TermPattern, ...]
    rows: np.ndarray  # (nnz,) int32, coalesced COO rows of the KKT matrix
    cols: np.ndarray  # (nnz,) int32
    hessian_targets: tuple[np.ndarray, ...]  # per Hessian term (chunks, cells per chunk, sd²) int32, 64-byte
    #   aligned (`in_chunks` order): the coalesced entry of each raw Hessian value (nnz: dropped, and padding)
    jacobian_target: np.ndarray  # (2, n_jacobian_raw) int32: entries of each raw Jacobian value in −J and −Jᵀ
    diagonal: np.ndarray  # (n + m,) int32: the diagonal entries
    coupled: np.ndarray  # KKT indices of the multipliers of global sums (e.g. a chord)
    key: tuple = ()  # the Spec key it was built from: equal keys give interchangeable patterns

    @property
    def nnz(self) -> int:
        return int(self.rows.size)

    def split(self) -> Bordered | None:
        """The KKT matrix split at the coupled multipliers; None if there are none."""
        if not self.coupled.size:
            return None
        return derived(self, "split", self._analysed_split)

    def _analysed_split(self) -> Bordered:
        """The split with KLU's analysis of its block made now, outside any trace."""
        split = bordered(self.rows, self.cols, self.coupled, self.n + self.m)
        split.symbolic()
        return split

    def symbolic(self):
        """KLU's symbolic analysis (ordering) of the KKT matrix, made once and kept here.

        Made outside any trace and kept as long as this pattern lives (`_cache.derived`), which
        `jit`'s cache holds through the static `SparseAlgebra`; every factorisation then skips the
        ordering.  The analysis depends on the pattern only, so the complex Levenberg–Marquardt
        solves reuse it.
        """
        return derived(self, "symbolic", lambda: _analyze(self.rows, self.cols, self.n + self.m))

    def blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """Value indices `(H entries, −J entries)` of the coalesced KKT matrix."""
        n = self.n
        return np.flatnonzero((self.rows < n) & (self.cols < n)), np.flatnonzero((self.rows >= n) & (self.cols < n))


@dataclass(frozen=True, eq=False)
class Bordered:
    """A sparse matrix `[[A, B], [Bᵗ, C]]` split at a few coupled indices (the border).

    A constraint that sums over all cells (a chord, a closure) fills a whole row and column of
    the KKT matrix; LU with pivoting turns such rows into catastrophic fill.  Eliminating the border by its Schur complement keeps
    the factorised block `A` banded:  `A Y = [b_A, B]`,  `S = C − Bᵗ Y_B`,
    `x_C = S⁻¹ (b_C − Bᵗ y_b)`,  `x_A = y_b − Y_B x_C` — one KLU factorisation with
    1 + (border size) right-hand sides, and a tiny dense solve.

    Index arrays refer to the coalesced COO values of the whole matrix (`take_*`) and to the
    compact numbering of the interior (`interior`) and the border (`border`).
    """

    size: int
    interior: np.ndarray
    border: np.ndarray
    a_rows: np.ndarray  # sorted (row, col) COO of A in interior numbering, int32
    a_cols: np.ndarray
    take_a: np.ndarray  # value index of each A entry
    b_rows: np.ndarray  # B: (interior row, border col)
    b_cols: np.ndarray
    take_b: np.ndarray
    bt_rows: np.ndarray  # Bᵗ block: (border row, interior col)
    bt_cols: np.ndarray
    take_bt: np.ndarray
    c_rows: np.ndarray
    c_cols: np.ndarray
    take_c: np.ndarray

    def symbolic(self):
        """KLU's analysis of A, made once (outside any trace) and kept while this split lives."""
        return derived(self, "symbolic", lambda: _analyze(self.a_rows, self.a_cols, len(self.interior)))


def bordered(rows: np.ndarray, cols: np.ndarray, border: np.ndarray, size: int) -> Bordered:
    """Split the COO pattern (rows, cols) of a size×size matrix at the indices `border`."""
    in_border = np.zeros(size, bool)
    in_border[border] = True
    interior = np.flatnonzero(~in_border)
    number = np.empty(size, np.int64)
    number[interior] = np.arange(len(interior))
    number[border] = np.arange(len(border))
    rb, cb = in_border[rows], in_border[cols]

    def block(mask):
        idx = np.flatnonzero(mask)
        r, c = number[rows[idx]], number[cols[idx]]
        order = np.lexsort((c, r))
        return r[order].astype(np.int32), c[order].astype(np.int32), idx[order]

    return Bordered(size, interior, np.asarray(border), *block(~rb & ~cb), *block(~rb & cb), *block(rb & ~cb), *block(rb & cb))


def _columns(term: Term, width: int, n_rows: int) -> np.ndarray:
    if term.stencil.size and term.stencil.max() >= n_rows:
        k = int(np.argwhere(term.stencil >= n_rows)[0][0])
        raise InvalidInputError(
            f"stencil row {k} reads row {int(term.stencil[k].max())} of x, which has only {n_rows} rows"
        )
    return (term.stencil[:, :, None] * width + np.arange(width)).reshape(len(term.stencil), -1)


def _output_size(term: Term, x0, params) -> int:
    local = jax.ShapeDtypeStruct((term.stencil.shape[1],) + x0.shape[1:], x0.dtype)
    data = jax.tree_util.tree_map(lambda a: jax.ShapeDtypeStruct(a.shape[1:], a.dtype), term.data)
    out = jax.eval_shape(lambda xl, dk: term.cell(xl, dk, params), local, data)
    return int(np.prod(out.shape, dtype=int))


def _constraint_rows(constraints: Local, x0, params):
    """Per term, the (K, c) array of constraint-vector rows it writes."""
    out, offset = [], 0
    for group in constraints.groups:
        sizes = []
        for term in group:
            c = _output_size(term, x0, params)
            K = len(term.stencil)
            if term.reduce == "sum":
                rows = np.broadcast_to(offset + np.arange(c), (K, c))
                sizes.append(c)
            else:
                rows = offset + np.arange(K * c).reshape(K, c)
                sizes.append(K * c)
            out.append((term, rows))
        offset += sizes[0]
    return out


RAW_PER_CHUNK = 1 << 21
"""Raw KKT entries handled at once while building a pattern: bounds its memory to a few times
this many integers instead of several times the number of raw entries (16·10⁶ at 10⁵ vertices)."""


def _raw_entries(terms_h, terms_j, free_of: np.ndarray, n: int, size: int):
    """The raw KKT entries, term by term and cell by cell, in chunks of about `RAW_PER_CHUNK`:
    `(kind, term, count, kept, key)`: `count` raw values of `kind` ("h": Hessian of `terms_h[term]`,
    "j": −J, "jt": −Jᵀ, each in its own order), of which those at `kept` add to a free entry with
    key row·size + col (entries on fixed unknowns are dropped)."""
    for i, tp in enumerate(terms_h):  # Hessian blocks: every (row, col) pair of a cell's columns
        K, sd = tp.columns.shape
        step = max(1, RAW_PER_CHUNK // (sd * sd))
        for k0 in range(0, K, step):
            cols = free_of[tp.columns[k0 : k0 + step]]
            fr = np.repeat(cols, sd, axis=1).ravel()
            fc = np.tile(cols, (1, sd)).ravel()
            kept = np.flatnonzero((fr >= 0) & (fc >= 0))
            yield "h", i, fr.size, kept, fr[kept] * size + fc[kept]
    for tp in terms_j:  # Jacobian blocks, stored once, used for −J (rows n + r) and −Jᵀ
        K, sd = tp.columns.shape
        c = tp.rows.shape[1]
        step = max(1, RAW_PER_CHUNK // (c * sd))
        for k0 in range(0, K, step):
            kc = len(tp.columns[k0 : k0 + step])
            rr = n + np.repeat(tp.rows[k0 : k0 + step], sd, axis=1).ravel()
            fc = free_of[np.broadcast_to(tp.columns[k0 : k0 + step, None, :], (kc, c, sd))].ravel()
            kept = np.flatnonzero(fc >= 0)
            yield "j", None, fc.size, kept, rr[kept] * size + fc[kept]
            yield "jt", None, fc.size, kept, fc[kept] * size + rr[kept]


def _distinct(a: np.ndarray) -> np.ndarray:
    """The sorted distinct values of `a` (by a sort: numpy's hashing `unique` is slower on keys)."""
    a = np.sort(a)
    return a[np.concatenate([[True], a[1:] != a[:-1]])] if a.size else a


def build_pattern(spec: Spec, x0, params) -> SparsePattern:
    """Static sparsity of the KKT matrix of a local problem (see module docstring).

    Two passes over the raw entries in chunks: the sorted distinct keys (row·size + col, the
    diagonal included), then each raw entry's position among them (`searchsorted`), or nnz for
    an entry on a fixed unknown (a slot that `kkt_values` drops).  The Hessian's positions are
    written straight into their chunked, device-ready arrays (`_hessian_chunks`): at 10⁵
    vertices they are 16·10⁶ integers, which exist once.
    """
    shape = spec.layout.shapes[0]
    width = shape[1] if len(shape) == 2 else 1
    n_rows = shape[0]
    n, m = spec.n, spec.m
    size = n + m
    free_of = np.full(spec.layout.n_total, -1, dtype=np.int64)
    free_of[spec.layout.free] = np.arange(n)

    energy_terms = tuple(TermPattern(t, _columns(t, width, n_rows), None) for t in spec.energy.groups[0])
    cons = [] if spec.constraints is None else _constraint_rows(spec.constraints, x0, params)
    constraint_terms = tuple(TermPattern(t, _columns(t, width, n_rows), rows) for t, rows in cons)

    def entries():
        return _raw_entries(energy_terms + constraint_terms, constraint_terms, free_of, n, size)

    diagonal = np.arange(size, dtype=np.int64) * (size + 1)
    keys = _distinct(np.concatenate([_distinct(key) for *_, key in entries()] + [diagonal]))
    hessian_targets = tuple(in_chunks_empty(tp.columns.shape[0], chunk_count(tp.columns.shape[0]),
                                            (tp.columns.shape[1] ** 2,), fill=keys.size)
                            for tp in energy_terms + constraint_terms)
    written = [0] * len(hessian_targets)
    targets = {"j": [], "jt": []}
    for kind, term, count, kept, key in entries():
        target = np.full(count, keys.size, dtype=np.int32)
        target[kept] = np.searchsorted(keys, key)
        if kind == "h":
            hessian_targets[term].reshape(-1)[written[term] : written[term] + count] = target
            written[term] += count
        else:
            targets[kind].append(target)
    joined = {kind: np.concatenate(t) if t else np.zeros((0,), np.int32) for kind, t in targets.items()}
    return SparsePattern(
        n=n,
        m=m,
        energy_terms=energy_terms,
        constraint_terms=constraint_terms,
        rows=device_ready(keys // size),
        cols=device_ready(keys % size),
        hessian_targets=hessian_targets,
        jacobian_target=np.stack([joined["j"], joined["jt"]]),
        diagonal=device_ready(np.searchsorted(keys, diagonal)),
        coupled=np.unique([n + r for tp in constraint_terms if tp.term.reduce == "sum" for r in tp.rows[0]]).astype(np.int64),
        key=spec.key(),
    )


PATTERNS = LRU(8)
"""Sparsity patterns by declaration (`Spec.key()`): the few most recent, since they can be large."""


def cached_pattern(spec: Spec, x0, params) -> SparsePattern:
    """`build_pattern`, memoised on the problem's declaration in the bounded `PATTERNS`."""
    return PATTERNS.get(spec.key(), lambda: build_pattern(spec, x0, params))


CELLS_PER_CHUNK = 1 << 13
"""Cells whose Hessian blocks are evaluated and added at once: the assembly's working memory is
a chunk's blocks, not every cell's (at 10⁵ vertices that is 8·10³ faces' blocks instead of 2·10⁵)."""


def chunk_count(cells: int) -> int:
    """Number of chunks of at most `CELLS_PER_CHUNK` cells, and at least 1."""
    return max(1, -(-cells // CELLS_PER_CHUNK))


def in_chunks_empty(cells: int, chunks: int, shape: tuple, fill: int) -> np.ndarray:
    """A device-ready int32 array (chunks, ⌈cells / chunks⌉, *shape) laid out as `in_chunks`
    lays out `cells` rows, every entry `fill` (to be overwritten by the first `cells` rows)."""
    out = aligned_int32((chunks, -(-cells // chunks)) + tuple(shape))
    out.fill(fill)
    return out


def in_chunks(a: np.ndarray, chunks: int, fill) -> np.ndarray:
    """(K, ...) → (chunks, ⌈K / chunks⌉, ...): consecutive cells, the last chunk padded with `fill`."""
    size = -(-len(a) // chunks)
    padded = np.concatenate([a, np.full((chunks * size - len(a),) + a.shape[1:], fill, a.dtype)])
    return padded.reshape((chunks, size) + a.shape[1:])


def _hessian_chunks(pattern: SparsePattern) -> dict:
    """Per Hessian term i: its cells' stencils, constraint rows and entries in chunks
    (`cells_i`, `rows_i`, `targets_i`); padding cells read row 0 and add to the dropped slot."""
    arrays = {}
    for i, tp in enumerate(pattern.energy_terms + pattern.constraint_terms):
        chunks = chunk_count(tp.columns.shape[0])
        arrays[f"cells_{i}"] = in_chunks(tp.term.stencil, chunks, 0)
        arrays[f"targets_{i}"] = pattern.hessian_targets[i]
        if tp.rows is not None:
            arrays[f"rows_{i}"] = in_chunks(tp.rows, chunks, 0)
    return arrays


def _add_cell_hessians(K, term: Term, x, params, cells, targets, lam=None, rows=None):
    """K + Σ_k P_kᵀ ∇²e_k P_k over the term's cells, chunk by chunk (`cells`, `targets`, `rows`
    from `_hessian_chunks`); for a constraint term `e_k = −λ_{rows_k} · g_k`."""

    def add_chunk(K, chunk):
        st, tg, dk, rk = chunk
        H = term.hessians(x[st], dk, params, None if rk is None else lam[rk])
        return K.at[tg.reshape(-1)].add(H.reshape(-1)), None

    chunks = cells.shape[0]
    data = jax.tree_util.tree_map(lambda leaf: in_chunks(np.asarray(leaf), chunks, np.asarray(leaf)[:1]), term.data)
    if chunks == 1:
        return add_chunk(K, jax.tree_util.tree_map(lambda a: a[0], (cells, targets, data, rows)))[0]
    return jax.lax.scan(add_chunk, K, (cells, targets, data, rows))[0]


def _cell_jacobians(term: Term, x, params):
    return term.jacobians(x[term.stencil], term.data, params).reshape(-1)


def kkt_values(pattern: SparsePattern, index: dict, kkt: KKT, w, identity_hessian: bool = False):
    """Coalesced COO values (at `pattern.rows`, `pattern.cols`) of K at w (∇²L replaced by I if asked);
    `index = index_arrays(pattern)`, or the same arrays traced.

    Each raw block value is added in place to its entry (a scatter-add into nnz + 1 slots, the
    last one collecting the values on fixed unknowns and padding cells), the Hessian blocks
    chunk by chunk: no array of all raw values is made.
    """
    n = pattern.n
    u, lam = kkt.split(w)
    x = kkt.x(u)
    K = jnp.zeros((pattern.nnz + 1,), dtype=w.dtype)
    if identity_hessian:
        K = K.at[index["diagonal"][:n]].add(1.0)
    else:
        for i, tp in enumerate(pattern.energy_terms + pattern.constraint_terms):
            K = _add_cell_hessians(K, tp.term, x, kkt.params, index[f"cells_{i}"], index[f"targets_{i}"],
                                   lam, index.get(f"rows_{i}"))
    if pattern.constraint_terms:
        jac = jnp.concatenate([_cell_jacobians(tp.term, x, kkt.params) for tp in pattern.constraint_terms])
        K = K.at[index["jacobian_target"][0]].add(-jac).at[index["jacobian_target"][1]].add(-jac)
    return K[: pattern.nnz]


SPLIT_ARRAYS = ("interior", "border", "a_rows", "a_cols", "take_a", "b_rows", "b_cols", "take_b",
                "bt_rows", "bt_cols", "take_bt", "c_rows", "c_cols", "take_c")


def index_arrays(pattern: SparsePattern) -> dict:
    """The pattern's index arrays as int32 device arrays, made once per pattern (`_cache.derived`).

    The solvers take them as *arguments* of the compiled solver, not as constants compiled into
    it: large constants inflate XLA's compile memory for the executable's lifetime, and gathers
    with traced indices are as fast.
    """
    return derived(pattern, "index", lambda: _device_index_arrays(pattern))


def _device_index_arrays(pattern: SparsePattern) -> dict:
    h_at, j_at = pattern.blocks()
    arrays = {"jacobian_target": pattern.jacobian_target, "rows": pattern.rows, "cols": pattern.cols,
              "diagonal": pattern.diagonal, "h_at": h_at, "j_at": j_at, **_hessian_chunks(pattern)}
    split = pattern.split()
    if split is not None:
        arrays.update({f"split_{name}": getattr(split, name) for name in SPLIT_ARRAYS})
    # concrete arrays even when first made under a trace (shard_map)
    with jax.ensure_compile_time_eval():
        return {k: jax.device_put(device_ready(v)) for k, v in arrays.items()}


ALIGNMENT = 64  # bytes: XLA's CPU client shares a NumPy buffer aligned so, and copies any other


def device_ready(a: np.ndarray) -> np.ndarray:
    """`a` as a C-contiguous int32 array whose buffer starts on a 64-byte boundary (itself if it
    is one already), so that `jax.device_put` on the CPU shares it instead of copying it: the
    index arrays of a 10⁵-vertex mesh are tens of MB each, held by the pattern and the solver."""
    a = np.asarray(a)
    if a.dtype == np.int32 and a.flags.c_contiguous and a.ctypes.data % ALIGNMENT == 0:
        return a
    out = aligned_int32(a.shape)
    out[...] = a
    return out


def aligned_int32(shape: tuple) -> np.ndarray:
    """An uninitialised C-contiguous int32 array of `shape` starting on a 64-byte boundary."""
    size = int(np.prod(shape, dtype=np.int64))
    buffer = np.empty(size * 4 + ALIGNMENT, np.uint8)
    start = -buffer.ctypes.data % ALIGNMENT
    return buffer[start : start + size * 4].view(np.int32).reshape(shape)


class PatternKey:
    """A pattern as static data of a pytree: equal (and hashing) by the problem structure it was
    built from, so that every problem declared alike reuses one compiled solver."""

    def __init__(self, pattern: SparsePattern):
        self.pattern = pattern

    def __hash__(self):
        return hash(self.pattern.key)

    def __eq__(self, other):
        return isinstance(other, PatternKey) and other.pattern.key == self.pattern.key
