"""The `ddgjax` command line: one-line errors with a hint and exit code 2, the verify report
(table, convergence tables, figures present), a failing check gives a non-zero exit."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ddgjax import cli, verify
from ddgjax.errors import InvalidInputError

ROOT = Path(__file__).resolve().parent.parent


def test_bad_input_is_one_line_with_hint_and_exit_code_2():
    """A real process: no traceback, one line on stderr, exit code 2."""
    run = subprocess.run([sys.executable, "-m", "ddgjax", "solve", "elastica", "--n", "-3"], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in run.stderr
    assert lines[0].startswith("ddgjax: error: ") and "must be at least 3, got -3" in lines[0] and "(hint: " in lines[0]


@pytest.mark.parametrize("argv, message", [
    (["solve", "elastica", "--chord", "1.5", "0", "0"], "not shorter than the length"),
    (["solve", "elastica", "--n", "10", "--t-start", "0", "0", "0"], "t_start"),
    (["solve", "rod", "--alpha", "-1"], "alpha must be positive"),
    (["bench", "no-such-benchmark"], "no benchmark named"),
    (["verify", "--only", "no-such-check"], "no check matches"),
])
def test_errors_in_process(argv, message, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err and "(hint: " in err


def _bad_files(tmp_path):
    """A regular file, a 25-byte OFF header asking for 3·10⁹ vertices, an OBJ with the index 0,
    and a closed surface (the octahedron), in tmp_path."""
    from ddgjax import mesh

    (tmp_path / "file").write_text("x")
    (tmp_path / "huge.off").write_bytes(b"OFF\n3000000000 1 0\n0 0 0\n")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    mesh.write(tmp_path / "closed.off", *mesh.octahedron())


@pytest.mark.parametrize("argv, message", [
    (["verify", "--jobs", "0"], "verify: argument --jobs: must be a positive integer, got '0'"),
    (["verify", "--jobs", "-3"], "must be a positive integer, got '-3'"),
    (["verify", "--only", "sec4", "--out", "/proc/x"], "cannot write in the directory /proc/x"),
    (["verify", "--only", "sec4", "--out", "{tmp}/file/report"], "{tmp}/file is not a directory"),
    (["solve", "elastica", "--n", "8", "--plot", "/proc/x/e.png"], "cannot write in the directory /proc/x"),
    (["solve", "elastica", "--n", "8", "--plot", "{tmp}/e.xyz"], "unknown format '.xyz'"),
    (["solve", "elastica", "--n", "8", "--plot", "{tmp}"], "it is a directory"),
    (["solve", "minimal-surface", "--mesh", "{tmp}/missing.obj"], "{tmp}/missing.obj: no such file"),
    (["solve", "minimal-surface", "--mesh", "{tmp}/huge.off"], "promises 3000000000 vertices and 1 faces"),
    (["solve", "minimal-surface", "--mesh", "{tmp}/bad.obj"], "line 4: the face corner '0' refers to no vertex"),
    (["solve", "minimal-surface", "--mesh", "{tmp}/closed.off"], "is closed: a minimal surface spans a boundary"),
    (["solve", "no-such-object"], "invalid choice: 'no-such-object'"),
    ([], "the following arguments are required: command"),
])
def test_bad_paths_files_and_arguments_are_one_line_and_exit_code_2(tmp_path, capsys, argv, message):
    """Unwritable outputs, missing or malformed mesh files, bad arguments: exit code 2 and one
    line on stderr with a hint, before any work is done (nothing on stdout)."""
    _bad_files(tmp_path)
    assert cli.main([a.format(tmp=tmp_path) for a in argv]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("ddgjax: error: ") and message.format(tmp=tmp_path) in err and "(hint: " in err


def test_a_hostile_mesh_file_is_one_line_in_a_real_process(tmp_path):
    """The 25-byte OFF header asking for 3·10⁹ vertices (67 GiB, once): exit code 2, one line."""
    _bad_files(tmp_path)
    run = subprocess.run([sys.executable, "-m", "ddgjax", "solve", "minimal-surface", "--mesh", str(tmp_path / "huge.off")],
                         cwd=ROOT, capture_output=True, text=True, timeout=120)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1 and "promises 3000000000 vertices" in lines[0], run.stderr


def test_debug_shows_the_exception():
    with pytest.raises(InvalidInputError, match="must be at least 3, got 2"):
        cli.main(["--debug", "solve", "elastica", "--n", "2"])


@pytest.fixture
def saved_figures(monkeypatch):
    """{path: figure} of every figure this process writes with `savefig` during the test."""
    from matplotlib.figure import Figure

    saved, savefig = {}, Figure.savefig

    def recording(fig, fname, *args, **kwargs):
        saved[Path(fname)] = fig
        return savefig(fig, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", recording)
    return saved


def assert_planar_elastica_shown(fig, n, chord, length=1.0):
    """The `--plot` figure of a planar elastica: one 2-D axes, one polyline of n edges of length
    length/n from the origin to the chord, all inside the view."""
    (ax,) = fig.axes
    (line,) = ax.lines
    points = np.column_stack(line.get_data())
    assert ax.name == "rectilinear" and points.shape == (n + 1, 2)
    np.testing.assert_allclose(points[0], 0.0, atol=1e-12)
    np.testing.assert_allclose(points[-1], chord, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(np.diff(points, axis=0), axis=1), length / n, rtol=1e-9)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= points[:, 0].min() and x1 >= points[:, 0].max() and y0 <= points[:, 1].min() and y1 >= points[:, 1].max()


def test_solve_elastica_prints_and_plots(tmp_path, capsys, saved_figures):
    import matplotlib.pyplot as plt

    path = tmp_path / "e.png"
    assert cli.main(["solve", "elastica", "--n", "16", "--chord", "0.6", "0", "0", "--plot", str(path)]) == 0
    out = capsys.readouterr().out
    residual = float(re.search(r"KKT residual\s+(\S+)", out).group(1))
    assert residual <= 1e-10 and "Thm 3.8" in out and re.search(r"figure\s+" + re.escape(str(path)), out)
    assert plt.imread(path).shape == (480, 540, 4)  # dg.plot.curve: 4.5 × 4 in at 120 dpi
    assert list(saved_figures) == [path]
    assert_planar_elastica_shown(saved_figures[path], 16, [0.6, 0.0])
    with pytest.raises(AssertionError):  # negative control: not the elastica of another chord
        assert_planar_elastica_shown(saved_figures[path], 16, [0.5, 0.0])


def _referenced_figures(report: Path) -> list[Path]:
    return [report.parent / p for p in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report.read_text())]


def test_verify_writes_the_report_with_existing_figures(tmp_path, capsys):
    """Two processes (`--jobs 2`) over two modules' checks: the report has the table, every
    check passes, every referenced figure is a PNG image."""
    import matplotlib.pyplot as plt

    code = cli.main(["verify", "--quick", "--only", "sec4", "steiner", "mean_curvature", "--out", str(tmp_path),
                     "--no-progress", "--jobs", "2"])
    assert code == 0, capsys.readouterr()
    report = tmp_path / "report.md"
    text = report.read_text()
    assert "| statement | reference | quantity | value | tolerance | result |" in text
    assert "**FAIL**" not in text and "Thm 4.1" in text and "fitted order" in text
    figures = _referenced_figures(report)
    assert figures and any(p.name.startswith("convergence_") for p in figures)
    for path in figures:  # drawn in the worker processes: each a PNG image of its figure's size
        image = plt.imread(path)
        assert image.ndim == 3 and image.shape[2] == 4 and min(image.shape[:2]) >= 300
        if path.name.startswith("convergence_"):
            assert image.shape == (420, 540, 4)  # dg.plot.convergence: 4.5 × 3.5 in at 120 dpi


def test_a_failing_check_gives_exit_code_1(tmp_path, capsys):
    @verify.check("Test 0.0", "one plus one is three", quantity="|1 + 1 − 3|", at_most=1e-12, name="deliberately_false")
    def deliberately_false(ctx):
        return abs(1 + 1 - 3)

    try:
        assert cli.main(["verify", "--only", "deliberately_false", "--out", str(tmp_path), "--no-progress"]) == 1
    finally:
        del verify.registry["deliberately_false"]
    assert "FAIL deliberately_false" in capsys.readouterr().err
    assert "**FAIL**" in (tmp_path / "report.md").read_text()


def test_check_tolerances_and_registration_errors():
    verify.load_checks()
    c = verify.registry["total_mean_curvature_limit"]
    assert c.passes(2.05) and not c.passes(2.2) and not c.passes(float("nan")) and c.tolerance == "2 ± 0.1"
    with pytest.raises(InvalidInputError, match="exactly one"):
        verify.check("Def 0", "nothing", quantity="x", at_most=1.0, at_least=0.0)


def test_verify_list(capsys):
    assert cli.main(["verify", "--list", "--only", "Thm 5.6"]) == 0
    assert "gauss_bonnet_builtin" in capsys.readouterr().out


def test_entry_point_is_declared():
    assert 'ddgjax = "ddgjax.cli:main"' in (ROOT / "pyproject.toml").read_text()


@pytest.mark.slow
def test_quick_verify_passes_every_check(tmp_path):
    """The acceptance run of `make demo`: every check passes, every referenced figure exists."""
    outcomes, report = verify.verify(tmp_path, quick=True, jobs=2)
    assert [o.check.name for o in outcomes if not o.passed] == []
    assert all(p.is_file() for p in _referenced_figures(report))
