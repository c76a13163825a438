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

Measured on the shared 2-core machine, one process per row after a warming one (`--repeats 1`,
load 1.1; a machine about 2× slower than that of the earlier table kept in git history):

    problem                 N | KLU first   solve steps | SD first   solve steps | first SD/KLU solve SD/KLU
    bubble 2              487 |      0.54   0.026     4 |     6.37   0.029     4 |        11.86         1.13
    saddle 15             507 |      0.41   0.015     4 |     4.21   0.026     4 |        10.14         1.78
    double bubble 24     1019 |      1.08   0.472    35 |     6.18   0.309    13 |         5.74         0.66
    saddle 20             972 |      0.53   0.025     4 |     3.91   0.035     4 |         7.34         1.38
    bubble 3             1927 |      0.95   0.326     8 |     6.29   0.076     5 |         6.62         0.23
    saddle 30            2352 |      0.41   0.065     4 |     4.52   0.059     4 |        10.97         0.91
    bubble 4             7687 |      6.08   4.734    11 |     7.97   1.311    10 |         1.31         0.28

At verify's tolerance for bubbles (tol 1e-12) bubble 3 takes 9 Newton steps with KLU and 8 with
Pardiso (earlier Newton iterations took 45 with KLU there); `solvers._solve.KLU_MAX` is 2500.

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
