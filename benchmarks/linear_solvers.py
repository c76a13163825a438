"""Sparse direct back ends for the Newton–KKT solves, side by side on the real KKT matrices.

The matrix is the one a sparse Newton step factorises: `K + μS` with `K = [[∇²L, −Jᵀ], [−J, 0]]`
assembled from the declared locality (`solvers._sparse.kkt_values`, coalesced COO on
`pattern.rows/cols`), `S = diag(I_n, −I_m)`, `μ = 1e-14 · max(max|K|, 1)` (as `factor_matrix`),
at `w = (u0, λ0)` with `λ0` the least-squares multipliers `argmin |∇E − Jᵀλ|` (as `solve` starts).

Problems (n free unknowns, m constraints):
- area k: `scale.area_problem(k)` (k×k noisy saddle grid after 5 Pinkall–Polthier steps, border
  fixed), n ≈ 3k², m = 0; k = 30, 100, 180.
- area+volume k: the same surface with the signed volume `Σ_F det(v0, v1, v2)/6` held at its
  start value (`dg.local_sum` constraint: one dense row and column), m = 1; k = 30, 100.
- elastica n: `energies.elastica.clamped(n, chord=(0.6, 0.2, 0), t_start=e1, t_end=e2)` at its
  default start (unit constraints plus the 3-row chord that couples every edge); n = 10⁴, 10⁵.

Reference: scipy `splu` (default COLAMD) of the 3×3-block Laplacian of the same graph,
`kron(L_int, I₃)`, L_int the cotan Laplacian of the surface restricted to the free vertices (for
the elastica: the path Laplacian of the free edges); `ref×` = factor time ÷ the reference's.

Candidates (columns; "a / f / s" = analyse / numeric factorisation with that analysis reused /
one solve, ms, medians after a warm-up; process CPU time, which other jobs on a shared machine
inflate less than wall time, or wall time with `--wall`; "–" where a library has no separate
analysis):
- `klu`: klujax (the current back end): `analyze`, `factor`, `solve_with_numeric`.  With coupled
  multipliers (a `local_sum` constraint) KLU factorises the interior block only and eliminates
  the border by its Schur complement, as `solvers` does (`Bordered`): the factor column includes
  the p border solves and the p×p Schur complement.
- `splu`: scipy SuperLU, default COLAMD ordering (analysis and factorisation fused: no reuse).
- `splu mmd sym`: SuperLU, `permc_spec="MMD_AT_PLUS_A"`, `SymmetricMode`, `diag_pivot_thresh=0.1`.
- `umfpack`: scikit-umfpack `UmfpackContext("di")`: `symbolic`, `numeric`, `solve`.
- `chol LLᵀ`: CHOLMOD (scikit-sparse) supernodal Cholesky; fails ("not PD") when K is indefinite.
- `chol LDLᵀ`: CHOLMOD simplicial LDLᵀ without pivoting, AMD ordering (quasi-definite systems).
- `chol LDLᵀ kkt`: the same with a KKT-aware ordering made here: AMD on the primal graph
  (H plus the cliques of the local constraints), each local multiplier placed right after the
  last unknown of its constraint, the coupled multipliers last; then CHOLMOD with that order.
- `qdldl`: QDLDL (OSQP's LDLᵀ, AMD): `Solver(A)` (analyse + factor), `update(A)`, `solve`.
- `pardiso`: MKL Pardiso through pypardiso with `mtype=-2` (real symmetric indefinite,
  Bunch–Kaufman pivoting inside supernodes, pivot perturbation), upper triangle, phases 11/22/33;
  pypardiso's public `factorize` runs phase 12 (the analysis again) on every call, so reusing the
  analysis takes `set_phase(22)` and its private `_call_pardiso`.

A candidate that is not installed shows "n/a"; "not PD" where Cholesky meets a nonpositive pivot;
"skip" where its factorisation at the previous size of that problem, extrapolated as (n + m)²,
would take more than `--slow` seconds (default 120).  The second table gives, per
problem and candidate, the relative residual ‖Kx − b‖/‖b‖ (b normal random), the same after one
step of iterative refinement, the number of negative pivots of LDLᵀ (the inertia: K has n − q
positive and m + q negative eigenvalues, q = negative curvature directions of ∇²L on ker J),
the peak resident memory of the factorisation (VmHWM of the worker minus its RSS with the matrix
loaded) and `GIL free`: the main thread's progress while another thread factorises (≈ 1: the
library releases the GIL; ≈ 0: it holds it; "–" where a factorisation is too short to tell).

Each candidate runs in a fresh process (the matrices are built once here and handed over in a
file) with `--threads` BLAS/OpenMP/MKL threads (default 1: the machine is shared and KLU,
SuperLU, QDLDL are single-threaded).

    python benchmarks/linear_solvers.py [--quick] [--repeats 5] [--threads 1] [--slow 120] [--wall]

Measured 2026-12-01 on the shared 2-core machine (load 5 falling to 2 during the run, 1 thread per
candidate; process CPU ms, analyse / factor / solve, factor ÷ the reference's; ±30 % between runs):

| problem | n + m | ref | klu | splu | splu mmd sym | umfpack | chol LLᵀ | chol LDLᵀ | qdldl | pardiso |
|---|---|---|---|---|---|---|---|---|---|---|
| area 30 | 2352 + 0 | – / 6.5 / 0.16 | 1.6 / 9.7 / 0.31 (1.5×) | – / 17.9 / 0.85 (2.7×) | – / 8.8 / 0.18 (1.4×) | 0.78 / 7.2 / 0.71 (1.1×) | 1.3 / 4.8 / 0.16 (0.7×) | 0.92 / 6.6 / 0.17 (1.0×) | 7.2 / 4.8 / 0.18 (0.7×) | 3.8 / 3.5 / 0.68 (0.5×) |
| area 100 | 28812 + 0 | – / 130 / 5.2 | 18.5 / 555 / 15.8 (4.3×) | – / 848 / 22.1 (6.5×) | – / 12070 / 44.8 (93×) | 18.9 / 155 / 23.3 (1.2×) | 14.1 / 102 / 6.0 (0.8×) | 8.4 / 182 / 6.8 (1.4×) | 178 / 152 / 7.8 (1.2×) | 40.0 / 50.5 / 26.3 (0.4×) |
| area 180 | 95052 + 0 | – / 521 / 20.6 | 37.9 / 3686 / 54.9 (7.1×) | – / 5830 / 81.5 (11×) | skip | 107 / 637 / 93.9 (1.2×) | 74.4 / 665 / 24.4 (1.3×) | 54.7 / 1558 / 30.5 (3.0×) | 1891 / 1892 / 38.4 (3.6×) | 225 / 295 / 77.3 (0.6×) |
| area+volume 100 | 28812 + 1 | – / 130 / 6.4 | 12.2 / 421 / 14.2 (3.2×) | – / 870 / 26.6 (6.7×) | – / 19027 / 57.5 (147×) | 94.1 / 163 / 24.9 (1.3×) | not PD | 11.1 / 227 / 6.7 (1.7×) | 247 / 236 / 12.5 (1.8×) | 106 / 72.8 / 31.1 (0.6×) |
| elastica 10⁴ | 29994 + 10001 | – / 19.4 / 0.59 | 15.2 / 29.5 / 2.4 (1.5×) | – / 61.9 / 3.4 (3.2×) | – / 694 / 4.4 (36×) | 372 / 3347 / 385 (173×) | not PD | 7.5 / 4.4 / 0.31 (0.2×) | 25.4 / 6.6 / 0.62 (0.3×) | 43.2 / 11.0 / 8.5 (0.6×) |
| elastica 10⁵ | 299994 + 100001 | – / 188 / 6.6 | 127 / 256 / 19.3 (1.4×) | – / 530 / 26.9 (2.8×) | – / 62584 / 40.5 (333×) | skip | not PD | 103 / 72.6 / 5.4 (0.4×) | 265 / 67.8 / 7.7 (0.4×) | 639 / 123 / 99.4 (0.7×) |

Read with care: the reference `kron(L_int, I₃)` is three *decoupled* scalar Laplacians, while ∇²A
couples x, y, z at every vertex pair (dense 3×3 blocks): on the same 180² mesh the factor of that
block pattern has 2.4× the entries (CHOLMOD: 1.06×10⁷ against 4.3×10⁶) and splu of
`kron(L_int, M)`, M a dense SPD 3×3, takes 5.6× the reference's time, so ≈ 1× is the best a KKT
factorisation can reach.  KLU's growth (p ≈ 1.6 from 100² to 180²) is that of every direct method
here (CHOLMOD 1.6, Pardiso 1.5: nested-dissection fill on a 2-D mesh); what differs is the
constant: no supernodes/BLAS.  (`chol LDLᵀ kkt`, left out above for width, factorises within
30 % of `chol LDLᵀ`; its ordering, made in Python, costs 2–5× CHOLMOD's analysis.)

Other findings of that run: the LDLᵀ inertia is the same for CHOLMOD, QDLDL and Pardiso (area:
0 negative pivots, ∇²A + μI positive definite at the start; area+volume: m; elastica at its
default start: m + 75 at 10⁴ and m + 245 at 10⁵, a saddle).  LDLᵀ without pivoting under AMD
leaves ‖Kx − b‖/‖b‖ = 4×10⁻⁶ (10⁴) and 3×10⁻⁷ (10⁵) on the elastica: minimum degree eliminates
some unit multipliers before their tangents, giving tiny pivots (min |D| 3×10⁻¹⁰, against 3×10⁻⁵
in the KKT-aware order); one refinement step or the KKT-aware ordering gives 10⁻¹¹.  MMD on
AᵀA + A (`splu mmd sym`) fails badly on both the 3×3-block mesh and the dense chord rows;
UMFPACK's dense chord rows cost 3.3 s and 624 MB at 10⁴.  GIL (main thread's progress, at 10⁵):
CHOLMOD (scikit-sparse 0.4.16) 0.03–0.09 and UMFPACK 0.05 hold it; KLU, SuperLU, QDLDL and
Pardiso (ctypes) 0.4–1.3 release it.

Install (the `apt-get` line gives SuiteSparse 5 headers and an optimised BLAS for CHOLMOD and
UMFPACK; scikit-sparse 0.5 needs SuiteSparse 7, hence `<0.5`; scikit-umfpack 0.4.2 needs swig,
and its build stops at "umfpack_dep not found in dependencies" (its `meson_swig.py` reads the
include directory from meson's introspection data, which lacks it): patched to fall back to
`/usr/include/suitesparse`, the sdist builds):

    apt-get install libsuitesparse-dev libopenblas0-pthread swig
    pip install qdldl pypardiso "scikit-sparse<0.5" scikit-umfpack
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CANDIDATES = ("ref", "klu", "splu", "splu mmd sym", "umfpack", "chol LLᵀ", "chol LDLᵀ", "chol LDLᵀ kkt",
              "qdldl", "pardiso")


# --------------------------------------------------------------------------------------------
# worker side: one candidate on one matrix, in its own process (NumPy/SciPy and the candidate)
# --------------------------------------------------------------------------------------------


class Unavailable(Exception):
    pass


def _rss_mb(field: str) -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith(field)) / 1024.0


def _reset_peak():
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # resets VmHWM to the current RSS (Linux ≥ 4.0)
    except OSError:
        pass


class Ref:
    """splu (default COLAMD) of the block Laplacian; analysis fused with the factorisation."""

    def __init__(self, data):
        self.A = sp.csc_matrix((data["ref_data"], data["ref_indices"], data["ref_indptr"]),
                               shape=tuple(data["ref_shape"]))

    def analyse(self):
        return None

    def factor(self, sym):
        return spla.splu(self.A)

    def solve(self, fac, b):
        return fac.solve(b)


class SuperLU:
    def __init__(self, A, **kw):
        self.A, self.kw = A, kw

    def analyse(self):
        return None

    def factor(self, sym):
        return spla.splu(self.A, **self.kw)

    def solve(self, fac, b):
        return fac.solve(b)


class KLU:
    """klujax on K, or on its interior block with the border eliminated (Schur complement)."""

    def __init__(self, A, coupled):
        os.environ.setdefault("JAX_PLATFORMS", "cpu")
        import jax

        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp
        import klujax

        self.jnp, self.klujax = jnp, klujax
        self.border = np.asarray(coupled, np.int64)
        size = A.shape[0]
        self.interior = np.setdiff1d(np.arange(size), self.border)
        A = A.tocsr()
        inner = A[self.interior][:, self.interior].tocsr()
        inner.sort_indices()
        coo = inner.tocoo()
        self.rows, self.cols = jnp.asarray(coo.row, jnp.int32), jnp.asarray(coo.col, jnp.int32)
        self.values = jnp.asarray(coo.data)
        self.n_in = inner.shape[0]
        if self.border.size:
            self.B = A[self.interior][:, self.border].toarray()
            self.Bt = A[self.border][:, self.interior].toarray()
            self.C = A[self.border][:, self.border].toarray()

    def analyse(self):
        return self.klujax.analyze(self.rows, self.cols, self.n_in)

    def _solve(self, num, sym, rhs):
        return np.asarray(self.klujax.solve_with_numeric(num, self.jnp.asarray(rhs), sym))

    def factor(self, sym):
        num = self.klujax.factor(self.rows, self.cols, self.values, sym)
        if not self.border.size:
            return sym, num, None, None
        Y = self._solve(num, sym, self.B)
        return sym, num, Y, self.C - self.Bt @ Y

    def solve(self, fac, b):
        sym, num, Y, S = fac
        if Y is None:
            return self._solve(num, sym, b)
        y = self._solve(num, sym, b[self.interior])
        xb = np.linalg.solve(S, b[self.border] - self.Bt @ y)
        x = np.empty_like(b)
        x[self.interior], x[self.border] = y - Y @ xb, xb
        return x


class Umfpack:
    def __init__(self, A):
        try:
            import scikits.umfpack as um
        except ImportError as e:
            raise Unavailable(str(e))
        self.um, self.A = um, A.tocsc()
        self.A.sort_indices()
        self.ctx = um.UmfpackContext("di")

    def analyse(self):
        self.ctx.symbolic(self.A)
        return self.ctx

    def factor(self, sym):
        sym.numeric(self.A)
        return sym

    def solve(self, fac, b):
        return fac.solve(self.um.UMFPACK_A, self.A, b, autoTranspose=True)


class Cholmod:
    def __init__(self, A, mode, perm=None):
        try:
            from sksparse.cholmod import analyze
        except ImportError as e:
            raise Unavailable(str(e))
        self.analyze, self.mode = analyze, mode
        self.A, self.perm = A.tocsc(), perm

    def analyse(self):
        if self.perm is None:
            return self.analyze(self.A, mode=self.mode, ordering_method="amd")
        perm = self.perm()
        Ap = self.A[perm][:, perm].tocsc()
        return perm, Ap, self.analyze(Ap, mode=self.mode, ordering_method="natural")

    def factor(self, sym):
        from sksparse.cholmod import CholmodNotPositiveDefiniteError

        try:
            if self.perm is None:
                return None, sym.cholesky(self.A)
            perm, Ap, f = sym
            return perm, f.cholesky(Ap)
        except CholmodNotPositiveDefiniteError as e:
            raise NotPositiveDefinite(str(e))

    def solve(self, fac, b):
        perm, F = fac
        if perm is None:
            return F.solve_A(b)
        x = np.empty_like(b)
        x[perm] = F.solve_A(b[perm])
        return x

    def negative(self, fac):
        return int(np.sum(fac[1].D() < 0)) if self.mode == "simplicial" else None


class NotPositiveDefinite(Exception):
    pass


def kkt_order(A, n: int, coupled: np.ndarray) -> np.ndarray:
    """A symmetric permutation of K for LDLᵀ without pivoting: AMD (CHOLMOD's) on the primal graph
    H ∪ JₗᵀJₗ (J_l the rows of the local constraints), each local multiplier right after the last
    unknown its constraint reads, the coupled multipliers (global sums) last.  Every multiplier is
    then eliminated after its unknowns: its pivot is a Schur complement −J H⁻¹ Jᵀ − μ, not −μ."""
    from sksparse.cholmod import analyze

    A = A.tocsr()
    size = A.shape[0]
    local = np.setdiff1d(np.arange(n, size), coupled)
    H = A[:n][:, :n].tocsr()
    H.data[:] = 1.0  # the pattern, explicit zeros included
    Jl = A[local][:, :n].tocsr()
    Jl.data[:] = 1.0
    G = (H + Jl.T @ Jl).tocsc()
    P = analyze(G, mode="simplicial", ordering_method="amd").P()
    position = np.empty(n, np.int64)
    position[P] = np.arange(n)
    counts = np.diff(Jl.indptr)
    last = np.full(len(local), -1, np.int64)
    nonempty = counts > 0
    if nonempty.any():
        last[nonempty] = np.maximum.reduceat(position[Jl.indices], Jl.indptr[:-1][nonempty])
    key = np.concatenate([position + 0.0, last + 0.5, np.full(len(coupled), np.inf)])
    order = np.concatenate([np.arange(n), local, np.asarray(coupled, np.int64)])
    return order[np.argsort(key, kind="stable")]


class QDLDL:
    def __init__(self, A):
        try:
            import qdldl
        except ImportError as e:
            raise Unavailable(str(e))
        self.qdldl, self.A = qdldl, A.tocsc()
        self.solver = None

    def analyse(self):
        # QDLDL has no separate symbolic phase: the constructor orders (AMD), analyses and factors
        self.solver = self.qdldl.Solver(self.A)
        return self.solver

    def factor(self, sym):
        sym.update(self.A)  # numeric refactorisation on the kept ordering and elimination tree
        return sym

    def solve(self, fac, b):
        return fac.solve(b)

    def negative(self, fac):
        return int(np.sum(fac.factors()[1] < 0))


class Pardiso:
    def __init__(self, A, threads):
        try:
            import pypardiso
        except ImportError as e:
            raise Unavailable(str(e))
        self.ps = pypardiso.PyPardisoSolver(mtype=-2)
        self.ps.libmkl.MKL_Set_Num_Threads(threads)
        self.A = sp.triu(A, format="csr")
        self.A.sort_indices()
        self.ps._check_A(self.A)

    def _phase(self, phase, b):
        self.ps.set_phase(phase)
        return self.ps._call_pardiso(self.A, self.ps._check_b(self.A, b))

    def analyse(self):
        self._phase(11, np.zeros(self.A.shape[0]))
        return self.ps

    def factor(self, sym):
        self._phase(22, np.zeros(self.A.shape[0]))
        return sym

    def solve(self, fac, b):
        return self._phase(33, b)

    def negative(self, fac):
        return int(self.ps.iparm[22])  # iparm(23): number of negative eigenvalues

    def close(self):
        self.ps.free_memory(everything=True)


def make_candidate(name, data, threads):
    n, m = int(data["n"]), int(data["m"])
    size = n + m
    A = sp.csc_matrix((data["values"], (data["rows"], data["cols"])), shape=(size, size))
    coupled = np.asarray(data["coupled"], np.int64)
    if name == "ref":
        return Ref(data), A
    if name == "klu":
        try:
            import klujax  # noqa: F401
        except ImportError as e:
            raise Unavailable(str(e))
        return KLU(A, coupled), A
    if name == "splu":
        return SuperLU(A), A
    if name == "splu mmd sym":
        return SuperLU(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options={"SymmetricMode": True}), A
    if name == "umfpack":
        return Umfpack(A), A
    if name == "chol LLᵀ":
        return Cholmod(A, "supernodal"), A
    if name == "chol LDLᵀ":
        return Cholmod(A, "simplicial"), A
    if name == "chol LDLᵀ kkt":
        return Cholmod(A, "simplicial", perm=lambda: kkt_order(A, n, coupled)), A
    if name == "qdldl":
        return QDLDL(A), A
    if name == "pardiso":
        return Pardiso(A, threads), A
    raise ValueError(name)


def _median(fn, repeats: int, budget: float) -> tuple[float, float]:
    """Median (wall, process CPU) ms of `repeats` calls (15 for calls under 20 ms), fewer if they
    exceed `budget` s."""
    walls, cpus, start = [], [], time.perf_counter()
    while True:
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        if len(walls) >= (max(repeats, 15) if walls[0] < 0.02 else repeats) or time.perf_counter() - start > budget:
            return 1e3 * statistics.median(walls), 1e3 * statistics.median(cpus)


def _gil_free(fn, seconds: float = 0.6) -> float:
    """Main-thread progress (pure Python counting) while `fn` runs in a loop in another thread,
    relative to counting alone: ≈ 1 if `fn` releases the GIL, ≈ 0 if it holds it."""
    def count(stop):
        c = 0
        while time.perf_counter() < stop:
            c += 1
        return c

    base = count(time.perf_counter() + seconds / 2)
    done = threading.Event()

    def loop():
        while not done.is_set():
            fn()

    worker = threading.Thread(target=loop)
    worker.start()
    time.sleep(0.001)
    busy = count(time.perf_counter() + seconds / 2)
    done.set()
    worker.join()
    return busy / max(base, 1)


def worker(path: str, name: str, repeats: int, threads: int, budget: float) -> dict:
    data = np.load(path)
    out = {"candidate": name}
    try:
        cand, A = make_candidate(name, data, threads)
    except Unavailable as e:
        return {**out, "status": "n/a", "note": str(e).splitlines()[0][:80]}
    if name == "ref":
        A = cand.A
    b = np.random.default_rng(0).normal(size=A.shape[0])
    base_mb = _rss_mb("VmRSS")
    _reset_peak()
    try:
        t0 = time.perf_counter()
        sym = cand.analyse()
        fac = cand.factor(sym)
        x = cand.solve(fac, b)
        first = time.perf_counter() - t0
    except NotPositiveDefinite as e:
        return {**out, "status": "not PD", "note": str(e)[:80]}
    out["peak_mb"] = max(_rss_mb("VmHWM") - base_mb, 0.0)
    norm_b = np.linalg.norm(b)
    out["residual"] = float(np.linalg.norm(A @ x - b) / norm_b)
    x2 = x + cand.solve(fac, b - A @ x)
    out["refined"] = float(np.linalg.norm(A @ x2 - b) / norm_b)
    out["negative"] = cand.negative(fac) if hasattr(cand, "negative") else None
    if first > budget:  # one sample is all a slow candidate gets
        repeats = 1
    if name not in ("ref", "splu", "splu mmd sym"):
        out["analyse_wall"], out["analyse_cpu"] = _median(cand.analyse, repeats, budget)
    if name == "qdldl":  # analyse() refactorises too: keep the solver it made
        sym = cand.solver
    out["factor_wall"], out["factor_cpu"] = _median(lambda: cand.factor(sym), repeats, budget)
    fac = cand.factor(sym)
    out["solve_wall"], out["solve_cpu"] = _median(lambda: cand.solve(fac, b), repeats, budget)
    out["gil_free"] = _gil_free(lambda: cand.factor(sym)) if out["factor_wall"] >= 20 else None
    if hasattr(cand, "close"):
        cand.close()
    out["status"] = "ok"
    return out


# --------------------------------------------------------------------------------------------
# main side: build the problems and their KKT matrices (JAX), run the workers, print the tables
# --------------------------------------------------------------------------------------------


def _volume(P, params):
    """Signed volume of the tetrahedron (0, v0, v1, v2) minus an equal share of the target."""
    import jax.numpy as jnp

    return jnp.reshape(jnp.dot(P[0], jnp.cross(P[1], P[2])) / 6.0 - params["share"], (1,))


def area_volume_problem(k: int):
    """`scale.area_problem(k)` with the signed volume held at its start value (m = 1)."""
    import scale

    import ddgjax as dg
    from energies import area

    V, F, boundary = scale.saddle_grid(k)
    W = area.minimal_surface(V, F, boundary, method="cotan", max_iter=5, throw=False)[0]
    W = np.asarray(W)
    fixed = np.zeros(W.shape, bool)
    fixed[boundary] = True
    volume = float(np.sum(np.einsum("fi,fi->f", W[F[:, 0]], np.cross(W[F[:, 1]], W[F[:, 2]]))) / 6.0)
    return dg.Problem(dg.local_sum(area.face_area, F), W, constraints=dg.local_sum(_volume, F),
                      params={"share": volume / len(F)}, fixed=fixed, name=f"area+volume (k={k})")


def kkt_matrix(problem, mu_rel: float = 1e-14):
    """(rows, cols, values of K + μS, n, m, coupled) at w = (u0, least-squares λ0)."""
    import jax
    import jax.numpy as jnp

    from solvers._kkt import KKT, spec_of
    from solvers._sparse import cached_pattern, index_arrays, kkt_values

    spec = spec_of(problem)
    pattern = cached_pattern(spec, problem.x0, problem.params)
    index = index_arrays(pattern)
    z0 = spec.layout.ravel(problem.x0)
    kkt = KKT(spec, z0, problem.params)
    n, m = spec.n, spec.m
    u0 = z0[spec.layout.free]
    diagonal = np.asarray(index["diagonal"])
    shift = np.concatenate([np.ones(n), -np.ones(m)])

    def regularised(w, identity, mu):
        values = np.array(kkt_values(pattern, index, kkt, w, identity))
        values[diagonal] += mu * max(np.abs(values).max(), 1.0) * shift
        return values

    lam = jnp.zeros((m,))
    if m:  # least-squares multipliers, as `solve` starts: the KKT system with ∇²L replaced by I
        values = regularised(jnp.concatenate([u0, lam]), True, 1e-12)
        K_I = sp.csc_matrix((values, (pattern.rows, pattern.cols)), shape=(n + m, n + m))
        rhs = np.concatenate([np.asarray(jax.grad(kkt.energy)(u0)), np.zeros(m)])
        lam = jnp.asarray(-spla.splu(K_I).solve(rhs)[n:])
    values = regularised(jnp.concatenate([u0, lam]), False, mu_rel)
    return pattern.rows, pattern.cols, values, n, m, np.asarray(pattern.coupled)


def block_laplacian(problem, kind: str) -> sp.csc_matrix:
    """kron(L_int, I₃): the cotan Laplacian of the surface on its free vertices (area), or the
    path Laplacian of the free edges with Dirichlet ends (elastica)."""
    free = ~np.asarray(problem.fixed)[:, 0]
    if kind == "elastica":
        k = int(free.sum())
        L = sp.diags([-np.ones(k - 1), 2 * np.ones(k), -np.ones(k - 1)], [-1, 0, 1])
    else:
        import ddgjax as dg

        F = problem.energy.groups[0][0].stencil
        L = dg.laplace.cotan_laplacian(np.asarray(problem.x0), F)[free][:, free]
    return sp.kron(L, sp.eye(3), format="csc")


def build_cases(quick: bool):
    import scale

    from energies import elastica

    if quick:
        return [("area", 30, lambda: scale.area_problem(30)), ("area+volume", 30, lambda: area_volume_problem(30)),
                ("elastica", 10_000, lambda: elastica.clamped(10_000, **scale.ELASTICA))]
    return ([("area", k, lambda k=k: scale.area_problem(k)) for k in (30, 100, 180)]
            + [("area+volume", k, lambda k=k: area_volume_problem(k)) for k in (30, 100)]
            + [("elastica", n, lambda n=n: elastica.clamped(n, **scale.ELASTICA)) for n in (10_000, 100_000)])


def run_worker(path, name, args) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS=str(args.threads), MKL_NUM_THREADS=str(args.threads),
               OPENBLAS_NUM_THREADS=str(args.threads), JAX_PLATFORMS="cpu")
    cmd = [sys.executable, __file__, "--worker", path, name, "--repeats", str(args.repeats),
           "--threads", str(args.threads), "--budget", str(args.budget)]
    try:
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=args.timeout, env=env, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return {"candidate": name, "status": f"timeout {args.timeout:.0f}s"}
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode or not lines:
        tail = (proc.stderr.strip().splitlines() or ["?"])[-1]
        return {"candidate": name, "status": "error", "note": tail[:100]}
    return json.loads(lines[-1])


def _ms(v) -> str:
    if v is None:
        return "–"
    return f"{v:.0f}" if v >= 100 else f"{v:.1f}" if v >= 1 else f"{v:.2f}"


def cell(r: dict, ref: dict | None, clock: str) -> str:
    if r.get("status") != "ok":
        return r.get("status", "?")
    text = " / ".join(_ms(r.get(f"{phase}_{clock}")) for phase in ("analyse", "factor", "solve"))
    if ref and ref.get("status") == "ok" and r["candidate"] != "ref":
        text += f" ({r[f'factor_{clock}'] / ref[f'factor_{clock}']:.1f}×)"
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="area 30², area+volume 30², elastica 10⁴ only")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1, help="BLAS/OpenMP/MKL threads of each candidate")
    ap.add_argument("--slow", type=float, default=120.0, help="a candidate is not run on a larger size of a "
                    "problem when its factorisation there, extrapolated as (n + m)², would take longer (s)")
    ap.add_argument("--wall", action="store_true", help="tabulate wall time instead of process CPU time")
    ap.add_argument("--budget", type=float, default=20.0, help="s of timing per phase and candidate")
    ap.add_argument("--timeout", type=float, default=900.0, help="s per candidate and problem")
    ap.add_argument("--candidates", nargs="*", default=list(CANDIDATES))
    ap.add_argument("--worker", nargs=2, metavar=("NPZ", "CANDIDATE"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(args.worker[0], args.worker[1], args.repeats, args.threads, args.budget)))
        return

    sys.path.insert(0, str(HERE))
    sys.path.insert(0, str(ROOT))
    import ddgjax  # noqa: F401  (float64)

    cores = os.cpu_count() or 1
    load0 = os.getloadavg()[0]
    print(f"cores: {cores}, load average: {load0:.1f}, threads per candidate: {args.threads}"
          + ("  (LOADED MACHINE: timings are inflated)" if load0 > cores else ""), flush=True)
    names = [c for c in CANDIDATES if c in args.candidates]
    rows, slow, last = [], set(), {}
    with tempfile.TemporaryDirectory() as tmp:
        for family, size, make in build_cases(args.quick):
            t0 = time.perf_counter()
            problem = make()
            r, c, v, n, m, coupled = kkt_matrix(problem)
            R = block_laplacian(problem, family)
            path = os.path.join(tmp, f"{family}-{size}.npz")
            np.savez(path, rows=r, cols=c, values=v, n=n, m=m, coupled=coupled, ref_data=R.data,
                     ref_indices=R.indices, ref_indptr=R.indptr, ref_shape=np.array(R.shape))
            print(f"built {family} {size}: n = {n}, m = {m}, nnz(K) = {len(v)}, coupled = {len(coupled)} "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)
            results = {}
            for name in names:
                before = last.get((family, name))
                if (family, name) in slow or (before and before[1] * ((n + m) / before[0]) ** 2 > 1e3 * args.slow):
                    results[name] = {"candidate": name, "status": "skip"}
                    continue
                res = run_worker(path, name, args)
                results[name] = res
                status = res.get("status")
                if status == "ok":
                    last[(family, name)] = (n + m, res["factor_wall"])
                elif status == "error" or status.startswith("timeout"):
                    slow.add((family, name))
                print(f"  {name}: {json.dumps(res)}", flush=True)
            rows.append((family, size, n, m, len(v), results))

    clock = "wall" if args.wall else "cpu"
    print(f"\n{'wall' if args.wall else 'process CPU'} ms: analyse / factor / solve (factor ÷ reference factor), medians; load average now "
          f"{os.getloadavg()[0]:.1f} (at start {load0:.1f}) on {cores} cores, {args.threads} thread(s) per candidate\n")
    print("| problem | n + m | nnz(K) | " + " | ".join(names) + " |")
    print("|---|---|---|" + "---|" * len(names))
    for family, size, n, m, nnz, results in rows:
        ref = results.get("ref")
        print(f"| {family} {size} | {n} + {m} | {nnz} | " + " | ".join(cell(results[c], ref, clock) for c in names) + " |")

    area = [(n + m, res) for family, size, n, m, nnz, res in rows if family == "area" and size >= 100]
    if len(area) >= 2:
        (n0, r0), (n1, r1) = area[0], area[-1]
        fits = [f"{c} {np.log(r1[c][f'factor_{clock}'] / r0[c][f'factor_{clock}']) / np.log(n1 / n0):.2f}"
                for c in names if r0[c].get("status") == "ok" and r1[c].get("status") == "ok"]
        print(f"\nfactor time ∝ (n + m)^p on the area problem, {n0} → {n1}: p = " + ", ".join(fits))

    print("\n| problem | candidate | ‖Kx−b‖/‖b‖ | after 1 refinement | negative pivots | peak MB | GIL free | note |")
    print("|---|---|---|---|---|---|---|---|")
    for family, size, n, m, nnz, results in rows:
        for c in names:
            r = results[c]
            if r.get("status") != "ok":
                print(f"| {family} {size} | {c} | {r.get('status')} | | | | | {r.get('note', '')} |")
                continue
            neg = "–" if r["negative"] is None else f"{r['negative']} (m = {m})"
            gil = "–" if r["gil_free"] is None else f"{r['gil_free']:.2f}"
            print(f"| {family} {size} | {c} | {r['residual']:.1e} | {r['refined']:.1e} | {neg} | "
                  f"{r['peak_mb']:.0f} | {gil} | |")
    load1 = os.getloadavg()[0]
    if max(load0, load1) > cores:
        print(f"\nnote: load average {max(load0, load1):.1f} > {cores} cores during the run: other processes share the CPU")


if __name__ == "__main__":
    main()
