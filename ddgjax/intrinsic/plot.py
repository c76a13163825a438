"""Figures of triangulations with their non-Delaunay edges highlighted (Fig 7.14, 7.15).

Edges are drawn as straight segments between the vertex positions: exact for flat surfaces in
the plane, chords of the geodesic edges otherwise.  matplotlib (Agg) is imported inside the
functions, never when ddgjax is imported.
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from .delaunay import DELAUNAY_TOL, delaunay_edges, flip_to_delaunay
from .triangulation import Triangulation, from_mesh

__all__ = ["before_after", "draw_fig_7_26", "triangulation"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def triangulation(tri: Triangulation, V, ax=None, *, title: str | None = None, tol: float = DELAUNAY_TOL):
    """Draw the edges of `tri` at the positions `V` (nv, 2) or (nv, 3, first two coordinates):
    Delaunay edges thin and grey, non-Delaunay edges (Prop 7.9) thick and red.  Returns the
    axes."""
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[0] != tri.n_vertices or V.shape[1] < 2:
        raise ShapeError(f"V must have shape ({tri.n_vertices}, 2 or 3), got {V.shape}")
    from matplotlib.collections import LineCollection

    if ax is None:
        _, ax = _pyplot().subplots(figsize=(5, 5))
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
    return ax


def before_after(V, F, path, *, tol: float = DELAUNAY_TOL):
    """Two panels: the triangulation (V, F) and its intrinsic Delaunay triangulation after edge
    flipping (Fig 7.13), non-Delaunay edges highlighted; saved to `path` (PNG).  Returns the
    `FlipResult`."""
    plt = _pyplot()
    tri = from_mesh(V, F)
    result = flip_to_delaunay(tri, tol=tol)
    fig, axes = plt.subplots(1, 2, figsize=(10, 5))
    triangulation(tri, V, axes[0], title="start triangulation", tol=tol)
    triangulation(result.triangulation, V, axes[1], title=f"after {result.n_flips} flips", tol=tol)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return result


def draw_fig_7_26(path, V, F, cotan, narrow):
    """Three surfaces (the start, the last Fig 6.5 iterate, the Fig 7.23 result) above the two
    residual histories; saved to `path` (PNG)."""
    plt = _pyplot()
    fig = plt.figure(figsize=(12.0, 7.5))
    panels = ((V, F, "start (skinny triangles)"), (cotan[0], F, f"Fig 6.5 after {cotan[2]['iterations']} steps"),
              (narrow[0], narrow[1], f"Fig 7.23 after {narrow[2]['iterations']} steps"))
    for k, (X, G, title) in enumerate(panels):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        G = np.asarray(G)
        G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 2] != G[:, 0])]
        ax.plot_trisurf(X[:, 0], X[:, 1], X[:, 2], triangles=G, color="lightsteelblue", edgecolor="k", linewidth=0.2)
        ax.set_title(title, fontsize=10)
        ax.set_box_aspect((1, 1, 0.6))
        ax.set_axis_off()
    ax = fig.add_subplot(2, 1, 2)
    for (_, _, info), label in ((cotan, "Fig 6.5 (cotan Laplacian of the surface)"),
                                (narrow, "Fig 7.23 (flips + Laplace–Beltrami)")):
        ax.semilogy(np.maximum(info["history"], 1e-300), "o-", ms=3, label=label)
    ax.set_xlabel("iteration")
    ax.set_ylabel("max |Δf| at free vertices")
    ax.legend(fontsize=9)
    fig.suptitle("Fig 7.26: a start unsuited to the minimal surface")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
