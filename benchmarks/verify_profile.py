"""Where the time of a warm `ddgjax verify --quick` goes: every check run in one process, its
seconds split by what JAX and XLA did.

The run is serial (one process, the fast-compile flags of `verify`'s workers, the user's
compilation cache and exported solvers, warmed by a first run of `ddgjax verify --quick`), so the
parts add up: the parallel run spreads the same work over its processes.  Per check and in all:

- `load`: executables read from the compilation cache (XLA:CPU rebuilds each from its HLO:
  its cost grows with the program's size); the exported solvers (`jit(call)`) apart;
- `compile`: programs compiled in this run, i.e. not in the cache: programs with host callbacks
  (never cached, named in the last table) or new ones;
- `trace` and `lower`: JAX's tracing and lowering to StableHLO (before the cache is looked up);
- `other`: the rest (running the programs, NumPy, figures, Python).

    ddgjax verify --quick --no-progress --out /tmp/warm     # once, to fill the caches
    python benchmarks/verify_profile.py [--top 15] [WORD ...]

WORD selects checks as `ddgjax verify --only` does; `--quick` (as `ddgjax bench --quick` passes
it) profiles only `QUICK`, the two groups that show each kind of cost (~20 s).  The machine may
be shared: compare runs made one after the other only.
"""

from __future__ import annotations

import argparse
import collections
import logging
import os
import re
import tempfile
import time
from pathlib import Path

from ddgjax import compile_cache

EVENTS = {
    "/jax/core/compile/jaxpr_trace_duration": "trace",
    "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower",
}
"""`jax.monitoring` duration events and their columns; `load` and `compile` come from JAX's log
(a cache hit, then XLA's "compilation", which is then the load of the cached executable)."""

QUICK = ("sec3_rod_limits", "ext_bubbles")
"""The checks of `--quick`: rods (the largest exported solvers) and bubbles (Pardiso's uncached
solvers, a stalled Newton solve)."""

COMPILED = re.compile(r"Finished XLA compilation of (\S+) in ([0-9.e-]+) sec")
HIT = re.compile(r"Persistent compilation cache hit for '(\S+)'")


class Recorder(logging.Handler):
    """Collects, per check, the seconds of each column and the programs XLA compiled or loaded."""

    def __init__(self):
        super().__init__(logging.DEBUG)
        self.seconds = collections.Counter()
        self.loaded: list[tuple[str, float]] = []
        self.compiled: list[tuple[str, float]] = []
        self._hits: set[str] = set()

    def reset(self) -> None:
        self.seconds.clear()
        self.loaded.clear()
        self.compiled.clear()
        self._hits.clear()

    def duration(self, event: str, seconds: float, **_) -> None:
        if event in EVENTS:
            self.seconds[EVENTS[event]] += seconds

    def emit(self, record: logging.LogRecord) -> None:
        message = record.getMessage()
        if hit := HIT.search(message):
            self._hits.add(hit.group(1))
        elif done := COMPILED.search(message):
            name, seconds = done.group(1), float(done.group(2))
            cache_name = name.replace("(", "_").replace(")", "")  # jit(f) is cached as jit_f
            (self.loaded if cache_name in self._hits else self.compiled).append((name, seconds))
            self._hits.discard(cache_name)


def install() -> Recorder:
    import jax
    from jax import monitoring

    recorder = Recorder()
    monitoring.register_event_duration_secs_listener(recorder.duration)
    for name in ("jax._src.compiler", "jax._src.dispatch", "jax._src.interpreters.pxla"):
        logger = logging.getLogger(name)
        logger.addHandler(recorder)
        logger.setLevel(logging.DEBUG)
        logger.propagate = False
    jax.config.update("jax_log_compiles", True)
    return recorder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("only", nargs="*", metavar="WORD")
    parser.add_argument("--top", type=int, default=15, help="checks listed, the slowest first")
    parser.add_argument("--quick", action="store_true", help=f"only the checks of {' and '.join(QUICK)}")
    args = parser.parse_args()
    words = list(QUICK) if args.quick and not args.only else args.only
    os.environ.setdefault("XLA_FLAGS", compile_cache.fast_compile_xla_flags())  # as verify's workers
    compile_cache.enable()
    recorder = install()

    from ddgjax.verify._registry import run_check
    from ddgjax.verify._run import load_checks, select

    load_checks()
    rows, uncached = [], collections.Counter()
    out = Path(tempfile.mkdtemp(prefix="verify_profile_"))
    start = time.perf_counter()
    for check in select(words or None):
        recorder.reset()
        began = time.perf_counter()
        outcome = run_check(check, out, True)
        wall = time.perf_counter() - began
        solvers = sum(s for name, s in recorder.loaded if name == "jit(call)")
        load = sum(s for _, s in recorder.loaded)
        compiled = sum(s for _, s in recorder.compiled)
        for name, s in recorder.compiled:
            uncached[name] += s
        parts = {"trace": recorder.seconds["trace"], "lower": recorder.seconds["lower"], "load": load,
                 "solvers": solvers, "compile": compiled}
        other = wall - parts["trace"] - parts["lower"] - load - compiled
        rows.append((check.name, wall, parts, other, len(recorder.loaded), len(recorder.compiled), outcome.passed))
    total = time.perf_counter() - start

    columns = ("trace", "lower", "load", "solvers", "compile")
    print(f"{len(rows)} checks in one process: {total:.1f} s")
    header = f"{'check':44s} {'s':>6s} " + " ".join(f"{c:>8s}" for c in columns) + f" {'other':>7s} {'loaded':>6s} {'new':>4s}"
    print(header)
    for name, wall, parts, other, n_loaded, n_compiled, passed in sorted(rows, key=lambda r: -r[1])[: args.top]:
        print(f"{name[:44]:44s} {wall:6.2f} " + " ".join(f"{parts[c]:8.2f}" for c in columns)
              + f" {other:7.2f} {n_loaded:6d} {n_compiled:4d}" + ("" if passed else "  FAIL"))
    sums = {c: sum(r[2][c] for r in rows) for c in columns}
    other = sum(r[3] for r in rows)
    print(f"{'all':44s} {sum(r[1] for r in rows):6.2f} " + " ".join(f"{sums[c]:8.2f}" for c in columns)
          + f" {other:7.2f} {sum(r[4] for r in rows):6d} {sum(r[5] for r in rows):4d}")
    print("(solvers: the part of load that is the exported solvers, jit(call); new: programs compiled in this run)")
    if uncached:
        print("\ncompiled in this run (host callbacks, never cached; or new):")
        for name, s in uncached.most_common(12):
            print(f"  {s:6.2f} s  {name}")


if __name__ == "__main__":
    main()
