"""The one place that loads matplotlib and writes figures.

matplotlib is imported, and switched to the non-interactive Agg backend, on the first call,
never when ddgjax is imported.
"""

from __future__ import annotations

__all__ = ["pyplot", "save_figure"]


def pyplot():
    """`matplotlib.pyplot` with the Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path, dpi: int = 120, *, tight: bool = True):
    """Lay out `fig` (`tight`: matplotlib's tight layout), write it to `path` (PNG by its
    suffix), close it; returns `path`."""
    if tight:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
    return path
