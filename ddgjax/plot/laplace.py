"""Figures of harmonic functions and simplicial minimal surfaces (Sec 6), matplotlib Agg.

matplotlib is imported inside the functions, never when ddgjax is imported.  Each function
returns the figure, or, when `path` is given, saves it there, closes it and returns `path`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ShapeError
from ..mesh import angle_defect
from ..mesh.connectivity import from_faces
from ..mesh.curvature import boundary_vertex_mask
from ._figure import pyplot, save_figure
from .surface import surface

__all__ = ["harmonic_function", "minimal_surface"]



def harmonic_function(V, F, f, path=None, *, title: str = "discrete harmonic function", cmap: str = "viridis"):
    """Draw the piecewise affine function f (nv,) on the triangle mesh (V, F).

    Planar meshes (z ≡ const) are drawn flat: one 2-D axes with f Gouraud-shaded over the
    triangles (`tripcolor`), 12 contour lines, the triangle edges and a colour bar labelled "f".
    Others are drawn in 3-D by `surface.surface`, faces coloured by the mean of f over their
    vertices.  Returns the figure, or `path` (a `Path`) after saving there.
    **Raises:** `ShapeError` when f does not have one value per vertex.
    """
    V, F, f = np.asarray(V, float), np.asarray(F), np.asarray(f, float)
    if f.shape != (len(V),):
        raise ShapeError(f"f must have one value per vertex, shape ({len(V)},), got {f.shape}")
    if V.shape[1] == 3 and np.ptp(V[:, 2]) > 1e-12 * max(np.ptp(V), 1e-300):
        fig = surface(V, F, color_by=f[F].mean(axis=1), cmap=cmap, title=title)
        return fig if path is None else Path(save_figure(fig, path, dpi=110, tight=False))
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.0, 4.5))
    shading = ax.tripcolor(V[:, 0], V[:, 1], F, f, shading="gouraud", cmap=cmap)
    ax.tricontour(V[:, 0], V[:, 1], F, f, levels=12, colors="k", linewidths=0.4)
    ax.triplot(V[:, 0], V[:, 1], F, color="w", linewidth=0.15, alpha=0.5)
    ax.set_aspect("equal")
    ax.set_title(title)
    fig.colorbar(shading, ax=ax, shrink=0.8, label="f")
    return fig if path is None else Path(save_figure(fig, path, dpi=110, tight=False))


def minimal_surface(V, F, path=None, *, history=None, title: str = "simplicial minimal surface"):
    """Draw a simplicial minimal surface in 3-D (`surface.surface`) coloured by its angle defect
    K at the interior vertices (Def 5.2; a minimal surface is saddle-shaped, K ≤ 0; boundary
    vertices count 0, so that their turning angles do not swamp the scale), and, when `history`
    (the area-gradient residuals of `energies.area.minimal_surface`'s `info`) is given, its
    convergence beside it: a second, 2-D axes with the residuals against the iteration, log scale.

    Returns the figure, or `path` (a `Path`) after saving there.
    """
    F = np.asarray(F)
    K = np.where(boundary_vertex_mask(from_faces(F, n_vertices=len(V))), 0.0, np.asarray(angle_defect(V, F)))
    if history is None:
        fig = surface(V, F, color_by=K[F].mean(axis=1), label="angle defect K", title=title)
    else:
        fig = pyplot().figure(figsize=(10.0, 4.5))
        grid = fig.add_gridspec(1, 2, width_ratios=[1.2, 1], left=0.02, right=0.97, bottom=0.12, wspace=0.3)
        surface(V, F, color_by=K[F].mean(axis=1), label="angle defect K", title=title,
                ax=fig.add_subplot(grid[0], projection="3d"))
        right = fig.add_subplot(grid[1])
        history = np.asarray(history, float)
        right.semilogy(np.arange(len(history)), np.maximum(history, 1e-300), "o-", markersize=3)
        right.set_xlabel("iteration")
        right.set_ylabel("max |∇A| at interior vertices")
        right.set_title("convergence")
    return fig if path is None else Path(save_figure(fig, path, dpi=110, tight=False))
