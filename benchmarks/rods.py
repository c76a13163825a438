"""Benchmark: static equilibria of clamped elastic rods, ddgjax vs PyElastica (issue 4).

Two clamped rods of length L = 1, both ends' frames fixed, chord c = (0.7, 0, 0):
- **planar strut**: both end tangents e1, no twist: the first clamped–clamped buckling mode
  (an elastica in the xy-plane);
- **twisted 3D**: the end frame turned by ψ about e1 as well: the strut twists out of its plane.

**ddgjax**: `energies.rod.clamped` (unit-quaternion edge frames, energy ½Σ(κ² + ατ²) in the
discrete form of Def 3.6/3.7), solved by `solvers.solve` (Newton–KKT, tol 1e-10), with
`clamp="vertex"` (second order) and `clamp="edge"` (the end *edge* frames clamped, like
PyElastica's first element).  Time: median of `--repeats` solves after a warm-up; the
compile time (first call minus median) separately.

**PyElastica** (the anchor): a Cosserat rod of radius r = 0.01 (slenderness 100), E = 10⁶,
G = αE/2 so that the twist/bend stiffness ratio GJ/EI = α as in ddgjax, density 10³, with
shear and stretch stiffnesses EA, GA ~ 10⁴ EI (nearly inextensible), both end nodes and end
element directors held by `FixedConstraint`, relaxed with `AnalyticalLinearDamper` and
`PositionVerlet` (dt = 0.01·Δs, the value of PyElastica's examples) from the same initial
shape until the largest node speed falls below `--speed-tol` (checked every 0.25 time units).
Time: wall time of the relaxation (its first run includes numba's compilation, reported
separately as the difference to a second run).

**Accuracy**: both are compared with the smooth rod of Thm 3.13 with the same clamps at
s = 0 and s = L, computed independently by shooting (`ddgjax.kirchhoff`: the Kirchhoff
analogy, a Lagrange top motion): the max distance of the nodes γ(s_k) to the smooth centreline.
The initial shape (for both) has tangents ∝ (1, β sin 2πs, 0) (β fitted to the chord), with
frames turning by ψs about the tangent.

    python benchmarks/rods.py [--n 50] [--repeats 5] [--alpha 0.6] [--twist 3.0] [--quick]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

import ddgjax as dg  # noqa: F401  (float64)
from ddgjax.smooth import kirchhoff
from ddgjax import quaternion as qt
from energies import rod
from solvers import solve

E1, E3 = np.eye(3)[0], np.eye(3)[2]
CHORD = np.array([0.7, 0.0, 0.0])
REFERENCE_GUESS_N = 128  # the discrete rod that starts the shooting for the smooth reference


def progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def initial_shape(n: int, twist: float):
    """Edge frames (n, 4) and nodes (n + 1, 3) of the start shape (module docstring): unit
    tangents T ∝ (1, β sin 2πs, 0) at the edge midpoints, β fitted so the nodes end at the chord."""
    from scipy.optimize import brentq

    s = (np.arange(n) + 0.5) / n

    def tangents(beta):
        T = np.stack([np.ones(n), beta * np.sin(2 * np.pi * s), np.zeros(n)], axis=1)
        return T / np.linalg.norm(T, axis=1, keepdims=True)

    beta = brentq(lambda b: tangents(b)[:, 0].mean() - CHORD[0], 0.0, 100.0, xtol=1e-15)
    T = tangents(beta)
    turn = qt.from_axis_angle(jnp.asarray(E3), jnp.arctan2(T[:, 1], T[:, 0]))
    frames = qt.mul(turn, qt.from_axis_angle(jnp.asarray(E1), twist * s))
    nodes = np.concatenate([np.zeros((1, 3)), np.cumsum(T / n, axis=0)])
    return np.asarray(frames), nodes


def end_frames(twist: float):
    return np.array([1.0, 0, 0, 0]), np.asarray(qt.from_axis_angle(jnp.asarray(E1), twist))


def run_ddgjax(n: int, alpha: float, twist: float, clamp: str, repeats: int):
    q0, q1 = end_frames(twist)
    frames, _ = initial_shape(n, twist)
    problem = rod.clamped(n, alpha=alpha, chord=CHORD, frame_start=q0, frame_end=q1, clamp=clamp, x0=frames)
    t0 = time.perf_counter()
    sol = solve(problem)
    first = time.perf_counter() - t0
    times = [first]
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = jax.block_until_ready(solve(problem))
        times.append(time.perf_counter() - t0)
    median = statistics.median(times[1:] or times)
    nodes = np.asarray(rod.curve(sol.x, problem))
    return {"time": median, "compile": first - median, "nodes": nodes, "residual": float(sol.residual),
            "steps": int(sol.steps), "problem": problem, "solution": sol}


def import_pyelastica():
    """PyElastica's `elastica`, not this folder's benchmarks/elastica.py (the script's folder
    comes first on sys.path)."""
    import importlib
    import os

    here = os.path.dirname(os.path.abspath(__file__))
    saved = list(sys.path)
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != here]
    try:
        sys.modules.pop("elastica", None)
        return importlib.import_module("elastica")
    finally:
        sys.path[:] = saved


def run_pyelastica(n: int, alpha: float, twist: float, speed_tol: float, max_time: float):
    ea = import_pyelastica()

    frames, nodes = initial_shape(n, twist)
    # PyElastica's directors: rows (d1, d2, d3) with d3 the tangent; ours: columns (T, N, B) of
    # R(Φ) with T = Φ e1 Φ⁻¹.  So d3 = T, d1 = N, d2 = B (right-handed: d1 × d2 = d3).
    R = np.asarray(qt.to_matrix(frames))
    directors = np.stack([R[:, :, 1], R[:, :, 2], R[:, :, 0]], axis=1).transpose(1, 2, 0)
    radius, E, density = 0.01, 1e6, 1e3
    ds = 1.0 / n
    dt = 0.01 * ds

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Damping):
        pass

    sim = Simulator()
    cosserat = ea.CosseratRod.straight_rod(
        n, np.zeros(3), E1, np.array([0.0, 1.0, 0.0]), 1.0, radius, density,
        youngs_modulus=E, shear_modulus=alpha * E / 2, position=nodes.T.copy(), directors=directors.copy(),
    )
    sim.append(cosserat)
    sim.constrain(cosserat).using(ea.FixedConstraint, constrained_position_idx=(0, -1), constrained_director_idx=(0, -1))
    sim.dampen(cosserat).using(ea.AnalyticalLinearDamper, uniform_damping_constant=5.0, time_step=dt)
    sim.finalize()
    stepper = ea.PositionVerlet()
    chunk = 0.25
    steps = int(round(chunk / dt))
    t, speed = 0.0, np.inf
    t0 = time.perf_counter()
    while t < max_time and speed > speed_tol:
        with contextlib.redirect_stdout(io.StringIO()):  # it prints the final time of each call
            t = ea.integrate(stepper, sim, chunk, steps, restart_time=t, progress_bar=False)
        speed = float(np.max(np.linalg.norm(cosserat.velocity_collection, axis=0)))
    wall = time.perf_counter() - t0
    return {"time": wall, "nodes": cosserat.position_collection.T.copy(), "sim_time": t, "speed": speed,
            "steps": int(round(t / dt))}


def error_to(smooth, nodes: np.ndarray) -> float:
    s = np.linspace(0.0, 1.0, nodes.shape[0])
    _, gamma = kirchhoff.sample(smooth, s)
    return float(np.max(np.linalg.norm(nodes - np.asarray(gamma), axis=1)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=50)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--alpha", type=float, default=0.6)
    parser.add_argument("--twist", type=float, default=3.0, help="ψ of the twisted case (radians)")
    parser.add_argument("--speed-tol", type=float, default=1e-6)
    parser.add_argument("--max-time", type=float, default=100.0)
    parser.add_argument("--pyelastica-repeats", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="n = 20, fewer repeats")
    args = parser.parse_args()
    if args.quick:
        args.n, args.repeats, args.pyelastica_repeats = 20, 3, 2
    try:
        import_pyelastica()
    except ImportError:
        print("PyElastica is not installed (pip install -e '.[bench]'); nothing to compare with.")
        return

    rows, verdicts = [], []
    for case, twist in (("planar strut", 0.0), ("twisted 3D", args.twist)):
        progress(f"{case}: ddgjax ...")
        vertex = run_ddgjax(args.n, args.alpha, twist, "vertex", args.repeats)
        edge = run_ddgjax(args.n, args.alpha, twist, "edge", args.repeats)
        guess = run_ddgjax(REFERENCE_GUESS_N, args.alpha, twist, "vertex", 0)
        smooth = kirchhoff.from_discrete(guess["problem"], guess["solution"])
        progress(f"{case}: PyElastica ...")
        runs = [run_pyelastica(args.n, args.alpha, twist, args.speed_tol, args.max_time)
                for _ in range(args.pyelastica_repeats)]
        pe = dict(runs[-1], time=statistics.median(r["time"] for r in runs[1:] or runs),
                  compile=runs[0]["time"] - statistics.median(r["time"] for r in runs[1:] or runs))
        pe_err = error_to(smooth, pe["nodes"])
        base = vertex["time"]
        for name, r, detail in (
            ("ddgjax (vertex clamp)", vertex, f"{vertex['steps']} Newton steps, KKT residual {vertex['residual']:.1e}"),
            ("ddgjax (edge clamp)", edge, f"{edge['steps']} Newton steps, KKT residual {edge['residual']:.1e}"),
            ("PyElastica", pe, f"{pe['steps']} time steps to t = {pe['sim_time']:.2f}, max speed {pe['speed']:.1e}"),
        ):
            err = error_to(smooth, r["nodes"])
            rows.append(f"| {case} | {args.n} | {name} | {r['time']:.4g} | {r['compile']:.2f} | {err:.2e} | "
                        f"{ratio(r['time'] / base)} | {detail} |")
        shape_diff = float(np.max(np.linalg.norm(vertex["nodes"] - pe["nodes"], axis=1)))
        rows.append(f"| {case} | {args.n} | shape difference ddgjax (vertex) − PyElastica | | | {shape_diff:.2e} | | |")
        speedup = pe["time"] / base
        verdicts.append(f"- {case}: ddgjax {speedup:.0f}× faster than PyElastica "
                        f"({'PASS' if speedup >= 50 else 'FAIL'} ≥ 50×), error to the smooth rod "
                        f"{error_to(smooth, vertex['nodes']):.1e} vs {pe_err:.1e} "
                        f"({'PASS' if error_to(smooth, vertex['nodes']) <= pe_err else 'FAIL'}: equal or better)")

    print(f"\nClamped rods, L = 1, chord {CHORD.tolist()}, α = {args.alpha}, ψ = {args.twist} (twisted case); "
          f"medians after warm-up, compile separately; ratio = time / ddgjax (vertex clamp) time.\n")
    print("| case | n | method | time s | compile s | max error to smooth rod | ratio | notes |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print("\nGoals (issue 4): ddgjax ≥ 50× faster than PyElastica at equal or better accuracy")
    print("\n".join(verdicts))


def ratio(x: float) -> str:
    return f"{x:.2g}×" if x < 10 else f"{x:.0f}×"


if __name__ == "__main__":
    main()
