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


def test_trapezoid_rule_has_order_two():
    table = dg.limits.convergence(trapezoid_error, [8, 16, 32, 64, 128])
    assert abs(table.fitted_order - 2) <= 0.01
    assert np.all(np.abs(table.orders - 2) <= 0.02)
    md = table.to_markdown()
    assert "fitted order: 2.00" in md and md.count("\n|") == 6


def assert_convergence_plot_shows(fig, table):
    """`table.plot()`: one 2-D log-log axes with the errors against n (labelled with the table's
    label) and a straight reference line of slope −(fitted order) through the first error, both
    inside the view; the title names the fitted order."""
    (ax,) = fig.axes
    assert ax.name == "rectilinear" and ax.get_xscale() == ax.get_yscale() == "log"
    errors, reference = ax.lines
    np.testing.assert_array_equal(errors.get_xdata(), table.ns)
    np.testing.assert_array_equal(errors.get_ydata(), table.errors)
    np.testing.assert_array_equal(reference.get_xdata(), table.ns)
    assert reference.get_ydata()[0] == table.errors[0] and reference.get_linestyle() == "--"
    slope, _ = np.polyfit(np.log(reference.get_xdata()), np.log(reference.get_ydata()), 1)
    assert abs(slope + table.fitted_order) <= 1e-12
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= table.ns.min() and x1 >= table.ns.max()
    assert y0 <= min(table.errors.min(), reference.get_ydata().min()) and y1 >= table.errors.max()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [table.label, f"slope −{table.fitted_order:.2f}"]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("n", table.label)
    assert ax.get_title() == f"fitted order {table.fitted_order:.2f}"


def test_convergence_plot_shows_the_table(tmp_path):
    import matplotlib.pyplot as plt

    table = dg.limits.convergence(trapezoid_error, [8, 16, 32, 64], label="|I − I_h|")
    fig = table.plot()
    assert_convergence_plot_shows(fig, table)
    noisy = dg.limits.ConvergenceTable.from_errors(table.ns, table.errors * [1.0, 1.3, 0.8, 1.1], table.label)
    with pytest.raises(AssertionError):  # negative control: another table's errors and slope
        assert_convergence_plot_shows(fig, noisy)
    plt.close(fig)
    fig = dg.plot.convergence(table, title="trapezoid rule")
    assert fig.axes[0].get_title() == "trapezoid rule"
    plt.close(fig)
    open_figures = len(plt.get_fignums())
    path = table.plot(tmp_path / "order.png")  # with a path: written, closed, the path returned
    assert path == tmp_path / "order.png" and len(plt.get_fignums()) == open_figures
    assert plt.imread(path).shape == (420, 540, 4)  # 4.5 × 3.5 in at 120 dpi


def test_convergence_plot_ticks_the_resolutions(tmp_path):
    """The n axis is ticked at the table's resolutions, labelled "16" … "1024"; an error axis
    spanning two decades or more has only its decades (no minor ticks), a narrower one keeps
    matplotlib's labelled minor ticks.  Negative control: a plain log-log axes has minor ticks."""
    import matplotlib.pyplot as plt

    ns = [16, 32, 64, 128, 256, 512, 1024]
    wide = dg.limits.ConvergenceTable.from_errors(np.array(ns), 3.0 / np.array(ns, dtype=float) ** 2)
    fig = dg.plot.convergence(wide)
    fig.canvas.draw()
    ax = fig.axes[0]
    np.testing.assert_array_equal(ax.get_xticks(), ns)
    assert [t.get_text() for t in ax.get_xticklabels()] == [str(n) for n in ns]
    assert len(ax.xaxis.get_minorticklocs()) == 0 and len(ax.yaxis.get_minorticklocs()) == 0
    plt.close(fig)
    narrow = dg.limits.ConvergenceTable.from_errors(np.array([8, 16, 32]), np.array([1.1e-3, 1.0e-3, 0.95e-3]))
    fig = dg.plot.convergence(narrow)
    fig.canvas.draw()
    assert any(t.get_text() for t in fig.axes[0].yaxis.get_minorticklabels())
    plt.close(fig)
    fig, ax = plt.subplots()
    ax.loglog(wide.ns, wide.errors)
    fig.canvas.draw()
    assert len(ax.yaxis.get_minorticklocs()) > 0
    plt.close(fig)


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
