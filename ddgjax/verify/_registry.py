"""The registry of checks: one small function per statement of the reference.

A check is a function `fn(ctx, **size) -> float` registered with `@check(...)`: it computes one
number the theory fixes (a residual, an observed order, a defect) and the registry compares it
with a tolerance.  The decorator records the statement, its number in the reference, what the
number is, the tolerance and the problem sizes of the quick and the full run:

```python
from ddgjax.verify import check

@check("Thm 5.6", "Σ K(p) = 2πχ on every built-in mesh", quantity="max |Σ K − 2πχ|",
       at_most=1e-12, quick=dict(level=1), full=dict(level=4))
def gauss_bonnet(ctx, level):
    ...
    return defect
```

Tolerances come in three kinds: `at_most` (value ≤ tol: residuals, defects), `at_least`
(value ≥ tol: a quantity that must not vanish, e.g. a bracket that must be of order one) and
`target`, `within` (|value − target| ≤ within: fitted orders of convergence).

The context `ctx` hands out figure paths (`ctx.figure("name.png")`) and records convergence
tables with their log-log plots (`ctx.convergence(table, "name")`), which the report embeds.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import InvalidInputError

__all__ = ["Check", "Context", "Outcome", "check", "one_line", "registry", "run_check"]


@dataclass(frozen=True)
class Check:
    """One registered statement: `fn(ctx, **sizes)` returns the value compared with the tolerance."""

    name: str
    reference: str
    statement: str
    quantity: str
    fn: Callable
    quick: dict
    full: dict
    at_most: float | None = None
    at_least: float | None = None
    target: float | None = None
    within: float | None = None
    section: str = ""
    full_only: bool = False

    def passes(self, value: float) -> bool:
        """Whether `value` meets the tolerance (NaN never does)."""
        if not math.isfinite(value):
            return False
        if self.target is not None:
            return abs(value - self.target) <= self.within
        if self.at_least is not None:
            return value >= self.at_least
        return value <= self.at_most

    @property
    def tolerance(self) -> str:
        """The tolerance as the report prints it: `≤ 1e-10`, `≥ 0.01`, `2 ± 0.2`."""
        if self.target is not None:
            return f"{self.target:g} ± {self.within:g}"
        if self.at_least is not None:
            return f"≥ {self.at_least:.0e}" if self.at_least < 1e-2 else f"≥ {self.at_least:g}"
        return f"≤ {self.at_most:.0e}" if self.at_most < 1e-2 else f"≤ {self.at_most:g}"

    def sizes(self, quick: bool) -> dict:
        return dict(self.quick if quick else self.full)


@dataclass
class Context:
    """What a check may use besides its sizes: where figures go, and what it records."""

    out: Path
    quick: bool
    figures: list = field(default_factory=list)
    tables: list = field(default_factory=list)  # (ConvergenceTable, figure path)

    def figure(self, name: str) -> Path:
        """A path `out/figures/<name>` for a PNG the check writes; listed in the report."""
        path = self.out / "figures" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        self.figures.append(path)
        return path

    def convergence(self, table, name: str, title: str | None = None):
        """Record a `ddgjax.limits.ConvergenceTable` and its log-log plot `figures/<name>.png`;
        returns the table."""
        path = self.out / "figures" / f"{name}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        table.plot(path, title=title)
        self.tables.append((table, path))
        return table


@dataclass
class Outcome:
    """The result of running one check."""

    check: Check
    value: float
    passed: bool
    seconds: float
    sizes: dict
    figures: list
    tables: list
    error: str | None = None
    skipped: bool = False


registry: dict[str, Check] = {}

_NAME = re.compile(r"^[a-z0-9_]+$")


def check(
    reference: str,
    statement: str,
    *,
    quantity: str,
    at_most: float | None = None,
    at_least: float | None = None,
    target: float | None = None,
    within: float | None = None,
    quick: dict | None = None,
    full: dict | None = None,
    name: str | None = None,
    section: str | None = None,
    full_only: bool = False,
) -> Callable:
    """Register `fn(ctx, **sizes) -> float` as the check of `statement` (reference number
    `reference`, e.g. "Thm 3.8").  Exactly one tolerance: `at_most`, `at_least`, or `target`
    with `within`.  `quick`/`full`: keyword arguments of the two runs (`full` defaults to
    `quick`); `full_only=True` skips the check in the quick run (listed as such in the report:
    for checks whose compilation alone would take most of the quick run's budget).  `name`
    defaults to the function's name and must be unique; `section` (the report's grouping)
    defaults to the first line of the module's docstring.

    **Raises:** `InvalidInputError` for a missing or ambiguous tolerance or a repeated name.
    """
    kinds = [at_most is not None, at_least is not None, target is not None]
    if sum(kinds) != 1 or (target is not None) != (within is not None):
        raise InvalidInputError(f"check {statement!r}: give exactly one of at_most, at_least, or target with within")

    def register(fn: Callable) -> Callable:
        key = name or fn.__name__
        if not _NAME.match(key):
            raise InvalidInputError(f"check name {key!r} must be lower-case letters, digits and underscores")
        if key in registry and registry[key].fn.__module__ != fn.__module__:
            raise InvalidInputError(f"check {key!r} is registered twice ({registry[key].fn.__module__} and {fn.__module__})")
        registry[key] = Check(
            name=key, reference=reference, statement=statement, quantity=quantity, fn=fn,
            quick=dict(quick or {}), full=dict(full if full is not None else quick or {}),
            at_most=at_most, at_least=at_least, target=target, within=within,
            section=section or _module_title(fn), full_only=full_only,
        )
        return fn

    return register


def _module_title(fn: Callable) -> str:
    import sys

    doc = getattr(sys.modules.get(fn.__module__), "__doc__", None) or fn.__module__
    return doc.strip().splitlines()[0].rstrip(".")


def one_line(exc: BaseException) -> str:
    """`Type: first line of the message` (the report and the command line print one line)."""
    lines = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {lines[0]}" if lines else type(exc).__name__


def run_check(c: Check, out: Path, quick: bool, debug: bool = False) -> Outcome:
    """Run one check; an exception is a failure whose message is kept (re-raised if `debug`)."""
    ctx = Context(Path(out), quick)
    sizes = c.sizes(quick)
    if quick and c.full_only:
        return Outcome(c, float("nan"), True, 0.0, c.sizes(False), [], [], None, skipped=True)
    start = time.perf_counter()
    try:
        value, error = float(c.fn(ctx, **sizes)), None
    except Exception as exc:  # a check that crashes is a failed check, reported, not a crash
        if debug:
            raise
        value, error = float("nan"), one_line(exc)
    seconds = time.perf_counter() - start
    return Outcome(c, value, error is None and c.passes(value), seconds, sizes, ctx.figures, ctx.tables, error)
