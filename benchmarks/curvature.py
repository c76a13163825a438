"""Benchmark of `mesh.angle_defect` (Def 5.2) and `mesh.edge_mean_curvature` (Def 5.3) on
icospheres of about 10⁴, 10⁵, 10⁶ faces, side by side with libigl when it is importable.

ddgjax: each function jit-compiled as a function of V alone (F closed over, so the connectivity
is built and validated once, at trace time).  Reported: compile time (first call minus the
median), and the median of `--repeats` calls after a warm-up, `block_until_ready` included.

libigl: `igl.gaussian_curvature(V, F)` (2π − Σ α at every vertex, the same as ours at interior
vertices; the icosphere has none on the boundary) and, for the edge quantity, the dihedral angles
from `igl.per_face_normals` + `igl.edge_topology`, θ·l/2 assembled in numpy: libigl has no
per-edge mean curvature, so this is the nearest like-for-like.  Max differences between the two
are printed as a check.

    python benchmarks/curvature.py [--levels 5 6 8] [--repeats 5]

Measured 2026-11-21 on an otherwise idle 2-core CPU (load ≈ 1), libigl 2.x from pip, medians of 5
after warm-up; "compile" includes building and validating the halfedge connectivity at trace
time:

| faces | quantity | ddgjax compile (s) | ddgjax median (ms) | libigl median (ms) | igl/ddgjax | max diff |
|---|---|---|---|---|---|---|
| 20480 | angle defect | 0.30 | 5.06 | 2.77 | 0.55 | 1.8e-15 |
| 20480 | edge mean curvature | 0.31 | 4.24 | 15.22 | 3.59 | 1.8e-15 |
| 81920 | angle defect | 0.66 | 10.57 | 17.50 | 1.66 | 1.6e-15 |
| 81920 | edge mean curvature | 0.67 | 8.49 | 101.27 | 11.92 | 4.8e-15 |
| 1310720 | angle defect | 10.85 | 344.36 | 361.28 | 1.05 | 1.8e-15 |
| 1310720 | edge mean curvature | 12.36 | 347.05 | 2562.17 | 7.38 | 2.1e-14 |

A second idle run at 1.3×10⁶ faces gave 327 ms against 450 ms for the angle defect; on a
machine loaded by other jobs (load ≈ 4) the angle defect was 0.57× libigl's speed, so the margin
at 10⁶ faces is thin.  At 2×10⁴ faces libigl's angle defect is faster (fixed overheads).

libigl's edge number includes its `edge_topology` (ours is built once, at trace time), so that
column compares a full recomputation with a cached one; the angle defect is like for like.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import numpy as np

import ddgjax  # noqa: F401  (float64)
from ddgjax import mesh


def _time(fn, repeats):
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    return first - median, median


def _igl_mean_curvature(igl, V, F):
    N = igl.per_face_normals(V, F, np.array([0.0, 0.0, 1.0]))
    EV, FE, EF = igl.edge_topology(V, F)
    n1, n2 = N[EF[:, 0]], N[EF[:, 1]]
    d = V[EV[:, 1]] - V[EV[:, 0]]
    length = np.linalg.norm(d, axis=1)
    theta = np.arctan2(np.abs(np.einsum("ij,ij->i", np.cross(n1, n2), d / length[:, None])),
                       np.einsum("ij,ij->i", n1, n2))
    return 0.5 * theta * length


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--levels", type=int, nargs="+", default=[5, 6, 8])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    try:
        import igl
    except ImportError:
        igl = None
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}; libigl {'yes' if igl else 'not installed'}")
    header = "| faces | quantity | ddgjax compile (s) | ddgjax median (ms) | libigl median (ms) | ratio igl/ddgjax | max diff |"
    print(header)
    print("|" + "---|" * 7)
    for level in args.levels:
        V, F = mesh.icosphere(level)
        Vj = jax.device_put(V)
        kernels = {
            "angle defect": (jax.jit(lambda X: mesh.angle_defect(X, F)),
                             (lambda: igl.gaussian_curvature(V, F)) if igl else None),
            "edge mean curvature": (jax.jit(lambda X: mesh.edge_mean_curvature(X, F)),
                                    (lambda: _igl_mean_curvature(igl, V, F)) if igl else None),
        }
        for name, (ours, theirs) in kernels.items():
            compile_s, median = _time(lambda: ours(Vj), args.repeats)
            row = f"| {F.shape[0]} | {name} | {compile_s:.2f} | {1e3 * median:.2f} |"
            if theirs is None:
                print(row + " – | – | – |")
                continue
            _, igl_median = _time(theirs, args.repeats)
            a, b = np.asarray(ours(Vj)), np.asarray(theirs())
            diff = float(np.max(np.abs(np.sort(a) - np.sort(b))))
            print(row + f" {1e3 * igl_median:.2f} | {igl_median / median:.2f} | {diff:.1e} |")


if __name__ == "__main__":
    main()
