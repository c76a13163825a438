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

_NEXT = None
"""In every process of a parallel run: the shared index of the next unclaimed task (`_claim`)."""


def _started_worker(progress, next_task) -> None:
    """A worker's initialiser: keep the progress queue and the shared task index (handed to a
    process when it starts, not with each task)."""
    global _PROGRESS, _NEXT
    _PROGRESS, _NEXT = progress, next_task


def _claim() -> int:
    """The index of the next task no process has taken yet (and take it)."""
    with _NEXT.get_lock():
        index = _NEXT.value
        _NEXT.value = index + 1
    return index


def _run_names(modules: list[str], names: list[str], out: str, quick: bool, report) -> list[dict]:
    """Import `modules`, run the checks `names` (`report(status line)` after each), return plain data."""
    for module in modules:
        importlib.import_module(module)
    results = []
    for name in names:
        outcome = run_check(registry[name], Path(out), quick)
        report(_status(outcome))
        results.append({k: getattr(outcome, k) for k in ("value", "passed", "seconds", "sizes", "figures", "tables",
                                                         "error", "skipped")} | {"name": name})
    return results


def _drain(tasks: list[tuple[list[str], list[str]]], out: str, quick: bool, report=None) -> dict[int, list[dict]]:
    """Run the tasks `(modules, check names)` that no other process has claimed, one after the
    other, until none is left; returns `{task index: rows}`.  In a worker the status lines go to
    the progress queue, in the calling process to `report`."""
    report = report or _PROGRESS.put
    done = {}
    while (index := _claim()) < len(tasks):
        done[index] = _run_names(*tasks[index], out, quick, report)
    return done


def _warm_up() -> None:
    """A worker's first task: import what every group of checks imports (JAX, the library)."""
    importlib.import_module("ddgjax.verify.checks._shared")


@contextmanager
def _workers(jobs: int):
    """`(pool, queue, count)`: `count = jobs − 1` spawned worker processes, started at once (they
    import JAX and the library while the caller loads the checks; the caller is the last of the
    `jobs` processes that run checks), and a queue for their progress; `None` if `jobs` ≤ 1."""
    global _NEXT
    if jobs <= 1:
        yield None
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    # The checks solve small problems once each: XLA's compile time, not their run time, is
    # most of a run.  Spawned workers start a fresh JAX backend, so the fast-compile flags apply
    # there, and in this process if its backend has not started yet (unless XLA_FLAGS is set).
    os.environ.setdefault("XLA_FLAGS", compile_cache.fast_compile_xla_flags())
    context = multiprocessing.get_context("spawn")
    progress, _NEXT = context.Queue(), context.Value("i", 0)
    pool = ProcessPoolExecutor(jobs - 1, mp_context=context, initializer=_started_worker, initargs=(progress, _NEXT))
    try:
        for _ in range(jobs - 1):
            pool.submit(_warm_up)
        yield pool, progress, jobs - 1
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
        _NEXT = None


def _run_parallel(checks: list[Check], out, quick: bool, workers, advance) -> list[Outcome]:
    """Run groups of checks in this process and on the workers `(pool, queue, count)` of `_workers` (JIT
    compilation is single-threaded, so two cores compile two problems at once): each process
    takes the next group no other has taken, the longest groups first; returns outcomes in the
    order of `checks`."""
    pool, queue, count = workers
    groups: dict[str, list[Check]] = {}
    for c in checks:
        groups.setdefault(_group(c), []).append(c)
    groups_in_order = sorted(groups.values(), key=len, reverse=True)
    tasks = [(sorted({c.fn.__module__ for c in group}), [c.name for c in group]) for group in groups_in_order]
    with _NEXT.get_lock():
        _NEXT.value = 0
    futures = [pool.submit(_drain, tasks, str(out), quick) for _ in range(count)]

    def progressed(block: bool = False) -> None:
        """Advance the bar by the workers' status lines that have arrived (waiting for one if `block`)."""
        while True:
            try:
                advance(queue.get(timeout=0.5) if block else queue.get_nowait())
            except Empty:
                return
            block = False

    def report(line: str) -> None:
        advance(line)
        progressed()

    done = _drain(tasks, str(out), quick, report)
    while not all(f.done() for f in futures):
        progressed(block=True)
    for future in futures:
        done |= _rows_of(future)
    progressed()
    results = {}
    for index, group in enumerate(groups_in_order):
        rows = done.get(index) or _failed_rows(group, quick, "its worker process failed")
        for c, row in zip(group, rows, strict=True):
            results[c.name] = row
    return [Outcome(c, **{k: v for k, v in results[c.name].items() if k != "name"}) for c in checks]


def _rows_of(future) -> dict[int, list[dict]]:
    """A worker's `{task index: rows}`, or nothing if the worker itself failed (e.g. killed for
    memory): its unfinished tasks are then reported failed, not waited for."""
    try:
        return future.result()
    except Exception:
        return {}


def _failed_rows(task: list[Check], quick: bool, why: str) -> list[dict]:
    return [dict(name=c.name, value=float("nan"), passed=False, seconds=0.0, sizes=c.sizes(quick), figures=[],
                 tables=[], error=why, skipped=False) for c in task]


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
