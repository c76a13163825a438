"""`solve_batch`: one problem solved for a batch of parameters, vectorised and sharded over devices.

The batch solver is `jax.vmap` of `solve`'s Newton solver (`_batch_impl`), compiled once per
declaration, options and shapes and kept in a bounded cache (`_cache.LRU`): a second call on a
problem declared alike reuses the executable.  On one device it is a `_exported.Program`
(`PROGRAMS`), exported to disk like `solve`'s, so that a new process (a resumed or repeated
`ddgjax sweep`) calls it without tracing it; split over devices, the `jax.shard_map` executable
is kept by structure in `COMPILED`.  The bound linear solver is an argument: KLU's analysis,
an address in each process, is never a constant of the program.
"""

from __future__ import annotations

import math
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ddgjax.errors import ConvergenceError, InvalidInputError, ShapeError
from ddgjax.problem import Problem

from ._cache import LRU, cleared_by_jax
from ._exported import Program
from ._solve import METHODS, Solution, _solve_impl, solver_inputs

BATCH_AXIS = "batch"

COMPILED_BATCH_SOLVERS = 32
"""Executables `solve_batch` keeps, the least recently used dropped first (each is megabytes
and, on the CPU, a few hundred memory mappings)."""

COMPILED = cleared_by_jax(LRU(COMPILED_BATCH_SOLVERS), "solvers.solve_batch executables")
"""`solve_batch`'s executables by structure (`structure_key`); `jax.clear_caches()` empties it."""


def _checked_batch(problem: Problem, params_batch):
    """`params_batch`, either a pytree like `problem.params` with a leading batch axis on every
    leaf, or (for dict params) a dict of some of its keys, the others kept from `problem`
    (`_member_params`)."""
    base = problem.params
    if isinstance(base, dict) and isinstance(params_batch, dict) and set(params_batch) < set(base):
        return params_batch
    if jax.tree_util.tree_structure(params_batch) != jax.tree_util.tree_structure(base):
        raise ShapeError(
            "params_batch must have the structure of problem.params (or, for dict params, a subset "
            f"of its keys): got {jax.tree_util.tree_structure(params_batch)}, "
            f"expected {jax.tree_util.tree_structure(base)}"
        )
    return params_batch


def _batch_size(batched) -> int:
    leaves = [jnp.asarray(a) for a in jax.tree_util.tree_leaves(batched)]
    if not leaves or any(a.ndim == 0 for a in leaves):
        raise ShapeError("every leaf of params_batch needs a leading batch axis")
    sizes = {a.shape[0] for a in leaves}
    if len(sizes) != 1:
        raise ShapeError(f"the leaves of params_batch have different batch sizes {sorted(sizes)}")
    return sizes.pop()


def _device_tuple(devices) -> tuple | None:
    """`devices` as a tuple (`"all"`: `jax.devices()`), or None for the default device."""
    if devices is None:
        return None
    devices = tuple(jax.devices() if devices == "all" else devices)
    if not devices:
        raise InvalidInputError("solve_batch: devices is empty")
    return devices


def structure_key(spec, args: tuple, options: tuple, devices) -> tuple:
    """What the compiled solver depends on: the declaration (`Spec`: the energy and constraint
    functions, by identity or, declared local, by value; the layout of the unknowns and the
    fixed entries), the options, the devices and backend, and the arguments' tree structure,
    shapes, dtypes and placements — not their values."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    avals = tuple((jax.typeof(a), a.sharding) for a in leaves)
    return (spec, options, devices, jax.default_backend(), treedef, avals)


def _member_params(params, member):
    """A member's full params: its batched entries (all of them, or some keys of dict params)
    in place of the template's."""
    return {**params, **member} if isinstance(params, dict) else member


def _batch_impl(spec, linear, z0, params, weights, batched, *, tol: float, max_steps: int) -> Solution:
    """`solve`'s Newton solver (`_solve_impl`, no first-order phase) of every member of `batched`
    (`jax.vmap` over its leading axis), each from `z0` with `_member_params(params, member)`."""

    def member(p):
        return _solve_impl(spec, linear, z0, _member_params(params, p), None, weights, tol=tol, max_steps=max_steps,
                           first_order=0, newton_phase=True)

    return jax.vmap(member)(batched)


PROGRAMS = cleared_by_jax(LRU(COMPILED_BATCH_SOLVERS), "solvers.solve_batch programs")
"""The batch solvers on one device, by declaration and options (`_exported.Program`: kept across
processes like `solve`'s, a new process calls the exported program without tracing it)."""


def _program(spec, tol: float, max_steps: int) -> Program:
    static = dict(tol=tol, max_steps=max_steps)
    return PROGRAMS.get((spec, tuple(static.items())), lambda: Program(_batch_impl, spec, static))


def _compile_sharded(spec, args: tuple, options: tuple, devices):
    """The executable of `_batch_impl` split over `devices` with `jax.shard_map`, compiled for `args`."""
    _, tol, max_steps = options
    impl = partial(_batch_impl, spec, tol=tol, max_steps=max_steps)
    # shard_map, not jit with shardings: XLA's partitioner cannot split KLU's custom call,
    # and partitioning the batched Newton loop took minutes to compile
    mesh = _mesh(devices)
    replicated, split = PartitionSpec(), PartitionSpec(BATCH_AXIS)
    batched = jax.shard_map(impl, mesh=mesh, in_specs=(replicated,) * 4 + (split,), out_specs=split, check_vma=False)
    return jax.jit(batched).lower(*args).compile()


def _mesh(devices) -> Mesh:
    return Mesh(np.array(devices), (BATCH_AXIS,))


def _placed(args: tuple, size: int, devices) -> tuple:
    """`args` on the mesh of `devices`: the batch padded with copies of its last member to a
    multiple of the number of devices and split along `"batch"`, the rest replicated."""
    padded = math.ceil(size / len(devices)) * len(devices)
    batched = args[-1]
    if padded > size:
        batched = jax.tree_util.tree_map(lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], padded - size, axis=0)]), batched)
    mesh = _mesh(devices)
    shared = jax.tree_util.tree_map(lambda a: _replicated(a, NamedSharding(mesh, PartitionSpec())), args[:-1])
    return (*shared, jax.device_put(batched, NamedSharding(mesh, PartitionSpec(BATCH_AXIS))))


def _replicated(a: jax.Array, sharding: NamedSharding) -> jax.Array:
    """`a` on every device of the mesh, each process placing its own value on its devices.

    Not `jax.device_put`, which checks across processes that the values are equal: the address
    of KLU's analysis (a leaf of the bound linear solver) is each process's own."""
    return jax.make_array_from_single_device_arrays(
        a.shape, sharding, [jax.device_put(a, device) for device in sharding.addressable_devices])


def solve_batch(
    problem: Problem,
    params_batch,
    *,
    devices=None,
    method: str = "auto",
    linear_solver=None,
    tol: float = 1e-10,
    max_steps: int = 100,
    throw: bool = True,
) -> Solution:
    """Solve `problem` for every member of a batch of parameters in one compiled call.

    `jax.vmap` of `solve` (its Newton solver, without the L-BFGS retry) over the parameters,
    jit-compiled once for the whole batch (and kept across processes, module docstring); with
    `devices`, the batch is split over them (a `jax.sharding.Mesh` with one axis, `"batch"`,
    the parameters placed with `NamedSharding(mesh, PartitionSpec("batch"))` and each device
    solving its slice with `jax.shard_map`).  The batch is padded with copies of its last
    member to a multiple of the number of devices; the padding is dropped from the result.

    Each member runs its own Newton iteration (under `vmap` the loop runs until every member
    has converged; finished members stay put), so the result equals a loop of `solve` calls.
    Every linear-algebra path batches: `method="sparse"` (KLU, CPU only; vmapped as a loop of
    factorisations inside the compiled call), `"dense"` (batched LU, any backend) and
    `"krylov"` (matrix-free, any backend).  `"auto"` picks as `solve` does (`choose_method`).

    **Compiled once per structure.**  The executable is kept in `solvers._batch.COMPILED`, an
    LRU of at most `COMPILED_BATCH_SOLVERS` (32) entries, keyed by the problem's declaration
    (the same energy and constraint functions, by identity, or declared with `dg.local_sum`,
    by value; the same fixed entries), the shapes and dtypes of `x0` and of the parameters,
    the batch size, `method`, `linear_solver`, `tol`, `max_steps` and `devices`.  The values
    of `x0`, of the parameters and of `residual_scale` are arguments of the executable, so a
    second call on a problem declared alike runs without tracing or compiling.  A new function
    per call (a fresh `lambda`) is a new structure: it compiles, and the least recently used
    executable is dropped.  `jax.clear_caches()` empties the cache.

    **Arguments:**
    - `problem`: the template; its `x0`, `fixed`, functions and the unbatched parameters are
      shared by the batch.
    - `params_batch`: a pytree like `problem.params` whose leaves have a leading batch axis,
      or, for dict parameters, a dict of only the keys that vary (e.g. `{"chord": (B, 3)}`).
    - `devices`: `None` (default device), `"all"` (`jax.devices()`), or a list of devices.
    - `method`, `linear_solver`, `tol`, `max_steps`: as in `solve`.
    - `throw`: raise `ConvergenceError` naming the first member that did not converge.

    **Returns:** a `Solution` whose leaves have a leading batch axis (sharded over `devices`
    of this process; gathered whole into every process when `devices` span several).

    **Several processes** (one per host, or several on one host; tested with two local CPU
    processes in `tests/test_multiprocess.py`).  Every process

    1. calls `jax.distributed.initialize(coordinator_address="HOST0:PORT", num_processes=P,
       process_id=RANK)` before any other JAX call (under Slurm's `srun`, one task per host,
       a bare `jax.distributed.initialize()` reads all three from Slurm's environment);
    2. builds the same `problem` and the same full `params_batch` (all B members, not its
       slice: each process places its devices' slices from its own copy, unchecked, so
       different batches give a wrong result, not an error);
    3. calls `solve_batch(problem, params_batch, devices="all")` with the same options, in the
       same order as the other processes (it compiles in each and ends in an all-gather, a
       collective: a process that skips a call leaves the others waiting).

    `jax.devices()` lists the devices of all processes; the batch (padded to a multiple of
    their number) is split over them, each device solving its slice, and the result is
    gathered (`multihost_utils.process_allgather`), so every process gets the full `Solution`
    of all B members on its default device, fully addressable, and `throw` raises the same
    `ConvergenceError` in every process.  On CPU hosts the gather uses JAX's CPU collectives
    (`jax_cpu_collectives_implementation`, `"gloo"` by default in JAX 0.10).  With
    `devices=None`, or devices of this process only, each process solves the whole batch on
    its own, without communicating.  `method="sparse"` runs on CPU hosts only; GPU/TPU hosts
    use `"dense"` or `"krylov"`.

    **Raises:** `ShapeError` (batch axes missing or unequal), `InvalidInputError` (bad
    `method` or `devices`), `ConvergenceError` when `throw` and a member did not converge.
    """
    if method not in METHODS or method == "lbfgs":
        raise InvalidInputError(f"solve_batch: method must be one of auto, dense, sparse, krylov, got {method!r}")
    batched = _checked_batch(problem, params_batch)
    size = _batch_size(batched)
    devices = _device_tuple(devices)
    # every leaf an argument of the compiled program, not a constant in it: what varies between
    # problems declared alike, and the linear solver's index arrays and KLU's analysis (bound
    # now, before any tracing); `problem.params` at a member's shapes, whose batched entries
    # each member replaces (`_member_params`)
    spec, linear, z0, weights, max_steps = solver_inputs(problem, method, linear_solver, tol, max_steps)
    args = jax.tree_util.tree_map(jnp.asarray, (linear, z0, problem.params, weights, batched))
    if devices is None:
        sol = _program(spec, float(tol), max_steps)(*args)
    else:
        args = _placed(args, size, devices)
        options = (method, float(tol), max_steps)
        compiled = COMPILED.get(structure_key(spec, args, options, devices),
                                lambda: _compile_sharded(spec, args, options, devices))
        sol = compiled(*args)
    if not sol.steps.is_fully_addressable:
        sol = _gathered(sol)
    if sol.steps.shape[0] > size:  # the padding of `_placed`
        sol = jax.tree_util.tree_map(lambda a: a[:size], sol)
    if throw:
        _raise_if_not_converged(sol, tol)
    return sol


def _gathered(sol: Solution) -> Solution:
    """`sol`, sharded over the devices of several processes, gathered whole into this process
    (an all-gather across processes: every process must call it) and placed on its default
    device."""
    from jax.experimental import multihost_utils

    return jax.tree_util.tree_map(jnp.asarray, multihost_utils.process_allgather(sol, tiled=True))


def _raise_if_not_converged(sol: Solution, tol: float) -> None:
    """`ConvergenceError` naming the first member of `sol` that did not converge."""
    bad = np.flatnonzero(~np.asarray(sol.converged))
    if bad.size:
        k = int(bad[0])
        raise ConvergenceError(
            f"solve_batch: member {k} (and {bad.size - 1} more) did not converge: KKT residual "
            f"{float(sol.residual[k]):.3e} > tol {tol:.1e} after {int(sol.steps[k])} steps",
            residual=float(sol.residual[k]), steps=int(sol.steps[k]), solution=sol,
        )
