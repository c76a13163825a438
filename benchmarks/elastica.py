"""Benchmark of `solve` on the clamped planar discrete elastica (Def 3.2), side by side with
`scipy.optimize.minimize` (SLSQP, and trust-constr with a quasi-Newton or the exact Hessian).

The problem (`energies.elastica.clamped`, `clamp="edge"`): n unit edge tangents T_0..T_{n−1} of
a curve of length 1, T_0 = (0, 1, 0) and T_{n−1} = (0, −1, 0) fixed, chord (0.6, 0, 0): an arch
in the xy-plane that leaves upwards and comes back down, a planar problem in R³.  Energy
`(2/h) Σ log(1 + κ_k²/4)`, constraints |T_k|² = 1 for the n − 2 free tangents and the chord
`c − h Σ T_k = 0`: N = 3(n − 2) unknowns, n + 1 constraints.  Every method starts from
`problem.x0` (the great-circle interpolation of the clamps fitted to the chord), from which
ddgjax's Newton converges at every n benchmarked.

The scipy runs see the very same functions: the energy and constraints of the `Problem` as
functions of the flat vector u of free entries (`~problem.fixed`), jit-compiled, with
`jax.grad` for the gradient, `jax.jacfwd` for the dense constraint Jacobian and `jax.hessian`
for the dense Hessians (Σ v_i ∇²c_i as the Hessian of v·c, scipy's convention).  The JAX
functions are compiled before the clock starts; each call still pays JAX's dispatch.

- SLSQP: exact gradient and Jacobian, `ftol` 1e-14; by default only up to n = 200 (at n = 400
  one run takes more than 15 minutes).
- trust-constr (BFGS): exact gradient and Jacobian, `hess=scipy.optimize.BFGS()` for the
  energy and for the constraints (what scipy uses when no Hessian is given).
- trust-constr (exact): exact Hessians of the energy and of the constraints as well.
  Both with `gtol` 1e-12, `xtol` 1e-14.

All with `maxiter` 100,000; a stop at the iteration limit is marked "(limit)", and every
stopping message of scipy is printed under the table.  BLAS runs on one thread unless
OPENBLAS_NUM_THREADS is set (see below): scipy's best case on a small machine.

Reported: compile time of ddgjax (first call minus the median), the median of `--repeats`
solves after a warm-up (the same `problem` object, so the compiled solver is reused), the
median of `--scipy-repeats` scipy runs, iterations (Newton steps, scipy's `nit`), and the KKT
residual `max(|∇E − Jᵀλ|∞, |g|∞)` at each answer with the least-squares multipliers
λ = argmin |∇E − Jᵀλ|, the same measure for every method (ddgjax's own residual, with its own
multipliers, in parentheses).  ddgjax runs `solve(problem, tol=1e-12)`: the same tolerance
scipy's trust-constr is given as gtol (`--tol 0` uses solve's default 1e-10, where Newton stops
at the first step below 1e-10: at n = 400 that left 2.8e-11, only 74× below trust-constr's
2.1e-9; one more Newton step reaches 6e-14).  Ratios
are method / ddgjax.  Then the two goals of the issue, PASS/FAIL from the measured numbers.

    python benchmarks/elastica.py [--sizes 50 100 200 400] [--repeats 5] [--scipy-repeats 3]
                                  [--slsqp-max 200] [--bfgs-max 400] [--exact-max 400] [--tol T]
"""

from __future__ import annotations

import os

# Multi-threaded OpenBLAS makes SLSQP ~100× slower on a 2-core machine (n = 50: 17 s instead
# of 0.16 s; the small dense products of its subproblem pay the thread hand-off on every
# call), and trust-constr several times slower.  Give scipy its best case unless told
# otherwise; it must be set before numpy is imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import scipy.optimize  # noqa: E402

import ddgjax as dg  # noqa: E402  (float64)
from ddgjax.problem import constraint_values  # noqa: E402
from energies import elastica  # noqa: E402
from solvers import solve  # noqa: E402

CHORD, T_START, T_END = (0.6, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)
MAXITER = 100_000
DDGJAX = "ddgjax solve"
SLSQP = "scipy SLSQP"
BFGS = "scipy trust-constr (BFGS)"
EXACT = "scipy trust-constr (exact)"


def progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


class FlatProblem:
    """The problem's energy and constraints as jit-compiled functions of the free entries u."""

    def __init__(self, problem: dg.Problem):
        free = ~np.asarray(problem.fixed)
        x0 = jnp.asarray(problem.x0)
        params = problem.params
        self.u0 = np.asarray(x0[free])

        def x_of(u):
            return x0.at[free].set(u)

        def energy(u):
            return problem.energy(x_of(u), params)

        def constraints(u):
            return constraint_values(problem, x_of(u), params)

        self.free = free
        self.f = jax.jit(energy)
        self.grad = jax.jit(jax.grad(energy))
        self.g = jax.jit(constraints)
        self.jac = jax.jit(jax.jacfwd(constraints))
        self.hess_f = jax.jit(jax.hessian(energy))
        self.hess_vg = jax.jit(jax.hessian(lambda u, v: v @ constraints(u)))

    def compile(self) -> None:
        u, v = jnp.asarray(self.u0), jnp.zeros(self.g(self.u0).shape)
        for fn in (self.f, self.grad, self.g, self.jac, self.hess_f):
            jax.block_until_ready(fn(u))
        jax.block_until_ready(self.hess_vg(u, v))

    def kkt_residual(self, u) -> float:
        """max(|∇E − Jᵀλ|∞, |g|∞) with λ = argmin |∇E − Jᵀλ| (least squares)."""
        grad, J, g = (np.asarray(fn(jnp.asarray(u))) for fn in (self.grad, self.jac, self.g))
        lam = np.linalg.lstsq(J.T, grad, rcond=None)[0]
        return float(max(np.abs(grad - J.T @ lam).max(), np.abs(g).max()))


def numpy_of(fn):
    return lambda *args: np.asarray(fn(*(jnp.asarray(a) for a in args)))


def run_scipy(flat: FlatProblem, method: str):
    if method == SLSQP:
        constraint = {"type": "eq", "fun": numpy_of(flat.g), "jac": numpy_of(flat.jac)}
        return scipy.optimize.minimize(
            numpy_of(flat.f), flat.u0, jac=numpy_of(flat.grad), constraints=[constraint], method="SLSQP",
            options={"ftol": 1e-14, "maxiter": MAXITER},
        )
    exact = method == EXACT
    constraint = scipy.optimize.NonlinearConstraint(
        numpy_of(flat.g), 0.0, 0.0, jac=numpy_of(flat.jac),
        hess=numpy_of(flat.hess_vg) if exact else scipy.optimize.BFGS(),
    )
    return scipy.optimize.minimize(
        numpy_of(flat.f), flat.u0, jac=numpy_of(flat.grad),
        hess=numpy_of(flat.hess_f) if exact else scipy.optimize.BFGS(),
        constraints=[constraint], method="trust-constr",
        options={"gtol": 1e-12, "xtol": 1e-14, "maxiter": MAXITER},
    )


def hit_iteration_limit(method: str, res) -> bool:
    # SLSQP: status 9 "Iteration limit reached"; trust-constr: status 0 "maxiter or maxfev"
    return res.status == 9 if method == SLSQP else res.status == 0


def time_scipy(flat: FlatProblem, method: str, repeats: int) -> dict:
    times, res = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = run_scipy(flat, method)
        times.append(time.perf_counter() - t0)
    return {
        "solve": statistics.median(times), "compile": None, "steps": int(res.nit),
        "residual": flat.kkt_residual(res.x), "own": None,
        "limit": hit_iteration_limit(method, res), "message": str(res.message),
    }


def time_ddgjax(problem: dg.Problem, flat: FlatProblem, repeats: int, tol: float | None) -> dict:
    options = {} if tol is None else {"tol": tol}
    t0 = time.perf_counter()
    sol = solve(problem, **options)
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = jax.block_until_ready(solve(problem, **options))
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    return {
        "solve": median, "compile": first - median, "steps": int(sol.steps),
        "residual": flat.kkt_residual(np.asarray(sol.x)[flat.free]), "own": float(sol.residual),
        "limit": False, "message": "",
    }


def ratio_text(ratio: float) -> str:
    if ratio < 10:
        return f"{ratio:.1f}×"
    return f"{ratio:.0f}×" if ratio < 1e4 else f"{ratio:.1e}×"


def row_text(n: int, method: str, r: dict, base: dict) -> str:
    compile_s = "—" if r["compile"] is None else f"{r['compile']:.2f}"
    steps = f"{r['steps']} (limit)" if r["limit"] else str(r["steps"])
    residual = f"{r['residual']:.1e}" + ("" if r["own"] is None else f" (own {r['own']:.1e})")
    return (f"| {n} | {method} | {r['solve']:.4g} | {compile_s} | {steps} | {residual} | "
            f"{ratio_text(r['solve'] / base['solve'])} | {ratio_text(r['residual'] / base['residual'])} |")


def stop_notes(results: dict) -> list[str]:
    """scipy's stopping messages, one line per method and message, with the sizes."""
    sizes = {}
    for (n, method), r in results.items():
        if method != DDGJAX:
            sizes.setdefault((method, r["message"], r["limit"]), []).append(str(n))
    return [
        f"{method} stopped {'BY THE ITERATION LIMIT' if limit else 'with'} \"{message}\" at n = {', '.join(ns)}"
        for (method, message, limit), ns in sizes.items()
    ]


def goal_text(results: dict, n: int, method: str, speed: float, accuracy: float) -> str:
    goal = f"ddgjax ≥ {speed:g}× faster than {method} at n = {n}, residual ≥ {accuracy:g}× smaller"
    if (n, method) not in results or (n, DDGJAX) not in results:
        return f"{goal}: NOT MEASURED"
    r, base = results[(n, method)], results[(n, DDGJAX)]
    t, a = r["solve"] / base["solve"], r["residual"] / base["residual"]
    verdict = "PASS" if t >= speed and a >= accuracy else "FAIL"
    return f"{goal}: {verdict} (measured {ratio_text(t)} faster, residual {ratio_text(a)} smaller)"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200, 400], help="numbers of edges n")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--scipy-repeats", type=int, default=3)
    parser.add_argument("--slsqp-max", type=int, default=200, help="largest n for SLSQP (n = 400: > 15 min a run)")
    parser.add_argument("--bfgs-max", type=int, default=400, help="largest n for trust-constr with BFGS")
    parser.add_argument("--exact-max", type=int, default=400, help="largest n for trust-constr, exact Hessian")
    parser.add_argument("--tol", type=float, default=1e-12,
                        help="tol of ddgjax's solve (default 1e-12, the gtol scipy is given; 0 = solve's default)")
    args = parser.parse_args(argv)
    limits = {SLSQP: args.slsqp_max, BFGS: args.bfgs_max, EXACT: args.exact_max}
    flags = {SLSQP: "--slsqp-max", BFGS: "--bfgs-max", EXACT: "--exact-max"}

    start = time.perf_counter()
    results = {}
    for n in args.sizes:
        problem = elastica.clamped(n, chord=CHORD, t_start=T_START, t_end=T_END)
        flat = FlatProblem(problem)
        progress(f"n = {n}: ddgjax")
        results[(n, DDGJAX)] = time_ddgjax(problem, flat, args.repeats, args.tol or None)
        flat.compile()
        for method, largest in limits.items():
            if n > largest:
                continue
            progress(f"n = {n}: {method} ({time.perf_counter() - start:.0f} s so far)")
            results[(n, method)] = time_scipy(flat, method, args.scipy_repeats)

    print(f"jax {jax.__version__} on {jax.devices()[0].platform} ({os.cpu_count()} cores), scipy "
          f"{scipy.__version__}, OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}; clamped planar "
          f"elastica, length 1, chord {CHORD}, t_start {T_START}, t_end {T_END}")
    print()
    print("| n | method | time s (median) | compile s (ddgjax) | iterations | KKT residual | "
          "time ratio (method / ddgjax) | residual ratio (method / ddgjax) |")
    print("|---:|---|---:|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        for method in (DDGJAX, *limits):
            if (n, method) in results:
                print(row_text(n, method, results[(n, method)], results[(n, DDGJAX)]))
            else:
                print(f"| {n} | {method} | skipped (n > {flags[method]}) | | | | | |")
    print()
    for line in stop_notes(results):
        print(line)
    print()
    print(goal_text(results, 400, EXACT, 30, 100))
    print(goal_text(results, 200, SLSQP, 1000, 100))
    progress(f"total {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
