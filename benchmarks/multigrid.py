"""Multigrid-preconditioned Krylov on meshes: the area Newton solve of `benchmarks/scale.py` with
`Krylov(preconditioner="amg")` (MINRES preconditioned by the smoothed-aggregation cycle of
`solvers/_amg.py`, inside `jit`) side by side with the sparse direct solve (`SparseDirect`)
and the Jacobi-preconditioned MINRES (`Krylov()`, small grids only).

Problem: `scale.area_problem(k)`, the simplicial area of a k×k saddle grid with the border
fixed (3 unknowns per interior vertex, no constraints), for k = 32, 100, 316 (10³, 10⁴, 10⁵
vertices).

Columns: vertices, free unknowns N, linear solver, hierarchy sizes (unknowns per level),
compile s (first solve minus the median of the later ones; the hierarchy's construction is in
the first solve), s per Newton step (median solve after warm-up / steps), steps, final scaled
KKT residual, max |x − x_direct| against `SparseDirect` at the same tolerance, and the MINRES
iterations of the Newton solve `H d = −∇E` with the first step's matrix (at x0) and with the
last one's (at the solution, right-hand side `∇E(x0)`), counted by `Krylov.apply_counted`
outside the Newton loop.

    python benchmarks/multigrid.py [--sizes 32 100 316] [--repeats 3] [--jacobi-max 40] [--tol 1e-10]

The machine may be shared: when the load average exceeds the core count, timings are flagged.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import jax
import jax.numpy as jnp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import ddgjax as dg  # noqa: F401,E402  (float64)
from scale import area_problem  # noqa: E402
from solvers import Krylov, SparseDirect, solve  # noqa: E402
from solvers._kkt import KKT, spec_of  # noqa: E402
from solvers._newton import NEWTON_MU  # noqa: E402


def measure(problem, linear_solver, repeats: int, tol: float):
    t0 = time.perf_counter()
    sol = solve(problem, linear_solver=linear_solver, tol=tol, throw=False)
    sol.x.block_until_ready()
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = solve(problem, linear_solver=linear_solver, tol=tol, throw=False)
        sol.x.block_until_ready()
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    return sol, {"compile": first - median, "solve": median, "per_step": median / max(int(sol.steps), 1),
                 "steps": int(sol.steps), "residual": float(sol.residual), "converged": bool(sol.converged)}


def minres_iterations(problem, linear_solver, x) -> tuple[int, float]:
    """(iterations, relative residual) of the Krylov solve `H(x) d = −∇E(x0)`."""
    spec = spec_of(problem)
    algebra = linear_solver.bind(problem, spec)
    z0 = spec.layout.ravel(problem.x0)
    kkt = KKT(spec, z0, problem.params)
    b = -kkt.residual(z0[spec.layout.free])

    @jax.jit
    def run(algebra, w, b):
        K = algebra.matrix(kkt, w)
        fac = algebra.factor_matrix(kkt, K, NEWTON_MU)
        d, iterations = algebra.apply_counted(fac, b)
        return iterations, jnp.linalg.norm(K.hvp(d) + fac.mu * d - b) / jnp.linalg.norm(b)

    iterations, residual = run(algebra, spec.layout.ravel(x)[spec.layout.free], b)
    return int(iterations), float(residual)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 100, 316], help="grid sizes k (k² vertices)")
    ap.add_argument("--repeats", type=int, default=3, help="timed solves after warm-up (1 at 10⁵ vertices)")
    ap.add_argument("--jacobi-max", type=int, default=40, help="largest k for the Jacobi-preconditioned Krylov")
    ap.add_argument("--tol", type=float, default=1e-10)
    args = ap.parse_args()
    load = os.getloadavg()[0]
    cores = os.cpu_count() or 1
    print(f"cores: {cores}, load average: {load:.1f}" + ("  (LOADED MACHINE: timings are inflated)" if load > cores else ""))
    print("\n| vertices | N | solver | levels (unknowns) | compile s | s/step | steps | residual | max abs x − x_direct "
          "| MINRES its, step 1 | MINRES its, last step |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    its = {}
    for k in args.sizes:
        problem = area_problem(k)
        spec = spec_of(problem)
        repeats = args.repeats if k * k < 50_000 else 1
        direct, r = measure(problem, SparseDirect(), repeats, args.tol)
        print(f"| {k * k} | {spec.n} | SparseDirect | | {r['compile']:.1f} | {r['per_step']:.3f} | {r['steps']} | "
              f"{r['residual']:.1e} | | | |", flush=True)
        solvers = [("Krylov(amg)", Krylov(preconditioner="amg"))] + ([("Krylov(jacobi)", Krylov())] if k <= args.jacobi_max else [])
        for name, linear_solver in solvers:
            sol, r = measure(problem, linear_solver, repeats, args.tol)
            first, res_first = minres_iterations(problem, linear_solver, problem.x0)
            last, res_last = minres_iterations(problem, linear_solver, sol.x)
            its[(name, k)] = (first, last)
            diff = float(jnp.max(jnp.abs(sol.x - direct.x)))
            bound = linear_solver.bind(problem, spec)
            levels = "" if bound.hierarchy is None else " → ".join(
                str(s * b) for s, b in zip(bound.hierarchy.sizes, bound.hierarchy.blocks))
            print(f"| {k * k} | {spec.n} | {name} | {levels} | {r['compile']:.1f} | {r['per_step']:.3f} | {r['steps']} | "
                  f"{r['residual']:.1e} | {diff:.1e} | {first} ({res_first:.0e}) | {last} ({res_last:.0e}) |", flush=True)
    amg = sorted((k, v) for (name, k), v in its.items() if name == "Krylov(amg)")
    if len(amg) >= 2:
        (k0, (a0, b0)), (k1, (a1, b1)) = amg[0], amg[-1]
        ratio = max(a1 / a0, b1 / b0)
        print(f"\n{'PASS' if ratio <= 2 else 'FAIL'}: MINRES iterations with the multigrid cycle, {k0 * k0} → {k1 * k1} "
              f"vertices: step 1 {a0} → {a1}, last step {b0} → {b1} (ratio {ratio:.2f} ≤ 2)")
    if load > cores or os.getloadavg()[0] > cores:
        print(f"note: load average {max(load, os.getloadavg()[0]):.1f} > {cores} cores during the run: other processes share the CPU")


if __name__ == "__main__":
    main()
