"""Smooth limits: observed orders of convergence of a discrete quantity to its smooth value.

For errors `e(n)` at resolutions `n_1 < n_2 < …` the observed order between consecutive
resolutions is `p_i = log(e_i / e_{i+1}) / log(n_{i+1} / n_i)`, and the fitted order is the
least-squares slope of `−log e` against `log n`.  An error `O(h²)` with `h ∝ 1/n` has order 2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from .errors import InvalidInputError

__all__ = ["ConvergenceTable", "convergence", "observed_orders", "fitted_order"]


def observed_orders(ns: Sequence[float], errors: Sequence[float]) -> np.ndarray:
    """`p_i = log(e_i / e_{i+1}) / log(n_{i+1} / n_i)`, one fewer than the resolutions."""
    ns, errors = np.asarray(ns, float), np.asarray(errors, float)
    return np.log(errors[:-1] / errors[1:]) / np.log(ns[1:] / ns[:-1])


def fitted_order(ns: Sequence[float], errors: Sequence[float]) -> float:
    """Least-squares slope of `−log e` against `log n`."""
    slope, _ = np.polyfit(np.log(np.asarray(ns, float)), np.log(np.asarray(errors, float)), 1)
    return float(-slope)


@dataclass(frozen=True)
class ConvergenceTable:
    """Errors at increasing resolutions with their observed and fitted orders."""

    ns: np.ndarray
    errors: np.ndarray
    orders: np.ndarray
    fitted_order: float
    label: str = "error"

    @classmethod
    def from_errors(cls, ns, errors, label: str = "error") -> "ConvergenceTable":
        ns = np.asarray(ns, dtype=float)
        errors = np.asarray(errors, dtype=float)
        _validate(ns, errors)
        return cls(ns, errors, observed_orders(ns, errors), fitted_order(ns, errors), label)

    def to_markdown(self) -> str:
        label = self.label.replace("|", "\\|")  # a label such as |γ − γ_h| must not split the column
        lines = [f"| n | {label} | observed order |", "|---:|---:|---:|"]
        for i, (n, e) in enumerate(zip(self.ns, self.errors)):
            order = "" if i == 0 else f"{self.orders[i - 1]:.3f}"
            lines.append(f"| {n:g} | {e:.3e} | {order} |")
        lines.append(f"\nfitted order: {self.fitted_order:.3f}")
        return "\n".join(lines)

    def plot(self, path=None, *, title: str | None = None):
        """Log-log plot of the errors against n with a reference line of slope −fitted order
        (drawn by `ddgjax.plot.convergence`): the figure, or `path` after saving there."""
        from .plot.lines import convergence as draw  # output layer, loaded on use

        return draw(self, path, title=title)


def _validate(ns: np.ndarray, errors: np.ndarray) -> None:
    if ns.ndim != 1 or ns.shape != errors.shape or ns.size < 2:
        raise InvalidInputError(f"need at least two resolutions with one error each, got ns {ns.shape}, errors {errors.shape}")
    if np.any(np.diff(ns) <= 0):
        i = int(np.argwhere(np.diff(ns) <= 0)[0][0])
        raise InvalidInputError(f"resolutions must increase: ns[{i}] = {ns[i]:g} >= ns[{i + 1}] = {ns[i + 1]:g}")
    bad = np.flatnonzero(~(np.isfinite(errors) & (errors > 0)))
    if bad.size:
        i = int(bad[0])
        raise InvalidInputError(
            f"error at n = {ns[i]:g} (index {i}) is {errors[i]}: orders need finite positive errors"
        )


def convergence(error_of_n: Callable[[int], float], ns: Sequence[int], label: str = "error") -> ConvergenceTable:
    """Evaluate `error_of_n(n)` for each `n` in `ns` and tabulate the orders of convergence."""
    errors = [float(error_of_n(n)) for n in ns]
    return ConvergenceTable.from_errors(ns, errors, label)
