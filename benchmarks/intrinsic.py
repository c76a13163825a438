"""Benchmark of the intrinsic Delaunay Laplace–Beltrami operator (Sec 7.3, 7.4):
`ddgjax.intrinsic.laplace_beltrami(V, F)` = gluing + edge flips to Delaunay + cotan assembly,
side by side with libigl's `intrinsic_delaunay_cotmatrix` and robust-laplacian's
`mesh_laplacian(V, F, mollify_factor=0)` (geometry-central's intrinsic Delaunay Laplacian).

Meshes of about 10⁴, 10⁵, 10⁶ faces: a round icosphere (Delaunay already, no flips), a strongly
stretched ellipsoid (the icosphere scaled 20 : 1 : 1) and a sheared, squashed torus of thin
triangles; the last two need about 1.5 flips per face.  ddgjax's flip loop is compiled by numba
(cached on disk: a fresh machine compiles it once, about 4 s CPU); its cotan weights are one
jit-compiled autodiff kernel, compiled for a few shape buckets (the first call is a warm-up and
not counted).  Calls are interleaved and both wall and CPU time (`time.process_time`, all three
run on one core) are reported: on a shared machine the CPU time is the fairer measure.  The flip
phase is also timed alone (`flip_to_delaunay` on a prebuilt triangulation, no history: the
flip loop with the keys of its start, and the derived cotangents of the result) and divided
by the flip count.

    python benchmarks/intrinsic.py [--quick | --large] [--repeats 3] [--repeats-large 2] [--rl-repeats-large 0]

Measured 2026-12-01 on the shared 2-core development machine (other jobs running, load about
2–4: noisy; CPU times are the comparison), libigl and robust-laplacian from pip, medians of 3 (2
above 5·10⁵ faces; robust-laplacian once there; the flip phase one call):

| mesh | faces | flips | rounds | flip phase CPU (ns/flip) | ddgjax CPU (s) | libigl CPU (s) | robust-laplacian CPU (s) | igl / ddgjax | rl / ddgjax | ddgjax wall (s) | libigl wall (s) | robust-laplacian wall (s) | max rel diff vs igl |
|---|---|---|---|---|---|---|---|---|---|---|---|---|---|
| sphere | 20480 | 0 | 0 | – | 0.010 | 0.017 | 0.058 | 1.64 | 5.65 | 0.010 | 0.018 | 0.058 | 6.1e-16 |
| sphere | 81920 | 0 | 0 | – | 0.034 | 0.084 | 0.373 | 2.43 | 10.82 | 0.035 | 0.084 | 0.377 | 4.9e-16 |
| sphere | 1310720 | 0 | 0 | – | 0.739 | 1.745 | 11.122 | 2.36 | 15.05 | 0.798 | 1.793 | 11.379 | 6.1e-16 |
| ellipsoid 20:1:1 | 20480 | 31052 | 18 | 157 | 0.011 | 0.021 | 0.116 | 1.84 | 10.26 | 0.011 | 0.023 | 0.116 | 3.9e-13 |
| ellipsoid 20:1:1 | 81920 | 126239 | 19 | 118 | 0.054 | 0.154 | 0.793 | 2.83 | 14.60 | 0.054 | 0.157 | 0.804 | 2.5e-12 |
| ellipsoid 20:1:1 | 1310720 | 2025068 | 17 | 124 | 1.047 | 3.510 | 19.704 | 3.35 | 18.83 | 1.047 | 3.467 | 19.730 | 2.5e-12 |
| sheared torus | 10000 | 15351 | 13 | 146 | 0.005 | 0.009 | 0.024 | 1.64 | 4.34 | 0.005 | 0.009 | 0.024 | 1.5e-13 |
| sheared torus | 102400 | 158208 | 10 | 121 | 0.031 | 0.066 | 0.251 | 2.13 | 8.14 | 0.031 | 0.066 | 0.251 | 3.6e-15 |
| sheared torus | 1310720 | 2552580 | 12 | 84 | 0.484 | 1.238 | 6.849 | 2.56 | 14.14 | 0.500 | 1.274 | 6.913 | 3.2e-15 |

Reading: at 1.3·10⁶ faces ddgjax is 2.4× faster than libigl on the sphere, 3.4× on the
stretched ellipsoid and 2.6× on the sheared torus, and 14–19× faster than robust-laplacian.  The
flip phase costs 124 (ellipsoid) and 84 (torus) ns per flip at 1.3·10⁶ faces; the code before
(derived start keys and a non-inlined loop) cost 283 and 226 in a run of the same hour (igl /
ddgjax 2.29, 2.24, 1.52).  In three `--large` runs at a higher load the same day the flip phase
took 166–183 and 107–120 ns per flip and igl / ddgjax was 2.5–2.7, 3.1–3.3 and 2.2–2.5: the
single call on a freshly built triangulation also pays for first-touch page faults (30–40 ns per
flip more than a repeated call).  Of the flip phase, the compiled loop with its start keys
takes about 100–130 (ellipsoid) and 70–90 (torus) ns per flip, memory-bound on the ellipsoid
(65–80 ns per flip on meshes that fit in cache), and the derived cotangents of the result
(gather, one autodiff kernel on all faces, interleave) about 25–45 ms.
On 2026-12-04 (a slower 2-core machine, load 1–2), before the Laplacian was assembled row by
row in CSR (`ddgjax.csr_assembly`) one `--large` run gave igl / ddgjax 2.07 (sphere), 2.61
(ellipsoid), 1.96 (torus); after it three runs gave 2.88, 2.06, 2.08 (sphere), 2.74, 2.89, 2.78
(ellipsoid), 2.09, 2.18, 2.04 (torus), flip phase 141–146 and 98–103 ns per flip.  Of the
torus's 0.61 s: gluing 0.13, lengths and checks 0.08, flips 0.19 plus the derived cotangents of
the result 0.04, CSR assembly 0.09 (was 0.15 through scipy's COO → CSR).
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
