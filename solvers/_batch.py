"""`solve_batch`: one problem solved for a batch of parameters, vectorised and sharded over devices."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ddgjax.errors import ConvergenceError, InvalidInputError, ShapeError
from ddgjax.problem import Problem

from ._solve import METHODS, Solution, solve

BATCH_AXIS = "batch"


def _split_params(problem: Problem, params_batch):
    """`(batched, merge)`: the batched leaves and a function putting them back into full params.

    `params_batch` is either a pytree like `problem.params` with a leading batch axis on every
    leaf, or (for dict params) a dict of some of its keys, the others kept from `problem`.
    """
    base = problem.params
    if isinstance(base, dict) and isinstance(params_batch, dict) and set(params_batch) < set(base):
        fixed = {k: v for k, v in base.items() if k not in params_batch}
        return params_batch, lambda batched: {**fixed, **batched}
    if jax.tree_util.tree_structure(params_batch) != jax.tree_util.tree_structure(base):
        raise ShapeError(
            "params_batch must have the structure of problem.params (or, for dict params, a subset "
            f"of its keys): got {jax.tree_util.tree_structure(params_batch)}, "
            f"expected {jax.tree_util.tree_structure(base)}"
        )
    return params_batch, lambda batched: batched


def _batch_size(batched) -> int:
    leaves = [jnp.asarray(a) for a in jax.tree_util.tree_leaves(batched)]
    if not leaves or any(a.ndim == 0 for a in leaves):
        raise ShapeError("every leaf of params_batch needs a leading batch axis")
    sizes = {a.shape[0] for a in leaves}
    if len(sizes) != 1:
        raise ShapeError(f"the leaves of params_batch have different batch sizes {sorted(sizes)}")
    return sizes.pop()


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

    `jax.vmap` of `solve` over the parameters, jit-compiled once for the whole batch; with
    `devices`, the batch is split over them (a `jax.sharding.Mesh` with one axis, `"batch"`,
    the parameters placed with `NamedSharding(mesh, PartitionSpec("batch"))` and each device
    solving its slice with `jax.shard_map`).  The batch is padded with copies of its last
    member to a multiple of the number of devices; the padding is dropped from the result.

    Each member runs its own Newton iteration (under `vmap` the loop runs until every member
    has converged; finished members stay put), so the result equals a loop of `solve` calls.
    Every linear-algebra path batches: `method="sparse"` (KLU, CPU only; vmapped as a loop of
    factorisations inside the compiled call), `"dense"` (batched LU, any backend) and
    `"krylov"` (matrix-free, any backend).  `"auto"` picks as `solve` does (`choose_method`).

    **Arguments:**
    - `problem`: the template; its `x0`, `fixed`, functions and the unbatched parameters are
      shared by the batch.
    - `params_batch`: a pytree like `problem.params` whose leaves have a leading batch axis,
      or, for dict parameters, a dict of only the keys that vary (e.g. `{"chord": (B, 3)}`).
    - `devices`: `None` (default device), `"all"` (`jax.devices()`), or a list of devices.
    - `method`, `linear_solver`, `tol`, `max_steps`: as in `solve`.
    - `throw`: raise `ConvergenceError` naming the first member that did not converge.

    **Returns:** a `Solution` whose leaves have a leading batch axis (sharded over `devices`).

    **Several hosts.**  On a cluster, start every process with
    `jax.distributed.initialize(coordinator_address, num_processes, process_id)` (on Slurm or
    Cloud TPU the arguments are found automatically) before any other JAX call; `jax.devices()`
    then lists the devices of all hosts, and `solve_batch(problem, params_batch,
    devices="all")` run identically in every process splits the batch over all of them.  Each
    process must pass the same full `params_batch` (it is placed with `jax.device_put`, each
    host keeping its own slice); gather the result where it is needed with
    `jax.experimental.multihost_utils.process_allgather`.  `method="sparse"` runs on CPU
    hosts only; GPU/TPU hosts use `"dense"` or `"krylov"`.

    **Raises:** `ShapeError` (batch axes missing or unequal), `InvalidInputError` (bad
    `method` or `devices`), `ConvergenceError` when `throw` and a member did not converge.
    """
    if method not in METHODS or method == "lbfgs":
        raise InvalidInputError(f"solve_batch: method must be one of auto, dense, sparse, krylov, got {method!r}")
    batched, merge = _split_params(problem, params_batch)
    size = _batch_size(batched)

    def one(p):
        return solve(problem.with_params(merge(p)), method=method, linear_solver=linear_solver, tol=tol, max_steps=max_steps, throw=False)

    if devices is None:
        sol = jax.jit(jax.vmap(one))(batched)
    else:
        devices = list(jax.devices() if devices == "all" else devices)
        if not devices:
            raise InvalidInputError("solve_batch: devices is empty")
        sol = _sharded(one, batched, size, devices)
    if throw:
        bad = np.flatnonzero(~np.asarray(sol.converged))
        if bad.size:
            k = int(bad[0])
            raise ConvergenceError(
                f"solve_batch: member {k} (and {bad.size - 1} more) did not converge: KKT residual "
                f"{float(sol.residual[k]):.3e} > tol {tol:.1e} after {int(sol.steps[k])} steps",
                residual=float(sol.residual[k]), steps=int(sol.steps[k]), solution=sol,
            )
    return sol


def _sharded(one, batched, size: int, devices) -> Solution:
    n_dev = len(devices)
    padded = math.ceil(size / n_dev) * n_dev
    pad = jax.tree_util.tree_map(
        lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], padded - size, axis=0)]) if padded > size else jnp.asarray(a),
        batched,
    )
    mesh = Mesh(np.array(devices), (BATCH_AXIS,))
    spec = PartitionSpec(BATCH_AXIS)
    pad = jax.device_put(pad, NamedSharding(mesh, spec))
    # shard_map, not jit with shardings: XLA's partitioner cannot split KLU's custom call, and
    # partitioning the batched Newton loop took minutes to compile
    run = jax.jit(jax.shard_map(jax.vmap(one), mesh=mesh, in_specs=spec, out_specs=spec, check_vma=False))
    sol = run(pad)
    return jax.tree_util.tree_map(lambda a: a[:size], sol) if padded > size else sol
