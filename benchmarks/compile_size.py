"""The size of the compiled solver and its compile time: what the first solve of a new problem waits for.

For each problem, in a fresh process (no compilation cache), the program `solve` compiles is
lowered again and compiled again, timed apart: lines of its StableHLO text, seconds to lower
(trace), and seconds for XLA to compile under three settings side by side (`SETTINGS`: XLA's
defaults as the command line uses them, LLVM's backend optimisation off, and the fast-compile
flags of the test suite and `verify`), with the ratio fast / defaults.  Medians of `--repeats`
processes.

    python benchmarks/compile_size.py [--repeats 3]

Rows: the clamped elastica (n = 100, KLU), the same at n = 30 on the dense path, the twisted rod
(n = 50, KLU) and the area of a 12 × 12 saddle grid (N = 300: KLU).  The machine may be shared:
compare rows of one run only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from ddgjax.compile_cache import fast_compile_xla_flags

HERE = Path(__file__).resolve().parent

PROBE = """
import json, sys, time
from functools import partial
sys.path.insert(0, {here!r})
import jax
import numpy as np
import solvers._solve as S
from solvers import solve

def problem(name):
    if name.startswith("elastica"):
        from energies import elastica
        n = 100 if name == "elastica" else 30
        return elastica.clamped(n, chord=(0.5, 0, 0), t_start=(0, 1, 0), t_end=(0, -1, 0)), {{}}
    if name == "rod":
        from ddgjax.cli import _rotation_taking_e1_to as frame
        from energies import rod
        return rod.clamped(50, alpha=0.7, chord=(0.6, 0, 0), frame_start=frame(np.array([0.0, 1, 0])),
                           frame_end=frame(np.array([0.0, -1, 0]))), {{}}
    import scale
    return scale.area_problem(12), {{}}

name = {name!r}
p, kw = problem(name)
if name == "elastica-dense":
    kw = dict(method="dense")
seen = {{}}
jitted = S._solve_jit

def spy(spec, linear, z0, params, lam0, weights, **static):
    seen.update(spec=spec, args=(linear, z0, params, lam0, weights), static=static)
    return jitted(spec, linear, z0, params, lam0, weights, **static)

S._solve_jit = spy
sol = solve(p, **kw)
f = jax.jit(partial(S._solve_impl, seen["spec"], **seen["static"]))
t0 = time.perf_counter(); lowered = f.lower(*seen["args"]); lower = time.perf_counter() - t0
t0 = time.perf_counter(); lowered.compile(); compile_s = time.perf_counter() - t0
print(json.dumps(dict(lines=lowered.as_text().count("\\n"), lower=lower, compile=compile_s, steps=int(sol.steps))))
"""

PROBLEMS = ("elastica", "elastica-dense", "rod", "area")


SETTINGS = {
    "defaults": "",
    "O0": "--xla_backend_optimization_level=0",
    "fast": fast_compile_xla_flags(),
}
"""The XLA flags compared: XLA's defaults (the command line), LLVM's backend optimisation off,
and `ddgjax.compile_cache.fast_compile_xla_flags()` (the test suite and `verify`'s workers)."""


def measure(name: str, xla_flags: str) -> dict:
    env = dict(os.environ, DDGJAX_COMPILE_CACHE="off", XLA_FLAGS=xla_flags)
    out = subprocess.run([sys.executable, "-c", PROBE.format(here=str(HERE), name=name)], env=env, check=True,
                         capture_output=True, text=True, cwd=HERE.parent).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    for setting, flags in SETTINGS.items():
        print(f"{setting:8s} XLA_FLAGS={flags!r}")
    columns = "".join(f" {'compile ' + k:>16s}" for k in SETTINGS)
    print(f"{'problem':16s} {'HLO lines':>9s} {'lower s':>8s}{columns} {'fast/defaults':>13s} {'steps':>5s}")
    for name in PROBLEMS:
        med = {}
        for setting, flags in SETTINGS.items():
            runs = [measure(name, flags) for _ in range(args.repeats)]
            med[setting] = {k: statistics.median(r[k] for r in runs) for k in ("lines", "lower", "compile", "steps")}
        fast = med["fast"]
        times = "".join(f" {med[k]['compile']:16.2f}" for k in SETTINGS)
        ratio = fast["compile"] / med["defaults"]["compile"]
        print(f"{name:16s} {fast['lines']:9.0f} {fast['lower']:8.2f}{times} {ratio:13.2f} {fast['steps']:5.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
