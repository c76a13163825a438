"""A family of sizes in one process: the first solve of each member, with and without cell buckets.

A convergence study solves one declaration at several sizes in one process.  The persistent
compilation cache loads each member's compiled program, but the program is traced and lowered
again for every size.  `ddgjax.locality` pads a term's cells to a bucket (`CELL_BUCKETS`), so
that members whose cell counts fall in one bucket share the traced and batched density and its
derivatives.  This script solves the clamped rod (vertex clamps, n = 8, 16, 32) and the Willmore
torus of revolution (n = 12, 16, 24 profile points) in fresh processes with the buckets (as
shipped) and without (`CELL_BUCKETS = ()`), and prints the seconds to the first solution of each
member (trace + lower + load or compile + run), medians of `--repeats` processes, with the
ratio.  Run it twice: the first run may fill the compilation cache.

    python benchmarks/size_family.py [--repeats 3]

The machine may be shared: compare rows of one run only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

PROBE = """
import json, os, sys, time
from ddgjax import compile_cache
os.environ.setdefault("XLA_FLAGS", compile_cache.fast_compile_xla_flags())
compile_cache.enable()
import jax
from ddgjax import locality
from energies import rod, willmore
from solvers import solve
if sys.argv[1] == "off":
    locality.CELL_BUCKETS = ()
members = [("rod", n, lambda n=n: rod.clamped(n, alpha=0.6, chord=(0.5, 0.3, 0.15), frame_start=[1.0, 0, 0, 0],
                                              frame_end=[0.0, 0, 0, 1.0], clamp="vertex")) for n in (8, 16, 32)]
members += [("torus", n, lambda n=n: willmore.torus_of_revolution(2 * n, n)) for n in (12, 16, 24)]
out = {}
for family, n, make in members:
    start = time.perf_counter()
    sol = solve(make())
    jax.block_until_ready(sol.x)
    out[f"{family} n={n}"] = time.perf_counter() - start
print(json.dumps(out))
"""


def run(setting: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", PROBE, setting], capture_output=True, text=True, check=True,
                          env=dict(os.environ))
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    runs = {s: [run(s) for _ in range(args.repeats)] for s in ("on", "off")}
    print(f"first solve of each member in one process, s (median of {args.repeats} processes)")
    print(f"{'member':12s} {'buckets':>8s} {'none':>8s} {'ratio':>6s}")
    for member in runs["on"][0]:
        on, off = (statistics.median(r[member] for r in runs[s]) for s in ("on", "off"))
        print(f"{member:12s} {on:8.2f} {off:8.2f} {off / on:6.2f}")


if __name__ == "__main__":
    main()
