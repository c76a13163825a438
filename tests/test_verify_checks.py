"""Every statement registered with `ddgjax verify`, run at its quick sizes, a test per group of
checks that share cached solutions (as `ddgjax verify` runs a group in one process).

The reference checks live once, in `ddgjax/verify/checks/`; `tests/` keeps API behaviour, errors
and properties.  A check's value is compared with its own tolerance (`Check.passes`); checks
registered `full_only` (their compilation alone is long) run at their full sizes under
`@pytest.mark.slow` (`make test-all`).
"""

from __future__ import annotations

import math

import pytest

from ddgjax.verify import load_checks, registry
from ddgjax.verify._registry import run_check
from ddgjax.verify._run import _group

LOAD_ERRORS = load_checks()
CHECKS = list(registry.values())


def _params():
    """One test per group of checks (`ddgjax.verify._run._group`: the checks of one module, or of
    modules with the same `GROUP`), run in one process as `ddgjax verify` runs them, so that they
    share the solutions their modules cache instead of each pytest-xdist worker solving and
    compiling them again; `full_only` checks in a slow test of their own per group."""
    groups: dict[tuple[str, bool], list] = {}
    for c in CHECKS:
        groups.setdefault((_group(c), c.full_only), []).append(c)
    for (group, full_only), checks in groups.items():
        marks = [pytest.mark.slow] if full_only else []
        yield pytest.param(checks, id=group.removeprefix("ddgjax.verify.checks.") + ("-full" if full_only else ""),
                           marks=marks)


def failures(checks, out) -> list[str]:
    """A line per check of `checks` that fails: an error, a value that is not finite, or one that
    misses its tolerance."""
    lines = []
    for check in checks:
        outcome = run_check(check, out, quick=not check.full_only)
        if outcome.error is not None:
            lines.append(f"{check.name} ({check.reference}): {outcome.error}")
        elif not math.isfinite(outcome.value) or not outcome.passed:
            lines.append(f"{check.name} ({check.reference}): {check.quantity} = {outcome.value:.3e}, "
                         f"tolerance {check.tolerance}")
    return lines


@pytest.mark.parametrize("checks", list(_params()))
def test_reference_checks(checks, tmp_path):
    assert failures(checks, tmp_path) == []


def test_every_check_is_in_one_group():
    assert sorted(c.name for p in _params() for c in p.values[0]) == sorted(c.name for c in CHECKS)


def test_negative_control_a_wrong_value_fails():
    """The comparison can fail: a check whose value misses its tolerance is reported failed."""
    c = next(c for c in CHECKS if c.at_most is not None)
    assert not c.passes(10 * c.at_most + 1.0)
    assert not c.passes(float("nan"))


def test_negative_control_a_failing_or_crashing_check_is_a_failure_of_its_group(tmp_path):
    """The group test can fail: a check whose function returns a value past its tolerance, or
    raises, is listed by name among the group's failures."""
    import dataclasses

    c = next(c for c in CHECKS if c.at_most is not None and not c.full_only)
    wrong = dataclasses.replace(c, fn=lambda ctx, **sizes: 10 * c.at_most + 1.0)

    def crash(ctx, **sizes):
        raise RuntimeError("boom")

    lines = failures([wrong, dataclasses.replace(c, fn=crash)], tmp_path)
    assert len(lines) == 2 and all(line.startswith(c.name) for line in lines) and "boom" in lines[1]
