"""The report `DIR/report.md`: the table of checks, the convergence tables, the figures."""

from __future__ import annotations

import datetime
import os
from itertools import groupby
from pathlib import Path

from .. import __version__
from ._registry import Outcome

__all__ = ["write_report", "figure_paths", "LEGEND"]

LEGEND = """\
Each row is one statement of the reference (Bobenko, *On some variational principles in discrete
differential geometry*; numbers as in the text), checked numerically on a discrete object of the
size given under *sizes*.  *value* is the quantity computed, *tolerance* what the theory and the
floating-point method allow: `≤ tol` for residuals and defects that vanish in exact arithmetic
(round-off tolerances are a few hundred ulps of the data), `≥ tol` for a quantity that must not
vanish (the negative controls), and `p ± δ` for the fitted order p of a smooth limit.  A check that
raises an exception fails with the message under *Failures*.  The convergence tables list the
error at each resolution n, the observed order between consecutive n, log(e_i/e_(i+1)) /
log(n_(i+1)/n_i), and the least-squares fitted order; `--quick` uses fewer resolutions, so its
orders are pre-asymptotic where the full run's are not."""


def _value(outcome: Outcome) -> str:
    v = outcome.value
    if outcome.skipped:
        return "—"
    if outcome.error is not None:
        return "error"
    if outcome.check.target is not None:
        return f"{v:.3f}"
    if float(v).is_integer() and abs(v) < 1e6:
        return f"{int(v)}"
    return f"{v:.2e}"


def _sizes(sizes: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in sizes.items()) if sizes else "—"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _relative(path: Path, out: Path) -> str:
    return Path(os.path.relpath(path, out)).as_posix()


def _check_tables(outcomes: list[Outcome]) -> list[str]:
    lines = []
    for section, group in groupby(outcomes, key=lambda o: o.check.section):
        lines += [f"### {section}", "",
                  "| statement | reference | quantity | value | tolerance | result | sizes | time (s) |",
                  "|---|---|---|---:|---|---|---|---:|"]
        for o in group:
            c = o.check
            result = "full run only" if o.skipped else "pass" if o.passed else "**FAIL**"
            lines.append(
                f"| {_cell(c.statement)} | {_cell(c.reference)} | {_cell(c.quantity)} | {_value(o)} | "
                f"{_cell(c.tolerance)} | {result} | {_cell(_sizes(o.sizes))} | {o.seconds:.1f} |"
            )
        lines.append("")
    return lines


def _failures(outcomes: list[Outcome]) -> list[str]:
    failed = [o for o in outcomes if not o.passed]
    if not failed:
        return []
    lines = ["## Failures", ""]
    for o in failed:
        why = o.error or f"value {_value(o)} does not meet {o.check.tolerance}"
        lines.append(f"- `{o.check.name}` ({_cell(o.check.reference)}): {_cell(why)}")
    return lines + [""]


def _convergence(outcomes: list[Outcome], out: Path) -> list[str]:
    lines = []
    for o in outcomes:
        for table, picture in o.tables:
            lines += [f"### {o.check.statement} ({o.check.reference})", "", table.to_markdown(), "",
                      f"![{picture.stem}]({_relative(picture, out)})", ""]
    return (["## Smooth limits: observed orders", ""] + lines) if lines else []


def _figures(outcomes: list[Outcome], out: Path) -> list[str]:
    lines = []
    for o in outcomes:
        for path in o.figures:
            lines += [f"**{o.check.reference}**: {o.check.statement}", "",
                      f"![{path.stem}]({_relative(path, out)})", ""]
    return (["## Figures", ""] + lines) if lines else []


def figure_paths(outcomes: list[Outcome]) -> list[Path]:
    """Every figure the report refers to."""
    return [p for o in outcomes for p in o.figures] + [p for o in outcomes for _, p in o.tables]


def write_report(outcomes: list[Outcome], out, *, quick: bool, seconds: float, header: str = "") -> Path:
    """Write `out/report.md` and return its path.  Every figure path it names was recorded by
    the check that drew it (`Context.figure`)."""
    import jax

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    passed = sum(o.passed and not o.skipped for o in outcomes)
    skipped = sum(o.skipped for o in outcomes)
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "# ddgjax verify report", "",
        f"`ddgjax verify{' --quick' if quick else ''}`: {len(outcomes)} checks in {seconds:.0f} s, {when}, "
        f"ddgjax {__version__}, jax {jax.__version__} on {jax.default_backend()}.", "",
        f"**{passed} of {len(outcomes) - skipped} checks passed.**"
        + ("" if passed + skipped == len(outcomes) else " See Failures.")
        + (f" {skipped} more run only in the full run (`ddgjax verify`)." if skipped else ""), "",
    ]
    lines += [LEGEND, ""]
    if header:
        lines += [header, ""]
    lines += ["## Checks", ""] + _check_tables(outcomes)
    lines += _failures(outcomes) + _convergence(outcomes, out) + _figures(outcomes, out)
    path = out / "report.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path
