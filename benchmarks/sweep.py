"""Members per second of a parameter sweep: a family of clamped elastica (`energies.elastica.
clamped(64, chord=(c, 0, 0), t_start=(0, 1, 0), t_end=(0, −1, 0))`, c evenly spaced on
`--chord START STOP`) solved, side by side in one run,

- by a plain Python loop of `solve(member, throw=False)` from `problem.x0` (the anchor);
- by `ddgjax.sweep.run` in one process: chunks of `--chunk` members, one `solve_batch` each,
  rows written to a temporary HDF5 file, `warm_start=None` (the same results as the loop) and
  `warm_start="previous"` (continuation by chunks);
- by `ddgjax.sweep.run(..., devices="all")` with two host devices
  (`XLA_FLAGS=--xla_force_host_platform_device_count=2`, set in a child process of this script,
  which must set it before jax is imported): each chunk is sharded over both;
- by `sweep.run` on `--processes` K local processes joined by `jax.distributed` (one CPU device
  each, child processes of this script; what `ddgjax sweep --processes K` starts): each chunk is
  split over them, process 0 writes the file; its times and peak RSS, no per-chunk RSS column.

Each row: the median of `--repeats` runs after a warm-up run (the warm-up compiles; "compile s"
is its time minus the median; "≈0 (reused)" where `solve_batch` reuses the executable compiled
for the row above, the starts being arguments of it), members per second, the ratio to the loop, converged members,
mean Newton steps, and memory: the peak RSS (VmHWM) before and after the timed runs, and the
current RSS (VmRSS) after the first, middle and last chunk of the last run (sampled by wrapping
`ddgjax.sweep._write`, the private function that writes a chunk): a flat sweep keeps these
equal.  The default chord range starts at 0.3: from the default start, chords below ~0.25 stop
at max_steps, and under `vmap` one such member keeps its whole chunk iterating to max_steps.

    python benchmarks/sweep.py [--quick] [--members 10000] [--chunk 128] [--repeats 3]
                               [--loop-members M] [--devices 2] [--processes 2] [--chord 0.3 0.8]

The machine may be shared: compare rows of one run only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

N = 64
T_START, T_END = (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)


def progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def memory() -> dict:
    """VmRSS and VmHWM of this process in MiB."""
    fields = {}
    for line in Path("/proc/self/status").read_text().splitlines():
        key, _, value = line.partition(":")
        if key in ("VmRSS", "VmHWM"):
            fields[key] = int(value.split()[0]) / 1024
    return fields


def family(members: int, chord: tuple[float, float]):
    import numpy as np

    from energies import elastica

    problem = elastica.clamped(N, chord=[0.5, 0.0, 0.0], t_start=T_START, t_end=T_END)
    chords = np.zeros((members, 3))
    chords[:, 0] = np.linspace(*chord, members)
    return problem, {"chord": chords}


def time_loop(problem, grid, repeats: int, members: int) -> dict:
    import jax
    import numpy as np

    from solvers import solve

    chords = grid["chord"][np.unique(np.linspace(0, len(grid["chord"]) - 1, members).round().astype(int))]
    member = lambda c: problem.with_params({**problem.params, "chord": c})  # noqa: E731
    start = time.perf_counter()
    jax.block_until_ready(solve(member(chords[0]), throw=False).x)
    first = time.perf_counter() - start
    before, times = memory(), []
    for _ in range(repeats):
        converged, steps = 0, 0  # counted on the fly: the loop keeps no solution
        start = time.perf_counter()
        for c in chords:
            sol = jax.block_until_ready(solve(member(c), throw=False))
            converged, steps = converged + bool(sol.converged), steps + int(sol.steps)
        times.append(time.perf_counter() - start)
    median = statistics.median(times)
    return {"members": len(chords), "seconds": median, "compile": first - median / len(chords),
            "converged": converged, "steps": steps / len(chords), "hwm": (before["VmHWM"], memory()["VmHWM"]),
            "rss": None}


def time_sweep(problem, grid, repeats: int, chunk: int, **options) -> dict:
    from ddgjax import sweep

    samples = []
    write = sweep._write

    def sampled(f, index, rows):
        write(f, index, rows)
        samples.append(memory()["VmRSS"])

    sweep._write = sampled
    try:
        with tempfile.TemporaryDirectory() as root:
            def once(k):
                samples.clear()
                start = time.perf_counter()
                path = sweep.run(problem, grid, Path(root) / f"run{k}.h5", chunk=chunk, progress=False, **options)
                seconds = time.perf_counter() - start
                data = sweep.read(path)
                path.unlink()
                return seconds, data

            first, _ = once(0)
            before = memory()
            times = []
            for k in range(repeats):
                seconds, data = once(k + 1)
                times.append(seconds)
    finally:
        sweep._write = write
    median = statistics.median(times)
    size = len(data["done"])
    return {"members": size, "seconds": median, "compile": first - median, "converged": int(data["converged"].sum()),
            "steps": float(data["steps"].mean()), "hwm": (before["VmHWM"], memory()["VmHWM"]),
            "rss": (samples[0], samples[len(samples) // 2], samples[-1])}


def devices_row(args) -> dict | None:
    """The `devices="all"` row, measured in a child process with two host devices."""
    env = dict(os.environ, XLA_FLAGS=f"{os.environ.get('XLA_FLAGS', '')} --xla_force_host_platform_device_count={args.devices}")
    command = [sys.executable, __file__, "--worker", "--members", str(args.members), "--chunk", str(args.chunk),
               "--repeats", str(args.repeats), "--chord", *map(str, args.chord)]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        progress(f"devices row failed: {done.stderr.strip().splitlines()[-1:]}")
        return None
    return json.loads(done.stdout.strip().splitlines()[-1])


def processes_row(args) -> dict | None:
    """The row of `sweep.run` on `--processes` K local processes joined by `jax.distributed`
    (`process_worker`), each with one CPU device: process 0's times and file."""
    import socket

    with socket.socket() as probe:
        probe.bind(("localhost", 0))
        port = probe.getsockname()[1]
    env = dict(os.environ, XLA_FLAGS=f"{os.environ.get('XLA_FLAGS', '')} --xla_force_host_platform_device_count=1")
    with tempfile.TemporaryDirectory() as scratch:
        procs = [subprocess.Popen([sys.executable, __file__, "--process-worker", f"{k}:{args.processes}:{port}:{scratch}",
                                   "--members", str(args.members), "--chunk", str(args.chunk), "--repeats",
                                   str(args.repeats), "--chord", *map(str, args.chord)],
                                  env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for k in range(args.processes)]
        outputs = [p.communicate() for p in procs]
    if any(p.returncode for p in procs):
        failed = next(k for k, p in enumerate(procs) if p.returncode)
        progress(f"processes row failed in process {failed}: {outputs[failed][1].strip().splitlines()[-1:]}")
        return None
    return json.loads(outputs[0][0].strip().splitlines()[-1])


def process_worker(args) -> None:
    """One of the processes of `processes_row`: `sweep.run` of the family, `warm_start=None`, a
    warm-up and `--repeats` timed runs into the shared scratch folder; process 0 prints the row."""
    process, count, port, scratch = args.process_worker.split(":", 3)
    import jax

    jax.distributed.initialize(coordinator_address=f"localhost:{port}", num_processes=int(count),
                               process_id=int(process), initialization_timeout=120)
    from jax.experimental import multihost_utils

    from ddgjax import sweep

    problem, grid = family(args.members, tuple(args.chord))
    times, before = [], None
    for k in range(args.repeats + 1):
        if k == 1:
            before = memory()
        start = time.perf_counter()
        sweep.run(problem, grid, Path(scratch) / f"run{k}.h5", chunk=args.chunk, progress=False, warm_start=None)
        times.append(time.perf_counter() - start)
        multihost_utils.sync_global_devices(f"run {k}")  # process 0 has closed the file
    if int(process) == 0:
        data = sweep.read(Path(scratch) / f"run{args.repeats}.h5")
        median = statistics.median(times[1:])
        print(json.dumps({"members": len(data["done"]), "seconds": median, "compile": times[0] - median,
                          "converged": int(data["converged"].sum()), "steps": float(data["steps"].mean()),
                          "hwm": (before["VmHWM"], memory()["VmHWM"]), "rss": None}))


def worker(args) -> None:
    import jax

    import ddgjax  # noqa: F401  (float64)

    problem, grid = family(args.members, tuple(args.chord))
    row = time_sweep(problem, grid, args.repeats, args.chunk, warm_start=None, devices="all")
    row["devices"] = len(jax.devices())
    print(json.dumps(row))


def row_text(name: str, r: dict, base: dict) -> str:
    rate, anchor = r["members"] / r["seconds"], base["members"] / base["seconds"]
    rss = "—" if r["rss"] is None else " / ".join(f"{v:.0f}" for v in r["rss"])
    hwm = "—" if r["hwm"] is None else f"{r['hwm'][0]:.0f} → {r['hwm'][1]:.0f}"
    compiled = f"{r['compile']:.1f}" if r["compile"] >= 0.5 else "≈0 (reused)"  # the executable of the row above
    return (f"| {name} | {r['members']} | {rate:.1f} | {rate / anchor:.2f}× | {compiled} | "
            f"{r['converged']} | {r['steps']:.2f} | {hwm} | {rss} |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--members", type=int, default=10_000)
    parser.add_argument("--quick", action="store_true", help="500 members (about a minute or two on 2 cores)")
    parser.add_argument("--chunk", type=int, default=128)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--loop-members", type=int, help="members of the loop (evenly spaced; default: all)")
    parser.add_argument("--devices", type=int, default=2, help="host devices of the sharded row (0: skip it)")
    parser.add_argument("--processes", type=int, default=2, help="processes of the `ddgjax sweep --processes` row (0: skip it)")
    parser.add_argument("--chord", type=float, nargs=2, default=[0.3, 0.8], metavar=("START", "STOP"))
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--process-worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:
        args.members = 500
    if args.worker:
        worker(args)
        return 0
    if args.process_worker:
        process_worker(args)
        return 0

    import jax

    import ddgjax  # noqa: F401  (float64)

    problem, grid = family(args.members, tuple(args.chord))
    progress(f"loop of solve ({args.loop_members or args.members} members)")
    rows = {"loop of solve": time_loop(problem, grid, args.repeats, args.loop_members or args.members)}
    progress("sweep.run, warm_start=None")
    rows["sweep.run, warm_start=None"] = time_sweep(problem, grid, args.repeats, args.chunk, warm_start=None)
    progress("sweep.run, warm_start='previous'")
    rows["sweep.run, warm_start='previous'"] = time_sweep(problem, grid, args.repeats, args.chunk)
    if args.devices > 1:
        progress(f"sweep.run, devices='all' ({args.devices} host devices, child process)")
        row = devices_row(args)
        if row is not None:
            rows[f"sweep.run, devices='all' ({row.pop('devices')} host devices), warm_start=None"] = row
    if args.processes > 1:
        progress(f"sweep.run on {args.processes} processes (jax.distributed, child processes)")
        row = processes_row(args)
        if row is not None:
            rows[f"sweep.run on {args.processes} processes × 1 device (jax.distributed), warm_start=None"] = row

    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cores, load "
          f"{os.getloadavg()[0]:.1f}; clamped elastica n = {N}, chord ({args.chord[0]}..{args.chord[1]}, 0, 0), "
          f"chunk {args.chunk}, medians of {args.repeats} after a warm-up")
    print()
    print("| method | members | members/s | × loop | compile s | converged | mean steps | peak RSS MiB before → after "
          "| RSS MiB after first / middle / last chunk |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = rows["loop of solve"]
    for name, r in rows.items():
        print(row_text(name, r, base))
    return 0


if __name__ == "__main__":
    sys.exit(main())
