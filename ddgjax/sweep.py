"""`ddgjax.sweep`: one problem solved over a grid of parameters, stored member by member in HDF5.

    from ddgjax import sweep
    path = sweep.run(problem, {"chord": chords}, "chords.h5", chunk=64)   # chords: (B, 3)
    data = sweep.read(path)       # data["x"] (B, n, 3), data["energy"] (B,), data["chord"] (B, 3), ...

**Members and chunks.**  `params_grid` is a dict `{name: (B, ...)}` of some of
`problem.params`' keys, as `solvers.solve_batch`'s `params_batch`: member `k` is `problem` with
`params[name] = params_grid[name][k]`.  The pending members are solved `chunk` at a time by one
`solve_batch` call (`jax.vmap` of `solve`, compiled once: a short last chunk is padded with
copies of its last member, so every call has the same shapes), and each finished chunk is
written to the file and flushed at once.  A member whose Newton iteration stops without
converging (max_steps reached, or stalled) is solved once more alone from the same start with
the L-BFGS phase first, and that solution kept if it converged: `solve`'s default
`warm_start="auto"`, which cannot run under `vmap` (its row then has `first_order_steps` > 0).
So every member's row equals
`solve(problem.with_params({**problem.params, **member}), throw=False)` from the chunk's `x0`.
If `solve_batch` raises on a chunk, that chunk's members are solved one by one with
`solve(..., throw=False)` so that the bad member is isolated.

**Failures never stop the sweep.**  A member that does not converge, or whose solve raises, is
recorded with `done = True`, `converged = False` and its message in `error` (its `x` is the last
iterate, or NaN if the solve raised); the other members go on.

**Warm starts.**  `warm_start="previous"`: every member of a chunk starts from the same `x0`, the
solution `x` of the *last converged member before the chunk's first member in grid order* (the
member with the largest index below it whose `converged` is True, in this run or a stored earlier
one), its fixed entries (the clamps) kept from `problem.x0`; the first chunk, and any chunk with
no converged member before it, starts from `problem.x0`.  Along a one-dimensional grid (a path
in parameter space) this is continuation by chunks: the members of a chunk start from the end of
the previous chunk.  For a product grid flattened in C order (the command line's) "previous" is
previous in that order.  Only `x` is carried over; the multipliers start from least squares, as
in `solve`.  `warm_start=None`: every member starts from `problem.x0`, and the results equal a
loop of `solve(problem.with_params(member), throw=False)`.

**Resuming.**  The file stores a fingerprint (SHA-256) of the problem's name, its `x0`, its
parameters outside the grid, the grid, and the solver options (`tol`, `max_steps`, `method`,
`warm_start`).  A rerun with the same `out` and the same fingerprint solves only the members not
yet `done` (and, with `retry_failed=True`, the failed ones again); a different fingerprint is
refused with `InvalidInputError` naming what differs.  `chunk` is not part of it: a rerun may
take another (with `"previous"` the starts, so possibly the solution a member finds, depend on
it).  A run killed between chunks loses only
the chunk in flight; HDF5 is not journaled, so a kill in the middle of a write (milliseconds per
chunk) can leave the file unreadable: delete it and start again.

**Processes.**  In one process (`processes=None` or 1) several devices are used through
`devices=` (passed to `solve_batch`, which shards each chunk over them).  Several processes (one
per host, or several on one machine) run the sweep SPMD on JAX's own multi-process runtime:
every process calls `jax.distributed.initialize(...)` and then `run` with the same arguments;
each chunk is one `solve_batch` over the devices of all processes (`devices="all"` by default
then), which hands every process the whole chunk; process 0 alone opens and writes the file,
and tells the others which members are pending and each chunk's warm start
(`multihost_utils.broadcast_one_to_all`), so the file is the same as a one-process run's.  A
failure of process 0 to open the file is raised in every process.  `processes=K` checks that
JAX runs K processes.  `ddgjax sweep ... --processes K` starts K local processes so joined.

**File layout** (`read` returns the same names):

| dataset | shape, dtype | |
|---|---|---|
| `x` | (B, *x0.shape) f8 | one array of unknowns; a pytree of them: group `x/<key>` |
| `multipliers` | (B, m) f8 | flat; named constraints: group `multipliers/<name>` |
| `energy`, `residual` | (B,) f8 | |
| `steps`, `status` | (B,) i8 | `status`: 0 converged, 1 max_steps, 2 stalled, 3 non-finite, -1 raised/not run |
| `first_order_steps` | (B,) i8 | L-BFGS steps before Newton: > 0 where the member came from the retry |
| `converged`, `done` | (B,) bool | |
| `error` | (B,) str | "" for converged members |
| `params/<name>` | (B, ...) f8 | the grid |

and the attributes `fingerprint`, `problem`, `tol`, `max_steps`, `method`, `warm_start`, `chunk`.
"""

from __future__ import annotations

import hashlib
import time
from pathlib import Path

import h5py
import jax
import numpy as np

from solvers import STATUS_TEXT, solve, solve_batch

from .errors import InvalidInputError
from .problem import Problem

__all__ = ["run", "read", "summary", "RESULT_NAMES"]

FORMAT = "ddgjax.sweep/1"
SCALARS = ("energy", "residual", "steps", "first_order_steps", "status", "converged")
"""The results with one value per member, as named in `Solution`."""
RESULT_NAMES = ("x", "multipliers", *SCALARS, "done", "error", "params")
WARM_STARTS = ("previous", None)
RAISED = -1  # status of a member whose solve raised (or that was never solved)
RETRIED = (1, 2)  # max_steps reached, stalled: `solve(warm_start="auto")` retries these with L-BFGS first


# --- the grid ---------------------------------------------------------------------------------


def _checked_grid(problem: Problem, params_grid) -> tuple[dict, int]:
    """`params_grid` as `{name: float64 array (B, ...)}` and B; `InvalidInputError` unless it is a
    dict of some of `problem.params`' keys whose arrays share the leading axis B ≥ 1."""
    if not isinstance(params_grid, dict) or not params_grid:
        raise InvalidInputError(f"params_grid must be a non-empty dict {{name: (B, ...) array}}, got {type(params_grid).__name__}")
    base = problem.params if isinstance(problem.params, dict) else {}
    grid = {}
    for name, values in params_grid.items():
        if name not in base:
            raise InvalidInputError(f"params_grid[{name!r}]: the problem has no parameter {name!r} (it has {sorted(base)})")
        values = np.asarray(values, dtype=np.float64)
        expected = np.shape(base[name])
        if values.ndim == 0 or values.shape[1:] != expected:
            raise InvalidInputError(f"params_grid[{name!r}] must have shape (B, {', '.join(map(str, expected))}) "
                                    f"(B members of params[{name!r}]), got {values.shape}")
        grid[name] = values
    sizes = {v.shape[0] for v in grid.values()}
    if len(sizes) != 1 or 0 in sizes:
        raise InvalidInputError(f"the arrays of params_grid need one common, non-zero number of members, got "
                                f"{ {k: v.shape[0] for k, v in grid.items()} }")
    return grid, sizes.pop()


def _digest(*parts) -> str:
    h = hashlib.sha256()
    for part in parts:
        if isinstance(part, np.ndarray):
            h.update(f"{part.dtype}{part.shape}".encode())
            h.update(np.ascontiguousarray(part).tobytes())
        else:
            h.update(repr(part).encode())
        h.update(b"\0")
    return h.hexdigest()


def _tree_digest(tree) -> str:
    leaves = jax.tree_util.tree_flatten_with_path(tree)[0]
    return _digest(*[p for path, leaf in leaves for p in (jax.tree_util.keystr(path), np.asarray(leaf, dtype=np.float64))])


def _fingerprint(problem: Problem, grid: dict, options: dict) -> dict:
    """The parts that make a stored sweep resumable with these arguments, each a string."""
    shared = {k: v for k, v in problem.params.items() if k not in grid}
    return {
        "problem name": problem.name,
        "x0": _tree_digest(problem.x0),
        "shared parameters": _tree_digest(shared),
        "grid": _tree_digest(grid),
        "solver options": repr(sorted(options.items())),
    }


# --- the file ---------------------------------------------------------------------------------


def _leaves(tree) -> list[tuple[str, np.ndarray]]:
    """`[(key, leaf)]`: key "" for a single array, else the leaves' paths ("chord", "0/a")."""
    flat, treedef = jax.tree_util.tree_flatten_with_path(tree)
    if treedef.num_nodes == 1:
        return [("", np.asarray(flat[0][1]))]
    return [("/".join(_key_name(k) for k in path), np.asarray(leaf)) for path, leaf in flat]


def _key_name(key) -> str:
    for attribute in ("key", "idx", "name"):  # DictKey, SequenceKey, GetAttrKey
        if hasattr(key, attribute):
            return str(getattr(key, attribute))
    return str(key)


def _create(f: h5py.File, problem: Problem, grid: dict, size: int, fingerprint: dict, attrs: dict) -> None:
    """The empty datasets of a sweep of `size` members (`done` all False)."""
    multipliers = problem.constraint_structure.unravel(np.zeros(problem.n_constraints))
    for name, tree in (("x", problem.x0), ("multipliers", multipliers)):
        for key, leaf in _leaves(tree):
            f.create_dataset(f"{name}/{key}" if key else name, shape=(size, *leaf.shape), dtype="f8", fillvalue=np.nan)
    for name in ("energy", "residual"):
        f.create_dataset(name, shape=(size,), dtype="f8", fillvalue=np.nan)
    _create_first_order_steps(f, size)
    f.create_dataset("steps", shape=(size,), dtype="i8", fillvalue=0)
    f.create_dataset("status", shape=(size,), dtype="i8", fillvalue=RAISED)
    f.create_dataset("converged", shape=(size,), dtype=bool, fillvalue=False)
    f.create_dataset("done", shape=(size,), dtype=bool, fillvalue=False)
    f.create_dataset("error", shape=(size,), dtype=h5py.string_dtype())
    for name, values in grid.items():
        f.create_dataset(f"params/{name}", data=values)
    f.attrs.update({"format": FORMAT, "fingerprint": _digest(*fingerprint.items()), **{f"fingerprint: {k}": v for k, v in fingerprint.items()},
                    **{k: ("None" if v is None else v) for k, v in attrs.items()}})
    f.flush()


def _create_first_order_steps(f: h5py.File, size: int) -> None:
    f.create_dataset("first_order_steps", shape=(size,), dtype="i8", fillvalue=0)


def _check_resumable(f: h5py.File, out, fingerprint: dict, size: int) -> None:
    if f.attrs.get("format") != FORMAT:
        raise InvalidInputError(f"{out} exists and is not a ddgjax sweep file; choose another --out / out")
    if f.attrs["fingerprint"] == _digest(*fingerprint.items()):
        return
    differ = [k for k, v in fingerprint.items() if f.attrs.get(f"fingerprint: {k}") != v]
    stored = f["done"].shape[0]
    detail = (f": stored {f.attrs.get('fingerprint: problem name')!r}, given {fingerprint['problem name']!r}"
              if differ == ["problem name"] else f": stored {stored} members, given {size}" if stored != size else "")
    raise InvalidInputError(f"{out} holds another sweep (different {', '.join(differ)}{detail}): it cannot be resumed with "
                            "these arguments; pass another out, or delete the file to start again")


def _open(out, problem: Problem, grid: dict, size: int, fingerprint: dict, attrs: dict) -> h5py.File:
    """The sweep file at `out`: created if absent, checked against `fingerprint` if present."""
    path = Path(out)
    try:
        if path.exists():
            f = h5py.File(path, "r+")
            try:
                _check_resumable(f, out, fingerprint, size)
            except BaseException:
                f.close()
                raise
            if "first_order_steps" not in f:  # a file written before the column existed
                _create_first_order_steps(f, size)
            return f
        path.parent.mkdir(parents=True, exist_ok=True)
        f = h5py.File(path, "w")
    except OSError as error:
        raise InvalidInputError(f"cannot open {out} as a sweep file: {' '.join(str(error).split())}") from None
    _create(f, problem, grid, size, fingerprint, attrs)
    return f


def _write(f: h5py.File, index: np.ndarray, rows: dict) -> None:
    """Rows `index` (increasing) of every result, then `done`, then a flush."""
    for name, tree in (("x", rows["x"]), ("multipliers", rows["multipliers"])):
        for key, leaf in _leaves(tree):
            f[f"{name}/{key}" if key else name][index] = leaf
    for name in (*SCALARS, "error"):
        f[name][index] = rows[name]
    f["done"][index] = True
    f.flush()


def read(path) -> dict:
    """The stored sweep at `path` as a dict of NumPy arrays, member axis first: `x`,
    `multipliers` (an array, or a dict by constraint name), `energy`, `residual`, `steps`,
    `first_order_steps`, `status`, `converged`, `done`, `error` (an array of str), `params` (dict by name), every
    parameter of the grid also under its own name (`read(p)["chord"]`) unless that name is one
    of the above, and `attrs` (the file's attributes: problem name, options, fingerprint).
    Members not yet solved have `done == False` and NaN in the float arrays.

    **Raises:** `InvalidInputError` when `path` cannot be read or is not a sweep file.
    """
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise InvalidInputError(f"{path} is not a ddgjax sweep file")
            out = {}

            def visit(name, obj):
                if isinstance(obj, h5py.Dataset):
                    value = obj.asstr()[()] if h5py.check_string_dtype(obj.dtype) else obj[()]
                    node, *keys = name.split("/")
                    if not keys:
                        out[node] = value
                    else:
                        target = out.setdefault(node, {})
                        for key in keys[:-1]:
                            target = target.setdefault(key, {})
                        target[keys[-1]] = value

            f.visititems(visit)
            out["error"] = np.asarray(out["error"], dtype=object).astype(str)
            out["attrs"] = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
    except OSError as error:
        raise InvalidInputError(f"cannot read the sweep file {path}: {' '.join(str(error).split())}") from None
    for name, values in out.get("params", {}).items():
        out.setdefault(name, values)
    return out


# --- solving ------------------------------------------------------------------------------------


def _member_params(grid: dict, k: int) -> dict:
    return {name: values[k] for name, values in grid.items()}


def _failure_message(residual: float, steps: int, status: int, tol: float) -> str:
    why = STATUS_TEXT.get(status, f"status {status}")
    return f"did not converge after {steps} steps, KKT residual {residual:.3e} > tol {tol:.1e}: {why}"


def _rows_of(sol, count: int, tol: float) -> dict:
    """The first `count` members of a batched `Solution` as rows to write."""
    take = lambda tree: jax.tree_util.tree_map(lambda a: np.array(a)[:count], tree)  # noqa: E731
    rows = {"x": take(sol.x), "multipliers": take(sol.multipliers)}
    for name in SCALARS:
        rows[name] = np.array(getattr(sol, name))[:count]
    rows["error"] = np.array(["" if ok else _failure_message(float(r), int(s), int(st), tol)
                              for ok, r, s, st in zip(rows["converged"], rows["residual"], rows["steps"], rows["status"])],
                             dtype=object)
    return rows


def _solve_one(template: Problem, params: dict, options: dict, warm_start: str | None = "auto") -> dict:
    """The member of `template` with `params` by `solve(..., throw=False)`: its row, a raised
    error (also from declaring the member, e.g. NaN parameters) recorded as a message."""
    tol, problem = options["tol"], template
    try:
        problem = template.with_params({**template.params, **params})
        sol = solve(problem, throw=False, warm_start=warm_start, **options)
    except Exception as error:  # noqa: BLE001: a member's failure is data, not the sweep's
        nan = lambda a: np.full(np.shape(a), np.nan)  # noqa: E731
        lam = problem.constraint_structure.unravel(np.zeros(problem.n_constraints))
        message = f"{type(error).__name__}: {' '.join(str(error).split())}"
        return {"x": jax.tree_util.tree_map(nan, problem.x0), "multipliers": jax.tree_util.tree_map(nan, lam),
                "energy": np.nan, "residual": np.nan, "steps": 0, "first_order_steps": 0, "status": RAISED,
                "converged": False, "error": message}
    row = {name: getattr(sol, name) for name in ("x", "multipliers", *SCALARS)}
    row = jax.tree_util.tree_map(np.asarray, row)
    row["error"] = "" if bool(row["converged"]) else _failure_message(float(row["residual"]), int(row["steps"]), int(row["status"]), tol)
    return row


def _stack(rows: list[dict]) -> dict:
    stacked = {name: jax.tree_util.tree_map(lambda *a: np.stack(a), *[r[name] for r in rows]) for name in ("x", "multipliers")}
    for name in SCALARS:
        stacked[name] = np.array([r[name] for r in rows])
    stacked["error"] = np.array([r["error"] for r in rows], dtype=object)
    return stacked


def _solve_chunk(template: Problem, grid: dict, index: np.ndarray, chunk: int, options: dict, devices) -> dict:
    """Rows of the members `index` started from `template.x0`: one `solve_batch` call on the
    members padded to `chunk` (one compilation for every chunk), else member by member."""
    padded = np.concatenate([index, np.repeat(index[-1:], chunk - len(index))])
    batch = {name: values[padded] for name, values in grid.items()}
    try:
        sol = solve_batch(template, batch, devices=devices, throw=False, **options)
    except Exception:  # noqa: BLE001: isolate the member that broke the batch
        return _stack([_solve_one(template, _member_params(grid, k), options) for k in index])
    rows = _rows_of(sol, len(index), options["tol"])
    for i in np.flatnonzero(np.isin(rows["status"], RETRIED)):
        # `solve`'s warm_start="auto", which vmap cannot do: the same start, L-BFGS first
        retry = _solve_one(template, _member_params(grid, int(index[i])), options, warm_start="lbfgs")
        if retry["converged"]:
            _set_row(rows, i, retry)
    return rows


def _set_row(rows: dict, i: int, row: dict) -> None:
    for name in ("x", "multipliers"):
        jax.tree_util.tree_map(lambda stacked, value: stacked.__setitem__(i, value), rows[name], row[name])
    for name in (*SCALARS, "error"):
        rows[name][i] = row[name]


def _warm_x0(problem: Problem, f: h5py.File, first: int):
    """`x0` of a chunk whose first member is `first` (module docstring, "Warm starts")."""
    converged = np.flatnonzero(f["converged"][:first])
    if not converged.size:
        return problem.x0
    k = int(converged[-1])
    x0_leaves, treedef = jax.tree_util.tree_flatten(problem.x0)
    if treedef.num_nodes == 1:
        stored = [f["x"][k]]
    else:
        stored = [f[f"x/{key}"][k] for key, _ in _leaves(problem.x0)]
    fixed = jax.tree_util.tree_leaves(problem.fixed)
    return jax.tree_util.tree_unflatten(treedef, [np.where(m, np.asarray(a), s) for a, m, s in zip(x0_leaves, fixed, stored)])


class _Progress:
    """A rich progress bar of members solved and members per second (on stderr), or nothing."""

    def __init__(self, enabled: bool, total: int, done: int, label: str):
        self.bar = None
        if enabled:
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                TextColumn("{task.fields[rate]} members/s, {task.fields[failed]} failed"), TimeElapsedColumn(),
                                console=Console(stderr=True))
            self.task = self.bar.add_task(label, total=total, completed=done, rate="–", failed=0)
            self.start, self.solved, self.failed = time.perf_counter(), 0, 0
            self.bar.start()

    def advance(self, count: int, failed: int) -> None:
        if self.bar is not None:
            self.solved, self.failed = self.solved + count, self.failed + failed
            rate = self.solved / max(time.perf_counter() - self.start, 1e-9)
            self.bar.update(self.task, advance=count, rate=f"{rate:.3g}", failed=self.failed)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()


def _pending(f: h5py.File, retry_failed: bool) -> np.ndarray:
    done = f["done"][()]
    if retry_failed:
        done &= f["converged"][()]
    return np.flatnonzero(~done)


def run(
    problem: Problem,
    params_grid: dict,
    out,
    *,
    chunk: int = 64,
    warm_start: str | None = "previous",
    progress: bool = True,
    processes: int | None = None,
    devices=None,
    retry_failed: bool = False,
    tol: float = 1e-10,
    max_steps: int = 100,
    method: str = "auto",
) -> Path:
    """Solve `problem` for every member of `params_grid`, chunk by chunk, into the HDF5 file `out`
    (module docstring: chunks, failures, warm starts, resuming, layout); read it with `read`.

    **Arguments:**
    - `problem`: the template (its `x0`, fixed entries and the parameters outside the grid).
    - `params_grid`: `{name: (B, ...)}`, some of `problem.params`' keys with a member axis.
    - `out`: the file; if it exists and holds this sweep (same fingerprint), only the members not
      yet done are solved.
    - `chunk`: members per `solve_batch` call (at most B).
    - `warm_start`: `"previous"` or `None` (module docstring).
    - `progress`: a rich progress bar with members per second on stderr.
    - `processes`: `None` (as many as JAX runs, `jax.process_count()`) or that number (module
      docstring, "Processes"); `devices`: `solve_batch`'s (default: one device, or every
      process's devices, `"all"`, when several processes run).
    - `retry_failed`: on a rerun, solve the recorded failures again too.
    - `tol`, `max_steps`, `method`: as in `solve` (part of the fingerprint).

    **Returns:** the path of the file.

    **Raises:** `InvalidInputError` for a malformed grid, a bad option, `processes` other than
    `jax.process_count()`, a file
    that is not a sweep file or holds another sweep (problem, x0, parameters, grid or options
    differ), or a path that cannot be written.  A member's failure is recorded, never raised.
    """
    count = jax.process_count()
    if processes is not None and (isinstance(processes, bool) or processes != count):
        raise InvalidInputError(
            f"processes={processes!r}, but JAX runs {count} process(es): start each process with "
            "jax.distributed.initialize(...) and call run in every one (or `ddgjax sweep --processes K`)")
    if warm_start not in WARM_STARTS:
        raise InvalidInputError(f"warm_start must be one of {WARM_STARTS}, got {warm_start!r}")
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise InvalidInputError(f"chunk must be a positive integer, got {chunk!r}")
    grid, size = _checked_grid(problem, params_grid)
    clash = sorted(set(grid) & set(RESULT_NAMES + ("attrs",)))
    if clash:
        raise InvalidInputError(f"params_grid: the parameter names {clash} clash with the names of the results")
    chunk = min(int(chunk), size)
    options = {"tol": float(tol), "max_steps": int(max_steps), "method": method}
    fingerprint = _fingerprint(problem, grid, {**options, "warm_start": warm_start})
    attrs = {**options, "warm_start": warm_start, "chunk": chunk, "problem": problem.name}
    lead = jax.process_index() == 0
    if count > 1 and devices is None:
        devices = "all"
    f = _open_on_lead(out, problem, grid, size, fingerprint, attrs)
    try:
        pending = _pending_on_lead(f, size, retry_failed)
        bar = _Progress(progress and lead, size, size - len(pending), "sweep")
        try:
            for start in range(0, len(pending), chunk):
                index = pending[start:start + chunk]
                template = problem if warm_start is None else problem.with_x0(_warm_x0_on_lead(problem, f, int(index[0])))
                rows = _solve_chunk(template, grid, index, chunk, options, devices)
                if f is not None:
                    _write(f, index, rows)
                bar.advance(len(index), int(np.count_nonzero(~rows["converged"])))
        finally:
            bar.close()
    finally:
        if f is not None:
            f.close()
    return Path(out)


def _from_lead(value):
    """`value` (a pytree of arrays, the same structure and shapes in every process) as process 0
    has it; itself in a one-process run."""
    if jax.process_count() == 1:
        return value
    from jax.experimental import multihost_utils

    value = jax.tree_util.tree_map(np.asarray, value)
    return jax.tree_util.tree_map(np.asarray, multihost_utils.broadcast_one_to_all(value))


def _open_on_lead(out, problem, grid, size, fingerprint, attrs) -> h5py.File | None:
    """The sweep file, opened by process 0 only (`None` in the others); an error opening it is
    raised in every process."""
    f, failure = None, None
    if jax.process_index() == 0:
        try:
            f = _open(out, problem, grid, size, fingerprint, attrs)
        except InvalidInputError as error:
            failure = error
    if bool(_from_lead(np.asarray(failure is not None))):
        raise failure if failure is not None else InvalidInputError(f"process 0 could not open the sweep file {out}")
    return f


def _pending_on_lead(f: h5py.File | None, size: int, retry_failed: bool) -> np.ndarray:
    """The members to solve, as process 0 reads them from the file."""
    mask = np.zeros(size, dtype=bool)
    if f is not None:
        mask[_pending(f, retry_failed)] = True
    return np.flatnonzero(_from_lead(mask))


def _warm_x0_on_lead(problem: Problem, f: h5py.File | None, first: int):
    """`_warm_x0` as process 0 reads it from the file."""
    x0 = _warm_x0(problem, f, first) if f is not None else problem.x0
    return _from_lead(x0)


def summary(path) -> dict:
    """Counts of a stored sweep: `members`, `done`, `converged`, `failed`."""
    data = read(path)
    done, converged = data["done"], data["converged"]
    return {"members": int(done.size), "done": int(done.sum()), "converged": int(converged.sum()),
            "failed": int((done & ~converged).sum())}

