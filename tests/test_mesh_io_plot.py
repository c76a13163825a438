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


def _rows(colours) -> list:
    """RGBA rows as a sorted list: the colours drawn, whatever order the faces are painted in."""
    return sorted(map(tuple, np.round(np.asarray(colours), 12)))


def assert_surface_shows(fig, V, F, color_by):
    """`plot_surface.surface`'s figure of (V, F): 3-D axes and a colour bar; one polygon per face,
    coloured by `face_values(V, F, color_by)` on coolwarm symmetric about 0; the view a cube
    around the vertices."""
    import matplotlib

    ax, bar = fig.axes
    assert ax.name == "3d" and bar.get_label() == "<colorbar>"
    (faces,) = ax.collections
    assert type(faces).__name__ == "Poly3DCollection"
    values = plot_surface.face_values(V, F, color_by)
    scale = np.max(np.abs(values))
    assert bar.get_ylim() == pytest.approx((-scale, scale), rel=1e-12)
    assert bar.get_ylabel() == (color_by if isinstance(color_by, str) else "value")
    expected = matplotlib.colormaps["coolwarm"]((values + scale) / (2 * scale))
    assert _rows(faces.get_facecolor()) == _rows(expected)
    fig.canvas.draw()  # the polygons are projected when drawn
    assert len(faces.get_paths()) == len(F)
    limits = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    assert np.all(limits[:, 0] <= V.min(axis=0)) and np.all(limits[:, 1] >= V.max(axis=0))
    np.testing.assert_allclose(np.ptp(limits, axis=1), np.max(np.ptp(V, axis=0)), rtol=1e-12)


def test_surface_plot_shows_the_faces_coloured_by_curvature(tmp_path):
    import matplotlib.pyplot as plt

    V, F = mesh.torus(10, 6)
    fig = plot_surface.surface(V, F, color_by="mean_curvature", title="torus")
    assert_surface_shows(fig, V, F, "mean_curvature")
    assert fig.axes[0].get_title() == "torus"
    with pytest.raises(AssertionError):  # negative control: the colours are not the angle defect's
        assert_surface_shows(fig, V, F, "angle_defect")
    plt.close(fig)
    fig = plot_surface.surface(*mesh.torus(8, 5), color_by="mean_curvature")
    with pytest.raises(AssertionError):  # negative control: another torus has other faces
        assert_surface_shows(fig, V, F, "mean_curvature")
    plt.close(fig)
    path = plot_surface.surface(V, F, tmp_path / "torus.png", color_by="mean_curvature")
    assert path == tmp_path / "torus.png"
    assert plt.imread(path).shape == (495, 550, 4)  # 5 × 4.5 in at 110 dpi


@pytest.mark.parametrize("label, plain", [
    (r"$\mathdefault{10^{-3}}$", "10⁻³"),
    (r"$\mathdefault{2\times10^{-4}}$", "2×10⁻⁴"),
    (r"$\mathdefault{10^{12}}$", "10¹²"),
    (r"$\mathdefault{-10^{2}}$", "−10²"),
    (r"$\mathdefault{0.5}$", "0.5"),
    ("", ""),
    (r"$\alpha$", r"$\alpha$"),  # not a number: left to mathtext
])
def test_log_tick_labels_as_plain_text(label, plain):
    from ddgjax.plot._figure import plain_number

    assert plain_number(label) == plain


def test_log_axes_are_labelled_without_mathtext(tmp_path):
    """The labels of a log-log figure's ticks are matplotlib's values (decades, and 2×10ⁿ … on
    an axis spanning under a decade) written as plain text; a formatter a caller set is kept."""
    from matplotlib.ticker import FormatStrFormatter

    from ddgjax.plot._figure import plain_number, pyplot, save_figure

    plt = pyplot()
    fig, (ax, kept) = plt.subplots(1, 2)
    ax.loglog([8, 16, 32], [1e-3, 2.4e-4, 6e-5], "o-")
    kept.loglog([1, 2], [1, 2])
    kept.yaxis.set_major_formatter(FormatStrFormatter("%.1f"))
    fig.canvas.draw()
    default = [t.get_text() for t in ax.get_yticklabels() + ax.xaxis.get_minorticklabels()]
    assert any("$" in label for label in default)  # negative control: matplotlib's own labels are mathtext
    save_figure(fig, tmp_path / "loglog.png")
    labels = [t.get_text() for t in ax.get_yticklabels() + ax.xaxis.get_minorticklabels()]
    assert labels == [plain_number(label) for label in default]
    assert "10⁻⁴" in labels and "2×10¹" in labels and not any("$" in label for label in labels)
    assert isinstance(kept.yaxis.get_major_formatter(), FormatStrFormatter)
