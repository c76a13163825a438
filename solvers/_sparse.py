"""Sparse KKT matrices from declared locality (finite-element style assembly).

For `E = Σ_k e(x[stencil_k])` the Hessian is `Σ_k P_kᵀ ∇²e P_k`: each cell adds a dense
(s·d)×(s·d) block at the rows and columns of the entries it reads.  The same holds for
`−λ·g` and, row by row, for the constraint Jacobian.  The pattern (which raw block entry goes
to which coalesced matrix entry) is computed once with NumPy from the stencils and the fixed
mask, and cached on the energy declaration; every Newton step then evaluates the blocks with
`vmap`ed `jax.hessian` / `jax.jacfwd` and sums duplicates with one `segment_sum`.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax.errors import InvalidInputError
from ddgjax.locality import Local, Term

from ._cache import LRU, derived
from ._kkt import KKT, Spec


def _analyze(rows: np.ndarray, cols: np.ndarray, size: int):
    """`klujax.analyze`, run now even when called under an outer `jit` (e.g. `jit(vmap(solve))`),
    where it would otherwise return a tracer instead of the KLU symbolic object."""
    import klujax

    with jax.ensure_compile_time_eval():
        return klujax.analyze(jnp.asarray(rows), jnp.asarray(cols), size)


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
    source: np.ndarray  # (n_raw,) int32: index into the raw block values
    target: np.ndarray  # (n_raw + n + m,) int32: coalesced entry of each raw value, then of the diagonal
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


def build_pattern(spec: Spec, x0, params) -> SparsePattern:
    """Static sparsity of the KKT matrix of a local problem (see module docstring)."""
    shape = spec.layout.shapes[0]
    width = shape[1] if len(shape) == 2 else 1
    n_rows = shape[0]
    n, m = spec.n, spec.m
    free_of = np.full(spec.layout.n_total, -1, dtype=np.int64)
    free_of[spec.layout.free] = np.arange(n)

    energy_terms = tuple(TermPattern(t, _columns(t, width, n_rows), None) for t in spec.energy.groups[0])
    cons = [] if spec.constraints is None else _constraint_rows(spec.constraints, x0, params)
    constraint_terms = tuple(TermPattern(t, _columns(t, width, n_rows), rows) for t, rows in cons)

    r_list, c_list, src_list, offset = [], [], [], 0
    for tp in energy_terms + constraint_terms:  # Hessian blocks
        K, sd = tp.columns.shape
        rr = np.repeat(tp.columns, sd, axis=1).ravel()
        cc = np.tile(tp.columns, (1, sd)).ravel()
        fr, fc = free_of[rr], free_of[cc]
        keep = (fr >= 0) & (fc >= 0)
        r_list.append(fr[keep]); c_list.append(fc[keep])
        src_list.append(offset + np.flatnonzero(keep))
        offset += K * sd * sd
    for tp in constraint_terms:  # Jacobian blocks, stored once, used for -J and -Jᵀ
        K, sd = tp.columns.shape
        c = tp.rows.shape[1]
        rr = np.repeat(tp.rows, sd, axis=1).reshape(K, c, sd)
        cc = np.broadcast_to(tp.columns[:, None, :], (K, c, sd))
        fc = free_of[cc.ravel()]
        keep = fc >= 0
        src = offset + np.flatnonzero(keep)
        r_list += [n + rr.ravel()[keep], fc[keep]]
        c_list += [fc[keep], n + rr.ravel()[keep]]
        src_list += [src, src]
        offset += K * c * sd
    diag = np.arange(n + m)
    rows = np.concatenate(r_list + [diag])
    cols = np.concatenate(c_list + [diag])
    keys, target = np.unique(rows * (n + m) + cols, return_inverse=True)
    return SparsePattern(
        n=n,
        m=m,
        energy_terms=energy_terms,
        constraint_terms=constraint_terms,
        rows=(keys // (n + m)).astype(np.int32),
        cols=(keys % (n + m)).astype(np.int32),
        source=np.concatenate(src_list).astype(np.int32),
        target=target.astype(np.int32),
        coupled=np.unique([n + r for tp in constraint_terms if tp.term.reduce == "sum" for r in tp.rows[0]]).astype(np.int64),
        key=spec.key(),
    )


PATTERNS = LRU(8)
"""Sparsity patterns by declaration (`Spec.key()`): the few most recent, since they can be large."""


def cached_pattern(spec: Spec, x0, params) -> SparsePattern:
    """`build_pattern`, memoised on the problem's declaration in the bounded `PATTERNS`."""
    return PATTERNS.get(spec.key(), lambda: build_pattern(spec, x0, params))


def _cell_hessians(term: Term, x, params, weights=None):
    def cell_value(xl, dk, wk):
        val = jnp.ravel(term.cell(xl, dk, params))
        return val[0] if wk is None else -jnp.dot(wk, val)

    local = x[term.stencil]
    H = jax.vmap(jax.hessian(cell_value), in_axes=(0, 0, 0))(local, term.data, weights)
    return H.reshape(-1)


def _cell_jacobians(term: Term, x, params):
    local = x[term.stencil]
    J = jax.vmap(jax.jacfwd(lambda xl, dk: jnp.ravel(term.cell(xl, dk, params))))(local, term.data)
    return J.reshape(-1)


def cell_blocks(pattern: SparsePattern, kkt: KKT, w, identity_hessian: bool):
    """Raw values `(hessian blocks, jacobian blocks)` in the order `build_pattern` expects."""
    u, lam = kkt.split(w)
    x = kkt.x(u)
    if identity_hessian:
        size = sum(tp.columns.shape[0] * tp.columns.shape[1] ** 2 for tp in pattern.energy_terms + pattern.constraint_terms)
        hess = jnp.zeros((size,), dtype=w.dtype)
    else:
        pieces = [_cell_hessians(tp.term, x, kkt.params) for tp in pattern.energy_terms]
        pieces += [_cell_hessians(tp.term, x, kkt.params, lam[tp.rows]) for tp in pattern.constraint_terms]
        hess = jnp.concatenate(pieces)
    jac = [_cell_jacobians(tp.term, x, kkt.params) for tp in pattern.constraint_terms]
    return hess, (jnp.concatenate(jac) if jac else jnp.zeros((0,), dtype=w.dtype))


def kkt_values(pattern: SparsePattern, index: dict, kkt: KKT, w, identity_hessian: bool = False):
    """Coalesced COO values (at `pattern.rows`, `pattern.cols`) of K at w (∇²L replaced by I if asked);
    `index = index_arrays(pattern)`, or the same arrays traced."""
    n, m = pattern.n, pattern.m
    hess, jac = cell_blocks(pattern, kkt, w, identity_hessian)
    raw = jnp.concatenate([hess, -jac])
    # a concatenation, not `zeros.at[:n].add`: XLA constant-folds that scatter (seconds at 10⁵)
    diag = jnp.concatenate([jnp.full((n,), 1.0 if identity_hessian else 0.0), jnp.zeros((m,))])
    values = jnp.concatenate([raw[index["source"]], diag])
    return jax.ops.segment_sum(values, index["target"], num_segments=pattern.nnz)


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
    arrays = {"source": pattern.source, "target": pattern.target, "rows": pattern.rows, "cols": pattern.cols,
              "diagonal": pattern.target[pattern.source.shape[0]:], "h_at": h_at, "j_at": j_at}
    split = pattern.split()
    if split is not None:
        arrays.update({f"split_{name}": getattr(split, name) for name in SPLIT_ARRAYS})
    with jax.ensure_compile_time_eval():  # concrete arrays even when first made under a trace (shard_map)
        return {k: jnp.asarray(np.asarray(v, dtype=np.int32)) for k, v in arrays.items()}


class PatternKey:
    """A pattern as static data of a pytree: equal (and hashing) by the problem structure it was
    built from, so that every problem declared alike reuses one compiled solver."""

    def __init__(self, pattern: SparsePattern):
        self.pattern = pattern

    def __hash__(self):
        return hash(self.pattern.key)

    def __eq__(self, other):
        return isinstance(other, PatternKey) and other.pattern.key == self.pattern.key
