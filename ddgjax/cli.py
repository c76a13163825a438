"""The `ddgjax` command line: `verify`, `solve`, `sweep`, `bench`.

    ddgjax verify [--quick] [--out DIR] [--only WORD ...] [--list] [--debug]
    ddgjax solve elastica --n 100 --chord 0.5 0 0 --t-start 0 1 0 --t-end 0 -1 0 --plot out.png
    ddgjax solve rod --n 60 --alpha 0.7 --chord 0.6 0 0 --twist 2.5 --plot rod.png
    ddgjax solve minimal-surface --mesh annulus --height 0.4 --method cotan --plot surface.png
    ddgjax sweep elastica --n 16 --param chord=0.2:0.9:50 --out chords.h5   (resumes if the file exists;
                                                                            --processes K: K local processes)
    ddgjax sweep minimal-surface --rings 8 --param height=0.3:0.7:41 --out catenoids.h5
    ddgjax sweep-plot chords.h5 [--out chords.png]
    ddgjax bench [--quick] [NAME ...]
    ddgjax --version                        (also `python -m ddgjax --version`)

Exit codes: 0 success, 1 a check failed (verify) or a benchmark script failed (bench), 2 bad
input: a `DDGError` (also a malformed argument, a mesh file that cannot be read, an output path
that cannot be written) is printed as one line `ddgjax: error: … (hint: …)`, without a traceback
unless `--debug`.

`solve`, `sweep` and `verify` keep XLA's compiled programs on disk (`ddgjax.compile_cache`): a second
cold run loads them instead of compiling, and calls the exported solvers instead of tracing
them (`solvers/_exported.py`).  `DDGJAX_COMPILE_CACHE=DIR` moves the cache,
`DDGJAX_COMPILE_CACHE=off` switches it off.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from . import __version__, compile_cache
from .errors import DDGError, InvalidInputError

__all__ = ["main", "build_parser", "hint_for"]

HINTS = {
    "InfeasibleChordError": "choose a chord shorter than --length",
    "ConvergenceError": "the problem may have no solution near the start: try a milder load (chord, twist, "
                        "height), fewer unknowns first, or more --max-steps",
    "NonFiniteError": "an input contains NaN or infinity",
    "ShapeError": "vectors take three numbers, e.g. --chord 0.5 0 0",
    "MeshError": "the mesh must be a valid surface (see `ddgjax.mesh.classify`)",
    "NotAvailableError": "this object is still being implemented; see README for what exists",
    "MeshFileError": "give a surface mesh file (OBJ, OFF, PLY, STL or VTK), or annulus or disk",
    "OutputPathError": "choose a path you can write to (a figure's ending in .png, .pdf or .svg)",
    "UsageError": "see `ddgjax --help` and `ddgjax <command> --help`",
    "OSError": "check the paths in the arguments",
}


class NotAvailableError(InvalidInputError):
    """A command needs a part of the library that is not there yet."""


class OutputPathError(InvalidInputError):
    """An output path (`--out`, `--plot`) cannot be created or written."""


class UsageError(InvalidInputError):
    """The command line does not parse: an unknown option, a missing or malformed value."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are `UsageError`s, printed by `main` as one line."""

    def error(self, message: str):
        command = self.prog.split(" ", 1)[1:]  # "ddgjax verify" -> ["verify"]
        raise UsageError(f"{command[0]}: {message}" if command else message)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def _writable_directory(path) -> Path:
    """`path` if it is, or can be created as, a directory to write in: its nearest existing
    ancestor is a directory in which a temporary file can be written (nothing is left behind);
    else `OutputPathError` naming the path and the reason."""
    path = Path(path)
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not existing.is_dir():
        raise OutputPathError(f"cannot write in the directory {path}: {existing} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as error:
        where = "" if existing == path else f"{existing}: "
        raise OutputPathError(f"cannot write in the directory {path}: {where}{error.strerror or error}") from None
    return path


def _writable_figure(path) -> Path:
    """`path` for `savefig`: its directory writable (`_writable_directory`), not itself a
    directory, its extension one matplotlib writes; else `OutputPathError`."""
    from matplotlib.backend_bases import FigureCanvasBase

    path = Path(path)
    formats = FigureCanvasBase.get_supported_filetypes()
    if path.suffix and path.suffix[1:].lower() not in formats:
        raise OutputPathError(f"cannot save a figure as {path}: unknown format {path.suffix!r} (use one of "
                              f"{', '.join(sorted(formats))})")
    _writable_directory(path.parent)
    if path.is_dir() or (path.exists() and not os.access(path, os.W_OK)):
        raise OutputPathError(f"cannot write the figure {path}: it is a directory or read-only")
    return path


def hint_for(error: Exception) -> str:
    """A short suggestion for the user, by the error's class (most specific first)."""
    for cls in type(error).__mro__:
        if cls.__name__ in HINTS:
            return HINTS[cls.__name__]
    return "check the arguments (`ddgjax <command> --help`), or rerun with --debug for the traceback"


def _one_line(error: BaseException) -> str:
    if isinstance(error, OSError) and error.filename is not None:
        return f"{error.filename}: {error.strerror}"
    return " ".join(str(error).split()) or type(error).__name__


# --- verify -----------------------------------------------------------------------------------


def _verify(args) -> int:
    from . import verify as v

    if args.list:
        v.load_checks()
        for c in v.select(args.only):
            print(f"{c.name:45s} {c.reference:25s} {c.statement}")
        return 0
    _writable_directory(args.out)
    start = time.perf_counter()
    outcomes, path = v.verify(args.out, quick=args.quick, only=args.only, progress=not args.no_progress, debug=args.debug,
                              jobs=args.jobs)
    failed = [o for o in outcomes if not o.passed]
    ran = [o for o in outcomes if not o.skipped]
    for o in failed:
        why = o.error or f"value {o.value:.3g} does not meet {o.check.tolerance}"
        print(f"FAIL {o.check.name} ({o.check.reference}): {why}", file=sys.stderr)
    print(f"{len(ran) - len(failed)} of {len(ran)} checks passed in {time.perf_counter() - start:.0f} s"
          + (f" ({len(outcomes) - len(ran)} run only without --quick)" if len(ran) < len(outcomes) else "")
          + f"; report: {path}")
    return 1 if failed else 0


# --- solve ------------------------------------------------------------------------------------


def _print_solution(sol, extra: dict) -> None:
    print(f"energy        {float(sol.energy):.12g}")
    for key, value in extra.items():
        print(f"{key:13s} {value}")
    print(f"KKT residual  {float(sol.residual):.2e} after {int(sol.steps)} Newton steps")


def _solver_options(args) -> dict:
    return {k: v for k, v in (("tol", args.tol), ("max_steps", args.max_steps)) if v is not None}


def _solve_elastica(args) -> int:
    import numpy as np

    from energies import elastica
    from solvers import solve

    problem = elastica.clamped(args.n, length=args.length, chord=args.chord, t_start=args.t_start, t_end=args.t_end,
                               clamp=args.clamp)
    sol = solve(problem, **_solver_options(args))
    gamma = np.asarray(elastica.curve(sol.x, problem))
    a = np.asarray(elastica.theorem_3_8_a(sol, problem))
    T = np.asarray(sol.x)
    W = np.cross(T[1:], T[:-1]) / (1 + np.sum(T[1:] * T[:-1], axis=1))[:, None]
    b = W - np.cross(a, gamma[1:-1])
    _print_solution(sol, {"load λ": np.round(np.asarray(elastica.load(sol)), 8),
                          "Thm 3.8": f"max_k |b_k − b_1| = {np.max(np.abs(b - b[0])):.1e}"})
    if args.plot:
        import ddgjax as dg

        planar = np.allclose(gamma[:, 2], 0.0)
        print("figure       ", dg.plot.curve(gamma[:, :2] if planar else gamma, path=args.plot))
    return 0


def _rotation_taking_e1_to(t):
    """The unit quaternion of the smallest rotation taking e1 to the unit vector t."""
    import numpy as np

    from . import quaternion as qt

    t = np.asarray(t, dtype=float)
    if t.shape != (3,) or not np.linalg.norm(t) > 0:
        raise InvalidInputError(f"a tangent must be a non-zero vector of three numbers, got {t}")
    t = t / np.linalg.norm(t)
    axis = np.cross([1.0, 0.0, 0.0], t)
    if np.linalg.norm(axis) < 1e-12:
        axis = np.array([0.0, 0.0, 1.0])
    return qt.from_axis_angle(axis / np.linalg.norm(axis), float(np.arccos(np.clip(t[0], -1.0, 1.0))))


def _rod_end_frames(args):
    """The rod's clamped end frames: the smallest rotations taking e1 to `--t-start`, `--t-end`,
    the end one turned by `--twist` about its tangent."""
    import numpy as np

    from . import quaternion as qt

    start, end = _rotation_taking_e1_to(args.t_start), _rotation_taking_e1_to(args.t_end)
    return start, qt.mul(qt.from_axis_angle(qt.rotate(end, np.array([1.0, 0.0, 0.0])), args.twist), end)


def _solve_rod(args) -> int:
    import numpy as np

    from energies import rod
    from solvers import solve

    start, end = _rod_end_frames(args)
    problem = rod.clamped(args.n, alpha=args.alpha, length=args.length, chord=args.chord, frame_start=start, frame_end=end)
    sol = solve(problem, **_solver_options(args))
    theta = np.asarray(rod.twist_angles(sol.x))
    _print_solution(sol, {"twist θ_k": f"{theta[0]:.8g} (spread {np.ptp(theta):.1e}, Lemma 3.12: constant)"})
    if args.plot:
        import ddgjax as dg

        gamma = dg.curves.from_tangents(rod.tangents(sol.x), edge_length=args.length / args.n)
        print("figure       ", dg.plot.curve(gamma, path=args.plot))
    return 0


def _solve_minimal_surface(args) -> int:
    import numpy as np

    from . import mesh

    try:
        from energies import area
    except ImportError:
        area = None
    if area is None or not hasattr(area, "minimal_surface"):
        raise NotAvailableError("minimal surfaces (energies.area.minimal_surface) are not available yet in this version")
    if args.mesh in ("annulus", "disk"):
        V, F = getattr(mesh, args.mesh)()
        V = np.array(V)
        if args.mesh == "annulus":  # lift the inner boundary circle: a catenoid-like neck
            V[np.linalg.norm(V[:, :2], axis=1) < 0.75, 2] = args.height
    else:
        V, F = mesh.read(args.mesh)
    loops = mesh.boundary_loops(F)
    if not loops:
        raise InvalidInputError(f"the mesh {args.mesh} is closed: a minimal surface spans a boundary, and it has none")
    boundary = np.unique(np.concatenate(loops))
    options = {k: v for k, v in (("tol", args.tol), ("max_iter", args.max_steps)) if v is not None}
    V, F, info = area.minimal_surface(V, F, boundary, method=args.method, **options)
    print(f"vertices      {len(V)}, faces {len(F)}")
    print(f"area          {float(mesh.surface_area(V, F)):.12g}")
    residual, iterations = info.get("residual", float("nan")), info.get("iterations", "?")
    print(f"residual      {residual:.2e} after {iterations} iterations ({args.method})")
    if args.plot:
        from .plot import surface as plot_surface

        print("figure       ", plot_surface.surface(V, F, path=args.plot, color_by="mean_curvature"))
    return 0


SOLVERS = {"elastica": _solve_elastica, "rod": _solve_rod, "minimal-surface": _solve_minimal_surface}


def _solve(args) -> int:
    if args.plot:
        _writable_figure(args.plot).parent.mkdir(parents=True, exist_ok=True)
    return SOLVERS[args.object](args)


# --- sweep ------------------------------------------------------------------------------------


def _grid_axis(text: str) -> tuple[str, "object"]:
    """`NAME=START:STOP:COUNT` -> (NAME, COUNT values from START to STOP, both included)."""
    import numpy as np

    name, _, values = text.partition("=")
    parts = values.split(":")
    if not name or len(parts) != 3:
        raise argparse.ArgumentTypeError(f"expected NAME=START:STOP:COUNT (e.g. chord=0.2:0.9:50), got {text!r}")
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"START and STOP must be numbers, got {text!r}") from None
    count = int(parts[2]) if parts[2].strip().isdigit() else 0
    if count < 1:
        raise argparse.ArgumentTypeError(f"COUNT must be a positive integer, got {text!r}")
    return name, np.linspace(start, stop, count)


def _elastica_chord(values):
    """`--param chord=...`: the chord vector (c, 0, 0), a chord of length c along x."""
    import numpy as np

    return np.stack([values, np.zeros_like(values), np.zeros_like(values)], axis=1)


def _scalar(values):
    """`--param NAME=...` of a scalar parameter: the values themselves (B,)."""
    return values


SWEEP_PARAMETERS = {"elastica": {"chord": _elastica_chord}, "rod": {"chord": _elastica_chord, "alpha": _scalar},
                    "minimal-surface": {"height": _scalar}}
"""The parameters `ddgjax sweep OBJECT --param` varies: name -> (member values -> the problem's
parameter array (B, ...))."""


def _sweep_grid(args) -> dict:
    """The product of the `--param` axes, flattened in C order (the last axis fastest), as the
    problem's parameter arrays."""
    import numpy as np

    known = SWEEP_PARAMETERS[args.object]
    axes = {}
    for name, values in args.param:
        if name not in known:
            raise InvalidInputError(f"unknown parameter {name!r} of {args.object} (have: {', '.join(sorted(known))})")
        if name in axes:
            raise InvalidInputError(f"--param {name} given twice")
        axes[name] = values
    mesh = np.meshgrid(*axes.values(), indexing="ij")
    return {name: known[name](m.ravel()) for name, m in zip(axes, mesh)}


def _sweep_template_elastica(args, grid):
    """The clamped elastica at the first member with a feasible chord (its start is the sweep's
    `x0`); the first member's if none is feasible (which raises `InfeasibleChordError`)."""
    from energies import elastica

    return elastica.clamped(args.n, length=args.length, chord=_first_feasible_chord(args, grid), t_start=args.t_start,
                            t_end=args.t_end, clamp=args.clamp)


def _first_feasible_chord(args, grid):
    """The chord of the first member shorter than the length (the first member's if none is: it
    raises `InfeasibleChordError`); `--chord`'s (c, 0, 0) when the chord is not swept."""
    import numpy as np

    chords = grid.get("chord", np.array([[args.chord, 0.0, 0.0]]))
    feasible = np.flatnonzero(np.linalg.norm(chords, axis=1) < args.length)
    return chords[feasible[0] if feasible.size else 0]


def _sweep_template_rod(args, grid):
    """The clamped rod (`--t-start`, `--t-end`, `--twist`, `--alpha`) at the first feasible chord
    and the first α of the grid: the sweep's `x0`."""
    from energies import rod

    start, end = _rod_end_frames(args)
    alpha = float(grid["alpha"][0]) if "alpha" in grid else args.alpha
    return rod.clamped(args.n, alpha=alpha, length=args.length, chord=_first_feasible_chord(args, grid),
                       frame_start=start, frame_end=end)


def _sweep_template_minimal_surface(args, grid):
    """The catenoid between the unit circles at z = ±H (`area.between_circles`, `--rings`) at the
    first H of the grid (`--height` when H is not swept): the sweep's `x0` is its cylinder."""
    from energies import area

    height = float(grid["height"][0]) if "height" in grid else args.height
    return area.between_circles(args.rings, height)


SWEEP_TEMPLATES = {"elastica": _sweep_template_elastica, "rod": _sweep_template_rod,
                   "minimal-surface": _sweep_template_minimal_surface}


def _writable_file(path) -> Path:
    """`path` for a data file: its directory writable (`_writable_directory`), not a directory."""
    path = Path(path)
    _writable_directory(path.parent)
    if path.is_dir():
        raise OutputPathError(f"cannot write the file {path}: it is a directory")
    return path


SWEEP_PROCESS = "DDGJAX_SWEEP_PROCESS"
"""Set by `ddgjax sweep --processes K` in the K processes it starts: `ID:K:HOST:PORT`."""


def _sweep(args) -> int:
    grid = _sweep_grid(args)
    out = _writable_file(args.out)
    if args.processes > 1 and SWEEP_PROCESS not in os.environ:
        return _launch_sweep_processes(args)
    process = _join_sweep_processes(args)
    from . import sweep

    problem = SWEEP_TEMPLATES[args.object](args, grid)
    before = sweep.summary(out) if out.exists() and process == 0 else {"done": 0, "failed": 0}
    kept = before["done"] - (before["failed"] if args.retry_failed else 0)
    start = time.perf_counter()
    sweep.run(problem, grid, out, chunk=args.chunk, warm_start=None if args.warm_start == "none" else args.warm_start,
              progress=not args.no_progress, retry_failed=args.retry_failed, processes=args.processes,
              **_solver_options(args))
    seconds = time.perf_counter() - start
    if process > 0:  # process 0 reports (and alone touches the file)
        return 0
    counts = sweep.summary(out)
    solved = counts["members"] - kept
    print(f"{counts['members']} members: {counts['converged']} converged, {counts['failed']} failed "
          f"({solved} solved now, {kept} already done)" + (f" on {args.processes} processes" if args.processes > 1 else ""))
    rate = f"{solved / seconds:.3g} members/s" if solved else "nothing left to solve"
    print(f"time          {seconds:.2f} s ({rate})")
    print(f"file          {out}")
    return 0


def _join_sweep_processes(args) -> int:
    """In a process started by `_launch_sweep_processes`: join the others through
    `jax.distributed.initialize` (before any JAX computation); its process index (0 otherwise)."""
    if SWEEP_PROCESS not in os.environ:
        return 0
    process, count, host, port = os.environ[SWEEP_PROCESS].split(":")
    import jax

    jax.distributed.initialize(coordinator_address=f"{host}:{port}", num_processes=int(count),
                               process_id=int(process), initialization_timeout=120)
    return int(process)


def _launch_sweep_processes(args) -> int:
    """`ddgjax sweep ... --processes K`: the same command in K local processes joined by
    `jax.distributed` (process 0 coordinates on a free localhost port, shows the progress and
    writes the file; the others' output goes to a log kept on failure).  When one fails the
    others are stopped; the exit code is the first failure's."""
    import socket

    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        port = probe.getsockname()[1]
    procs, logs = [], []
    for k in range(args.processes):
        env = dict(os.environ, **{SWEEP_PROCESS: f"{k}:{args.processes}:localhost:{port}"})
        log = None if k == 0 else tempfile.TemporaryFile(mode="w+")
        logs.append(log)
        procs.append(subprocess.Popen([sys.executable, "-m", "ddgjax", *args.argv], env=env,
                                      stdout=log, stderr=subprocess.STDOUT if log else None))
    try:
        while None in (codes := [p.poll() for p in procs]) and not any(codes):
            time.sleep(0.1)
    finally:
        for p in procs:
            if p.poll() is None:
                p.terminate()
            p.wait()
    failed = next((k for k, p in enumerate(procs) if p.returncode), None)
    if failed is not None and failed > 0:
        logs[failed].seek(0)
        lines = logs[failed].read().strip().splitlines() or ["(no output)"]
        print(f"ddgjax: error: sweep process {failed} of {args.processes} failed (exit {procs[failed].returncode}): "
              f"{lines[-1]}", file=sys.stderr)
    for log in logs:
        if log is not None:
            log.close()
    return 0 if failed is None else procs[failed].returncode


def _sweep_plot(args) -> int:
    from .plot import sweep as plot_sweep

    out = _writable_figure(args.out or Path(args.file).with_suffix(".png"))
    data = plot_sweep.load(args.file)
    out.parent.mkdir(parents=True, exist_ok=True)
    print("figure       ", plot_sweep.family(data, out=out))
    return 0


# --- bench ------------------------------------------------------------------------------------


def _benchmark_dir() -> Path:
    """`benchmarks/` of the working directory, else of the source tree ddgjax was installed from."""
    for candidate in (Path.cwd() / "benchmarks", Path(__file__).resolve().parent.parent / "benchmarks"):
        if candidate.is_dir():
            return candidate
    raise NotAvailableError("no benchmarks/ directory here or next to the ddgjax sources; run from a clone of the repository")


def _bench(args) -> int:
    available = sorted(_benchmark_dir().glob("*.py"))
    scripts = [s for s in available if not args.names or s.stem in args.names]
    if not scripts:
        raise InvalidInputError(f"no benchmark named {args.names}; have {[s.stem for s in available]}")
    status = 0
    for script in scripts:
        quick = ["--quick"] if args.quick and "--quick" in script.read_text(encoding="utf-8") else []
        print(f"== {script.name} {' '.join(quick)}".rstrip(), flush=True)
        status |= subprocess.run([sys.executable, str(script), *quick], check=False).returncode != 0
    return int(status)


# --- parser -----------------------------------------------------------------------------------


def _vector(name: str, default):
    return dict(type=float, nargs=3, metavar=("X", "Y", "Z"), default=default, help=f"{name} (default: {default})")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ddgjax", description="Variational discrete differential geometry in JAX.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")
    parser.add_argument("--version", action="version", version=f"ddgjax {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)

    verify = commands.add_parser("verify", help="check every implemented statement of the reference; write a report")
    verify.add_argument("--quick", action="store_true", help="small sizes (under 2 minutes on 2 cores)")
    verify.add_argument("--out", default="report", help="directory of report.md and figures/ (default: report)")
    verify.add_argument("--only", nargs="+", metavar="WORD", help="run the checks whose name, reference or module contains WORD")
    verify.add_argument("--list", action="store_true", help="list the checks and exit")
    verify.add_argument("--no-progress", action="store_true", help="no progress bar")
    verify.add_argument("--jobs", type=_positive_int, default=min(2, os.cpu_count() or 1),
                        help="worker processes (default: 2, or 1 on a single core)")
    verify.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                        help="stop at the first failing check with its traceback")
    verify.set_defaults(run=_verify)

    solve = commands.add_parser("solve", help="solve one object and print (and plot) it")
    solve.add_argument("object", choices=sorted(SOLVERS))
    solve.add_argument("--n", type=int, default=100, help="number of edges (default: 100)")
    solve.add_argument("--length", type=float, default=1.0, help="length of the curve (default: 1)")
    solve.add_argument("--chord", **_vector("end point minus start point", [0.5, 0.0, 0.0]))
    solve.add_argument("--t-start", **_vector("tangent at the start", [0.0, 1.0, 0.0]))
    solve.add_argument("--t-end", **_vector("tangent at the end", [0.0, -1.0, 0.0]))
    solve.add_argument("--clamp", choices=["edge", "vertex"], default="edge", help="elastica: Def 3.2 (edge) or vertex tangents")
    solve.add_argument("--alpha", type=float, default=0.7, help="rod: twist stiffness (default: 0.7)")
    solve.add_argument("--twist", type=float, default=0.0, help="rod: extra twist of the end frame in radians")
    solve.add_argument("--mesh", default="annulus", help="minimal-surface: annulus, disk, or a mesh file")
    solve.add_argument("--height", type=float, default=0.4, help="minimal-surface: lift of the annulus' inner circle")
    solve.add_argument("--method", choices=["cotan", "newton", "delaunay"], default="newton",
                       help="minimal-surface: Fig 6.5 iteration (cotan), Newton on the area, or Fig 7.23 (delaunay)")
    solve.add_argument("--max-steps", type=int, help="Newton steps / iterations (default: the solver's)")
    solve.add_argument("--tol", type=float, help="tolerance on the residual (default: the solver's, 1e-10)")
    solve.add_argument("--plot", metavar="PNG", help="save a figure there")
    solve.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    solve.set_defaults(run=_solve)

    sweep = commands.add_parser("sweep", help="solve one object over a grid of parameters into an HDF5 file (resumable)")
    sweep.add_argument("object", choices=sorted(SWEEP_PARAMETERS))
    sweep.add_argument("--param", type=_grid_axis, action="append", required=True, metavar="NAME=START:STOP:COUNT",
                       help="a grid axis, COUNT values from START to STOP; several give their product "
                            "(elastica: chord, the chord's length along x; rod: chord, alpha; "
                            "minimal-surface: height, the half-distance H of the circles at z = ±H)")
    sweep.add_argument("--out", required=True, metavar="FILE", help="the HDF5 file; an existing one of the same sweep is resumed")
    sweep.add_argument("--n", type=int, default=100, help="number of edges (default: 100)")
    sweep.add_argument("--length", type=float, default=1.0, help="length of the curve (default: 1)")
    sweep.add_argument("--t-start", **_vector("tangent at the start", [0.0, 1.0, 0.0]))
    sweep.add_argument("--t-end", **_vector("tangent at the end", [0.0, -1.0, 0.0]))
    sweep.add_argument("--clamp", choices=["edge", "vertex"], default="edge", help="elastica: Def 3.2 (edge) or vertex tangents")
    sweep.add_argument("--chord", type=float, default=0.5, help="the chord (c, 0, 0) when it is not swept (default: 0.5)")
    sweep.add_argument("--alpha", type=float, default=0.7, help="rod: twist stiffness when it is not swept (default: 0.7)")
    sweep.add_argument("--twist", type=float, default=0.0, help="rod: extra twist of the end frame in radians")
    sweep.add_argument("--rings", type=_positive_int, default=8,
                       help="minimal-surface: the cylinder's n (n + 1 circles of 3n vertices; default: 8)")
    sweep.add_argument("--height", type=float, default=0.45,
                       help="minimal-surface: the half-distance H when it is not swept (default: 0.45)")
    sweep.add_argument("--chunk", type=_positive_int, default=64, help="members per batched solve (default: 64)")
    sweep.add_argument("--warm-start", choices=["previous", "none"], default="previous",
                       help="previous: a chunk starts from the last converged member before it (default); none: all from x0")
    sweep.add_argument("--retry-failed", action="store_true", help="solve the members recorded as failed again")
    sweep.add_argument("--max-steps", type=int, help="Newton steps (default: the solver's)")
    sweep.add_argument("--tol", type=float, help="tolerance on the residual (default: the solver's, 1e-10)")
    sweep.add_argument("--processes", type=_positive_int, default=1, metavar="K",
                       help="run the sweep in K local processes joined by jax.distributed (default: 1)")
    sweep.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweep.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    sweep.set_defaults(run=_sweep)

    sweep_plot = commands.add_parser("sweep-plot", help="draw a stored sweep: energy, residual, steps and shapes")
    sweep_plot.add_argument("file", metavar="FILE", help="the HDF5 file of `ddgjax sweep`")
    sweep_plot.add_argument("--out", metavar="PNG", help="the figure (default: FILE with the suffix .png)")
    sweep_plot.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    sweep_plot.set_defaults(run=_sweep_plot)

    bench = commands.add_parser("bench", help="run the benchmark scripts (benchmarks/*.py) and print their tables")
    bench.add_argument("names", nargs="*", help="only these benchmarks (file names without .py)")
    bench.add_argument("--quick", action="store_true", help="pass --quick to the scripts that accept it")
    bench.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    bench.set_defaults(run=_bench)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code (also used by the `ddgjax` entry point).

    A `DDGError` or an `OSError` (a path that cannot be read or written) is one line on stderr
    and exit code 2, or its traceback with `--debug`.
    """
    args = None
    try:
        args = build_parser().parse_args(argv)
        args.argv = list(sys.argv[1:] if argv is None else argv)
        if args.command in ("solve", "sweep", "verify"):  # not for `bench`, which measures compile times
            compile_cache.enable()
        return args.run(args)
    except (DDGError, OSError) as error:
        if getattr(args, "debug", False):
            raise
        print(f"ddgjax: error: {_one_line(error)} (hint: {hint_for(error)})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ddgjax: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
