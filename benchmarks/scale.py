"""Scaling of `solve` (issue 9): the clamped elastica at 10³–10⁵ edges and the simplicial-area
Newton solve with fixed boundary up to ~10⁵ vertices, sparse path (declared locality: KLU on the
chains, the fill-reducing `SparseDirect` on the meshes, with KLU beside it there up to `--klu-max`)
side by side with the dense path and the Krylov path (`method="krylov"`: for the elastica GMRES
preconditioned by the block-tridiagonal solve, at every size; for the area, a 2-D mesh, MINRES
on the tangent space with a Jacobi metric, up to `--krylov-max`) where they fit.

Columns: unknowns N (free) + constraints, compile s (first call minus the median of the later
ones), s per Newton step (median full solve / steps), steps, final scaled KKT residual, and
peak MB = the process's peak resident set size so far (`resource.getrusage(RUSAGE_SELF)
.ru_maxrss`, monotone over the run, so a row's value bounds that row's own peak); the memory
goal is checked on the 10⁵-edge elastica alone, in a new process.
The time per step is fitted as `c nᵖ` over the sparse elastica rows with n ≥ 10³ and p is printed.

Problems:
- elastica: `energies.elastica.clamped(n, chord=(0.6, 0.2, 0), t_start=e1, t_end=e2)`, started
  from the solved n = 64 curve resampled to n edges (`elastica.resample`), tol 1e-9.
- area: a k×k triangulated grid on [−1, 1]² with the border fixed on the saddle
  z = 0.25(x² − y²), the interior started on the saddle plus z-noise of 0.1 h (h the grid
  step), then 5 Pinkall–Polthier iterations (`area.minimal_surface(method="cotan")`), then
  `energies.area.simplicial(V, F, boundary)`, tol 1e-9 (the area gradient, max-norm).

    python benchmarks/scale.py [--quick] [--repeats 3] [--dense-max 3000] [--krylov-max 5000] [--klu-max 40000] [--big-area]

The machine may be shared: when the load average exceeds the core count, timings are flagged.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

import ddgjax as dg  # noqa: F401  (float64)
from energies import area, elastica
from ddgjax.mesh import saddle_grid
from solvers import KLU, solve


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def vm_hwm_mb() -> float:
    """This process's peak resident set (VmHWM); unlike `ru_maxrss`, which a child inherits from
    its parent across fork and exec, it starts afresh in a new process."""
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmHWM")) / 1024.0


def fresh_peak_mb(problem: str, tol: float) -> tuple[float, float]:
    """(peak MB, residual) of one sparse solve of `problem` (a call in this module, e.g.
    "elastica_problem(100000)"), problem built and compile included, in a new process: this
    process's peak also holds every earlier row's compiled solvers and patterns."""
    code = (f"import sys; sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r}); import scale; "
            f"s = scale.solve(scale.{problem}, method='sparse', tol={tol}, throw=False); "
            "print(scale.vm_hwm_mb(), float(s.residual))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return float(out[-2]), float(out[-1])


ELASTICA = dict(chord=(0.6, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))
_COARSE = {}


def elastica_problem(n: int):
    """Started from the solved 64-edge elastica resampled to n edges (continuation in n): the
    default great-circle start is too far for undamped-enough Newton at n ≥ 10³."""
    if "T" not in _COARSE:
        _COARSE["T"] = np.asarray(solve(elastica.clamped(64, **ELASTICA), tol=1e-10).x)
    return elastica.clamped(n, **ELASTICA, x0=elastica.resample(_COARSE["T"], n))


def area_problem(k: int, cotan_steps: int = 5):
    """The noisy saddle grid after `cotan_steps` Pinkall–Polthier iterations (Fig 6.5)."""
    V, F, b = saddle_grid(k)
    W = area.minimal_surface(V, F, b, method="cotan", max_iter=cotan_steps, throw=False)[0]
    return area.simplicial(W, F, b)


def measure(problem, method: str, repeats: int, tol: float) -> dict:
    """Compile and per-step time of `solve(problem, method=...)`; `method` may also name a
    linear-solver object (`"klu"`: `KLU()`, to compare with `"sparse"` on meshes)."""
    kw = {"linear_solver": KLU()} if method == "klu" else {"method": method}
    t0 = time.perf_counter()
    sol = solve(problem, tol=tol, throw=False, **kw)
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = solve(problem, tol=tol, throw=False, **kw)
        sol.x.block_until_ready()
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    steps = max(int(sol.steps), 1)
    return {
        "compile": first - median, "solve": median, "per_step": median / steps, "steps": int(sol.steps),
        "residual": float(sol.residual), "converged": bool(sol.converged), "peak": peak_mb(),
    }


def splu_block_laplacian(k: int, repeats: int) -> float:
    """Median seconds of scipy's `splu` of the 3×3-block cotan Laplacian (`kron(L_interior, I₃)`)
    of the k×k saddle grid: the reference a sparse direct Newton step is compared with."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from ddgjax.laplace import cotan_laplacian

    V, F, b = saddle_grid(k)
    interior = np.setdiff1d(np.arange(len(V)), b)
    L = cotan_laplacian(V, F)[interior][:, interior]
    B = sp.kron(L, sp.eye(3)).tocsc()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        spla.splu(B)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def row(name, n, size, method, r) -> str:
    return (f"| {name} | {n} | {size} | {method} | {r['compile']:.2f} | {r['solve']:.3f} | {r['per_step']:.4f} | "
            f"{r['steps']} | {r['residual']:.1e} | {r['peak']:.0f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes only (elastica ≤ 10³, area ≤ 30²)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dense-max", type=int, default=3000, help="largest N (unknowns + constraints) for the dense path")
    ap.add_argument("--krylov-max", type=int, default=5000, help="largest N for the Krylov path on meshes (Jacobi-"
                    "preconditioned: its iteration count grows with the condition number)")
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("--klu-max", type=int, default=40_000, help="largest N for KLU on meshes, beside the default sparse path")
    ap.add_argument("--big-area", action="store_true",
                    help="add the 316² ≈ 10⁵-vertex area solve")
    args = ap.parse_args()

    load = os.getloadavg()[0]
    cores = os.cpu_count() or 1
    print(f"cores: {cores}, load average: {load:.1f}" + ("  (LOADED MACHINE: timings are inflated)" if load > cores else ""))
    el_sizes = [100, 1000] if args.quick else [100, 300, 1000, 10_000, 100_000]
    grid_sizes = [10, 32] if args.quick else [32, 100, 178] + ([316] if args.big_area else [])
    results = []
    print("\n| problem | n | N | method | compile s | solve s | s/step | steps | residual | peak MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    cases = [("elastica", n, elastica_problem) for n in el_sizes] + [("area", k * k, lambda nv, k=k: area_problem(k)) for k in grid_sizes]
    for name, n, make in cases:
        problem = make(n)
        size = int(np.sum(~np.asarray(problem.fixed))) + problem.n_constraints
        repeats = args.repeats if size < 100_000 else 1
        for method in ("sparse", "klu", "dense", "krylov"):
            krylov_max = size if name == "elastica" else args.krylov_max  # a chain: block-tridiagonal preconditioner
            limit = {"sparse": size, "klu": args.klu_max if name == "area" else -1, "dense": args.dense_max, "krylov": krylov_max}
            if size > limit[method]:
                continue
            r = measure(problem, method, repeats, args.tol)
            results.append((name, n, method, r))
            print(row(name, n, size, method, r), flush=True)

    print()
    el = [(n, r) for name, n, m, r in results if name == "elastica" and m == "sparse" and n >= 1000]
    if len(el) >= 2:
        p = np.polyfit(np.log([n for n, _ in el]), np.log([r["per_step"] for _, r in el]), 1)[0]
        print(f"fitted exponent of s/step vs n (sparse elastica, n ≥ 10³): {p:.2f}")
        big = dict(el).get(100_000)
        if big is not None:
            print(f"{'PASS' if big['converged'] and big['residual'] <= 1e-9 else 'FAIL'}: elastica 10⁵ edges residual "
                  f"{big['residual']:.1e} ≤ 1e-9")
            print(f"{'PASS' if big['solve'] <= 10 else 'FAIL'}: elastica 10⁵ edges solve {big['solve']:.2f} s ≤ 10 s after compile")
            peak, residual = fresh_peak_mb("elastica_problem(100_000)", args.tol)
            print(f"{'PASS' if peak <= 2048 else 'FAIL'}: peak memory {peak:.0f} MB ≤ 2048 MB (VmHWM of a new process "
                  f"that builds, compiles and solves the 10⁵-edge elastica, residual {residual:.1e})")
        print(f"{'PASS' if p <= 1.2 else 'FAIL'}: exponent {p:.2f} ≤ 1.2")
    ar = [(n, r) for name, n, m, r in results if name == "area" and m == "sparse"]
    if ar:
        print("\n| area vertices | sparse s/step | splu of the 3×3-block cotan Laplacian s | ratio |")
        print("|---|---|---|---|")
        for n, r in ar:
            ref = splu_block_laplacian(int(round(n**0.5)), args.repeats)
            r["splu"] = ref
            print(f"| {n} | {r['per_step']:.4f} | {ref:.4f} | {r['per_step'] / ref:.2f} |", flush=True)
        big = [(n, r) for n, r in ar if n >= 1000]
        if len(big) >= 2:
            p = np.polyfit(np.log([n for n, _ in big]), np.log([r["per_step"] for _, r in big]), 1)[0]
            print(f"{'PASS' if p <= 1.3 else 'FAIL'}: fitted exponent of s/step vs vertices (area, sparse, n ≥ 10³): {p:.2f} ≤ 1.3")
        near = min(ar, key=lambda item: abs(np.log(item[0] / 1e4)))
        n, r = near
        print(f"{'PASS' if r['per_step'] <= 2 * r['splu'] else 'FAIL'}: area Newton at {n} vertices {r['per_step']:.3f} s/step "
              f"≤ 2 × splu {r['splu']:.3f} s")
        n, r = ar[-1]
        print(f"{'PASS' if r['converged'] else 'FAIL'}: area Newton solve with {n} vertices converged "
              f"(residual {r['residual']:.1e}, {r['steps']} steps, {r['solve']:.1f} s after compile, peak {r['peak']:.0f} MB)")
        if n >= 90_000:
            peak, residual = fresh_peak_mb(f"area_problem({int(round(n**0.5))})", args.tol)
            print(f"{'PASS' if peak <= 1536 else 'FAIL'}: peak memory {peak:.0f} MB ≤ 1536 MB (VmHWM of a new process that "
                  f"builds the {n}-vertex area problem, compiles and solves it, residual {residual:.1e})")
    if load > cores:
        print(f"note: load average {load:.1f} > {cores} cores during the run: other processes share the CPU")


if __name__ == "__main__":
    main()
