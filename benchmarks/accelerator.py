"""Surfaces on whatever JAX runs on: the area Newton solve and the Dirichlet problem at 10⁴–10⁶
vertices, on the default backend (a GPU where JAX has one, else the CPU), with the linear
solvers that backend can use.

Problems (the same meshes as `benchmarks/scale.py` and `benchmarks/multigrid.py`):
- area: `scale.area_problem(k)`, the simplicial area of the k×k saddle grid with the border
  fixed, after 5 Pinkall–Polthier steps (3 unknowns per interior vertex), tol 1e-9 (`--area-tol`);
- dirichlet: `energies.dirichlet.cotan(V, F, border, eˣ sin y)` on the flat k×k grid of the
  same mesh's (x, y) (1 unknown per interior vertex, one Newton step), tol 1e-10.

Linear solvers:
- `Krylov(amg)`: MINRES preconditioned by the smoothed-aggregation cycle (`solvers/_amg.py`),
  everything inside `jit` on the device; the aggregates are made on the host once per pattern;
- `SparseDirect`: the host factorisation (Pardiso where installed, else SuperLU) in a host
  callback; on a GPU the KKT values travel to the host and the step back at every Newton step;
- `spsolve (device QR)`: the only sparse direct solver JAX reaches on a GPU without extra
  libraries, `jax.experimental.sparse.linalg.spsolve` (cuSOLVER's sparse QR, `csrlsvqr`), on the
  Dirichlet problem's interior Laplacian: one solve, no symbolic reuse, no `vmap`/`grad`
  rules, so it is a reference point, not a back end of `solve`.  GPU only.

Columns: backend, problem, vertices, unknowns N, solver, first-call overhead s (host pattern,
multigrid hierarchy and compilation: first call minus the median of the later ones), s per
Newton step (median solve / steps), steps, KKT residual, max |x − x_ref| against the first
solver's x for the same problem, and the device's peak memory (GB, where the backend reports it).
Rows run in the order given; a row whose predicted time would pass `--budget` seconds is
skipped and listed, so a lease-bound run still returns a table.

    python benchmarks/accelerator.py [--area 100 316] [--area-tol 1e-9] [--dirichlet 316 1000]
                                     [--solvers amg direct qr] [--repeats 3] [--budget 600] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import ddgjax as dg  # noqa: F401,E402  (float64)
from ddgjax.laplace import cotan_laplacian  # noqa: E402
from ddgjax.mesh import saddle_grid  # noqa: E402
from energies import dirichlet  # noqa: E402
from multigrid import measure  # noqa: E402
from scale import area_problem  # noqa: E402
from solvers import Krylov, SparseDirect, solve  # noqa: E402

START = time.perf_counter()


def elapsed() -> float:
    return time.perf_counter() - START


def device_peak_gb() -> float | None:
    stats = jax.devices()[0].memory_stats() or {}
    peak = stats.get("peak_bytes_in_use")
    return None if peak is None else peak / 2**30


def dirichlet_problem(k: int):
    """The Dirichlet problem of eˣ sin y on the flat k×k grid of the saddle mesh's (x, y)."""
    V, F, b = saddle_grid(k)
    V = np.column_stack([V[:, 0], V[:, 1], np.zeros(len(V))])
    return dirichlet.cotan(V, F, b, np.exp(V[b, 0]) * np.sin(V[b, 1])), (V, F, b)


def device_qr(mesh, repeats: int):
    """`jax.experimental.sparse.linalg.spsolve` of `L_II f_I = −L_IB f_B` on the device."""
    from jax.experimental.sparse.linalg import spsolve

    V, F, b = mesh
    L = cotan_laplacian(V, F).tocsr()
    interior = np.setdiff1d(np.arange(len(V)), b)
    f_b = np.exp(V[b, 0]) * np.sin(V[b, 1])
    A = L[interior][:, interior].tocsr()
    rhs = -(L[interior][:, b] @ f_b)
    args = (jnp.asarray(A.data), jnp.asarray(A.indices.astype(np.int32)), jnp.asarray(A.indptr.astype(np.int32)),
            jnp.asarray(rhs))
    run = jax.jit(lambda d, i, p, r: spsolve(d, i, p, r, tol=0.0))
    t0 = time.perf_counter()
    x = run(*args).block_until_ready()
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        x = run(*args).block_until_ready()
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    residual = float(np.max(np.abs(A @ np.asarray(x) - rhs)) / np.max(np.abs(rhs)))
    f = np.zeros(len(V))
    f[b], f[interior] = f_b, np.asarray(x)
    return f, {"compile": first - median, "solve": median, "per_step": median, "steps": 1, "residual": residual,
               "converged": residual < 1e-8}


SOLVERS = {"amg": ("Krylov(amg)", lambda: Krylov(preconditioner="amg")),
           "direct": ("SparseDirect", lambda: SparseDirect()),
           "qr": ("spsolve (device QR)", None)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--area", type=int, nargs="*", default=[100, 316], help="saddle grid sizes k (k² vertices)")
    ap.add_argument("--area-cotan-steps", type=int, default=5, help="Pinkall–Polthier steps before Newton (area start)")
    ap.add_argument("--area-tol", type=float, default=1e-9, help="KKT tolerance of the area solve (at 10⁶ vertices the "
                    "default start is already within 1e-9: pass 1e-11 to time Newton steps there)")
    ap.add_argument("--dirichlet", type=int, nargs="*", default=[316, 1000], help="grid sizes k of the Dirichlet problem")
    ap.add_argument("--solvers", nargs="+", default=["amg", "direct", "qr"], choices=sorted(SOLVERS))
    ap.add_argument("--direct-max", type=int, default=10**6, help="largest N for SparseDirect")
    ap.add_argument("--repeats", type=int, default=3, help="timed solves after the first (1 above 10⁵ unknowns)")
    ap.add_argument("--budget", type=float, default=600.0, help="skip rows predicted to end after this many seconds")
    ap.add_argument("--json", help="append each row as a JSON line to this file")
    args = ap.parse_args()

    backend = jax.default_backend()
    device = jax.devices()[0]
    print(f"jax {jax.__version__}, backend {backend}, device {getattr(device, 'device_kind', device)}, "
          f"host cores {os.cpu_count()}, load {os.getloadavg()[0]:.1f}", flush=True)
    print("\n| backend | problem | vertices | N | solver | first-call overhead s | s/step | steps | residual | "
          "max abs x − x_ref | device peak GB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|", flush=True)
    cases = [("dirichlet", k) for k in args.dirichlet] + [("area", k) for k in args.area]
    cases.sort(key=lambda case: case[1] ** 2 * (3 if case[0] == "area" else 1))
    skipped, last_cost = [], {}
    for name, k in cases:
        t_build = time.perf_counter()
        if name == "area":
            problem, mesh, tol = area_problem(k, args.area_cotan_steps), None, args.area_tol
        else:
            (problem, mesh), tol = dirichlet_problem(k), 1e-10
        build = time.perf_counter() - t_build
        n = int(np.sum(~np.asarray(problem.fixed)))
        x_ref = None
        for key in args.solvers:
            label, make = SOLVERS[key]
            if key == "qr" and (name != "dirichlet" or backend == "cpu"):
                continue
            if key == "direct" and n > args.direct_max:
                continue
            # predicted: the same solver's last row scaled by the unknowns (like n for the multigrid
            # cycle, like n^1.5 for a factorisation of a 2-D mesh), plus the build
            previous = last_cost.get((name, key))
            power = 1.0 if key == "amg" else 1.5
            predicted = build + (previous[1] * (n / previous[0]) ** power if previous else 0.0)
            if elapsed() + predicted > args.budget:
                skipped.append(f"{name} {k * k} {label} (predicted {predicted:.0f} s)")
                continue
            repeats = args.repeats if n <= 100_000 else 1
            t_row = time.perf_counter()
            try:
                if key == "qr":
                    x, r = device_qr(mesh, repeats)
                else:
                    sol, r = measure(problem, make(), repeats, tol)
                    x = np.asarray(sol.x)
            except Exception as error:  # a back end the device cannot run: reported, the table goes on
                print(f"| {backend} | {name} | {k * k} | {n} | {label} | failed: {type(error).__name__}: "
                      f"{str(error).splitlines()[0][:160]} |||||", flush=True)
                continue
            last_cost[(name, key)] = (n, time.perf_counter() - t_row)
            diff = "" if x_ref is None else f"{float(np.max(np.abs(x - x_ref))):.1e}"
            x_ref = x if x_ref is None else x_ref
            peak = device_peak_gb()
            print(f"| {backend} | {name} | {k * k} | {n} | {label} | {r['compile']:.1f} | {r['per_step']:.4f} | "
                  f"{r['steps']} | {r['residual']:.1e} | {diff} | {'' if peak is None else f'{peak:.2f}'} |", flush=True)
            if args.json:
                with open(args.json, "a") as out:
                    out.write(json.dumps(dict(r, backend=backend, problem=name, vertices=k * k, N=n, solver=label,
                                              build=build, diff=diff, peak_gb=peak, jax=jax.__version__)) + "\n")
    for line in skipped:
        print(f"skipped (budget {args.budget:.0f} s): {line}")
    print(f"total {elapsed():.0f} s")


if __name__ == "__main__":
    main()
