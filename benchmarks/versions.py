"""This tree against another checkout of ddgjax, side by side in one run: the surface operators.

    git worktree add /tmp/old <commit>
    python benchmarks/versions.py /tmp/old [--large] [--repeats 5]

Each operation runs in a fresh process per version (the meshes are built once here and handed
over in a file, so both versions see the same arrays); the versions alternate, operation by
operation, so that a changing machine load hits both alike.  Per operation: one warm-up call
(compilation), then the median CPU time of `--repeats` calls.

Both CPU time (all threads) and wall time are reported.

Operations: `dg.intrinsic.laplace_beltrami(V, F)` (gluing, flips to intrinsic Delaunay,
derived cotan weights), the flip phase alone (`flip_to_delaunay` without history, on a prebuilt
triangulation; reported per flip), and the extrinsic `dg.laplace.cotan_laplacian(V, F)`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]

WORKER = r"""
import json, statistics, sys, time
import numpy as np
import ddgjax as dg
from ddgjax.intrinsic.ordering import is_local, local_numbering

data = np.load(sys.argv[1])
V, F, op, repeats = data["V"], data["F"], sys.argv[2], int(sys.argv[3])
if op == "flips":
    local = (V, F)
    if not is_local(F, len(V)):
        order, F_local = local_numbering(V, F)
        local = (V[order], F_local)
    tri = dg.intrinsic.from_mesh(*local)
    call = lambda: dg.intrinsic.flip_to_delaunay(tri, record_history=False)
elif op == "laplace_beltrami":
    call = lambda: dg.intrinsic.laplace_beltrami(V, F)
else:
    call = lambda: dg.laplace.cotan_laplacian(V, F)
out = call()
cpu, wall = [], []
for _ in range(repeats):
    c, w = time.process_time(), time.perf_counter()
    call()
    cpu.append(time.process_time() - c)
    wall.append(time.perf_counter() - w)
flips = int(out.n_flips) if op == "flips" else 0
print(json.dumps({"cpu": statistics.median(cpu), "wall": statistics.median(wall), "flips": flips}))
"""


def meshes(large: bool):
    """The meshes of `benchmarks/intrinsic.py` (all sizes, or the 1.3e6-face ones only)."""
    sys.path.insert(0, str(HERE / "benchmarks"))
    import intrinsic

    return intrinsic.meshes(quick=False, large=large)


def run(tree: Path, mesh_file: str, op: str, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), JAX_PLATFORMS="cpu")
    out = subprocess.run([sys.executable, "-c", WORKER, mesh_file, op, str(repeats)], env=env, cwd=tree,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("old", type=Path, help="a checkout (worktree) of the version to compare with")
    parser.add_argument("--large", action="store_true", help="the meshes of about 1.3e6 faces only")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"old: {args.old}   new: {HERE}   medians of {args.repeats} after a warm-up call; CPU time counts every")
    print("thread (XLA kernels may use both cores), wall time is what a user waits\n")
    print("| mesh | faces | operation | flips | old CPU | new CPU | new / old CPU | old wall | new wall | new / old wall |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (V, F) in meshes(args.large):
            path = f"{tmp}/mesh.npz"
            np.savez(path, V=V, F=F)
            for op in ("laplace_beltrami", "flips", "cotan_laplacian"):
                old = run(args.old, path, op, args.repeats)
                new = run(HERE, path, op, args.repeats)
                unit = 1.0
                label = op
                if op == "flips":
                    if not new["flips"]:
                        continue
                    unit, label = 1e-9 * new["flips"], "flip phase (ns/flip)"
                print(f"| {name} | {len(F)} | {label} | {new['flips'] or ''} | {old['cpu'] / unit:.3g} "
                      f"| {new['cpu'] / unit:.3g} | {new['cpu'] / old['cpu']:.2f} | {old['wall'] / unit:.3g} "
                      f"| {new['wall'] / unit:.3g} | {new['wall'] / old['wall']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
