"""Reading and writing surface meshes through meshio (.obj, .off, .ply, .vtk, .stl, ...)."""

from __future__ import annotations

import numpy as np

from ..errors import MeshError
from .connectivity import faces_as_corners

__all__ = ["read", "write"]

_CELL_TYPES = {3: "triangle", 4: "quad"}


def read(path):
    """`(V, F)` from a mesh file: V (nv, 3) float64; F an (nf, k) int64 array when all faces have
    k corners, else a list of polygons.  Non-surface cells (lines, vertices) are ignored.

    **Raises:** `MeshError` if the file holds no triangles, quads or polygons.
    """
    import meshio

    m = meshio.read(path)
    V = np.asarray(m.points, dtype=np.float64)
    if V.shape[1] == 2:
        V = np.hstack([V, np.zeros((V.shape[0], 1))])
    blocks = [np.asarray(c.data, dtype=np.int64) for c in m.cells if c.type in ("triangle", "quad") or c.type.startswith("polygon")]
    if not blocks:
        raise MeshError(f"{path} contains no surface cells (triangles, quads or polygons)")
    if len({b.shape[1] for b in blocks}) == 1:
        return V, np.concatenate(blocks)
    return V, [list(f) for b in blocks for f in b.tolist()]


def write(path, V, F) -> None:
    """Write `(V, F)` to `path`, format from the extension; faces are grouped by corner count into
    meshio cell blocks ("triangle", "quad", "polygon").  Face order is kept within each size.
    """
    import meshio

    vertex, face, _ = faces_as_corners(F)
    sizes = np.bincount(face)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    cells = []
    for k in np.unique(sizes):
        rows = starts[sizes == k][:, None] + np.arange(k)[None]
        cells.append((_CELL_TYPES.get(int(k), "polygon"), vertex[rows]))
    meshio.write(path, meshio.Mesh(np.asarray(V, dtype=np.float64), cells))
