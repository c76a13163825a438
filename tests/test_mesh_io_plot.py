"""meshio round trips and the curvature surface plot."""

import numpy as np
import pytest

from ddgjax import mesh
from ddgjax.plot import surface as plot_surface
from ddgjax.errors import InvalidInputError, ShapeError


@pytest.mark.parametrize("suffix", [".obj", ".off", ".vtk"])
def test_meshio_round_trip_keeps_the_surface(tmp_path, suffix):
    """Write and read back: same vertices, faces and χ; quads survive in .vtk and .obj."""
    for V, F in (mesh.torus(8, 5), mesh.cube()):
        if suffix == ".off" and F.shape[1] == 4:
            continue
        path = tmp_path / f"m{F.shape[1]}{suffix}"
        mesh.write(path, V, F)
        V2, F2 = mesh.read(path)
        assert np.max(np.abs(V2 - V)) < 1e-12
        assert np.array_equal(F2, F)
        assert mesh.euler_characteristic(F2) == mesh.euler_characteristic(F)


def test_meshio_mixed_polygons(tmp_path):
    """A pyramid (one quad, four triangles) comes back as a list with the same χ = 2."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]])
    F = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    mesh.write(tmp_path / "p.vtk", V, F)
    _, F2 = mesh.read(tmp_path / "p.vtk")
    assert sorted(map(tuple, F2)) == sorted(map(tuple, F))
    assert mesh.euler_characteristic(F2) == 2


def test_face_values_average_the_curvature():
    """On the cube every face averages K = π/2 and H(e) = (π/2)/2 = π/4."""
    V, F = mesh.cube()
    assert np.allclose(plot_surface.face_values(V, F, "angle_defect"), np.pi / 2, atol=1e-14, rtol=0)
    assert np.allclose(plot_surface.face_values(V, F, "mean_curvature"), np.pi / 4, atol=1e-14, rtol=0)
    with pytest.raises(InvalidInputError, match="color_by"):
        plot_surface.face_values(V, F, "gauss")
    with pytest.raises(ShapeError, match=r"\(6,\)"):
        plot_surface.face_values(V, F, np.ones(5))


def test_surface_plot_writes_png(tmp_path):
    V, F = mesh.torus(10, 6)
    path = plot_surface.surface(V, F, tmp_path / "torus.png", color_by="mean_curvature")
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
