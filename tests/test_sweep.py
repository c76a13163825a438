"""`ddgjax.sweep`: a grid of clamped elastica (n = 16, 20 chords, one longer than the curve)
solved in chunks into HDF5 equals a loop of `solve`; a killed sweep resumes without recomputing
its finished members; failures are recorded, not raised; another grid on the same file is
refused; `ddgjax sweep` on the command line."""

import dataclasses

import h5py
import jax
import numpy as np
import pytest

from ddgjax import cli, sweep
from ddgjax.errors import InvalidInputError
from energies import elastica, rod
from solvers import solve, solve_batch

N, MEMBERS, CHUNK, INFEASIBLE = 16, 20, 8, 7  # member 7, the last of the first chunk, cannot be solved
T_START, T_END = [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]  # the command line's defaults


@pytest.fixture(scope="module")
def problem():
    return elastica.clamped(N, chord=[0.5, 0.0, 0.0], t_start=T_START, t_end=T_END)


@pytest.fixture(scope="module")
def grid():
    chords = np.zeros((MEMBERS, 3))
    chords[:, 0] = np.linspace(0.2, 0.8, MEMBERS)
    chords[INFEASIBLE, 0] = 1.3  # longer than the length 1
    return {"chord": chords}


@pytest.fixture(scope="module")
def cold(problem, grid, tmp_path_factory):
    """The file of the sweep with every member started from `problem.x0`."""
    path = tmp_path_factory.mktemp("sweep") / "cold.h5"
    sweep.run(problem, grid, path, chunk=CHUNK, warm_start=None, progress=False)
    return path


@pytest.fixture(scope="module")
def loop(problem, grid):
    """A loop of `solve`, one call per member, from `problem.x0` (speed: `benchmarks/sweep.py`)."""
    member = lambda c: problem.with_params({**problem.params, "chord": c})  # noqa: E731
    return [solve(member(c), throw=False) for c in grid["chord"]]


@pytest.fixture(scope="module")
def warm(problem, grid, cold, tmp_path_factory):
    """`(path, x0s)`: the sweep with `warm_start="previous"`, and the `x0` of each chunk."""
    counter = _Counting()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(sweep, "solve_batch", counter)
        path = sweep.run(problem, grid, tmp_path_factory.mktemp("sweep") / "warm.h5", chunk=CHUNK, progress=False)
    return path, counter.x0s


def _max_diff(a, b) -> float:
    return max(jax.tree_util.tree_leaves(jax.tree_util.tree_map(lambda u, v: float(np.max(np.abs(np.asarray(u) - np.asarray(v)))), a, b)))


def _results(data: dict) -> dict:
    """The stored numbers (the flags as integers)."""
    out = {k: data[k] for k in ("x", "multipliers", "energy", "residual", "steps", "status")}
    return {**out, "converged": data["converged"].astype(int), "done": data["done"].astype(int)}


def test_sweep_equals_a_loop_of_solve(cold, loop):
    data = sweep.read(cold)
    solutions = loop
    for k in range(MEMBERS):  # the infeasible member too: the same last iterate
        sol = solutions[k]
        assert bool(sol.converged) == data["converged"][k] == (k != INFEASIBLE)
        assert _max_diff(data["x"][k], sol.x) <= 1e-10
        assert _max_diff({n: v[k] for n, v in data["multipliers"].items()}, sol.multipliers) <= 1e-10
        assert abs(data["energy"][k] - float(sol.energy)) <= 1e-10 and data["steps"][k] == int(sol.steps)


def test_infeasible_member_is_recorded_failed_the_others_converge(cold):
    data = sweep.read(cold)
    assert data["done"].all()
    assert np.flatnonzero(~data["converged"]).tolist() == [INFEASIBLE]
    assert data["error"][INFEASIBLE].startswith("did not converge") and "KKT residual" in data["error"][INFEASIBLE]
    from solvers import STATUS_TEXT  # the reason, as the solver states it for the member's status

    assert data["error"][INFEASIBLE].endswith(STATUS_TEXT[int(data["status"][INFEASIBLE])])
    assert all(e == "" for k, e in enumerate(data["error"]) if k != INFEASIBLE)
    assert sweep.summary(cold) == {"members": MEMBERS, "done": MEMBERS, "converged": MEMBERS - 1, "failed": 1}


def test_read_returns_the_documented_arrays(cold, grid):
    data = sweep.read(cold)
    assert data["x"].shape == (MEMBERS, N, 3) and data["x"].dtype == np.float64
    assert data["multipliers"]["chord"].shape == (MEMBERS, 3) and data["multipliers"]["unit"].shape == (MEMBERS, N - 2)
    for name, dtype in [("energy", np.float64), ("residual", np.float64), ("steps", np.int64), ("status", np.int64),
                        ("converged", np.bool_), ("done", np.bool_)]:
        assert data[name].shape == (MEMBERS,) and data[name].dtype == dtype, name
    assert data["error"].shape == (MEMBERS,) and isinstance(data["error"][0], str)
    assert np.array_equal(data["chord"], grid["chord"]) and np.array_equal(data["params"]["chord"], grid["chord"])
    assert data["attrs"]["problem"] == f"clamped elastica (n={N}, clamp=edge)" and data["attrs"]["warm_start"] == "None"


class _Counting:
    """`solve_batch` that counts the members it is asked for and raises `KeyboardInterrupt` (a
    kill) on call number `kill_at`."""

    def __init__(self, kill_at=None):
        self.members, self.calls, self.kill_at, self.x0s = [], 0, kill_at, []

    def __call__(self, problem, params_batch, **kwargs):
        self.calls += 1
        if self.calls == self.kill_at:
            raise KeyboardInterrupt
        self.x0s.append(np.asarray(problem.x0))
        self.members.append(len(params_batch["chord"]))
        return solve_batch(problem, params_batch, **kwargs)


@pytest.mark.parametrize("warm_start", [None, "previous"])
def test_a_killed_sweep_resumes_without_recomputing_finished_members(problem, grid, cold, warm, tmp_path, monkeypatch,
                                                                     warm_start):
    path = tmp_path / "killed.h5"
    killer = _Counting(kill_at=2)
    monkeypatch.setattr(sweep, "solve_batch", killer)
    with pytest.raises(KeyboardInterrupt):
        sweep.run(problem, grid, path, chunk=CHUNK, warm_start=warm_start, progress=False)
    assert sweep.read(path)["done"].tolist() == [True] * CHUNK + [False] * (MEMBERS - CHUNK)  # the first chunk is kept

    counter = _Counting()
    monkeypatch.setattr(sweep, "solve_batch", counter)
    sweep.run(problem, grid, path, chunk=CHUNK, warm_start=warm_start, progress=False)
    assert counter.calls == 2  # the members 8..19, in two chunks of eight (the last padded)
    resumed = sweep.read(path)
    assert resumed["done"].all()

    whole = sweep.read(cold if warm_start is None else warm[0])  # uninterrupted
    assert _max_diff(_results(resumed), _results(whole)) == 0.0 and resumed["error"].tolist() == whole["error"].tolist()

    again = _Counting()  # negative control: a finished sweep solves nothing
    monkeypatch.setattr(sweep, "solve_batch", again)
    sweep.run(problem, grid, path, chunk=CHUNK, warm_start=warm_start, progress=False)
    assert again.calls == 0


def test_warm_start_previous_starts_a_chunk_from_the_last_converged_member(problem, cold, warm):
    (path, x0s), cold_data = warm, sweep.read(cold)
    data = sweep.read(path)
    assert len(x0s) == 3 and np.array_equal(x0s[0], np.asarray(problem.x0))
    # chunk 1 starts from member 6: member 7, the last of chunk 0, failed
    assert np.array_equal(x0s[1], data["x"][INFEASIBLE - 1])
    assert np.array_equal(x0s[2], data["x"][2 * CHUNK - 1])
    assert data["converged"].tolist() == cold_data["converged"].tolist()
    ok = data["converged"]
    assert np.max(np.abs(data["x"][ok] - cold_data["x"][ok])) < 1e-8  # the same elastica from another start
    assert data["steps"][CHUNK:].sum() < cold_data["steps"][CHUNK:].sum()  # and fewer Newton steps


def test_progress_shows_members_per_second(problem, grid, tmp_path, capfd):
    sweep.run(problem, {"chord": grid["chord"][CHUNK:2 * CHUNK]}, tmp_path / "p.h5", chunk=CHUNK, warm_start=None)
    err = capfd.readouterr().err
    assert "members/s" in err and "8/8" in err
    sweep.run(problem, {"chord": grid["chord"][CHUNK:2 * CHUNK]}, tmp_path / "q.h5", chunk=CHUNK, warm_start=None, progress=False)
    assert capfd.readouterr().err == ""  # negative control


def test_a_chunk_that_raises_is_solved_member_by_member(problem, tmp_path, monkeypatch):
    chords = np.zeros((4, 3))
    chords[:, 0] = [0.3, np.nan, 0.5, 0.6]

    def broken(*args, **kwargs):
        raise RuntimeError("the batch failed")

    monkeypatch.setattr(sweep, "solve_batch", broken)
    data = sweep.read(sweep.run(problem, {"chord": chords}, tmp_path / "s.h5", chunk=4, warm_start=None, progress=False))
    assert data["converged"].tolist() == [True, False, True, True] and data["done"].all()
    assert data["error"][1].startswith("NonFiniteError") and data["status"][1] == -1 and np.isnan(data["x"][1]).all()
    direct = solve(problem.with_params({**problem.params, "chord": chords[2]}), warm_start=None)
    assert _max_diff(data["x"][2], direct.x) <= 1e-10


def test_another_grid_or_problem_on_the_same_file_is_refused(problem, grid, cold):
    path = cold
    before = path.read_bytes()
    other = {"chord": grid["chord"].copy()}
    other["chord"][3, 0] += 1e-3
    with pytest.raises(InvalidInputError, match="different grid"):
        sweep.run(problem, other, path, chunk=CHUNK, warm_start=None, progress=False)
    with pytest.raises(InvalidInputError, match=r"\(different grid: stored 20 members, given 19\)"):
        sweep.run(problem, {"chord": grid["chord"][:19]}, path, chunk=CHUNK, warm_start=None, progress=False)
    renamed = dataclasses.replace(problem, name="another")
    with pytest.raises(InvalidInputError, match="different problem name: stored 'clamped elastica"):
        sweep.run(renamed, grid, path, chunk=CHUNK, warm_start=None, progress=False)
    longer = elastica.clamped(N, length=1.1, chord=[0.5, 0.0, 0.0], t_start=T_START, t_end=T_END)  # same name
    with pytest.raises(InvalidInputError, match=r"\(different x0, shared parameters\)"):
        sweep.run(longer, grid, path, chunk=CHUNK, warm_start=None, progress=False)
    with pytest.raises(InvalidInputError, match="different solver options"):
        sweep.run(problem, grid, path, chunk=CHUNK, warm_start=None, progress=False, tol=1e-9)
    assert path.read_bytes() == before  # nothing was written


@pytest.mark.parametrize("kwargs, message", [
    (dict(processes=2), "JAX runs 1 process"),
    (dict(processes=True), "JAX runs 1 process"),
    (dict(warm_start="next"), "warm_start"),
    (dict(chunk=0), "chunk must be a positive integer"),
    (dict(params_grid={"chrod": np.zeros((2, 3))}), "no parameter 'chrod'"),
    (dict(params_grid={"chord": np.zeros((2, 2))}), r"shape \(B, 3\)"),
    (dict(params_grid={"chord": np.zeros((0, 3))}), "non-zero number of members"),
])
def test_bad_arguments_are_refused(problem, grid, tmp_path, kwargs, message):
    kwargs = {"params_grid": grid, **kwargs}
    with pytest.raises(InvalidInputError, match=message):
        sweep.run(problem, out=tmp_path / "s.h5", progress=False, **kwargs)
    assert not (tmp_path / "s.h5").exists()


def test_a_file_that_is_not_a_sweep_is_refused(problem, grid, tmp_path):
    (tmp_path / "text.h5").write_text("not hdf5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    for name, message in [("text.h5", "cannot open"), ("other.h5", "not a ddgjax sweep file")]:
        with pytest.raises(InvalidInputError, match=message):
            sweep.run(problem, grid, tmp_path / name, progress=False)
    with pytest.raises(InvalidInputError, match="not a ddgjax sweep file"):
        sweep.read(tmp_path / "other.h5")


# --- the command line ---------------------------------------------------------------------------


def test_cli_sweep_elastica(tmp_path, capsys):
    out = tmp_path / "chords.h5"
    argv = ["sweep", "elastica", "--n", str(N), "--param", "chord=0.3:0.65:8", "--chunk", "8", "--out", str(out),
            "--no-progress"]
    assert cli.main(argv) == 0
    printed = capsys.readouterr().out
    assert "8 members: 8 converged, 0 failed (8 solved now, 0 already done)" in printed and "members/s" in printed
    data = sweep.read(out)
    assert np.allclose(data["chord"][:, 0], np.linspace(0.3, 0.65, 8)) and not data["chord"][:, 1:].any()
    assert cli.main(argv) == 0 and "0 solved now" in capsys.readouterr().out  # resumed: nothing left


def test_cli_sweep_rod_over_the_twist_stiffness(tmp_path, capsys):
    """`ddgjax sweep rod --param alpha=...`: every member a critical rod with constant twist
    (Lemma 3.12), the stiffness stored per member; the twist angle falls as α grows (the end
    frames are fixed, so the same total twist costs αθ²: the rod bends to take some of it)."""
    out = tmp_path / "alpha.h5"
    argv = ["sweep", "rod", "--n", "8", "--param", "alpha=0.5:1.5:4", "--twist", "2.0", "--chord", "0.6",
            "--chunk", "4", "--out", str(out), "--no-progress"]
    assert cli.main(argv) == 0
    assert "4 members: 4 converged, 0 failed" in capsys.readouterr().out
    data = sweep.read(out)
    assert np.allclose(data["alpha"], np.linspace(0.5, 1.5, 4)) and data["x"].shape == (4, 8, 4)
    assert float(data["residual"].max()) <= 1e-10
    theta = np.stack([np.asarray(rod.twist_angles(x)) for x in data["x"]])
    assert float(np.ptp(theta, axis=1).max()) <= 1e-10
    assert np.all(np.diff(np.abs(theta[:, 0])) < 0), theta[:, 0]


def test_cli_sweep_minimal_surface_over_the_height_fails_beyond_the_fold(tmp_path, capsys):
    """`ddgjax sweep minimal-surface --param height=...`: catenoids between the unit circles at
    z = ±H (Sec 6.4).  Below the fold H* ≈ 0.6627 every member converges (residual ≤ 1e-10), the
    neck radius is the smooth catenoid's c (c cosh(H/c) = 1, the stable root) to the mesh's
    accuracy and falls with H, the area grows; beyond the fold there is no catenoid and those
    members are recorded as failed, with their message, without stopping the sweep.  Negative
    control: the start (the cylinder, radius 1) misses c by far more."""
    from scipy.optimize import brentq

    out = tmp_path / "heights.h5"
    argv = ["sweep", "minimal-surface", "--rings", "4", "--param", "height=0.45:0.75:3", "--chunk", "3", "--max-steps", "30",
            "--out", str(out), "--no-progress"]
    assert cli.main(argv) == 0
    assert "3 members: 2 converged, 1 failed" in capsys.readouterr().out
    data = sweep.read(out)
    H, ok = data["height"], data["converged"]
    assert np.array_equal(ok, H < 0.6627) and float(data["residual"][ok].max()) <= 1e-10
    assert all("did not converge" in e for e in data["error"][~ok]) and data["first_order_steps"].shape == (3,)
    middle = np.abs(data["x"][0, :, 2]) < 1e-12  # the unknowns are (x, y, ζ): ζ = 0 on the middle circle
    neck = np.linalg.norm(data["x"][ok][:, middle, :2], axis=2).mean(axis=1)
    smooth = np.array([brentq(lambda c, h=h: c * np.cosh(h / c) - 1.0, 0.55, 1.0) for h in H[ok]])
    assert np.max(np.abs(neck - smooth)) < 0.03 and np.all(np.diff(neck) < 0) and np.all(np.diff(data["energy"][ok]) > 0)
    assert np.min(np.abs(1.0 - smooth)) > 0.03  # the cylinder's radius fails the bound


@pytest.mark.parametrize("argv, message", [
    (["--param", "chord=0.2:0.8"], "sweep: argument --param: expected NAME=START:STOP:COUNT"),
    (["--param", "chord=0.2:0.8:0"], "COUNT must be a positive integer"),
    (["--param", "twist=0:1:3"], "unknown parameter 'twist' of elastica (have: chord)"),
    (["--processes", "0"], "argument --processes"),
    (["--param", "chord=0:0.5:3", "--param", "chord=0:0.5:3"], "--param chord given twice"),
    (["--param", "chord=1.5:2:3"], "not shorter than the length"),
    (["--param", "chord=0.1:0.5:3", "--out", "/proc/x/s.h5"], "cannot write in the directory /proc/x"),
    (["--param", "chord=0.1:0.5:3", "--out", "{tmp}"], "is a directory"),
    (["--param", "chord=0.1:0.6:8", "--chunk", "8", "--out", "{tmp}/s.h5"], "holds another sweep (different grid)"),
])
def test_cli_sweep_errors_are_one_line_with_exit_code_2(tmp_path, capsys, argv, message):
    existing = tmp_path / "s.h5"
    assert cli.main(["sweep", "elastica", "--n", str(N), "--param", "chord=0.1:0.5:8", "--chunk", "8", "--out",
                     str(existing), "--no-progress"]) == 0
    capsys.readouterr()
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    argv = ["sweep", "elastica", "--n", str(N), *argv] + ([] if "--out" in argv else ["--out", str(tmp_path / "t.h5")])
    assert cli.main([*argv, "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err and "(hint: " in err, err
