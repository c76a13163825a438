"""Loading the check modules and running the registered checks, with a progress bar."""

from __future__ import annotations

import importlib
import os
import pkgutil
import sys
import time
from contextlib import contextmanager
from pathlib import Path
from queue import Empty
from typing import Iterable

from .. import compile_cache
from ..errors import InvalidInputError
from ._registry import Check, Outcome, one_line, registry, run_check
from ._report import write_report

__all__ = ["load_checks", "select", "run", "verify"]

_LOAD_ERRORS: dict[str, str] = {}


def load_checks() -> dict[str, str]:
    """Import every module of `ddgjax.verify.checks` (each registers its checks on import).

    A module that fails to import is not fatal here: its error is returned (module → message)
    and `verify` reports it as a failed check, so one broken module does not hide the others.
    """
    from . import checks

    for info in sorted(pkgutil.iter_modules(checks.__path__), key=lambda i: i.name):
        if info.name.startswith("_"):  # helpers shared by the check modules
            continue
        module = f"{checks.__name__}.{info.name}"
        if module in _LOAD_ERRORS:
            continue
        try:
            importlib.import_module(module)
        except Exception as exc:
            _LOAD_ERRORS[module] = one_line(exc)
    return dict(_LOAD_ERRORS)


def select(only: Iterable[str] | None = None) -> list[Check]:
    """The registered checks in registration order, or those whose name, reference or module
    contains one of the words in `only` (case-insensitive).

    **Raises:** `InvalidInputError` if `only` matches no check.
    """
    checks = list(registry.values())
    if not only:
        return checks
    words = [w.lower() for w in only]
    chosen = [c for c in checks if any(w in f"{c.name} {c.reference} {c.fn.__module__}".lower() for w in words)]
    if not chosen:
        raise InvalidInputError(f"no check matches {list(only)}; `ddgjax verify --list` lists them")
    return chosen


@contextmanager
def _progress(total: int, enabled: bool):
    """A rich progress bar (on stderr) whose `advance(description)` moves it by one check."""
    if not enabled:
        yield lambda description: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
    )

    columns = (TextColumn("[bold]verify"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("{task.description}"))
    with Progress(*columns, console=Console(stderr=True), transient=False) as bar:
        task = bar.add_task("", total=total)
        yield lambda description: bar.update(task, advance=1, description=description)


def _status(outcome: Outcome) -> str:
    state = "skipped" if outcome.skipped else "pass" if outcome.passed else "FAIL"
    return f"{outcome.check.name}: {state} ({outcome.seconds:.1f} s)"


def _group(c: Check) -> str:
    """Checks of modules with the same `GROUP` share cached solutions: they run in one process."""
    return getattr(sys.modules[c.fn.__module__], "GROUP", c.fn.__module__)


_PROGRESS = None
"""In a worker process: the queue its outcomes' status lines go to (`_started_worker`)."""


def _started_worker(progress) -> None:
    """A worker's initialiser: keep the progress queue (a multiprocessing queue is handed to a
    process when it starts, not with each task)."""
    global _PROGRESS
    _PROGRESS = progress


def _run_names(modules: list[str], names: list[str], out: str, quick: bool) -> list[dict]:
    """Worker of the parallel run: import `modules`, run the checks `names`, return plain data."""
    for module in modules:
        importlib.import_module(module)
    results = []
    for name in names:
        outcome = run_check(registry[name], Path(out), quick)
        if _PROGRESS is not None:
            _PROGRESS.put(_status(outcome))
        results.append({k: getattr(outcome, k) for k in ("value", "passed", "seconds", "sizes", "figures", "tables",
                                                         "error", "skipped")} | {"name": name})
    return results


def _warm_up() -> None:
    """A worker's first task: import what every group of checks imports (JAX, the library)."""
    importlib.import_module("ddgjax.verify.checks._shared")


@contextmanager
def _workers(jobs: int):
    """`(pool, queue)`: `jobs` spawned worker processes, started at once (they import JAX and the
    library while the caller loads the checks), and a queue for their progress; `None` if
    `jobs` ≤ 1."""
    if jobs <= 1:
        yield None
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    # The checks solve small problems once each: XLA's compile time, not their run time, is
    # most of a run.  Spawned workers start a fresh JAX backend, so the fast-compile flags apply
    # there (unless XLA_FLAGS is set already).
    os.environ.setdefault("XLA_FLAGS", compile_cache.fast_compile_xla_flags())
    context = multiprocessing.get_context("spawn")
    progress = context.Queue()
    pool = ProcessPoolExecutor(jobs, mp_context=context, initializer=_started_worker, initargs=(progress,))
    try:
        for _ in range(jobs):
            pool.submit(_warm_up)
        yield pool, progress
    finally:
        # idle now (or after an error): stop the workers instead of waiting for their JAX to
        # shut down, seconds with thousands of compiled programs (no public API for this)
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        for process in processes:
            process.join(timeout=10)
        pool.shutdown(wait=True)  # the pool's thread sees its workers gone and ends before the interpreter does
        progress.close()


def _run_parallel(checks: list[Check], out, quick: bool, workers, advance) -> list[Outcome]:
    """Run groups of checks on the `(pool, queue)` of `_workers` (JIT compilation is
    single-threaded, so two cores compile two problems at once), the longest groups first;
    returns outcomes in the order of `checks`."""
    pool, queue = workers
    groups: dict[str, list[Check]] = {}
    for c in checks:
        groups.setdefault(_group(c), []).append(c)
    tasks = sorted(groups.values(), key=len, reverse=True)
    futures = [pool.submit(_run_names, sorted({c.fn.__module__ for c in task}), [c.name for c in task], str(out),
                           quick) for task in tasks]
    received = 0  # status lines: one per check, unless its worker died
    while received < len(checks):
        try:
            advance(queue.get(timeout=0.5))
            received += 1
        except Empty:
            if all(f.done() for f in futures):  # and nothing arrived for 0.5 s: a worker failed
                break
    results = {}
    for task, future in zip(tasks, futures, strict=True):
        for c, row in zip(task, _rows(task, future, quick), strict=True):
            results[c.name] = row
    return [Outcome(c, **{k: v for k, v in results[c.name].items() if k != "name"}) for c in checks]


def _rows(task: list[Check], future, quick: bool) -> list[dict]:
    """The worker's results, or one failed row per check if the worker itself failed."""
    try:
        return future.result()
    except Exception as exc:  # e.g. a worker killed for memory: report, do not hang or crash
        return [dict(name=c.name, value=float("nan"), passed=False, seconds=0.0, sizes=c.sizes(quick), figures=[],
                     tables=[], error=f"worker failed: {one_line(exc)}", skipped=False) for c in task]


def run(checks: list[Check], out, *, quick: bool, progress: bool = False, debug: bool = False,
        jobs: int = 1, workers=None) -> list[Outcome]:
    """Run `checks` (in `jobs` processes when > 1, or on the started `workers` of `_workers`;
    `debug` runs in this process and re-raises); figures go under `out/figures`."""
    with _progress(len(checks), progress) as advance:
        if workers is None and jobs > 1 and not debug and len(checks) > 1:
            with _workers(jobs) as started:
                return _run_parallel(checks, out, quick, started, advance)
        if workers is not None and not debug and len(checks) > 1:
            return _run_parallel(checks, out, quick, workers, advance)
        outcomes = []
        for c in checks:
            outcomes.append(run_check(c, Path(out), quick, debug))
            advance(_status(outcomes[-1]))
        return outcomes


def _load_failure(module: str, message: str) -> Outcome:
    pseudo = Check(name=module.rsplit(".", 1)[-1], reference="—", statement=f"module {module} imports",
                   quantity="import", fn=lambda ctx: 0.0, quick={}, full={}, at_most=0.0, section="Modules that failed to load")
    return Outcome(pseudo, float("nan"), False, 0.0, {}, [], [], message)


def verify(out, *, quick: bool = False, only=None, progress: bool = False, debug: bool = False,
           jobs: int = 1) -> tuple[list[Outcome], Path]:
    """Load and run the checks (all, or those matching `only`) in `jobs` processes and write
    `out/report.md`.

    **Returns:** `(outcomes, report_path)`; every outcome's `passed` tells whether its statement
    held within tolerance.  A check module that fails to import counts as a failed check.
    """
    start = time.perf_counter()
    with _workers(1 if debug else jobs) as workers:  # started before the checks load here
        errors = load_checks()
        if debug and errors:
            raise ImportError(f"check modules failed to import: {errors}")
        outcomes = run(select(only), out, quick=quick, progress=progress, debug=debug, jobs=jobs, workers=workers)
    if not only:
        outcomes += [_load_failure(m, msg) for m, msg in errors.items()]
    path = write_report(outcomes, out, quick=quick, seconds=time.perf_counter() - start)
    return outcomes, path
