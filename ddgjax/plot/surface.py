"""Figures of polyhedral surfaces coloured by curvature (matplotlib, Agg backend).

matplotlib is imported inside the function, never when ddgjax is imported.  `surface` returns
the figure, or, when `path` is given, saves it there, closes it and returns `path`.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError, ShapeError
from ..mesh import angle_defect, edge_mean_curvature, edges
from ..mesh.connectivity import faces_as_corners
from ._figure import pyplot, save_figure

__all__ = ["surface", "face_values"]


def face_values(V, F, color_by="angle_defect") -> np.ndarray:
    """One number per face for colouring.

    `color_by`: "angle_defect" (the mean of K(p) over the face's vertices, Def 5.2),
    "mean_curvature" (the mean of H(e) over the face's edges, Def 5.3), or an array of
    per-face values (nf,).  Raises `InvalidInputError` for an unknown name and `ShapeError` for
    an array of the wrong length.
    """
    vertex, face, nxt = faces_as_corners(F)
    nf = int(face.max()) + 1
    if isinstance(color_by, str):
        if color_by == "angle_defect":
            per_corner = np.asarray(angle_defect(V, F))[vertex]
        elif color_by == "mean_curvature":
            E = edges(F)
            lo, hi = np.minimum(vertex, vertex[nxt]), np.maximum(vertex, vertex[nxt])
            index = np.searchsorted(E[:, 0] * (E.max() + 1) + E[:, 1], lo * (E.max() + 1) + hi)
            per_corner = np.asarray(edge_mean_curvature(V, F))[index]
        else:
            raise InvalidInputError(f"color_by must be 'angle_defect', 'mean_curvature' or an array, got {color_by!r}")
        return np.bincount(face, per_corner, nf) / np.bincount(face, minlength=nf)
    values = np.asarray(color_by, dtype=float)
    if values.shape != (nf,):
        raise ShapeError(f"color_by must have one value per face, shape ({nf},), got {values.shape}")
    return values


def surface(V, F, path=None, *, color_by="angle_defect", cmap="coolwarm", title=None, label=None, ax=None):
    """Draw the faces of (V, F) with a Poly3DCollection, one polygon per face, coloured by
    `face_values(V, F, color_by)` on a colour scale symmetric about 0 (elliptic / hyperbolic in
    different hues), with a colour bar labelled `label` (default: the name `color_by`, or "value"
    for an array); the axes are a cube around the vertices' bounding box.

    `ax`: 3-D axes to draw into (the colour bar goes beside them), else a new figure's.
    Returns the figure, or `path` after saving there (PNG or any matplotlib format).
    """
    import matplotlib
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    values = face_values(V, F, color_by)
    V = np.asarray(V, dtype=float)
    vertex, face, _ = faces_as_corners(F)
    polygons = np.split(V[vertex], np.flatnonzero(np.diff(face)) + 1)
    scale = max(float(np.max(np.abs(values))), 1e-300)
    norm = matplotlib.colors.Normalize(-scale, scale)
    colormap = pyplot().get_cmap(cmap)
    if ax is None:
        ax = pyplot().figure(figsize=(5.0, 4.5)).add_subplot(projection="3d")
    fig = ax.figure
    ax.add_collection3d(Poly3DCollection(polygons, facecolors=colormap(norm(values)), edgecolors="k", linewidths=0.2))
    lo, hi = V.min(axis=0), V.max(axis=0)
    centre, radius = (lo + hi) / 2, max(float(np.max(hi - lo)) / 2, 1e-12)
    ax.set(xlim=(centre[0] - radius, centre[0] + radius), ylim=(centre[1] - radius, centre[1] + radius),
           zlim=(centre[2] - radius, centre[2] + radius))
    if label is None:
        label = color_by if isinstance(color_by, str) else "value"
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=colormap), ax=ax, shrink=0.7, pad=0.1, label=label)
    if title:
        ax.set_title(title)
    if path is None:
        return fig
    return save_figure(fig, path, dpi=110, tight=False)
