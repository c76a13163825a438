"""Smooth-limit tooling: observed and fitted orders."""

import numpy as np
import pytest

import ddgjax as dg
from ddgjax.errors import InvalidInputError


def trapezoid_error(n):
    """Composite trapezoid rule for ∫₀^π sin = 2: error = O(h²)."""
    x = np.linspace(0, np.pi, n + 1)
    y = np.sin(x)
    return abs(np.sum((y[1:] + y[:-1]) / 2) * (np.pi / n) - 2.0)


def test_trapezoid_rule_has_order_two(tmp_path):
    table = dg.limits.convergence(trapezoid_error, [8, 16, 32, 64, 128])
    assert abs(table.fitted_order - 2) <= 0.01
    assert np.all(np.abs(table.orders - 2) <= 0.02)
    md = table.to_markdown()
    assert "fitted order: 2.00" in md and md.count("\n|") == 6
    path = table.plot(tmp_path / "order.png")
    assert path.stat().st_size > 1000


def test_observed_orders_exact_power_law():
    ns = np.array([10, 20, 40])
    table = dg.limits.ConvergenceTable.from_errors(ns, 3.0 * ns**-1.5)
    np.testing.assert_allclose(table.orders, 1.5, rtol=1e-12)
    assert abs(table.fitted_order - 1.5) <= 1e-12


def test_bad_errors_are_named():
    with pytest.raises(InvalidInputError, match=r"n = 20 \(index 1\)"):
        dg.limits.ConvergenceTable.from_errors([10, 20], [1e-3, 0.0])
    with pytest.raises(InvalidInputError, match="must increase"):
        dg.limits.ConvergenceTable.from_errors([20, 10], [1e-3, 1e-4])


def test_markdown_escapes_bars_in_the_label():
    """A label such as "max |γ − γ_h|" stays in one column: every row has 3 cells."""
    table = dg.limits.ConvergenceTable.from_errors([8, 16], [1e-2, 2.5e-3], label="max |γ − γ_h|")
    rows = [line for line in table.to_markdown().splitlines() if line.startswith("|")]
    assert all(len(line.replace("\\|", "").strip("|").split("|")) == 3 for line in rows)
    assert abs(table.fitted_order - 2.0) <= 1e-12
