"""`ddgjax.plot.sweep.family`: the figure of a stored sweep from the file alone (a clamped
elastica, n = 16, 8 chords, the last longer than the curve so that it fails): energy, residual
and steps against the chord, the shapes overlaid at the edge length the chord constraint gives,
the failed member marked; `ddgjax sweep-plot` writes a PNG, its errors are one line, exit 2."""

import h5py
import numpy as np
import pytest

from ddgjax import cli, sweep
from ddgjax.plot import sweep as plot_sweep
from energies import elastica

N, CHORDS = 16, [0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 1.3]  # 1.3 > length 1: infeasible, recorded failed
FAILED = len(CHORDS) - 1


@pytest.fixture(scope="module")
def path(tmp_path_factory):
    problem = elastica.clamped(N, chord=[0.5, 0.0, 0.0], t_start=[0.0, 1.0, 0.0], t_end=[0.0, -1.0, 0.0])
    chords = np.zeros((len(CHORDS), 3))
    chords[:, 0] = CHORDS
    out = tmp_path_factory.mktemp("sweep") / "chords.h5"
    return sweep.run(problem, {"chord": chords}, out, chunk=len(CHORDS), warm_start=None, progress=False)


def test_the_plot_reads_the_format_the_sweep_writes(path):
    assert plot_sweep.FORMAT == sweep.FORMAT
    data, stored = plot_sweep.load(path), sweep.read(path)
    for name in ("x", *plot_sweep.FIELDS):
        assert np.array_equal(data[name], stored[name]), name
    assert np.flatnonzero(~data["converged"]).tolist() == [FAILED]


def test_family_shows_energy_residual_steps_and_the_shapes(path):
    import matplotlib.pyplot as plt

    fig = plot_sweep.family(path)
    energy, residual, steps, shapes = fig.axes
    assert [ax.get_xlabel() for ax in fig.axes[:3]] == ["chord[0]"] * 3
    assert [ax.get_ylabel() for ax in fig.axes[:3]] == ["energy", "KKT residual", "steps"]
    assert residual.get_yscale() == "log" and shapes.name == "rectilinear"  # planar: a 2-D panel
    for ax in (energy, residual, steps):
        line, marks = ax.lines  # the converged members, joined; the failed one, a red cross
        assert np.allclose(line.get_xdata(), CHORDS[:FAILED]) and marks.get_xdata().tolist() == [CHORDS[FAILED]]
        assert marks.get_color() == "red" and marks.get_marker() == "x"
    data = sweep.read(path)
    assert np.array_equal(steps.lines[0].get_ydata(), data["steps"][:FAILED])
    # one shape per member, the failed one red and dashed; h = 1/16 recovered from the chord
    assert len(shapes.lines) == len(CHORDS) and "h = 0.0625 from the chord" in shapes.get_title()
    assert shapes.lines[-1].get_color() == "red" and shapes.lines[-1].get_linestyle() == "--"
    for k, line in enumerate(shapes.lines[:FAILED]):
        end = np.array([line.get_xdata()[-1], line.get_ydata()[-1]])
        assert np.allclose(end, [CHORDS[k], 0.0], atol=1e-8)  # the curve ends at its chord
        assert len(line.get_xdata()) == N + 1
    assert "1 failed" in fig._suptitle.get_text()
    plt.close(fig)


def test_without_the_chord_the_shapes_are_normalised_and_the_abscissa_is_the_member(path):
    import matplotlib.pyplot as plt

    data = sweep.read(path)
    data["params"] = {"other": np.arange(len(CHORDS))[::-1] % 3}  # not monotone, no chord
    fig = plot_sweep.family(data)
    assert fig.axes[0].get_xlabel() == "member"
    assert "normalised to length 1 (edge length not stored)" in fig.axes[3].get_title()
    plt.close(fig)


def test_a_file_with_no_member_done_is_refused(path, tmp_path):
    empty = tmp_path / "empty.h5"
    empty.write_bytes(path.read_bytes())
    with h5py.File(empty, "r+") as f:
        f["done"][...] = False
    with pytest.raises(sweep.InvalidInputError, match="no member done"):
        plot_sweep.family(empty)


def test_cli_sweep_plot_writes_a_png(path, tmp_path, capsys):
    import matplotlib.pyplot as plt

    out = tmp_path / "figs" / "chords.png"
    assert cli.main(["sweep-plot", str(path), "--out", str(out)]) == 0
    assert str(out) in capsys.readouterr().out
    assert plt.imread(out).ndim == 3


@pytest.mark.parametrize("argv, message", [
    (["{tmp}/missing.h5"], "cannot read the sweep file {tmp}/missing.h5: no such file"),
    (["{tmp}/text.h5"], "cannot read the sweep file {tmp}/text.h5"),
    (["{tmp}/other.h5"], "other.h5 is not a ddgjax sweep file"),
    (["{path}", "--out", "/proc/x/f.png"], "cannot write in the directory /proc/x"),
    (["{path}", "--out", "{tmp}/f.xyz"], "unknown format '.xyz'"),
    (["{path}", "--out", "{tmp}"], "is a directory"),
    ([], "the following arguments are required: FILE"),
])
def test_cli_sweep_plot_errors_are_one_line_with_exit_code_2(path, tmp_path, capsys, argv, message):
    (tmp_path / "text.h5").write_text("not hdf5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    fill = lambda s: s.replace("{tmp}", str(tmp_path)).replace("{path}", str(path))  # noqa: E731
    assert cli.main(["sweep-plot", *map(fill, argv)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and fill(message) in err and "(hint: " in err, err
