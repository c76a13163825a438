"""`solve_batch` and `ddgjax sweep` over the devices of two JAX processes.

Two local CPU processes, joined by `jax.distributed.initialize`, each pass the same full batch
with `devices="all"`; the batch is split over the devices of both, and each process gets the
whole result back.  Every member must equal the single-process `solve_batch` to 1e-12.  The
sweep on two processes (`--processes 2`) writes the same file as on one.
"""

import os
import socket
import subprocess
import sys
import textwrap
import time

import jax
import numpy as np
import pytest

from energies import elastica
from solvers import solve_batch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

DEADLINE = 50.0
"""Seconds the two processes get, start to finish; then both are killed and the test fails."""

WORKER = textwrap.dedent(
    """
    import os, sys, traceback
    import jax
    port, process_id, out, size = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    try:
        jax.distributed.initialize(
            coordinator_address=f"localhost:{port}", num_processes=2, process_id=process_id,
            initialization_timeout=30,
        )
        import numpy as np
        from solvers import solve_batch
        from test_multiprocess import chords, problem
        sol = solve_batch(problem(), {"chord": chords(size)}, devices="all")
        assert all(a.is_fully_addressable for a in jax.tree_util.tree_leaves(sol))
        np.savez(out, jax.process_count(), jax.device_count(), *jax.tree_util.tree_leaves(sol))
    except BaseException:
        traceback.print_exc()
        sys.stdout.flush()
        os._exit(1)  # not the exit handler of jax.distributed: it waits for the other process
    """
)


def problem():
    return elastica.clamped(8, chord=(0.6, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))


def chords(size):
    return np.array([[0.5 + 0.05 * k, 0.2, 0.03 * np.sin(k)] for k in range(size)])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def _xla_flags(local_devices: int) -> str:
    """This process's XLA flags (the same compiler options) with `local_devices` CPU devices."""
    flags = [f for f in os.environ.get("XLA_FLAGS", "").split() if "xla_force_host_platform_device_count" not in f]
    return " ".join([*flags, f"--xla_force_host_platform_device_count={local_devices}"])


def _run_two_processes(tmp_path, local_devices: int, size: int) -> list:
    """The two processes' results (`np.load` of their .npz); kills both and fails when one fails
    or they pass `DEADLINE`."""
    env = dict(
        os.environ, JAX_PLATFORMS="cpu", XLA_FLAGS=_xla_flags(local_devices),
        PYTHONPATH=os.pathsep.join(filter(None, [f"{ROOT}/tests", ROOT, os.environ.get("PYTHONPATH")])),
    )
    port, outs = _free_port(), [tmp_path / f"process{k}.npz" for k in range(2)]
    logs = [tmp_path / f"process{k}.log" for k in range(2)]
    procs = []
    for k in range(2):  # output to files, not pipes: a full pipe would block the process
        with open(logs[k], "w") as log:
            procs.append(subprocess.Popen(
                [sys.executable, "-c", WORKER, str(port), str(k), str(outs[k]), str(size)],
                cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT,
            ))
    start, timed_out = time.monotonic(), False
    try:
        while None in (codes := [p.poll() for p in procs]) and not any(codes):
            timed_out = time.monotonic() - start > DEADLINE
            if timed_out:
                break
            time.sleep(0.1)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
            p.wait()
    what = f"killed at the {DEADLINE:.0f} s deadline" if timed_out else "failed"
    report = [f"two-process solve_batch {what} ({time.monotonic() - start:.1f} s)"]
    report += [f"--- process {k} (exit {p.returncode}):\n{log.read_text()[-3000:]}" for k, (p, log) in enumerate(zip(procs, logs))]
    assert all(p.returncode == 0 for p in procs), "\n".join(report)
    return [np.load(out) for out in outs]


@pytest.mark.parametrize(("local_devices", "size"), [
    pytest.param(1, 4, marks=pytest.mark.slow),  # one device per process: also the sweep test's case below
    (2, 5),
])
def test_two_process_solve_batch_equals_single_process(tmp_path, local_devices, size):
    """2 processes × `local_devices` CPU devices, the same batch of `size` clamped elastica in
    each (5 over 4 devices: padded to 8): both get every member, equal to a single-process solve
    to 1e-12 (the same compiled member solver on the same data: only the split differs).

    One device per process is also what `ddgjax sweep --processes 2` runs (the last test), whose
    every stored member is compared with the one-process result to 1e-12: `make test` runs that
    case there, `make test-all` here as well."""
    results = _run_two_processes(tmp_path, local_devices, size)
    reference = solve_batch(problem(), {"chord": chords(size)})
    paths, _ = zip(*jax.tree_util.tree_flatten_with_path(reference)[0])
    expected = jax.tree_util.tree_leaves(reference)
    assert bool(np.all(reference.converged))
    for process, result in enumerate(results):
        assert int(result["arr_0"]) == 2 and int(result["arr_1"]) == 2 * local_devices
        for k, (path, want) in enumerate(zip(paths, expected)):
            got = result[f"arr_{k + 2}"]
            name = f"process {process}, Solution{jax.tree_util.keystr(path)}"
            assert got.shape == want.shape, name
            np.testing.assert_allclose(got.astype(float), np.asarray(want, float), rtol=0, atol=1e-12, err_msg=name)


# --- ddgjax sweep --processes K ---------------------------------------------------------------


def test_sweep_on_two_processes_writes_the_file_of_one_process(tmp_path):
    """`ddgjax sweep ... --processes 2`: two local processes joined by jax.distributed solve each
    chunk together (`solve_batch` over both processes' devices) and process 0 writes the file;
    every stored result equals the one-process sweep's to 1e-12, the warm starts from the
    previous chunk included."""
    from ddgjax import cli, sweep

    argv = ["sweep", "elastica", "--n", "8", "--param", "chord=0.3:0.7:6", "--chunk", "2", "--no-progress"]
    assert cli.main([*argv, "--out", str(tmp_path / "one.h5")]) == 0
    env = dict(os.environ, JAX_PLATFORMS="cpu", XLA_FLAGS=_xla_flags(1),
               PYTHONPATH=os.pathsep.join(filter(None, [ROOT, os.environ.get("PYTHONPATH")])))
    command = [sys.executable, "-m", "ddgjax", *argv, "--processes", "2", "--out", str(tmp_path / "two.h5")]
    run = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "6 converged, 0 failed (6 solved now, 0 already done) on 2 processes" in run.stdout
    one, two = sweep.read(tmp_path / "one.h5"), sweep.read(tmp_path / "two.h5")
    assert bool(np.all(one["converged"])) and bool(np.all(two["done"]))
    for name in ("x", "energy", "residual", "multipliers"):
        for a, b in zip(jax.tree_util.tree_leaves(one[name]), jax.tree_util.tree_leaves(two[name])):
            np.testing.assert_allclose(b, a, rtol=0, atol=1e-12, err_msg=name)
    np.testing.assert_array_equal(two["steps"], one["steps"])

