"""Benchmark of the intrinsic Delaunay Laplace–Beltrami operator (Sec 7.3, 7.4):
`ddgjax.intrinsic.laplace_beltrami(V, F)` = gluing + edge flips to Delaunay + cotan assembly,
side by side with libigl's `intrinsic_delaunay_cotmatrix` and robust-laplacian's
`mesh_laplacian(V, F, mollify_factor=0)` (geometry-central's intrinsic Delaunay Laplacian).

Meshes of about 10⁴, 10⁵, 10⁶ faces: a round icosphere (Delaunay already, no flips), a strongly
stretched ellipsoid (the icosphere scaled 20 : 1 : 1) and a sheared, squashed torus of thin
triangles; the last two need about 1.5 flips per face.  ddgjax's flip loop is compiled by numba
(cached on disk: a fresh machine compiles it once, about 2.5 s CPU); its cotan weights are one
jit-compiled autodiff kernel, compiled for a few shape buckets (the first call is a warm-up and
not counted).  Calls are interleaved and both wall and CPU time (`time.process_time`, all three
run on one core) are reported: on a shared machine the CPU time is the fairer measure.  The flip
phase is also timed alone (`flip_to_delaunay` on a prebuilt triangulation, no history: the
derived cotangents of the start and of the result, and the flip loop) and divided by the flip
count.

    python benchmarks/intrinsic.py [--quick | --large] [--repeats 3] [--repeats-large 2] [--rl-repeats-large 0]

Measured 2026-12-01 on the shared 2-core development machine (other jobs running, load about
3–4: noisy; CPU times are the comparison), libigl and robust-laplacian from pip, medians of 3 (2
above 5·10⁵ faces; robust-laplacian once there):

| mesh | faces | flips | rounds | flip phase CPU (ns/flip) | ddgjax CPU (s) | libigl CPU (s) | robust-laplacian CPU (s) | igl / ddgjax | rl / ddgjax | ddgjax wall (s) | libigl wall (s) | robust-laplacian wall (s) | max rel diff vs igl |
|---|---|---|---|---|---|---|---|---|---|---|---|---|---|
| sphere | 20480 | 0 | 0 | – | 0.008 | 0.013 | 0.041 | 1.57 | 4.96 | 0.012 | 0.016 | 0.084 | 4.9e-16 |
| sphere | 81920 | 0 | 0 | – | 0.028 | 0.060 | 0.237 | 2.12 | 8.33 | 0.043 | 0.092 | 0.346 | 4.9e-16 |
| sphere | 1310720 | 0 | 0 | – | 0.876 | 1.638 | 8.633 | 1.87 | 9.85 | 1.307 | 2.432 | 12.368 | 6.1e-16 |
| ellipsoid 20:1:1 | 20480 | 31052 | 18 | 200 | 0.014 | 0.019 | 0.098 | 1.41 | 7.23 | 0.017 | 0.026 | 0.139 | 3.9e-13 |
| ellipsoid 20:1:1 | 81920 | 126239 | 19 | 197 | 0.047 | 0.107 | 0.622 | 2.26 | 13.09 | 0.068 | 0.167 | 0.921 | 2.5e-12 |
| ellipsoid 20:1:1 | 1310720 | 2025068 | 17 | 254 | 1.163 | 2.853 | 21.014 | 2.45 | 18.07 | 1.817 | 4.214 | 31.325 | 2.5e-12 |
| sheared torus | 10000 | 15351 | 13 | 217 | 0.006 | 0.009 | 0.024 | 1.59 | 4.31 | 0.010 | 0.021 | 0.034 | 1.5e-13 |
| sheared torus | 102400 | 158208 | 10 | 173 | 0.046 | 0.072 | 0.336 | 1.56 | 7.24 | 0.074 | 0.116 | 0.521 | 3.6e-15 |
| sheared torus | 1310720 | 2552580 | 12 | 182 | 0.884 | 1.393 | 6.782 | 1.58 | 7.67 | 1.337 | 2.070 | 10.018 | 3.2e-15 |

Reading: at 1.3·10⁶ faces ddgjax is 1.6× faster than libigl on the sheared torus, 2.5× on the
stretched ellipsoid and 1.9× on the sphere, and 8–18× faster than robust-laplacian.  The flip
phase costs 180–250 ns per flip at 1.3·10⁶ faces (a second `--large` run the same day: 185 and
247); the vectorised numpy rounds it replaced cost 488 (ellipsoid) and 321 (torus) ns per flip
in a `--large` run the same day.  Of the flip phase, the compiled loop itself takes 95–150 ns
per flip (timed alone on the same machine), the two derived-cotangent kernels (the autodiff
Hessian of the Dirichlet energy, of the start and of the result) about 0.15–0.2 s together,
i.e. 60–100 ns per flip on these meshes.
"rounds" is the longest cascade of flips (`FlipResult.n_rounds`).  Time grows about linearly;
meshes whose vertex labels are not spatially coherent are renumbered along a Morton curve first
(`ddgjax.intrinsic.ordering`), for cache locality.  Results do not depend on the flip order
beyond rounding: where two diagonals of a cocircular quadrilateral are both Delaunay (the
symmetric ellipsoid) the kept one may differ, and its cotan weight is 0 to rounding either way.
`--large` runs only the 1.3·10⁶-face meshes.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import ddgjax as dg
from ddgjax.intrinsic.ordering import is_local, local_numbering
from ddgjax.mesh.builtin import icosphere, torus


def _stretched(level):
    V, F = icosphere(level)
    return V * np.array([20.0, 1.0, 1.0]), F


def _sheared_torus(m, n):
    V, F = torus(m, n, R=1.0, r=0.25)
    shear = np.array([[1.0, 0.0, 2.0], [0.0, 0.4, 0.0], [0.0, 0.0, 1.0]])
    return V @ shear.T, F


def meshes(quick: bool, large: bool = False):
    levels = (4, 5) if quick else (8,) if large else (5, 6, 8)
    tori = ((35, 70), (80, 160)) if quick else ((512, 1280),) if large else ((50, 100), (160, 320), (512, 1280))
    for level in levels:
        yield "sphere", icosphere(level)
    for level in levels:
        yield "ellipsoid 20:1:1", _stretched(level)
    for m, n in tori:
        yield "sheared torus", _sheared_torus(m, n)


def _measure(fn):
    """(result, wall seconds, CPU seconds of this process) of one call."""
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def _row(name, V, F, igl, rl, repeats, rl_repeats):
    """Interleaved calls (ddgjax, libigl, robust-laplacian in turn) after one warm-up call each,
    so that a changing machine load hits all three alike; medians of wall and CPU time."""
    calls = {"ddgjax": lambda: dg.intrinsic.laplace_beltrami(V, F)}
    if igl is not None:
        calls["libigl"] = lambda: igl.intrinsic_delaunay_cotmatrix(V, F)[0]
    if rl is not None:
        calls["robust-laplacian"] = lambda: rl.mesh_laplacian(V, F, mollify_factor=0)[0]
    first = {k: _measure(fn) for k, fn in calls.items()}
    wall = {k: [] for k in calls}
    cpu = {k: [] for k in calls}
    for r in range(repeats):
        for k, fn in calls.items():
            if k == "robust-laplacian" and r >= rl_repeats:
                continue
            _, w, c = _measure(fn)
            wall[k].append(w)
            cpu[k].append(c)
    med = {k: (statistics.median(wall[k] or [first[k][1]]), statistics.median(cpu[k] or [first[k][2]])) for k in calls}
    local = V, F
    if not is_local(F, len(V)):  # the numbering laplace_beltrami uses internally
        order, F_local = local_numbering(V, F)
        local = V[order], F_local
    tri = dg.intrinsic.from_mesh(*local)
    result, _, flip_cpu = _measure(lambda: dg.intrinsic.flip_to_delaunay(tri, record_history=False))
    L = first["ddgjax"][0]
    diff = abs(L + first["libigl"][0]).max() / abs(first["libigl"][0]).max() if "libigl" in first else float("nan")
    nan = (float("nan"), float("nan"))
    ours, other, rlt = med["ddgjax"], med.get("libigl", nan), med.get("robust-laplacian", nan)
    per_flip = f"{1e9 * flip_cpu / result.n_flips:.0f}" if result.n_flips else "–"
    return (f"| {name} | {len(F)} | {result.n_flips} | {result.n_rounds} | {per_flip} "
            f"| {ours[1]:.3f} | {other[1]:.3f} | {rlt[1]:.3f} | {other[1] / ours[1]:.2f} | {rlt[1] / ours[1]:.2f} "
            f"| {ours[0]:.3f} | {other[0]:.3f} | {rlt[0]:.3f} | {diff:.1e} |")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="small meshes only")
    parser.add_argument("--large", action="store_true", help="the meshes of about 1.3e6 faces only")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--repeats-large", type=int, default=2, help="repeats above 5e5 faces")
    parser.add_argument("--rl-repeats-large", type=int, default=0,
                        help="robust-laplacian repeats above 5e5 faces besides the first call (tens of seconds each)")
    args = parser.parse_args()
    try:
        import igl
    except ImportError:
        igl = None
    try:
        import robust_laplacian as rl
    except ImportError:
        rl = None

    print("| mesh | faces | flips | rounds | flip phase CPU (ns/flip) | ddgjax CPU (s) | libigl CPU (s) "
          "| robust-laplacian CPU (s) | igl / ddgjax | rl / ddgjax | ddgjax wall (s) | libigl wall (s) "
          "| robust-laplacian wall (s) | max rel diff vs igl |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, (V, F) in meshes(args.quick, args.large):
        large = len(F) > 500_000
        repeats = args.repeats_large if large else args.repeats
        rl_repeats = args.rl_repeats_large if large else args.repeats
        print(_row(name, V, F, igl, rl, repeats, rl_repeats), flush=True)


if __name__ == "__main__":
    main()
