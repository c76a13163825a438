"""Where `method="sparse"` on a mesh switches from KLU to the fill-reducing `SparseDirect`
(`solvers._solve.KLU_MAX`, in unknowns + multipliers N): the time to a first solution in a new
process, and the time of a solve once compiled, for both, on the same problems in one run.

A new process with warm caches loads KLU's Newton solver from disk (an exported program and
XLA's executable, `solvers._exported`); `SparseDirect`'s factorisations are host callbacks, whose
programs JAX neither exports nor keeps in its compilation cache, so every process traces and
compiles its solver again.  Columns, per problem and linear solver:
- `first`: seconds from the start of `solve` to its result in a new process whose caches an
  earlier process warmed (median of `--repeats` processes; the interpreter's start-up and
  imports, the same for both, not included);
- `solve`: median seconds of 5 further solves in that process (the solver compiled);
- `steps`: Newton steps (0: Newton stalled and the L-BFGS retry of `warm_start="auto"` solved it);
  N = n + m, free unknowns and multipliers; the ratio columns give SparseDirect ÷ KLU.

Problems (`energies.area`):
- `bubble L`: `with_volume` on `dg.mesh.icosphere(L)` perturbed by 2 % of P2 (as verify's
  bubbles), volume 4π/3;
- `double bubble m`: `with_volumes` on `dg.mesh.builtin.double_bubble(m, m // 4, round(m / 6))`,
  volumes 9π/8 each;
- `saddle k`: `simplicial` on the k×k noisy saddle grid after 5 Pinkall–Polthier steps
  (`benchmarks/scale.py`'s `area_problem`), border fixed.

    python benchmarks/klu_max.py [--repeats 3] [--problems "bubble 3" ...]

Measured 2026-12-07 on the shared 2-core machine (load 1.3; N of the saddles counted with the
fixed border then, so 675 / 1200 / 2700 there are n + m = 507 / 972 / 2352):

    problem                 N | KLU first   solve steps | SD first   solve steps | first SD/KLU solve SD/KLU
    bubble 2              487 |      0.42   0.027     6 |     3.34   0.014     4 |         7.93         0.51
    saddle 15             675 |      0.25   0.008     4 |     2.40   0.015     4 |         9.45         1.80
    double bubble 24     1019 |      2.46   1.637     0 |     4.50   0.532    34 |         1.83         0.32
    saddle 20            1200 |      0.30   0.020     4 |     2.17   0.022     4 |         7.20         1.13
    bubble 3             1927 |      0.49   0.114     5 |     3.50   0.077     5 |         7.13         0.67
    saddle 30            2700 |      0.40   0.052     4 |     2.48   0.042     4 |         6.14         0.80
    bubble 4             7687 |      2.74   2.244    10 |     3.46   0.407    10 |         1.26         0.18

At the tolerance of verify's bubbles (tol 1e-12) KLU meets the rigid motions of a closed surface
(a nearly singular KKT matrix) worse than Pardiso's pivoting: bubble 3 takes 45 Newton steps with
KLU and 7 with Pardiso (1.7 vs 0.3 s once compiled); `solvers._solve.KLU_MAX` is 1000.

The machine may be shared: compare rows of one run only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

PROBLEMS = ("bubble 2", "saddle 15", "double bubble 24", "saddle 20", "bubble 3", "saddle 30", "bubble 4")

CHILD = r"""
import json, statistics, sys, time
import numpy as np
from ddgjax import compile_cache
compile_cache.enable()
import ddgjax as dg
from energies import area
from solvers import KLU, SparseDirect, solve
from solvers._kkt import spec_of

kind, size, solver = sys.argv[1], int(sys.argv[2]), sys.argv[3]
if kind == "bubble":
    V, F = dg.mesh.icosphere(size)
    problem = area.with_volume(V * (1.0 + 0.02 * (1.5 * V[:, 2:] ** 2 - 0.5)), F, 4.0 * np.pi / 3.0)
elif kind == "double":
    V, F, C = dg.mesh.builtin.double_bubble(size, size // 4, max(2, round(size / 6)))
    problem = area.with_volumes(V, F, C, np.full(2, 9.0 * np.pi / 8.0))
else:
    sys.path.insert(0, sys.argv[4])
    from scale import area_problem
    problem = area_problem(size)
spec = spec_of(problem)
make = {"KLU": KLU, "SparseDirect": SparseDirect}[solver]
start = time.perf_counter()
sol = solve(problem, linear_solver=make(), throw=False)
first = time.perf_counter() - start
times = []
for _ in range(5):
    start = time.perf_counter()
    solve(problem, linear_solver=make(), throw=False)
    times.append(time.perf_counter() - start)
print(json.dumps(dict(first=first, solve=statistics.median(times), steps=int(sol.steps),
                      N=spec.n + spec.m)))
"""


def run(problem: str, solver: str, cache: Path) -> dict:
    """One new process solving `problem` with `solver`, its caches in `cache`."""
    kind, size = problem.split()[0], problem.split()[-1]
    env = dict(os.environ, DDGJAX_COMPILE_CACHE=str(cache))
    out = subprocess.run([sys.executable, "-c", CHILD, kind, size, solver, str(Path(__file__).parent)], env=env,
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--problems", nargs="*", default=list(PROBLEMS))
    args = parser.parse_args(argv)
    print(f"medians of {args.repeats} new processes with warm caches; load {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores")
    print(f"{'problem':18s} {'N':>6s} | {'KLU first':>9s} {'solve':>7s} {'steps':>5s} | {'SD first':>8s} {'solve':>7s} "
          f"{'steps':>5s} | {'first SD/KLU':>12s} {'solve SD/KLU':>12s}")
    with tempfile.TemporaryDirectory() as root:
        for problem in args.problems:
            row = {}
            for solver in ("KLU", "SparseDirect"):
                cache = Path(root) / "cache"
                run(problem, solver, cache)  # warms the caches
                results = [run(problem, solver, cache) for _ in range(args.repeats)]
                row[solver] = {k: statistics.median(r[k] for r in results) for k in ("first", "solve", "steps", "N")}
            k, s = row["KLU"], row["SparseDirect"]
            print(f"{problem:18s} {int(k['N']):6d} | {k['first']:9.2f} {k['solve']:7.3f} {int(k['steps']):5d} | "
                  f"{s['first']:8.2f} {s['solve']:7.3f} {int(s['steps']):5d} | {s['first'] / k['first']:12.2f} "
                  f"{s['solve'] / k['solve']:12.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
