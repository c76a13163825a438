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

Measured 2026-11-21 on a 2-core CPU shared with other jobs (load ≈ 4), libigl 2.x from pip;
"compile" includes building and validating the halfedge connectivity at trace time:

| faces | quantity | ddgjax compile (s) | ddgjax median (ms) | libigl median (ms) | igl/ddgjax | max diff |
|---|---|---|---|---|---|---|
| 20480 | angle defect | 0.64 | 9.54 | 7.07 | 0.74 | 1.8e-15 |
| 20480 | edge mean curvature | 0.63 | 7.16 | 38.70 | 5.40 | 1.8e-15 |
| 81920 | angle defect | 1.62 | 28.08 | 24.86 | 0.89 | 1.6e-15 |
| 81920 | edge mean curvature | 1.72 | 13.87 | 305.61 | 22.03 | 4.8e-15 |
| 1310720 | angle defect | 31.50 | 1747.93 | 997.79 | 0.57 | 1.8e-15 |
| 1310720 | edge mean curvature | 35.36 | 689.41 | 13668.55 | 19.83 | 2.1e-14 |

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
