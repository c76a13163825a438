"""The one place that loads matplotlib and writes figures.

matplotlib is imported, and switched to the non-interactive Agg backend, on the first call,
never when ddgjax is imported.
"""

from __future__ import annotations

import functools
import re

__all__ = ["plain_log_labels", "pyplot", "save_figure"]


def pyplot():
    """`matplotlib.pyplot` with the Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path, dpi: int = 120, *, tight: bool = True):
    """Lay out `fig` (`tight`: matplotlib's tight layout; log axes labelled by
    `plain_log_labels`), write it to `path` (PNG by its suffix), close it; returns `path`."""
    for ax in fig.axes:
        plain_log_labels(ax)
    if tight:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
    return path


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
_MATHTEXT_NUMBER = re.compile(r"^\$\\mathdefault\{(-?)(?:([0-9.]+)\\times)?(?:([0-9.]+)\^\{(-?[0-9]+)\}|([0-9.e+-]+))\}\$$")


def plain_number(label: str) -> str:
    """A tick label of matplotlib's log formatter, `$\\mathdefault{2\\times10^{-3}}$`, as plain
    text with Unicode superscripts, "2×10⁻³" (other labels unchanged)."""
    match = _MATHTEXT_NUMBER.match(label)
    if match is None:
        return label
    sign, coefficient, base, exponent, plain = match.groups()
    sign = "−" if sign else ""  # matplotlib's minus sign (axes.unicode_minus)
    if plain is not None:
        return sign + plain
    return sign + (f"{coefficient}×" if coefficient else "") + base + exponent.translate(_SUPERSCRIPT)


def plain_log_labels(ax) -> None:
    """Give the log-scaled x and y axes of `ax` that carry matplotlib's default tick labels the
    same labels as plain text ("10⁻³", "2×10⁻⁴" by `plain_number`): matplotlib typesets its own
    as mathtext, whose parser is most of the time of drawing a small log-log figure."""
    from matplotlib.ticker import LogFormatterSciNotation

    for axis in (ax.xaxis, ax.yaxis):
        for formatter, setter in ((axis.get_major_formatter(), axis.set_major_formatter),
                                  (axis.get_minor_formatter(), axis.set_minor_formatter)):
            if type(formatter) is LogFormatterSciNotation:  # matplotlib's default, not one set by a caller
                plain = _plain_log_formatter()()
                plain.__dict__.update(formatter.__dict__)  # its base, which ticks it labels, its axis
                setter(plain)


@functools.cache
def _plain_log_formatter() -> type:
    """matplotlib's `LogFormatterSciNotation` with its labels passed through `plain_number`."""
    from matplotlib.ticker import LogFormatterSciNotation

    class PlainLogFormatter(LogFormatterSciNotation):
        def __call__(self, x, pos=None):
            return plain_number(super().__call__(x, pos))

    return PlainLogFormatter
