"""Every statement registered with `ddgjax verify`, run as a test at its quick sizes.

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

LOAD_ERRORS = load_checks()
CHECKS = list(registry.values())


def _params():
    for c in CHECKS:
        marks = [pytest.mark.slow] if c.full_only else []
        yield pytest.param(c, id=c.name, marks=marks)


def test_every_check_module_imports():
    assert LOAD_ERRORS == {}


def test_checks_are_registered():
    assert len(CHECKS) >= 90


@pytest.mark.parametrize("check", list(_params()))
def test_reference_check(check, tmp_path):
    outcome = run_check(check, tmp_path, quick=not check.full_only)
    assert outcome.error is None, outcome.error
    assert math.isfinite(outcome.value)
    assert outcome.passed, f"{check.reference}: {check.quantity} = {outcome.value:.3e}, tolerance {check.tolerance}"


def test_negative_control_a_wrong_value_fails():
    """The comparison can fail: a check whose value misses its tolerance is reported failed."""
    c = next(c for c in CHECKS if c.at_most is not None)
    assert not c.passes(10 * c.at_most + 1.0)
    assert not c.passes(float("nan"))
