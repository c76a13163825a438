"""Figures of triangulations with their non-Delaunay edges highlighted (Fig 7.14, 7.15).

Edges are drawn as straight segments between the vertex positions: exact for flat surfaces in
the plane, chords of the geodesic edges otherwise.  matplotlib (Agg) is imported inside the
functions, never when ddgjax is imported.  `triangulation` returns the figure, or, when `path` is
given, saves it there, closes it and returns `path`; `before_after` returns the flip result too.
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..intrinsic.delaunay import DELAUNAY_TOL, delaunay_edges, flip_to_delaunay
from ..intrinsic.triangulation import Triangulation, from_mesh
from ._figure import pyplot, save_figure

__all__ = ["before_after", "triangulation"]



def triangulation(tri: Triangulation, V, ax=None, *, path=None, title: str | None = None,
                  tol: float = DELAUNAY_TOL):
    """Draw the edges of `tri` at the positions `V` (nv, 2) or (nv, 3, first two coordinates) on
    2-D axes (`ax`, else a new figure's): two line collections, the Delaunay edges thin and grey,
    the non-Delaunay edges (Prop 7.9) thick and red, labelled with their count in the legend, and
    the vertices as dots.

    Returns the figure, or `path` after saving there.
    """
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[0] != tri.n_vertices or V.shape[1] < 2:
        raise ShapeError(f"V must have shape ({tri.n_vertices}, 2 or 3), got {V.shape}")
    from matplotlib.collections import LineCollection

    if ax is None:
        _, ax = pyplot().subplots(figsize=(5, 5))
    ok = delaunay_edges(tri, tol)
    segments = V[tri.edges][:, :, :2]
    ax.add_collection(LineCollection(segments[ok], colors="0.45", linewidths=0.8))
    ax.add_collection(LineCollection(segments[~ok], colors="tab:red", linewidths=2.0,
                                     label=f"non-Delaunay ({int((~ok).sum())})"))
    ax.plot(V[:, 0], V[:, 1], "k.", ms=3)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.legend(loc="upper right", fontsize=8)
    if title:
        ax.set_title(title)
    return ax.figure if path is None else save_figure(ax.figure, path, dpi=120)


def before_after(V, F, path=None, *, tol: float = DELAUNAY_TOL):
    """Flip the triangulation (V, F) to its intrinsic Delaunay triangulation (Fig 7.13) and draw
    both: two 2-D axes, "start triangulation" and "after k flips", each by `triangulation`
    (non-Delaunay edges highlighted).

    Returns the `FlipResult` after saving the figure to `path` (PNG), or, when `path` is None,
    the pair `(FlipResult, figure)`.
    """
    plt = pyplot()
    tri = from_mesh(V, F)
    result = flip_to_delaunay(tri, tol=tol)
    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    triangulation(tri, V, axes[0], title="start triangulation", tol=tol)
    triangulation(result.triangulation, V, axes[1], title=f"after {result.n_flips} flips", tol=tol)
    if path is None:
        return result, fig
    save_figure(fig, path, dpi=120)
    return result
