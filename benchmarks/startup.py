"""Start-up: what a user waits for before the first result, in fresh processes.

Each row is the median wall time of `--repeats` cold processes (a new interpreter each time),
measured in this one run side by side with `python -c "import jax"`, the floor every JAX
program pays:

- `import jax`, `import ddgjax`;
- `ddgjax solve elastica --n 100` and `ddgjax solve rod --n 50`, first cold run (an empty
  compilation cache per process: tracing and XLA compilation) and second cold run (the cache
  warmed by one earlier process: tracing, then the compiled programs loaded from disk);
- with `--verify`, `ddgjax verify --quick` once with a warm cache (it takes minutes).

Targets: `import ddgjax` ≤ 1.3 × `import jax`; the elastica's second cold run ≤ 2.5 ×
`import jax`; `verify --quick` with a warm cache ≤ 40 s.

    python benchmarks/startup.py [--repeats 3] [--verify]

The machine may be shared: compare rows of one run only.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PYTHON = sys.executable
DDGJAX = [PYTHON, "-m", "ddgjax"]
ELASTICA = [*DDGJAX, "solve", "elastica", "--n", "100"]
ROD = [*DDGJAX, "solve", "rod", "--n", "50"]


def wall(command: list[str], cache: Path | str, cwd: Path | None = None) -> float:
    """Seconds of one process running `command` with the compilation cache at `cache`."""
    env = dict(os.environ, DDGJAX_COMPILE_CACHE=str(cache))
    start = time.perf_counter()
    subprocess.run(command, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def median_cold(command: list[str], repeats: int, warm: bool) -> float:
    """Median over `repeats` processes; each with its own empty cache, or all with one cache
    warmed by an earlier process (`warm`)."""
    times = []
    with tempfile.TemporaryDirectory() as root:
        if warm:
            wall(command, Path(root) / "shared")
        for k in range(repeats):
            cache = Path(root) / ("shared" if warm else f"empty{k}")
            times.append(wall(command, cache))
    return statistics.median(times)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--verify", action="store_true", help="also time `ddgjax verify --quick` with a warm cache")
    args = parser.parse_args(argv)

    rows = [("import jax", [PYTHON, "-c", "import jax"], False, None)]
    rows += [("import ddgjax", [PYTHON, "-c", "import ddgjax"], False, 1.3)]
    rows += [("solve elastica --n 100, first cold run", ELASTICA, False, None),
             ("solve elastica --n 100, second cold run", ELASTICA, True, 2.5),
             ("solve rod --n 50, first cold run", ROD, False, None),
             ("solve rod --n 50, second cold run", ROD, True, None)]
    # one warm-up process, so that the first row does not pay for a cold file-system cache
    wall([PYTHON, "-c", "import ddgjax, energies, solvers"], "off")
    measured = [(name, median_cold(cmd, args.repeats, warm), target) for name, cmd, warm, target in rows]
    base = measured[0][1]
    print(f"medians of {args.repeats} cold processes, python {sys.version.split()[0]}, load {os.getloadavg()[0]:.1f}"
          f" on {os.cpu_count()} cores")
    print(f"{'':44s} {'seconds':>8s} {'× import jax':>13s}  target")
    failed = False
    for name, seconds, target in measured:
        verdict = ""
        if target is not None:
            ok = seconds <= target * base
            failed |= not ok
            verdict = f"≤ {target} × : {'PASS' if ok else 'FAIL'}"
        print(f"{name:44s} {seconds:8.2f} {seconds / base:13.2f}  {verdict}")
    if args.verify:
        with tempfile.TemporaryDirectory() as root:
            command = [*DDGJAX, "verify", "--quick", "--no-progress", "--out", str(Path(root) / "report")]
            first = wall(command, Path(root) / "cache")
            second = wall(command, Path(root) / "cache")
            shutil.rmtree(Path(root) / "report", ignore_errors=True)
        ok = second <= 40.0
        failed |= not ok
        print(f"{'verify --quick, first run (empty cache)':44s} {first:8.2f} {first / base:13.2f}")
        print(f"{'verify --quick, second run (warm cache)':44s} {second:8.2f} {second / base:13.2f}  "
              f"≤ 40 s: {'PASS' if ok else 'FAIL'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
