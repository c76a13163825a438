"""`KLU`: the KKT matrix assembled from local blocks (`_sparse.py`), factorised by KLU (klujax).

Inside `jit`, `vmap`-able (a loop of factorisations), CPU only.  KLU orders for circuit
matrices (block triangular form, then AMD on each block) and factorises left-looking without
supernodes: the fastest choice for chains (curves, rods), where the KKT matrix is banded and
fill is nil, but not for the 2-D fill of a mesh (`SparseLDL` there).  A constraint summed over
all cells (a chord) is eliminated by its Schur complement (`_sparse.Bordered`).  `apply`
factorises and solves in one call; `factorised` factorises once for the several solves of a
Newton step (a solve with the factors costs a fraction of a factorisation) and frees the
factors after.
Its Levenberg–Marquardt step is one complex solve with `K + i√ν I`, on K's own pattern and
KLU analysis.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax._checks import is_staged

from ._kkt import KKT
from ._linear import LinearSolver, row_regularisation
from ._sparse import SPLIT_ARRAYS, Bordered, PatternKey, SparsePattern, cached_pattern, index_arrays, kkt_values


def _klu_solve(rows, cols, values, b, handle):
    """Solve with KLU, reusing a symbolic analysis, for COO indices already sorted by (row, col).

    `klujax.solve_with_symbol` lexsorts the indices on every call; our patterns are sorted
    when built (`np.unique`), so we bind its primitive directly (`tests/test_solve.py` checks
    this against `klujax.solve`).  `handle` is the analysis' address (`symbolic_handle`), an
    argument of the compiled program: as a constant it would make every process compile a
    different program, and a program loaded from the persistent cache point into another
    process' memory.  `handle=None` (a solver bound while `jit` traces a program, where the
    address would be such a constant): analysis, factorisation and solve in one call.
    """
    import klujax

    rhs = b.reshape(1, b.shape[0], -1)  # (n_lhs = 1, n_col, n_rhs)
    complex_ = jnp.iscomplexobj(values)
    indices = (jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32))
    if handle is None:
        x = (klujax.solve_c128 if complex_ else klujax.solve_f64).bind(*indices, values[None, :], rhs)
    else:
        solve = klujax.solve_with_symbol_c128 if complex_ else klujax.solve_with_symbol_f64
        x = solve.bind(*indices, values[None, :], rhs, handle)
    return x.reshape(b.shape)


def symbolic_handle(pattern: SparsePattern | Bordered) -> jax.Array:
    """The address of the KLU analysis that `pattern` keeps alive, as a uint64 scalar."""
    with jax.ensure_compile_time_eval():
        return jax.device_put(np.uint64(pattern.symbolic().raw))


def _klu_factor(rows, cols, values, handle):
    """KLU's numeric factorisation (partial pivoting, on the analysis `handle`) of the matrix with
    sorted COO indices (rows, cols) and `values`: a (1,) uint64 address of the factors, to be
    freed by `_klu_free`."""
    import klujax

    factor = klujax.factor_c128 if jnp.iscomplexobj(values) else klujax.factor_f64
    return factor.bind(jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32), values[None, :], handle)


def _klu_solve_factored(numeric, b, handle):
    """Solve with KLU's factors `numeric` (`_klu_factor`): two triangular solves."""
    import klujax

    solve = klujax.solve_with_numeric_c128 if jnp.iscomplexobj(b) else klujax.solve_with_numeric_f64
    return solve.bind(handle, numeric, b.reshape(1, b.shape[0], -1)).reshape(b.shape)


FREE_NUMERIC, FREE_SYMBOLIC = "ddgjax_klu_free_numeric", "ddgjax_klu_free_symbolic"
_REGISTERED: set = set()  # FFI targets registered in this process


def _klu_analyze(rows, cols, size: int):
    """KLU's analysis of the pattern (rows, cols) of a size×size matrix, made inside the
    program: its address, a uint64 scalar, to be freed by `_klu_free_symbolic`.

    klujax's `analyze` handler, called as an operation with a side effect: XLA would otherwise
    merge two analyses of one pattern (common-subexpression elimination) or hoist one out of a
    loop, both of which free it (twice, or in every iteration)."""
    import klujax  # noqa: F401  (registers its handler "analyze")

    analyze = jax.ffi.ffi_call("analyze", jax.ShapeDtypeStruct((), jnp.uint64), has_side_effect=True)
    return analyze(jnp.asarray(rows, jnp.int32), jnp.asarray(cols, jnp.int32), jnp.int32(size))


def _klu_free(numeric, after) -> None:
    """Free KLU's factors `numeric` once `after` (a pytree) is computed.

    klujax frees factors made outside a trace when their Python object dies; inside a compiled
    program they are freed here, by klujax's own `free_numeric` handler (which frees every
    address in its operand), left unregistered by its Python side.  The free must follow
    every solve with the factors, so its operand is made to depend on all of `after`
    (`_depending_on`).  Under `vmap` a batch of factors is freed by one call, and factors
    shared by the batch (a matrix that does not depend on the batched values) once."""
    _register_frees()
    _free_numeric_after(numeric, after)


def _klu_free_symbolic(handle, after) -> None:
    """Free the analysis `handle` made in the program (`_klu_analyze`) once `after` is computed,
    by klujax's `free_symbolic` handler; once, also under `vmap` (`_klu_free`)."""
    _register_frees()
    _free_symbolic_after(handle, after)


def _register_frees() -> None:
    """Register `FREE_NUMERIC` and `FREE_SYMBOLIC` (klujax's handlers) once per process."""
    import klujax_cpp

    for name, handler in ((FREE_NUMERIC, klujax_cpp.free_numeric), (FREE_SYMBOLIC, klujax_cpp.free_symbolic)):
        if name not in _REGISTERED:
            jax.ffi.register_ffi_target(name, handler(), platform="cpu")
            _REGISTERED.add(name)


def _free_after(target: str):
    """`free(handle, after)`: the FFI handler `target` called on `handle` once `after` is
    computed.  Under `vmap` the whole (batched or shared) `handle` goes to one call, whose
    batch axis is just another axis there: a batch of factors is freed together, an analysis or
    factors shared by the batch once."""

    @jax.custom_batching.custom_vmap
    def free(handle, after):
        call = jax.ffi.ffi_call(target, jax.ShapeDtypeStruct((), jnp.int32), has_side_effect=True)
        return call(_depending_on(handle, after))

    @free.def_vmap
    def free_batched(axis_size, in_batched, handle, after):
        return free(handle, after), False

    return free


_free_numeric_after, _free_symbolic_after = _free_after(FREE_NUMERIC), _free_after(FREE_SYMBOLIC)


def _depending_on(handle, after):
    """`handle` plus an integer computed from every leaf of `after` that is 0 at run time
    (`isnan(s) & isfinite(s)`) but that the compiler cannot fold: a data dependency that orders
    what uses the result after `after`.  (An optimisation barrier does not: XLA's CPU pipeline
    drops it.)"""
    s = sum(jnp.sum(jnp.real(leaf).astype(jnp.float64)) for leaf in jax.tree_util.tree_leaves(after))
    return handle + (jnp.isnan(s) & jnp.isfinite(s)).astype(handle.dtype)


def _border_blocks(split, index: dict, values):
    """`(B, Bᵗ, C)` of the bordered matrix `[[A, B], [Bᵗ, C]]` (`Bordered`), dense; `index`
    holds its arrays (`split_*`)."""
    ix = {name: index[f"split_{name}"] for name in SPLIT_ARRAYS}
    n_in, p = len(split.interior), len(split.border)
    B = jnp.zeros((n_in, p), values.dtype).at[ix["b_rows"], ix["b_cols"]].add(values[ix["take_b"]])
    Bt = jnp.zeros((p, n_in), values.dtype).at[ix["bt_rows"], ix["bt_cols"]].add(values[ix["take_bt"]])
    C = jnp.zeros((p, p), values.dtype).at[ix["c_rows"], ix["c_cols"]].add(values[ix["take_c"]])
    return B, Bt, C


def _eliminate_border(index: dict, blocks, b, y, Y):
    """The solution of `[[A, B], [Bᵗ, C]] x = b` from `y = A⁻¹ b_A` and `Y = A⁻¹ B`, by the
    Schur complement `S = C − Bᵗ Y`: `x_C = S⁻¹ (b_C − Bᵗ y)`, `x_A = y − Y x_C`."""
    _, Bt, C = blocks
    interior, border = index["split_interior"], index["split_border"]
    x_border = jnp.linalg.solve(C - Bt @ Y, b[border] - Bt @ y)
    return jnp.zeros(b.shape, y.dtype).at[interior].set(y - Y @ x_border).at[border].set(x_border)


def _bordered_solve(split, index: dict, values, b):
    """Solve `[[A, B], [Bᵗ, C]] x = b` (`Bordered`): one KLU factorisation and solve of A with the
    right-hand sides `[b_A, B]`, then `_eliminate_border`."""
    blocks = _border_blocks(split, index, values)
    rhs = jnp.concatenate([b[index["split_interior"]][:, None], blocks[0]], axis=1)
    Y = _klu_solve(index["split_a_rows"], index["split_a_cols"], values[index["split_take_a"]], rhs, index.get("klu_symbolic"))
    return _eliminate_border(index, blocks, b, Y[:, 0], Y[:, 1:])


class AssembledSparse(LinearSolver):
    """What the sparse direct back ends share: K as the coalesced COO values of the pattern
    (`kkt_values`), its regularisation on the diagonal entries, and `K v` by a segment sum.
    Subclasses are pytrees whose leaves are the pattern's index arrays (`index_arrays`) and whose
    static part compares by the pattern's structure (`PatternKey`)."""

    needs_locality = True
    iterative_refinement = True

    def __init__(self, pattern: SparsePattern | None = None, index: dict | None = None):
        self.pattern = pattern
        if index is None and pattern is not None:
            index = {**index_arrays(pattern), **self.prepare(pattern)}
        self.index = index

    def prepare(self, pattern: SparsePattern) -> dict:
        """The back end's analysis of the pattern, made once, outside any trace; returns the
        further arguments its solves take (added to the index arrays)."""
        return {}

    def bind(self, problem, spec):
        """This back end on the problem's pattern; itself if already bound to it (its index
        arrays may then be arguments of a traced function: `solve_batch` passes them so)."""
        pattern = cached_pattern(spec, problem.x0, problem.params)
        return self if self.pattern is pattern else self.on(pattern)

    def on(self, pattern: SparsePattern) -> AssembledSparse:
        """A solver of this kind on `pattern`, with its index arrays and analysis made now."""
        return type(self)(pattern)

    def tree_flatten(self):
        names = () if self.index is None else tuple(sorted(self.index))
        key = None if self.pattern is None else PatternKey(self.pattern)
        return tuple(self.index[k] for k in names), (key, names)

    @classmethod
    def tree_unflatten(cls, aux, children):
        key, names = aux
        if key is None:
            return cls()
        return cls(key.pattern, dict(zip(names, children)))

    def __repr__(self):
        return f"{type(self).__name__}()" if self.pattern is None else f"{type(self).__name__}(N={self.pattern.n + self.pattern.m})"

    def matrix(self, kkt: KKT, w, identity_hessian=False):
        """Coalesced COO values of K (K's Hessian block replaced by I if asked)."""
        return kkt_values(self.pattern, self.index, kkt, w, identity_hessian)

    def factor_matrix(self, kkt: KKT, K, mu_rel):
        return self.regularised(K, mu_rel)

    def regularised(self, K, mu_rel):
        """The values of `K + μS`, μ scaled row by row (`row_regularisation`)."""
        n, m = self.pattern.n, self.pattern.m
        row_max = jax.ops.segment_max(jnp.abs(K), self.index["rows"], num_segments=n + m)
        return K.at[self.index["diagonal"]].add(row_regularisation(n, m, mu_rel, row_max))

    def matvec(self, K, v):
        return jax.ops.segment_sum(K * v[self.index["cols"]], self.index["rows"], num_segments=v.shape[0])


@jax.tree_util.register_pytree_node_class
class KLU(AssembledSparse):
    """Sparse KKT matrix assembled from local blocks; KLU solve (klujax), inside `jit`."""

    def prepare(self, pattern: SparsePattern) -> dict:
        """KLU's analysis of K (or of its interior block), made now, outside any trace; none
        while `jit` traces a program (`is_staged`): its address would be a constant of the
        program, which then differs in every process and is never found in the persistent
        cache, so the program analyses the pattern itself (`analysed`, `_klu_solve`)."""
        if is_staged():
            return {}
        split = pattern.split()
        return {"klu_symbolic": symbolic_handle(pattern if split is None else split)}

    def apply(self, fac, b):
        split = self.pattern.split()
        if split is not None:
            return _bordered_solve(split, self.index, fac, b)
        return _klu_solve(self.index["rows"], self.index["cols"], fac, b, self.index.get("klu_symbolic"))

    def analysed(self, run):
        """`run(self)`; without an analysis (`prepare` while `jit` traces), with one made in the
        program before `run`'s solves and freed after them.  The analysis is not made per
        factorisation: XLA would hoist it, a pure function of constant indices, out of Newton's
        loop, while the free stayed inside."""
        if "klu_symbolic" in self.index:
            return run(self)
        split, ix = self.pattern.split(), self.index
        if split is None:
            handle = _klu_analyze(ix["rows"], ix["cols"], self.pattern.n + self.pattern.m)
        else:
            handle = _klu_analyze(ix["split_a_rows"], ix["split_a_cols"], len(split.interior))
        out = run(type(self)(self.pattern, {**ix, "klu_symbolic": handle}))
        _klu_free_symbolic(handle, out)
        return out

    def factorised(self, fac, use):
        """`use(solve)` with one KLU factorisation of `fac` for all its solves (`LinearSolver`),
        freed after; bordered: with `A⁻¹ B` made once too.  Without an analysis (`prepare`
        while `jit` traces, outside `analysed`), each solve factorises anew."""
        if "klu_symbolic" not in self.index:
            return super().factorised(fac, use)
        ix, handle = self.index, self.index["klu_symbolic"]
        split = self.pattern.split()
        if split is None:
            numeric = _klu_factor(ix["rows"], ix["cols"], fac, handle)
            out = use(lambda b: _klu_solve_factored(numeric, b, handle))
        else:
            numeric = _klu_factor(ix["split_a_rows"], ix["split_a_cols"], fac[ix["split_take_a"]], handle)
            blocks = _border_blocks(split, ix, fac)
            Y = _klu_solve_factored(numeric, blocks[0], handle)

            def solve(b):
                y = _klu_solve_factored(numeric, b[ix["split_interior"]], handle)
                return _eliminate_border(ix, blocks, b, y, Y)

            out = use(solve)
        _klu_free(numeric, out)
        return out

    def lm_solve_matrix(self, K, nu, R):
        """`−(K² + ν I)⁻¹ K R = −Re[(K + i√ν I)⁻¹ R]` (K symmetric: `(K + isI)⁻¹ = (K − isI)(K² + s²I)⁻¹`),
        one complex KLU solve on K's own pattern and analysis, with smallest singular value ≥ √ν."""
        shifted = K.astype(jnp.complex128).at[self.index["diagonal"]].add(1j * jnp.sqrt(nu))
        return -jnp.real(self.apply(shifted, R.astype(jnp.complex128)))


def ffi_targets() -> tuple[str, ...]:
    """The custom-call targets a program with KLU solves may call, registered in this process:
    klujax's (under the names of `klujax_cpp`'s handlers), `FREE_NUMERIC` and `FREE_SYMBOLIC`."""
    import klujax  # noqa: F401  (registers its targets)
    import klujax_cpp

    _register_frees()
    handlers = [name for name in dir(klujax_cpp) if not name.startswith("_") and name[0].islower()]
    return (*handlers, FREE_NUMERIC, FREE_SYMBOLIC)
