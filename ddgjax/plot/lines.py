"""Figures of discrete curves and convergence tables (matplotlib, Agg backend).

matplotlib is imported and switched to the non-interactive Agg backend inside each function,
never when ddgjax is imported.  Each function returns the figure, or, when `path` is given,
saves it there, closes it and returns `path`; `animate_spin_chain` always writes its `path`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..curves import Curve, _as_curve
from ..errors import InvalidInputError
from ..limits import ConvergenceTable
from ._figure import pyplot, save_figure

__all__ = ["curve", "curves", "convergence", "spin_chain", "animate_spin_chain"]



def _axes(ax, dim: int):
    """`ax` or a new figure's axes, 3-D for space curves."""
    if ax is not None:
        return ax
    fig = pyplot().figure(figsize=(4.5, 4.0))
    return fig.add_subplot(projection="3d" if dim == 3 else None)


def _polyline(gamma, closed: bool) -> np.ndarray:
    """The vertices as a numpy array, with the first repeated at the end of a closed curve."""
    points = np.asarray(_as_curve(gamma, closed))
    return np.vstack([points, points[:1]]) if closed else points


def _finish(ax, path):
    fig = ax.figure
    if ax.name != "3d":
        ax.set_aspect("equal", adjustable="datalim")
    return fig if path is None else save_figure(fig, path)


def curve(gamma: Curve, ax=None, closed: bool = False, *, path=None, vertices: bool = True, **kw):
    """Draw one polyline, (N, 2) in the plane or (N, 3) in space; `kw` go to `ax.plot`.

    `vertices=True` marks the vertices.  Returns the figure, or `path` after saving there.
    """
    points = _polyline(gamma, closed)
    ax = _axes(ax, points.shape[1])
    kw.setdefault("marker", "o" if vertices else None)
    kw.setdefault("markersize", 2.5)
    ax.plot(*points.T, **kw)
    return _finish(ax, path)


def curves(
    gammas: Sequence[Curve],
    ax=None,
    closed: bool = False,
    *,
    path=None,
    cmap: str = "viridis",
    labels: Sequence[str] | None = None,
    **kw,
):
    """Draw a family of polylines (e.g. elastica at increasing load), coloured along `cmap`.

    All curves must have the same dimension.  `labels` (one per curve) adds a legend; `kw` go to
    `ax.plot`.  Returns the figure, or `path` after saving there.
    """
    polylines = [_polyline(gamma, closed) for gamma in gammas]
    if not polylines:
        raise InvalidInputError("curves: the family is empty, nothing to draw")
    ax = _axes(ax, polylines[0].shape[1])
    colours = pyplot().get_cmap(cmap)(np.linspace(0.0, 1.0, max(len(polylines), 2)))
    for i, points in enumerate(polylines):
        label = None if labels is None else labels[i]
        ax.plot(*points.T, color=colours[i], label=label, **kw)
    if labels is not None:
        ax.legend(fontsize="small")
    return _finish(ax, path)


def _ticks_at(axis, values) -> None:
    """Ticks of `axis` at `values` only, labelled as plain numbers ("16", "1024"): for the
    resolutions of a convergence table these say more than a log axis's decades, and matplotlib
    draws no minor ticks (on a log axis, most of the time of drawing a small figure)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    axis.set_major_locator(FixedLocator(np.asarray(values, dtype=float)))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_locator(NullLocator())


def _decades_only(axis, values) -> None:
    """No minor ticks on the log `axis` when `values` span two powers of ten or more (their
    decades label it; matplotlib would draw eight unlabelled minor ticks per decade)."""
    from matplotlib.ticker import NullLocator

    positive = np.asarray(values)[np.asarray(values) > 0]
    if positive.size and np.floor(np.log10(positive.max())) - np.ceil(np.log10(positive.min())) >= 1:
        axis.set_minor_locator(NullLocator())


CONVERGENCE_MARGINS = dict(left=0.2, right=0.96, bottom=0.14, top=0.9)
"""The axes of `convergence` in figure fractions: room for log tick labels and one-line labels."""


def convergence(table: ConvergenceTable, path=None, *, title: str | None = None):
    """Log-log plot of a `ddgjax.limits.ConvergenceTable`: one 2-D axes with the errors against n
    (points joined, labelled `table.label`) and a dashed reference line of slope −p through the
    first error, p the fitted order; a legend, and the title `title` or "fitted order p".  The
    n axis is ticked and labelled at the table's resolutions.

    Returns the figure, or `path` after saving there (= `table.plot(path)`).
    """
    fig, ax = pyplot().subplots(figsize=(4.5, 3.5))
    ax.loglog(table.ns, table.errors, "o-", label=table.label)
    reference = table.errors[0] * (table.ns / table.ns[0]) ** (-table.fitted_order)
    ax.loglog(table.ns, reference, "--", color="gray", label=f"slope −{table.fitted_order:.2f}")
    _ticks_at(ax.xaxis, table.ns)  # after the last loglog, which sets the axis's scale and locators anew
    _decades_only(ax.yaxis, np.concatenate([table.errors, reference]))
    ax.set_xlabel("n")
    ax.set_ylabel(table.label)
    # y given: the title sits at the top of the axes, where matplotlib would place it anyway (no
    # labels above the axes), without measuring every tick label at each draw to find the place
    ax.set_title(title or f"fitted order {table.fitted_order:.2f}", y=1.0)
    ax.legend()
    fig.subplots_adjust(**CONVERGENCE_MARGINS)  # fixed: matplotlib's tight layout would draw the figure twice
    return fig if path is None else save_figure(fig, path, tight=False)


def spin_chain(S, ax=None, *, path=None, title: str | None = None):
    """A closed chain of spins (N, 3) drawn as arrows standing on a ring in the plane z = 0.

    Returns the figure, or `path` after saving there.
    """
    S = np.asarray(S)
    ax = _axes(ax, 3)
    angle = 2 * np.pi * np.arange(len(S)) / len(S)
    base = np.stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)], axis=1)
    ax.plot(*np.vstack([base, base[:1]]).T, color="gray", lw=0.8)
    ax.quiver(*base.T, *S.T, length=0.3, normalize=True, color="C0")
    ax.set_zlim(-0.5, 0.5)
    if title:
        ax.set_title(title)
    return _finish(ax, path)


def animate_spin_chain(Ss, path, *, times=None, fps: int = 10):
    """An animated GIF of a spin chain evolving (frames Ss: (frames, N, 3)), one `spin_chain`
    per frame; matplotlib's Pillow writer.  Writes `path` (required) and returns it."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    plt = pyplot()
    fig = plt.figure(figsize=(4.0, 3.6))
    ax = fig.add_subplot(projection="3d")

    def frame(i):
        ax.clear()
        spin_chain(Ss[i], ax, title=None if times is None else f"t = {float(times[i]):.2f}")

    FuncAnimation(fig, frame, frames=len(Ss)).save(path, writer=PillowWriter(fps=fps))
    plt.close(fig)
    return path
