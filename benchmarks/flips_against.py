"""The flip phase of this working tree side by side with another commit's, in one run.

The flip phase is `ddgjax.intrinsic.flip_to_delaunay(tri, record_history=False)` on a prebuilt
triangulation (the compiled flip loop with the keys of its start, and the derived cotangents of
the result), on the two meshes of `benchmarks/intrinsic.py --large` that need flips: the icosphere
of level 8 stretched 20 : 1 : 1 and the sheared torus 512 × 1280 (1.3·10⁶ faces each).  The other
commit is checked out into a temporary `git worktree`; each tree runs in its own processes
(`PYTHONPATH` first on the tree; numba caches per source file, so each tree compiles once), the
processes alternate (this tree, the other, this tree, …) so that a changing machine load hits both
alike, and each process reports the median CPU time of `--repeats` calls after one warm-up.
Columns: flips (which must be equal: the same flips in the same order), ns per flip for each
tree (median over the processes), and their ratio.

    python benchmarks/flips_against.py [--against HEAD] [--processes 3] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

WORKER = """
import json, statistics, sys, time
sys.path.insert(0, sys.argv[1] + "/benchmarks")
import ddgjax as dg
from intrinsic import _sheared_torus, _stretched
from ddgjax.intrinsic.ordering import is_local, local_numbering
assert dg.__file__.startswith(sys.argv[1]), dg.__file__
out = {}
for name, (V, F) in (("ellipsoid 20:1:1", _stretched(8)), ("sheared torus", _sheared_torus(512, 1280))):
    if not is_local(F, len(V)):
        order, F = local_numbering(V, F)
        V = V[order]
    tri = dg.intrinsic.from_mesh(V, F)
    result = dg.intrinsic.flip_to_delaunay(tri, record_history=False)
    times = []
    for _ in range(int(sys.argv[2])):
        t = time.process_time()
        dg.intrinsic.flip_to_delaunay(tri, record_history=False)
        times.append(time.process_time() - t)
    out[name] = (int(result.n_flips), statistics.median(times))
print(json.dumps(out))
"""


def run_tree(tree: Path, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", WORKER, str(tree), str(repeats)], cwd=tree, env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--against", default="HEAD", help="the other commit (default HEAD: the working tree's changes against it)")
    ap.add_argument("--processes", type=int, default=3, help="processes per tree, alternating")
    ap.add_argument("--repeats", type=int, default=3, help="timed calls per process after a warm-up")
    args = ap.parse_args()
    rev = subprocess.run(["git", "rev-parse", "--short", args.against], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        other = Path(tmp) / "other"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(other), rev], cwd=ROOT, check=True)
        try:
            runs = {"this tree": [], rev: []}
            for _ in range(args.processes):
                runs["this tree"].append(run_tree(ROOT, args.repeats))
                runs[rev].append(run_tree(other, args.repeats))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(other)], cwd=ROOT, check=True)
    print(f"load average {os.getloadavg()[0]:.1f}; {args.processes} processes per tree, medians of {args.repeats} calls each\n")
    print(f"| mesh | flips (this tree) | flips ({rev}) | ns/flip this tree | ns/flip {rev} | this / {rev} |")
    print("|---|---:|---:|---:|---:|---:|")
    for name in runs["this tree"][0]:
        flips = {k: {r[name][0] for r in v} for k, v in runs.items()}
        ns = {k: statistics.median(1e9 * r[name][1] / r[name][0] for r in v) for k, v in runs.items()}
        print(f"| {name} | {','.join(map(str, flips['this tree']))} | {','.join(map(str, flips[rev]))} | "
              f"{ns['this tree']:.0f} | {ns[rev]:.0f} | {ns['this tree'] / ns[rev]:.2f} |")


if __name__ == "__main__":
    main()
