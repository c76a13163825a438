"""`SparseDirect`: a fill-reducing sparse direct solver on the host, for the KKT systems of meshes.

On a 2-D mesh the factor of the KKT matrix fills in like that of a 2-D Laplacian: with a
nested-dissection or minimum-degree ordering about O(n log n) entries and O(n^1.5) flops,
which supernodal codes do at dense-BLAS speed.  The factorisation runs in a host callback
(`jax.pure_callback`), so `solve` stays one compiled program: the KKT values are assembled on
the device exactly as for `KLU` (`AssembledSparse`), then

- `factor_matrix` hands the values of `K + μS` to the host, which factorises them (reusing the
  ordering and symbolic analysis made once per pattern) and returns a *token* naming the
  factorisation it keeps;
- `apply(token, b)` solves with that factorisation (Newton's damping test reuses it).

The host keeps the latest factorisation per batch member (`LIVE_PER_MEMBER`) and frees older
ones, reusing their memory: a Newton step's factorisation is dead once the next one is made,
because the next step depends on the results of the current step's solves (two solves of one
pattern running at once in two threads would free each other's: the solve that finds its
factorisation gone raises an error naming it).  XLA may run the callbacks on any of its threads, so nothing is kept per thread.
`jax.vmap` calls each callback once with the whole batch (`vmap_method="broadcast_all"`), which
factorises every member and keeps them all.
`jax.grad` works as on every back end (the adjoint is one more factorisation and solve, `K`
being symmetric).  Tracing, transformations and device placement are those of a host callback:
CPU and GPU runs both work, a GPU run copies the values to the host and back each step.

The KKT pattern is symmetric and kept sorted by (row, col), so its COO arrays are already the
CSR arrays of K and, K being symmetric, its CSC arrays too: no permutation per step.

Factorisers (`factoriser=`), chosen by measurement (`benchmarks/linear_solvers.py`: on the
area Hessian of a 180² grid Pardiso factorises in 0.6× the time scipy's `splu` takes for the
3×3-block cotan Laplacian of the same mesh, CHOLMOD's `LDLᵀ` 3×, KLU 7×):
- `"pardiso"` (default where MKL is installed, `pypardiso`): MKL Pardiso for real symmetric
  indefinite matrices (`mtype = −2`: supernodal `LDLᵀ` with Bunch–Kaufman pivoting and
  perturbation of tiny pivots), its analysis (nested-dissection ordering, symbolic
  factorisation) made once per pattern and thread, its inertia from `iparm(23)`;
- `"cholmod"` (scikit-sparse, which needs the SuiteSparse headers to build): CHOLMOD's simplicial
  `LDLᵀ` without pivoting under a nested-dissection ordering made once, its inertia from D;
  a (nearly) zero pivot falls back to
- `"superlu"`: SuperLU (scipy `splu`, COLAMD ordering, partial pivoting): any nonsingular K,
  inertia unknown; also the complex solves of the Levenberg–Marquardt fallback without Pardiso.

The Levenberg–Marquardt fallback's `(K + i√ν I)⁻¹` is, with Pardiso, one real symmetric
factorisation of `[[K, √ν I], [√ν I, −K]]` of twice the size with weighted matching
(`_solve_shifted_real`), not a complex factorisation of K + i√ν I.
"""

from __future__ import annotations

import functools
import threading
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from ddgjax.errors import InvalidInputError

from ._cache import derived
from ._klu import AssembledSparse
from ._sparse import SparsePattern

FACTORISERS = ("auto", "pardiso", "cholmod", "superlu")
PARDISO_THREADS = 1  # beside XLA's threads, MKL's OpenMP team spins: one thread solved 7× faster (measured, 2 cores)
ORDERING = "nesdis"  # CHOLMOD's nested dissection: the least fill and time on 2-D meshes (measured)


def _csc_structure(pattern: SparsePattern) -> tuple[np.ndarray, np.ndarray]:
    """`(indptr, indices)` of K in CSC (= CSR: K symmetric, the COO sorted by row then column)."""
    size = pattern.n + pattern.m
    indptr = np.zeros(size + 1, np.int64)
    np.cumsum(np.bincount(pattern.rows, minlength=size), out=indptr[1:])
    return indptr, pattern.cols.astype(np.int64)


@functools.cache
def pardiso_available() -> bool:
    try:
        pardiso_solver(11)
    except (ImportError, OSError):
        return False
    return True


def pardiso_solver(mtype: int):
    """A `pypardiso.PyPardisoSolver` for the matrix type `mtype` (−2: real symmetric indefinite).

    pypardiso looks MKL's runtime up on every construction (`find_library`, then a recursive
    glob of `sys.prefix`, a quarter of a second), unless `PYPARDISO_MKL_RT` names it.  We set it
    (`setdefault`: a path the user gave is kept; child processes inherit it) to the library that
    pip's `mkl` wheel puts in `sys.prefix/lib`, or else to the one the first construction found."""
    import glob
    import os
    import sys

    import pypardiso

    if "PYPARDISO_MKL_RT" not in os.environ:
        found = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")))
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found[0]
    solver = pypardiso.PyPardisoSolver(mtype=mtype)
    os.environ.setdefault("PYPARDISO_MKL_RT", solver.libmkl._name)
    return solver


def default_factoriser() -> str | None:
    """The fastest factoriser installed, None if only SuperLU (then KLU is the better choice)."""
    return "pardiso" if pardiso_available() else "cholmod" if cholmod_available() else None


@functools.cache
def cholmod_available() -> bool:
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


@functools.cache
def _malloc_trim():
    """glibc's `malloc_trim`, or None where the C library has none (macOS, musl)."""
    import ctypes

    try:
        return ctypes.CDLL(None).malloc_trim
    except (AttributeError, OSError):
        return None


def return_free_heap() -> None:
    """Hand the C heap's free pages back to the operating system (glibc `malloc_trim(0)`).

    XLA runs the host callbacks on several threads, each allocating from its own malloc arena,
    so the memory a dead factorisation freed in one arena is not reused by the next one made in
    another and the resident set grows by about one factor's size: on the 10⁵-vertex area
    Hessian (`benchmarks/scale.py --big-area`) the peak drops from about 1.7 GB to 1.5 GB.
    A trim costs about a millisecond, so only large factorisations (`TRIM_MIN_ENTRIES`) do it.
    """
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


def _release_pardiso(mkl_pardiso, pt, iparm, pt_type) -> None:
    """Free the memory MKL holds for a Pardiso handle (phase −1)."""
    import ctypes

    i32 = ctypes.POINTER(ctypes.c_int32)
    one, zero = ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(0))
    dummy = np.zeros(1)
    mkl_pardiso(pt.ctypes.data_as(ctypes.POINTER(pt_type)), one, one, ctypes.byref(ctypes.c_int32(-2)),
                ctypes.byref(ctypes.c_int32(-1)), one, dummy.ctypes.data_as(ctypes.c_void_p),
                np.ones(2, np.int32).ctypes.data_as(i32), np.ones(1, np.int32).ctypes.data_as(i32),
                np.zeros(1, np.int32).ctypes.data_as(i32), one, iparm.ctypes.data_as(i32), zero,
                dummy.ctypes.data_as(ctypes.c_void_p), dummy.ctypes.data_as(ctypes.c_void_p),
                ctypes.byref(ctypes.c_int32(0)))


@dataclass(frozen=True)
class Factorisation:
    """A numeric factorisation: `solve(b)` applies its inverse; `negative` is the number of
    negative eigenvalues of the matrix (its inertia, from the pivots of `LDLᵀ` by Sylvester's
    law), or −1 where the factoriser does not know it."""

    solve: object
    negative: int = -1
    handle: object = None  # the Pardiso handle holding the factors, returned to the pool when dead


TRIM_MIN_ENTRIES = 100_000  # upper-triangle entries above which a factorisation returns the heap's free pages first
SADDLE_POINT_IPARM = {1: 1, 2: 2, 10: 8, 11: 1, 13: 1, 21: 1}
"""Pardiso options (1-based) for `_solve_shifted_real`: user-set (1), METIS ordering (2), pivot
perturbation 1e-8 (10), and symmetric weighted matching and scaling (11, 13) with Bunch–Kaufman
pivots (21), MKL's advice for saddle-point matrices."""
LIVE_PER_MEMBER = 1  # factorisations kept per batch member: the current one (a Newton step's is dead at the next)
PIVOT_FLOOR = 1e-14  # an LDLᵀ pivot below this, relative to the largest, falls back to LU with pivoting


@dataclass(eq=False)
class HostFactors:
    """The host side of one pattern: its CSC structure, its symbolic analysis, and the live
    numeric factorisations by token (the latest, `LIVE_PER_MEMBER` per member).  Pardiso keeps
    its analysis and factors in handles: a pool of them, each analysed once, taken by a
    factorisation and returned when it dies (usually one handle per pattern)."""

    pattern: SparsePattern
    factoriser: str
    _symbolic: object = field(init=False, default=None)
    _live: OrderedDict = field(init=False, default_factory=OrderedDict)
    _handles: list = field(init=False, default_factory=list)  # free Pardiso handles, analysed
    _next: int = field(init=False, default=0)
    _lock: threading.Lock = field(init=False, default_factory=threading.Lock)

    def __post_init__(self):
        rows, cols = self.pattern.rows, self.pattern.cols
        self.upper = np.flatnonzero(cols >= rows).astype(np.int32)  # the values Pardiso reads: K's upper triangle, CSR
        counts = np.bincount(rows[self.upper], minlength=self.size)
        self.upper_indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32) + 1  # 1-based
        self.upper_indices = cols[self.upper].astype(np.int32) + 1

    @property
    def size(self) -> int:
        return self.pattern.n + self.pattern.m

    @functools.cached_property
    def csc(self) -> tuple[np.ndarray, np.ndarray]:
        """`(indptr, indices)` of K in CSC, made when a factoriser that reads CSC first needs it."""
        return _csc_structure(self.pattern)

    def matrix(self, values: np.ndarray):
        import scipy.sparse as sp

        indptr, indices = self.csc
        return sp.csc_matrix((values, indices, indptr), shape=(self.size, self.size))

    def _ldl(self, A) -> Factorisation | None:
        """CHOLMOD's simplicial `LDLᵀ` (no pivoting: the fill-reducing ordering is kept), with the
        analysis made once; None when a pivot is (nearly) zero or not finite."""
        from sksparse.cholmod import CholmodError, analyze

        if self._symbolic is None:
            self._symbolic = analyze(A, mode="simplicial", ordering_method=ORDERING)
        try:
            fac = self._symbolic.cholesky(A)
        except CholmodError:
            return None
        D = fac.D()
        big = np.max(np.abs(D)) if D.size else 0.0
        if not (np.all(np.isfinite(D)) and np.min(np.abs(D)) > PIVOT_FLOOR * big):
            return None
        return Factorisation(fac.solve_A, int(np.count_nonzero(D < 0)))

    @staticmethod
    def _lu(A) -> Factorisation:
        """SuperLU with partial pivoting (any nonsingular matrix); inertia unknown."""
        import scipy.sparse.linalg as spla

        return Factorisation(spla.splu(A, permc_spec="COLAMD").solve)

    def _new_pardiso_handle(self, structure=None, values=None, iparm: dict | None = None):
        """A Pardiso handle with its analysis (phase 11) of K's upper triangle, or of another
        upper-triangle CSR `structure = (indptr, indices, ...)` with `values` (read by the
        weighted matching), made; freed with it.  `iparm`: options (1-based, as MKL numbers
        them), used only with iparm(1) = 1 (else Pardiso's defaults)."""
        handle = pardiso_solver(-2)
        handle.libmkl.MKL_Set_Num_Threads(PARDISO_THREADS)
        handle.set_iparm(12, 0)  # CSR (of the upper triangle)
        for i, value in (iparm or {}).items():
            handle.iparm[i - 1] = value
        indptr = self.upper_indptr if structure is None else structure[0]
        values = np.zeros(indptr[-1] - 1) if values is None else values
        self._pardiso_call(handle, 11, values, np.zeros(indptr.size - 1), structure)
        weakref.finalize(handle, _release_pardiso, handle._mkl_pardiso, handle.pt, handle.iparm, handle._pt_type[0])
        return handle

    def _pardiso_call(self, handle, phase: int, values: np.ndarray, b: np.ndarray, structure=None) -> np.ndarray:
        """One call of MKL's `pardiso` on the upper-triangle CSR with these values (K's, or those
        of `structure = (indptr, indices, ...)`): phase 11 (analysis), 22 (numeric
        factorisation) or 33 (solve)."""
        import ctypes

        from pypardiso.pardiso_wrapper import PyPardisoError

        indptr, indices = (self.upper_indptr, self.upper_indices) if structure is None else structure[:2]
        b = np.asfortranarray(b, dtype=np.float64)
        x = np.zeros_like(b)
        error = ctypes.c_int32(0)
        i32, f64 = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
        one = ctypes.byref(ctypes.c_int32(1))
        handle._mkl_pardiso(
            handle.pt.ctypes.data_as(ctypes.POINTER(handle._pt_type[0])), one, one,
            ctypes.byref(ctypes.c_int32(-2)), ctypes.byref(ctypes.c_int32(phase)),
            ctypes.byref(ctypes.c_int32(indptr.size - 1)), values.ctypes.data_as(f64),
            indptr.ctypes.data_as(i32), indices.ctypes.data_as(i32),
            handle.perm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(1 if b.ndim == 1 else b.shape[1])),
            handle.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(0)),
            b.ctypes.data_as(f64), x.ctypes.data_as(f64), ctypes.byref(error),
        )
        if error.value != 0:
            raise PyPardisoError(error.value)
        return np.ascontiguousarray(x)

    def _pardiso(self, values: np.ndarray, handle) -> Factorisation:
        """Pardiso's `LDLᵀ` of the matrix with these (full CSR) values, kept in `handle`."""
        upper = np.ascontiguousarray(values[self.upper])
        self._pardiso_call(handle, 22, upper, np.zeros(self.size))
        negative = int(handle.iparm[22])  # iparm(23): the number of negative eigenvalues

        def solve(b):
            return self._pardiso_call(handle, 33, upper, b)

        return Factorisation(solve, negative, handle)

    def factorise(self, values: np.ndarray, handle=None) -> Factorisation:
        """A factorisation of the matrix with these CSC values (`handle`: where a factoriser
        that keeps its factors in a handle, Pardiso, keeps them)."""
        if self.factoriser == "pardiso":
            return self._pardiso(values, handle if handle is not None else self._new_pardiso_handle())
        A = self.matrix(values)
        if self.factoriser == "cholmod":
            fac = self._ldl(A)
            if fac is not None:
                return fac
        return self._lu(A)

    def factor(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Factorise each member of a batch of values (..., nnz); returns their tokens (...) and
        the numbers of negative eigenvalues (..., −1 if unknown)."""
        values = np.asarray(values)
        batch = values.shape[:-1]
        flat = values.reshape(-1, values.shape[-1])
        with self._lock:
            # the oldest factorisations are dead (module docstring): free them, keeping at most
            # `LIVE_PER_MEMBER` per batch member, their handles free for reuse
            capacity = LIVE_PER_MEMBER * len(flat)
            while self._live and len(self._live) + len(flat) > capacity:
                dead = self._live.popitem(last=False)[1]
                if dead.handle is not None:
                    self._handles.append(dead.handle)
            handles = [self._handles.pop() if self._handles else None for _ in range(len(flat))]
        if self.upper.size >= TRIM_MIN_ENTRIES:
            return_free_heap()
        made = [self.factorise(np.ascontiguousarray(v), h) for v, h in zip(flat, handles)]
        with self._lock:
            tokens = np.arange(self._next, self._next + len(made), dtype=np.int64)
            self._next += len(made)
            self._live.update(zip(tokens.tolist(), made))
        negative = np.array([fac.negative for fac in made], np.int64)
        return tokens.reshape(batch), negative.reshape(batch)

    def apply(self, tokens: np.ndarray, b: np.ndarray) -> np.ndarray:
        """`x = fac⁻¹ b` for each token (...) and right-hand side (..., size[, k])."""
        tokens, b = np.asarray(tokens), np.asarray(b)
        out = np.empty(b.shape, np.result_type(b.dtype, np.float64))
        flat_t = tokens.reshape(-1)
        flat_b = b.reshape((flat_t.size,) + b.shape[tokens.ndim:])
        flat_out = out.reshape(flat_b.shape)
        for i, token in enumerate(flat_t.tolist()):
            with self._lock:
                fac = self._live.get(token)
            if fac is None:
                raise RuntimeError(f"SparseDirect: factorisation {token} was freed: more concurrent solves of one "
                                   "pattern than it keeps (run them one after another)")
            flat_out[i] = fac.solve(np.ascontiguousarray(flat_b[i]))
        return out

    def solve_once(self, values: np.ndarray, b: np.ndarray) -> np.ndarray:
        """`K⁻¹ b` for values (..., nnz) and right-hand sides (..., size), leading axes broadcast
        (a leading axis of length 1 in `values`: one factorisation for every right-hand side);
        Pardiso borrows a pooled handle and returns it."""
        values, b = np.asarray(values), np.asarray(b)
        lead = values.ndim - 1
        shape = np.broadcast_shapes(values.shape[:lead], b.shape[:lead])
        flat_b = np.broadcast_to(b, shape + b.shape[lead:]).reshape((-1,) + b.shape[lead:])
        flat_v = values.reshape(-1, values.shape[-1])
        out = np.empty(flat_b.shape, np.float64)
        fac, row = None, -1
        for i in range(len(flat_b)):
            want = i if len(flat_v) > 1 else 0
            if want != row:
                fac, row = self._borrowed(flat_v[want], fac), want
            out[i] = fac.solve(np.ascontiguousarray(flat_b[i]))
        self._borrowed(None, fac)
        return out.reshape(shape + b.shape[lead:])

    def _borrowed(self, values, previous: Factorisation | None) -> Factorisation | None:
        """Return `previous`'s handle to the pool; factorise `values` (if given) in a pooled one."""
        with self._lock:
            if previous is not None and previous.handle is not None:
                self._handles.append(previous.handle)
            handle = self._handles.pop() if values is not None and self._handles else None
        return None if values is None else self.factorise(np.ascontiguousarray(values), handle)

    def solve_shifted(self, values: np.ndarray, shift: np.ndarray, b: np.ndarray) -> np.ndarray:
        """`(K + i·shift·I)⁻¹ b` for real values (..., nnz) of K, shifts (...) and right-hand sides
        (..., size), factorised and solved at once, kept nowhere: the Levenberg–Marquardt fallback.

        With Pardiso, as the real symmetric system of twice the size (`_solve_shifted_real`);
        otherwise one complex SuperLU factorisation."""
        values, b = np.asarray(values), np.asarray(b)
        flat_v = values.reshape(-1, values.shape[-1])
        flat_s = np.asarray(shift).reshape(-1)
        flat_b = b.reshape(flat_v.shape[0], -1).astype(np.complex128)
        diagonal = self.pattern.diagonal
        out = []
        for v, s, r in zip(flat_v, flat_s, flat_b):
            if self.factoriser == "pardiso":
                out.append(self._solve_shifted_real(v, float(s), r))
                continue
            shifted = v.astype(np.complex128)
            shifted[diagonal] += 1j * s
            out.append(self._lu(self.matrix(shifted)).solve(r))
        return np.stack(out).reshape(b.shape)

    def _solve_shifted_real(self, values: np.ndarray, s: float, b: np.ndarray) -> np.ndarray:
        """`(K + isI)⁻¹ b` from the real symmetric system (indefinite; nonsingular for s ≠ 0, its
        square being diag(K² + s², K² + s²))

            [[K, sI], [sI, −K]] [x; z] = [Re b; Im b],   (K + isI)⁻¹ b = x − i z

        (the real and imaginary parts of (K + isI)(x + iy) = b, z = −y), factorised by Pardiso
        with weighted matching and scaling (`SADDLE_POINT_IPARM`) in a handle of its own."""
        size, structure = self.size, self.shifted_structure
        upper = values[self.upper]
        doubled = np.empty(structure[2].size)
        doubled[structure[2]] = np.concatenate([upper, np.full(size, s), -upper])
        # the matching reads the values, so each solve analyses anew, in a handle of its own (no lock)
        handle = self._new_pardiso_handle(structure, doubled, SADDLE_POINT_IPARM)
        self._pardiso_call(handle, 22, doubled, np.zeros(2 * size), structure)
        xz = self._pardiso_call(handle, 33, doubled, np.concatenate([b.real, b.imag]), structure)
        return xz[:size] - 1j * xz[size:]

    @functools.cached_property
    def shifted_structure(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The upper-triangle CSR `(indptr, indices)` (1-based) of `[[K, sI], [sI, −K]]`, and the
        positions in its values of `[K's upper values, the couplings s, −K's upper values]`:
        row i holds K's row i then the coupling at column size + i, row size + i K's row i
        shifted by size."""
        size = self.size
        counts = np.diff(self.upper_indptr)
        indptr = np.concatenate([[1], 1 + np.cumsum(np.concatenate([counts + 1, counts]))]).astype(np.int32)
        row_of = np.repeat(np.arange(size), counts)
        within = np.arange(self.upper.size) - (self.upper_indptr[row_of] - 1)
        top = indptr[row_of] - 1 + within
        coupling = indptr[1 : size + 1] - 2
        bottom = indptr[size + row_of] - 1 + within
        indices = np.empty(indptr[-1] - 1, np.int32)
        indices[top] = self.upper_indices
        indices[coupling] = size + 1 + np.arange(size)
        indices[bottom] = self.upper_indices + size
        return indptr, indices, np.concatenate([top, coupling, bottom])


def host_factors(pattern: SparsePattern, factoriser: str) -> HostFactors:
    """The host side of a pattern, made once per (pattern, factoriser) and kept while it lives."""
    return derived(pattern, f"host:{factoriser}", lambda: HostFactors(pattern, factoriser))


@jax.tree_util.register_pytree_node_class
class SparseDirect(AssembledSparse):
    """Sparse KKT matrix assembled from local blocks, factorised on the host by a fill-reducing
    sparse direct solver (module docstring).  `factoriser="auto"` takes Pardiso where MKL is
    installed, else CHOLMOD where scikit-sparse is, else SuperLU."""

    def __init__(self, pattern: SparsePattern | None = None, index: dict | None = None, *, factoriser: str = "auto"):
        if factoriser not in FACTORISERS:
            raise InvalidInputError(f"factoriser must be one of {FACTORISERS}, got {factoriser!r}")
        if factoriser == "auto":
            factoriser = default_factoriser() or "superlu"
        if factoriser == "cholmod" and not cholmod_available():
            raise InvalidInputError("factoriser='cholmod' needs scikit-sparse (pip install 'scikit-sparse<0.5' "
                                    "with the SuiteSparse headers)")
        if factoriser == "pardiso" and not pardiso_available():
            raise InvalidInputError("factoriser='pardiso' needs MKL (pip install pypardiso; x86-64 only)")
        self.factoriser = factoriser
        super().__init__(pattern, index)

    def on(self, pattern):
        return type(self)(pattern, factoriser=self.factoriser)

    def tree_flatten(self):
        children, aux = super().tree_flatten()
        return children, (aux, self.factoriser)

    @classmethod
    def tree_unflatten(cls, aux, children):
        (key, names), factoriser = aux
        if key is None:
            return cls(factoriser=factoriser)
        return cls(key.pattern, dict(zip(names, children)), factoriser=factoriser)

    def __repr__(self):
        return f"SparseDirect(factoriser={self.factoriser!r})"

    @property
    def host(self) -> HostFactors:
        return host_factors(self.pattern, self.factoriser)

    def factor_matrix(self, kkt, K, mu_rel):
        """The token of the host's factorisation of `K + μS` (`inertia` also gives its count of
        negative eigenvalues)."""
        return self.factor_with_inertia(K, mu_rel)[0]

    def factor_with_inertia(self, K, mu_rel):
        """`(token, negative)`: the host's factorisation of `K + μS` and its number of negative
        eigenvalues (−1 when the `LDLᵀ` fell back to LU)."""
        values = self.regularised(K, mu_rel)
        out = jax.ShapeDtypeStruct(values.shape[:-1], jnp.int64)
        return jax.pure_callback(self.host.factor, (out, out), values, vmap_method="broadcast_all")

    def apply(self, fac, b):
        out = jax.ShapeDtypeStruct(b.shape, b.dtype)
        return jax.pure_callback(self.host.apply, out, fac, b, vmap_method="broadcast_all")

    def solve_once(self, kkt, w, mu_rel, b):
        """Factorise and solve in one host call, factorisation freed after it (the derivative's
        solve): unlike `factor` + `apply`, no order between independent calls is needed.  Under
        `vmap` over right-hand sides only (`jacfwd`, `jacrev`) the matrix is factorised once."""
        values = self.regularised(self.matrix(kkt, w), mu_rel)

        def host_solve(_, rhs):
            out = jax.ShapeDtypeStruct(rhs.shape, rhs.dtype)
            return jax.pure_callback(self.host.solve_once, out, values, rhs, vmap_method="expand_dims")

        # a host call is not transposable by JAX: declared a linear solve, with K + μS symmetric
        return jax.lax.custom_linear_solve(lambda v: self.matvec(values, v), b, host_solve, symmetric=True)

    def lm_solve_matrix(self, K, nu, R):
        """`−(K² + ν I)⁻¹ K R = −Re[(K + i√ν I)⁻¹ R]` (K symmetric), one host solve
        (`HostFactors.solve_shifted`): no complex copy of K on the device."""
        out = jax.ShapeDtypeStruct(R.shape, jnp.complex128)
        shift = jnp.broadcast_to(jnp.sqrt(nu), K.shape[:-1])
        return -jnp.real(jax.pure_callback(self.host.solve_shifted, out, K, shift, R, vmap_method="broadcast_all"))
