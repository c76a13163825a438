"""Surfaces at scale: the soap bubble from a cube and the Clifford torus, `solvers` side by side
with `scipy.optimize.minimize(method="trust-constr")` with exact derivatives, from the same start.

**Bubble from a cube** (Surface Evolver's first tutorial example, `cube.fe`).  The triangulated
cube `dg.mesh.cube(triangulated=True)`, centred and scaled to the volume 4π/3 of the unit ball,
subdivided k times by `dg.mesh.subdivide` (midpoints: the start is still the flat cube), so
nv = 6·4ᵏ + 2 vertices (k = 4…7: 1538, 6146, 24578, 98306).  The problem is
`energies.area.with_volume(V, F, 4π/3)`: the area with the named constraint "volume", whose
multiplier is the pressure p; at the discrete critical point p·r → 2 (r = 1, Laplace–Young).
ddgjax: `solve(problem, tol=--tol)` with its defaults, as `with_volume` documents for bubbles
(`minimize` takes no constraints).  From the flat cube Newton alone stalls (its merit function
has local minima there; measured with `warm_start=None` at 98 and 386 vertices: stopped after
88 and 100 steps at residuals 0.067 and 0.042), so the
default `warm_start="auto"` solves again from x0 with up to 50 augmented-Lagrangian L-BFGS steps
before Newton; "(after retry)" in the steps column says that the retry's solution was returned
(`Solution.first_order_steps` > 0, printed with the L-BFGS step count; when the retry fails
too, `solve` returns the first run, unmarked, and the time includes both).  `steps` is
`Solution.steps`, the Newton steps of the returned run: after a retry it does not count the
failed first run (100 Newton steps), so it is not comparable to scipy's iterations then; the
time is the whole call, both runs included.

**Refined bubble** (`--refine`, Surface Evolver's `r` then `g`).  `energies.refine.refine` with
Loop subdivision: the cube subdivided twice (98 vertices) solved, then each level started from
the previous solution Loop-subdivided (a curved, non-degenerate start: midpoint subdivision
would leave the new vertices on the old flat faces, where the area has exactly flat tangential
directions and Newton stalls as from the cube); every level from the first of `--refine` on is
timed from its own start, trust-constr from the same start.  Its "residual" is the scaled
max-norm KKT residual of `solve`, "volume error" |vol − 4π/3|.

**Anchor (scipy).**  The same `problem.energy` and `problem.constraints` (jit-compiled JAX),
the exact gradient (`jax.grad`), the Hessians of the area and of the volume as
`LinearOperator`s of Hessian-vector products (`jax.jvp` of `jax.grad`), the constraint's exact
Jacobian (a dense row, `jax.grad` of the volume); `gtol` = --tol, `xtol` 1e-14, `maxiter` 10⁵,
and a wall-clock budget (--scipy-budget s, a callback stops it): a run stopped by the budget is
printed "did not finish within …" with what it had reached, one that raises (NaN in its
projections after a degenerate step) "failed after … s".  Sizes above --scipy-max vertices
are skipped.  Its "residual" is scipy's own `optimality` (max-norm of the Lagrangian's
gradient) and "volume error" its constraint violation; "(xtol)" marks a run that stopped on
`xtol` (the trust region collapsed) before reaching `gtol`: with a residual far above --tol that
run did not converge, and its time ratio compares an unfinished run.  Its pressure is −v, v
scipy's multiplier.  The JAX functions are compiled by one evaluation before the clock starts.

**Clifford torus.**  `energies.willmore.helfrich(V, F)` (H₀ = 0, κ = 1: the Willmore energy
W = Σ H_i² A_i, scale invariant, so no area constraint is needed for `minimize`, whose
second-order test lets flat directions pass) on `dg.mesh.torus(m, n, R=1, r=0.4)`, the torus of
revolution with R/r = 2.5; the smooth minimiser among tori is the Clifford torus, R/r = √2,
W = 2π² (Marques–Neves).  ddgjax: `minimize(problem, tol=--torus-tol, max_steps=
--torus-steps)`; scipy: unconstrained trust-constr with the exact gradient and Hessian-vector
products, same budget.  Reported: W/2π² and R/r = (ρ_max + ρ_min)/(ρ_max − ρ_min), ρ the
distance of a vertex from the z axis.  The constrained Helfrich solve (`solve`) from a random
perturbation is known not to converge; `minimize` is used here, and a row that does not reach
the tolerance within the step budget is printed "not converged" with its residual.  "min A/mean
A" (smallest face area over the mean) shows tangential degeneration of the mesh.  Measured
on 24×12 (288 vertices): `minimize` does not converge: after 50 steps the residual is 1.1
(0.38 at the start, not decreasing), R/r = 1.40 (near √2) but W/2π² = 0.89, already *below* the
smooth minimum (the discrete W underestimates, as on icospheres where it is below 4π), and with
60 steps W/2π² = 0.83, R/r = 1.37: W keeps decreasing past the Clifford value with the mesh
intact (min A/mean A 0.36).  trust-constr stops on `xtol` at optimality 2e3 with a degenerate
mesh (min A/mean A 3e-6, W/2π² = 0.51); on 12×6 it drives W/2π² to 0.41.  On 48×24 (1152
vertices, 50 steps) `minimize` is at W/2π² = 1.003, R/r = 1.52, residual 1.2 (not converged,
23 s), trust-constr again at a degenerate mesh (W/2π² = 0.96, R/r = 1.33, min A/mean A 2e-6).
So no converged row of the free torus exists; those rows are printed as "not converged".

**Clifford torus as a torus of revolution** (`--revolution m×n …`, the converged rows).
`energies.willmore.torus_of_revolution(m, n)`: the same Helfrich energy of the revolved mesh
(m n vertices), with the profile polygon (n points) as the unknowns, its edges equal and p_0 and
its mean height fixed (its docstring), from R/r = 2.5.  ddgjax: `solve(problem,
tol=--torus-tol)`; scipy: trust-constr on the 2n − 2 free entries with the n constraints (exact
dense Jacobian, Hessian-vector products of the energy and of λ·g), same tolerance and budget.
Measured (`--levels --refine --no-torus --revolution 24x12 96x48 448x224 --repeats 3
--scipy-budget 120`, 2 cores, load 1–2.6, 2026-12-04; tol 1e-8):

| vertices (m × n) | ddgjax solve s | steps | residual | W/2π² | R/r | trust-constr s | its steps, residual | ratio |
|---:|---:|---:|---:|---:|---:|---:|---|---:|
| 288 (24 × 12) | 0.007 | 5 | 5.4e-12 | 0.953261 | 1.36990 | 0.39 | 31, 1.0e-7 (xtol), same W | 52× |
| 4,608 (96 × 48) | 0.021 | 5 | 2.7e-12 | 0.997001 | 1.41148 | 2.10 | 46, 4.7e-7 (xtol), same W | 101× |
| 100,352 (448 × 224) | 0.102 | 5 | 3.8e-10 | 0.999862 | 1.41409 | > 120 | 101, 3.2 (not finished; W/2π² 1.153) | > 1,177× |

Compile 14–16 s per size.  W/2π² − 1 and R/r − √2 fall at order 2 in 1/n (`ddgjax verify --only
clifford`).  At 10⁵ vertices the KKT residual cannot go below ~3e-10 in float64 (the m = 448
meridians multiply every star's terms): `tol=1e-10` stalls there (measured: 49 Newton steps
and the L-BFGS retry, 48 s, ending at 2.9e-10 with the same W), so the rows use --torus-tol.

**Columns.**  compile s = first call minus the median of the later ones (ddgjax); solve s = the
median of --repeats calls after warm-up (one call above 5·10⁴ vertices; scipy: one call);
peak MB = `ru_maxrss` of the process so far (monotone over the run: a bound on the row's own
peak); scipy s / ddgjax s the ratio of the two solve times.

**Measured** (`--quick --repeats 2`, 2 shared cores, load average 2–6, 2026-12-02): at 1538
vertices `solve` converges (KKT 3e-11, p·r = 2.00087) in 87 s after a 263 s compile, all but the
last Newton steps spent in the failed first run and the L-BFGS phase, while trust-constr stops
on `xtol` after 730 iterations (13 s) at optimality 6e-3, area 12.57647 against 12.57182: not
converged; at 6146 vertices neither converges: `solve` returns the first run (100 Newton steps,
residual 1.1e-2, p·r = 1.86, 283 s), the retry having failed too, and trust-constr raises
after 48 s (NaN in its least-squares projection).  At 26 and 98 vertices both
converge to the same area and p·r (trust-constr in 37 and 51 iterations, to optimality 2e-9,
faster than `solve`'s retry path).  The flat cube is a hard start for both; the full sizes
(24578, 98306 vertices) were not run to the end in the time available.

Refined bubble (`--levels --refine 4 5 6 --no-torus --repeats 2 --scipy-max 7000
--scipy-budget 60`, 2 cores, load 0.8, 2026-12-02), each level from its own Loop-subdivided start:
1538 vertices `solve` 0.09 s (4 Newton steps, KKT 4.7e-12, p·r = 2.00087) against trust-constr
4.70 s (35 iterations, same area, stopped on xtol at optimality 2.2e-10): 53×; 6146 vertices
2.47 s (11 steps, 5.4e-16, p·r = 2.00022) against 21.9 s (14 iterations, 5.2e-11): 8.9×; 24578
vertices 4.58 s (7 steps, 3.3e-11, p·r = 2.00005; trust-constr not run).  p·r − 2 falls by 4.0
per level (order 2 in the edge length).  98306 vertices (a separate run of the same chain):
15 steps, p·r = 2.000014, about 125 s and 7 GB, of which 73 s and most of the memory were one
Levenberg–Marquardt step (then a complex SuperLU factorisation of K + i√ν I); with that step now
one Pardiso factorisation of the real system [[K, √νI], [√νI, −K]] (`solvers/_direct.py`) it
took 15.7 s at a peak resident set of 2.7 GB (26 Newton steps in that run, 1.3–1.4 s per
factorisation).

**Surface Evolver.**  Its documentation of the cube example (`cube.htm`, "Cube evolving into a
sphere") was found with the search tools, but the stored copies end before the run; the
Hessian chapter's transcript shows the refined cube (194 vertices) taking a fixed `g 5` (five
gradient-descent steps, area 5.353 → 4.936 at volume 1), not a count of iterations to a
tolerance.  So no published iteration counts to convergence were found, and the table has no
Surface Evolver column.

The machine may be shared: the load average is printed, and timings under load are inflated;
compare rows of one run only.

    python benchmarks/surfaces.py [--quick] [--levels 4 5 6 7] [--repeats 3] [--scipy-max 30000]
                                  [--scipy-budget 120] [--torus 24x12 48x24] [--torus-steps 50]
                                  [--no-torus] [--revolution 24x12 96x48 448x224]

(`--levels` with no value: the torus only.)
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np
import scipy
import scipy.optimize
import scipy.sparse.linalg as spla

import ddgjax as dg
from energies import area, willmore
from solvers import minimize, solve

SPHERE_VOLUME = 4.0 * np.pi / 3.0  # the unit ball: p·r = 2
REFINE_FROM = 2  # the refined bubbles start from the cube subdivided this often (98 vertices)


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def cube_start(level: int) -> tuple[np.ndarray, np.ndarray]:
    """The flat cube of volume 4π/3 centred at the origin, subdivided `level` times."""
    V, F = dg.mesh.cube(triangulated=True)
    V = (V - 0.5) * SPHERE_VOLUME ** (1.0 / 3.0)
    for _ in range(level):
        V, F = dg.mesh.subdivide(V, F)
    return V, F


def sliver(X, F) -> float:
    """min over the faces of A(f) / mean A: near 0 when the mesh degenerates tangentially."""
    X = np.asarray(X)
    areas = np.linalg.norm(np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]), axis=1)
    return float(areas.min() / areas.mean())


def torus_ratio(X) -> float:
    """R/r of a torus about the z axis from the distances ρ of its vertices to the axis."""
    rho = np.hypot(np.asarray(X)[:, 0], np.asarray(X)[:, 1])
    return float((rho.max() + rho.min()) / (rho.max() - rho.min()))


def timed(call, repeats: int) -> tuple[object, float, float]:
    """`(result, compile s, median s)`: the first call compiles, the median of `repeats` more."""
    t0 = time.perf_counter()
    result = call()
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = call()
        jax.block_until_ready(result.x)
        times.append(time.perf_counter() - t0)
    median = statistics.median(times) if times else first
    return result, max(first - median, 0.0), median


class TrustConstr:
    """scipy's trust-constr on `problem` (all unknowns free, at most one named constraint
    "volume"), with exact derivatives from JAX: gradient, Hessian-vector products as
    `LinearOperator`s, the constraint's Jacobian row."""

    def __init__(self, problem, constraint: str | None):
        shape, params = np.shape(problem.x0), problem.params
        energy = lambda u: problem.energy(u.reshape(shape), params)  # noqa: E731
        self.u0 = np.asarray(problem.x0, dtype=np.float64).ravel()
        self.f, self.df, self.hf = self._derivatives(energy)
        self.constraint = None
        if constraint is not None:
            g = lambda u: problem.constraints(u.reshape(shape), params)[constraint][0]  # noqa: E731
            self.g, self.dg, self.hg = self._derivatives(g)
        u = jnp.asarray(self.u0)
        for fn in ((self.f, self.df) + ((self.g, self.dg) if constraint else ())):
            jax.block_until_ready(fn(u))  # compile before the clock starts
        jax.block_until_ready(self.hf(u, u))
        if constraint is not None:
            jax.block_until_ready(self.hg(u, u))
            self.constraint = scipy.optimize.NonlinearConstraint(
                lambda u: np.atleast_1d(float(self.g(jnp.asarray(u)))), 0.0, 0.0,
                jac=lambda u: np.asarray(self.dg(jnp.asarray(u)))[None, :],
                hess=lambda u, v: self._operator(self.hg, u, float(v[0])))

    @staticmethod
    def _derivatives(fn):
        hvp = lambda u, v: jax.jvp(jax.grad(fn), (u,), (v,))[1]  # noqa: E731
        return jax.jit(fn), jax.jit(jax.grad(fn)), jax.jit(hvp)

    def _operator(self, hvp, u, factor: float = 1.0):
        u, n = jnp.asarray(u), self.u0.size
        return spla.LinearOperator((n, n), dtype=np.float64, matvec=lambda v: factor * np.asarray(
            hvp(u, jnp.asarray(v, dtype=jnp.float64).ravel())))

    def run(self, tol: float, budget: float) -> dict:
        t0 = time.perf_counter()
        result = scipy.optimize.minimize(
            lambda u: float(self.f(jnp.asarray(u))), self.u0, jac=lambda u: np.asarray(self.df(jnp.asarray(u))),
            hess=lambda u: self._operator(self.hf, u), method="trust-constr",
            constraints=[] if self.constraint is None else [self.constraint],
            options={"gtol": tol, "xtol": 1e-14, "maxiter": 100_000},
            callback=lambda x, state: time.perf_counter() - t0 > budget)
        seconds = time.perf_counter() - t0
        return {"solve": seconds, "steps": int(result.nit), "x": result.x.reshape(-1, 3), "energy": float(result.fun),
                "residual": float(result.optimality), "violation": float(result.constr_violation),
                "pressure": -float(result.v[0][0]) if self.constraint is not None else float("nan"),
                "finished": result.status in (1, 2) and seconds <= budget, "message": result.message,
                "xtol": result.status == 2}


def bubble_row(level: int, args) -> list[str]:
    """The bubble from the flat cube subdivided `level` times (module docstring)."""
    V, F = cube_start(level)
    return bubble_rows(area.with_volume(V, F, SPHERE_VOLUME), F, "ddgjax solve", args)


def refined_bubble_rows(args) -> list[str]:
    """The bubble by refinement (`energies.refine.refine`, Loop subdivision): the cube subdivided
    `REFINE_FROM` times solved, then each level started from the last solution subdivided;
    every level from `args.refine[0]` on is timed from its own start (scipy from the same)."""
    from energies.refine import refine

    V, F = cube_start(REFINE_FROM)
    problem_of = lambda V, F: area.with_volume(V, F, SPHERE_VOLUME)  # noqa: E731
    rows = []
    for level in refine(problem_of, V, F, levels=max(args.refine) - REFINE_FROM, scheme="loop", tol=args.tol, throw=False):
        if len(level.V) >= 6 * 4 ** min(args.refine) + 2:
            rows += bubble_rows(problem_of(level.V, level.F), level.F, "ddgjax solve, refined", args)
    return rows


def bubble_rows(problem, F, label: str, args) -> list[str]:
    """The rows of `solve` and of trust-constr on one bubble problem (faces F), from its `x0`."""
    nv = len(problem.x0)
    repeats = args.repeats if nv <= 50_000 else 1
    sol, compile_s, solve_s = timed(lambda: solve(problem, tol=args.tol, throw=False), repeats)
    p = float(sol.multipliers["volume"][0])
    state = "" if bool(sol.converged) else " not converged"
    retry = f" (after retry: {int(sol.first_order_steps)} L-BFGS steps)" if int(sol.first_order_steps) else ""
    rows = [f"| bubble | {nv} | {label} | {compile_s:.1f} | {solve_s:.2f}{state} | {int(sol.steps)}{retry} | "
            f"{float(sol.residual):.1e} | {abs(area.enclosed_volume(np.asarray(sol.x), F) - SPHERE_VOLUME):.1e} | "
            f"{float(sol.energy):.6f} | p·r = {p:.5f} | {peak_mb():.0f} | |"]
    print(rows[0], flush=True)
    if nv > args.scipy_max:
        rows.append(f"| bubble | {nv} | scipy trust-constr | | skipped (nv > --scipy-max {args.scipy_max}) | | | | | | | |")
    else:
        rows.append(scipy_row("bubble", nv, TrustConstr(problem, "volume"), args.tol, args.scipy_budget, solve_s,
                              lambda r: f"p·r = {r['pressure']:.5f}"))
    print(rows[-1], flush=True)
    return rows


def scipy_row(name: str, nv: int, runner: TrustConstr, tol: float, budget: float, ours: float, quantity) -> str:
    t0 = time.perf_counter()
    try:
        r = runner.run(tol, budget)
    except (ValueError, np.linalg.LinAlgError) as error:  # e.g. NaN in its projections from a degenerate step
        return (f"| {name} | {nv} | scipy trust-constr | — | failed after {time.perf_counter() - t0:.1f} s "
                f"({type(error).__name__}: {error}) | | | | | | {peak_mb():.0f} | |")
    status = "" if r["finished"] else f" (did not finish within {budget:.0f} s: {r['message']})"
    stop = " (xtol)" if r["finished"] and r["xtol"] else ""
    return (f"| {name} | {nv} | scipy trust-constr | — | {r['solve']:.2f}{status} | {r['steps']} | {r['residual']:.1e}{stop} | "
            f"{r['violation']:.1e} | {r['energy']:.6f} | {quantity(r)} | {peak_mb():.0f} | {r['solve'] / ours:.1f} |")


def torus_rows(m: int, n: int, args) -> list[str]:
    V, F = dg.mesh.torus(m, n, R=1.0, r=0.4)
    problem = willmore.helfrich(V, F)
    run = lambda: minimize(problem, tol=args.torus_tol, max_steps=args.torus_steps, throw=False)  # noqa: E731
    sol, compile_s, solve_s = timed(run, 1 if len(V) > 2000 else args.repeats)
    w = float(sol.energy) / (2 * np.pi**2)
    state = "" if bool(sol.converged) else f" not converged (residual {float(sol.residual):.1e} after {int(sol.steps)} steps)"
    rows = [f"| torus | {len(V)} | ddgjax minimize | {compile_s:.1f} | {solve_s:.2f}{state} | {int(sol.steps)} | "
            f"{float(sol.residual):.1e} | — | {float(sol.energy):.6f} | W/2π² = {w:.5f}, R/r = {torus_ratio(sol.x):.4f}, "
            f"min A/mean A = {sliver(sol.x, F):.1e} | "
            f"{peak_mb():.0f} | |"]
    print(rows[0], flush=True)
    if len(V) <= args.scipy_max:
        rows.append(scipy_row("torus", len(V), TrustConstr(problem, None), args.torus_tol, args.scipy_budget, solve_s,
                              lambda r: f"W/2π² = {r['energy'] / (2 * np.pi**2):.5f}, R/r = {torus_ratio(r['x']):.4f}, "
                                        f"min A/mean A = {sliver(r['x'], F):.1e}"))
        print(rows[-1], flush=True)
    return rows


def profile_ratio(P) -> float:
    """R/r of a torus of revolution from its profile: the centroid's ρ over the mean distance to it."""
    P = np.asarray(P)
    centre = P.mean(axis=0)
    return float(centre[0] / np.mean(np.linalg.norm(P - centre, axis=1)))


class ProfileTrustConstr(TrustConstr):
    """trust-constr on the free entries of a problem with vector constraints (all named ones,
    flattened): exact gradient, Hessian-vector products of the energy and of λ·g, the dense
    constraint Jacobian (`jax.jacfwd`)."""

    def __init__(self, problem):
        x0 = jnp.asarray(problem.x0, dtype=jnp.float64)
        free = ~np.asarray(problem.fixed)
        params = problem.params
        x_of = lambda u: x0.at[free].set(u)  # noqa: E731
        energy = lambda u: problem.energy(x_of(u), params)  # noqa: E731
        g = lambda u: jnp.concatenate([jnp.ravel(v) for v in jax.tree_util.tree_leaves(problem.constraints(x_of(u), params))])  # noqa: E731
        self.u0 = np.asarray(x0[free])
        self.f, self.df, self.hf = self._derivatives(energy)
        self.shape = (-1, 2)
        self.x_of = lambda u: np.asarray(x_of(jnp.asarray(u)))  # noqa: E731
        g_jit, jac = jax.jit(g), jax.jit(jax.jacfwd(g))
        weighted = lambda u, v, w: jax.jvp(jax.grad(lambda u: jnp.dot(w, g(u))), (u,), (v,))[1]  # noqa: E731
        hg = jax.jit(weighted)
        u = jnp.asarray(self.u0)
        m = int(g_jit(u).size)
        for value in (self.f(u), self.df(u), self.hf(u, u), g_jit(u), jac(u), hg(u, u, jnp.ones(m))):
            jax.block_until_ready(value)  # compile before the clock starts
        n = self.u0.size
        self.constraint = scipy.optimize.NonlinearConstraint(
            lambda u: np.asarray(g_jit(jnp.asarray(u))), 0.0, 0.0, jac=lambda u: np.asarray(jac(jnp.asarray(u))),
            hess=lambda u, v: spla.LinearOperator((n, n), dtype=np.float64, matvec=lambda d: np.asarray(
                hg(jnp.asarray(u), jnp.asarray(d, dtype=jnp.float64).ravel(), jnp.asarray(v)))))

    def run(self, tol: float, budget: float) -> dict:
        t0 = time.perf_counter()
        result = scipy.optimize.minimize(
            lambda u: float(self.f(jnp.asarray(u))), self.u0, jac=lambda u: np.asarray(self.df(jnp.asarray(u))),
            hess=lambda u: self._operator(self.hf, u), method="trust-constr", constraints=[self.constraint],
            options={"gtol": tol, "xtol": 1e-14, "maxiter": 100_000},
            callback=lambda x, state: time.perf_counter() - t0 > budget)
        seconds = time.perf_counter() - t0
        return {"solve": seconds, "steps": int(result.nit), "x": self.x_of(result.x), "energy": float(result.fun),
                "residual": float(result.optimality), "violation": float(result.constr_violation),
                "finished": result.status in (1, 2) and seconds <= budget, "message": result.message,
                "xtol": result.status == 2}


def revolution_rows(m: int, n: int, args) -> list[str]:
    """The Willmore torus of revolution (`willmore.torus_of_revolution(m, n)`, module docstring)."""
    problem = willmore.torus_of_revolution(m, n)
    run = lambda: solve(problem, tol=args.torus_tol, throw=False)  # noqa: E731
    sol, compile_s, solve_s = timed(run, args.repeats)
    w = float(sol.energy) / (2 * np.pi**2)
    state = "" if bool(sol.converged) else f" not converged (residual {float(sol.residual):.1e})"
    rows = [f"| torus of revolution | {m * n} | ddgjax solve | {compile_s:.1f} | {solve_s:.3f}{state} | {int(sol.steps)} | "
            f"{float(sol.residual):.1e} | — | {float(sol.energy):.6f} | W/2π² = {w:.6f}, R/r = {profile_ratio(sol.x):.5f} | "
            f"{peak_mb():.0f} | |"]
    print(rows[0], flush=True)
    if m * n <= args.scipy_max * 4:
        rows.append(scipy_row("torus of revolution", m * n, ProfileTrustConstr(problem), args.torus_tol, args.scipy_budget,
                              solve_s, lambda r: f"W/2π² = {r['energy'] / (2 * np.pi**2):.6f}, R/r = {profile_ratio(r['x']):.5f}"))
        print(rows[-1], flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="bubbles up to ~6·10³ vertices, the coarse torus")
    ap.add_argument("--levels", type=int, nargs="*", help="subdivisions of the cube (nv = 6·4^k + 2); none: no bubbles")
    ap.add_argument("--refine", type=int, nargs="*", help="levels of the refined bubbles (from the cube subdivided "
                    f"{REFINE_FROM} times, Loop subdivision between levels); none: no refined bubbles")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tol", type=float, default=1e-10, help="KKT tolerance of the bubbles (both solvers)")
    ap.add_argument("--scipy-max", type=int, default=30_000, help="largest vertex count given to trust-constr")
    ap.add_argument("--scipy-budget", type=float, default=120.0, help="seconds per trust-constr run")
    ap.add_argument("--torus", nargs="+", default=None, help="torus sizes m×n, e.g. 24x12 48x24")
    ap.add_argument("--torus-tol", type=float, default=1e-8)
    ap.add_argument("--torus-steps", type=int, default=50)
    ap.add_argument("--no-torus", action="store_true")
    ap.add_argument("--revolution", nargs="*", default=None,
                    help="sizes m×n of the Willmore torus of revolution (default 24x12 96x48 448x224; none: no rows)")
    args = ap.parse_args()
    levels = args.levels if args.levels is not None else ([4, 5] if args.quick else [4, 5, 6, 7])
    if args.refine is None:
        args.refine = [4, 5] if args.quick else [4, 5, 6, 7]
    tori = [] if args.no_torus else [tuple(map(int, s.split("x"))) for s in (args.torus or (["24x12"] if args.quick else ["24x12", "48x24"]))]

    load, cores = os.getloadavg()[0], os.cpu_count() or 1
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, scipy {scipy.__version__}; cores: {cores}, "
          f"load average: {load:.1f}" + ("  (LOADED MACHINE: timings are inflated)" if load > cores else ""), flush=True)
    rows = []
    for level in levels:
        rows += bubble_row(level, args)
    if args.refine:
        rows += refined_bubble_rows(args)
    for m, n in tori:
        rows += torus_rows(m, n, args)
    revolution = args.revolution if args.revolution is not None else (["24x12", "96x48"] if args.quick else ["24x12", "96x48", "448x224"])
    for m, n in (tuple(map(int, size.split("x"))) for size in revolution):
        rows += revolution_rows(m, n, args)
    print("\n| problem | vertices | solver | compile s | solve s | steps | residual | volume error | area / W | "
          "result | peak MB | scipy s / ddgjax s |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    print("\n".join(rows))
    load = os.getloadavg()[0]
    if load > cores:
        print(f"note: load average {load:.1f} > {cores} cores at the end of the run: other processes share the CPU")


if __name__ == "__main__":
    main()
