"""The gallery (examples/*.py) runs at tiny sizes and draws its figures; the custom-energy
example (README's "define a functional and call solve()") finds the regular polygon."""

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FAST = ["custom_energy", "gauss_bonnet", "heisenberg_chain", "elastica_family", "pendulum_shooting", "catenoid",
        "intrinsic_delaunay", "narrow_minimal_surface"]
# the rod's KKT system takes minutes to compile on 2 cores, the bubbles' three KKT systems ~20 s
# (their physics is checked by `ddgjax verify`, ext_bubbles), the catenoid fold's continuation ~10 s
# (ext_continuation), the Willmore energies ~7 s and the Clifford torus ~60 s, the red blood cell ~30 s (ext_willmore): run with
# `make test-all`
SLOW = ["twisted_rod", "soap_bubble", "double_bubble", "catenoid_fold", "willmore_sphere", "clifford_torus", "red_blood_cell"]


def load(name: str):
    sys.path.insert(0, str(EXAMPLES))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(EXAMPLES))


def test_every_example_is_tested():
    scripts = {p.stem for p in EXAMPLES.glob("*.py") if not p.stem.startswith("_")}
    assert scripts == set(FAST + SLOW)


# What each written figure shows: per axes, (kind, number of lines, kinds of collections).
BAR = ("rectilinear", 0, ["LineCollection", "QuadMesh"])  # a colour bar
EDGES = ["LineCollection", "LineCollection"]  # Delaunay and non-Delaunay edges
SHOWN = {
    "custom_energy.png": [("rectilinear", 1, [])],
    "gauss_bonnet_torus.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    "heisenberg_chain.png": [("3d", 1, ["Line3DCollection"])],  # the ring and the spins' arrows
    "elastica_family.png": [("rectilinear", 4, [])],
    "figure_eight.png": [("rectilinear", 1, [])],
    "pendulum_shooting.png": [("3d", 3, [])],
    "catenoid.png": [("3d", 0, ["Poly3DCollection"]), BAR, ("rectilinear", 1, [])],
    "catenoid_profile.png": [("rectilinear", 2, [])],
    "intrinsic_delaunay_disk.png": [("rectilinear", 1, EDGES)] * 2,
    "intrinsic_delaunay_ellipsoid.png": [("rectilinear", 0, EDGES)] * 2 + [("rectilinear", 1, [])],
    "narrow_minimal_surface.png": [("3d", 0, ["Poly3DCollection"])] * 3 + [("rectilinear", 2, [])],
    "twisted_rod.png": [("3d", 3, [])],
    "soap_bubble.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    "liquid_bridges.png": [("rectilinear", 2, [])],
    "double_bubble.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    # area and neck radius against H: smooth catenoids, index 0, index 1, the fold, the smooth fold
    "catenoid_fold.png": [("rectilinear", 5, [])] * 2,
    "willmore_sphere.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    "willmore_convergence.png": [("rectilinear", 2, [])],  # |W − 4π| and the fitted slope
    "clifford_torus.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    "clifford_profiles.png": [("rectilinear", 3, [])],  # the start, the solution and the axis
    "clifford_convergence.png": [("rectilinear", 2, [])],  # |W/2π² − 1| and the fitted slope
    "red_blood_cell.png": [("3d", 0, ["Poly3DCollection"]), BAR],
    "red_blood_cell_section.png": [("rectilinear", 2, [])],  # the start and the discocyte
}


@pytest.fixture
def saved_figures(monkeypatch):
    """{path: (figure, dpi)} of every figure written to a file with `savefig` during the test."""
    import os

    from matplotlib.figure import Figure

    saved, savefig = {}, Figure.savefig

    def recording(fig, fname, *args, **kwargs):
        if isinstance(fname, (str, os.PathLike)):  # not the animation writer's in-memory frames
            saved[Path(fname)] = (fig, kwargs.get("dpi"))
        return savefig(fig, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", recording)
    return saved


def assert_figure_shows(fig, shown):
    """The figure has the axes `shown` lists, and every line and 2-D line collection lies inside
    its axes' view, with finite data."""
    assert [(ax.name, len(ax.lines), [type(c).__name__ for c in ax.collections]) for ax in fig.axes] == shown
    for ax in fig.axes:
        limits = [ax.get_xlim(), ax.get_ylim()] + ([ax.get_zlim()] if ax.name == "3d" else [])
        data = [np.column_stack(line.get_data_3d() if ax.name == "3d" else line.get_data()) for line in ax.lines]
        if ax.name != "3d":
            data += [np.concatenate(c.get_segments()) for c in ax.collections
                     if type(c).__name__ == "LineCollection" and c.get_segments() and ax.get_label() != "<colorbar>"]
        for points in data:
            points = points[~np.isnan(points).any(axis=1)].astype(float)
            assert len(points) and np.all(np.isfinite(points))
            lo, hi = np.array(limits).min(axis=1), np.array(limits).max(axis=1)
            assert np.all(points >= lo - 1e-12) and np.all(points <= hi + 1e-12)


@pytest.mark.parametrize("name", FAST + [pytest.param(n, marks=pytest.mark.slow) for n in SLOW])
def test_example_draws_its_figures(name, tmp_path, saved_figures):
    """Every figure an example returns is written to its output directory: a PNG image of the
    figure's size, showing the axes and data of `SHOWN` (an animation: a GIF of several frames)."""
    import matplotlib.pyplot as plt
    from PIL import Image

    result = load(name).main(tmp_path, tiny=True)
    paths = [Path(p) for p in (result if isinstance(result, list) else [result])]
    for path in paths:
        assert path.parent == tmp_path and path.is_file()
        if path.suffix == ".gif":
            with Image.open(path) as gif:
                assert gif.format == "GIF" and gif.n_frames > 1
            continue
        fig, dpi = saved_figures[path]
        width, height = np.round(fig.get_size_inches() * dpi).astype(int)
        assert plt.imread(path).shape == (height, width, 4)
        assert_figure_shows(fig, SHOWN[path.name])


def test_the_figure_check_rejects_what_is_not_shown():
    """Negative controls for `assert_figure_shows`: a line outside the view, a missing line."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0.0, 1.0, 2.0], [0.0, 1.0, 0.0])
    assert_figure_shows(fig, [("rectilinear", 1, [])])
    with pytest.raises(AssertionError):
        assert_figure_shows(fig, [("rectilinear", 2, [])])
    ax.set_xlim(0.0, 1.5)  # the last vertex is cut off
    with pytest.raises(AssertionError):
        assert_figure_shows(fig, [("rectilinear", 1, [])])
    plt.close(fig)


def test_custom_energy_finds_the_regular_polygon():
    """Dido's problem: area n h²/(4 tan(π/n)) and equal edge tensions −1/(4 tan(π/n)), h = 1/n
    (KKT residual ≤ 1e-10 bounds the area error by ~1e-11)."""
    n = 8
    sol, exact = load("custom_energy").dido(n)
    assert float(sol.residual) <= 1e-10
    assert abs(-float(sol.energy) - exact) <= 1e-11
    assert np.max(np.abs(np.asarray(sol.multipliers) + 1 / (4 * np.tan(np.pi / n)))) <= 1e-9


def test_output_directory_from_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("DDGJAX_EXAMPLES_OUT", str(tmp_path / "gallery"))
    assert load("_common").output_dir() == tmp_path / "gallery"
    assert (tmp_path / "gallery").is_dir()
