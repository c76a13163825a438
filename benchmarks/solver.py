"""Benchmark of `solve`: a banded constrained problem through the dense and sparse paths,
side by side with `scipy.optimize.minimize(method="trust-constr")` with exact derivatives.

The problem (`solvers.problems.unit_chain`): unit vectors X_0..X_{n-1}, ends fixed,
E = n Σ (1 − <X_k, X_{k+1}>) + Σ <f, X_k>, |X_k|² = 1, so N = 3n − 6 free unknowns and n − 2
constraints; its KKT matrix is block-tridiagonal.  Started from the normalised interpolation
of the ends with noise 0.5/n.

Reported: compile time (first call minus the median of the later ones), the median of
`--repeats` full solves after warm-up, and the KKT residual `max(|∇E − Jᵀλ|∞, |g|∞)`.  For
scipy the multipliers are the least-squares ones at its answer, so the residual is measured
the same way.  scipy gets the exact gradient, the exact sparse Hessians of the energy and of
the constraints, and the sparse constraint Jacobian, all from JAX (jit-compiled).

    python benchmarks/solver.py [--sizes 100 1000 10000] [--repeats 5] [--dense-max 1000]
                                [--scipy-max 10000]
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize
import scipy.sparse

import ddgjax as dg  # noqa: F401  (float64)
from solvers import solve
from solvers._kkt import KKT, spec_of
from solvers._sparse import build_pattern, index_arrays, kkt_values
from solvers.problems import unit_chain


def chain(N: int):
    n = max(4, (N + 6) // 3)
    return unit_chain(n, noise=0.5 / n)


def time_ddgjax(problem, method: str, repeats: int):
    t0 = time.perf_counter()
    sol = solve(problem, method=method)
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = solve(problem, method=method)
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    return {"compile": first - median, "solve": median, "residual": float(sol.residual), "steps": int(sol.steps)}


class ScipyChain:
    """Exact derivatives of the chain problem for scipy, from the sparse KKT assembly (jit)."""

    def __init__(self, problem):
        self.spec = spec_of(problem)
        self.pattern = build_pattern(self.spec, problem.x0, problem.params)
        self.z0 = self.spec.layout.ravel(problem.x0)
        self.kkt = KKT(self.spec, self.z0, problem.params)
        n, m = self.spec.n, self.spec.m
        p, index = self.pattern, index_arrays(self.pattern)
        self.size = n + m
        self.blocks = jax.jit(lambda w: kkt_values(p, index, self.kkt, w))  # the KKT matrix at `pattern.rows/cols`
        self.f = jax.jit(self.kkt.energy)
        self.grad = jax.jit(jax.grad(self.kkt.energy))
        self.g = jax.jit(self.kkt.g)
        self.rows, self.cols = np.asarray(p.rows), np.asarray(p.cols)

    def _matrix(self, u, lam):
        K = scipy.sparse.csr_matrix(
            (np.asarray(self.blocks(jnp.concatenate([u, lam]))), (self.rows, self.cols)), shape=(self.size,) * 2
        )
        n = self.spec.n
        return K[:n, :n], -K[n:, :n]  # ∇²L block and J

    def hess_energy(self, u):
        return self._matrix(jnp.asarray(u), jnp.zeros(self.spec.m))[0]

    def hess_constraints(self, u, v):
        # scipy's Lagrangian is f + Σ v_i c_i: Σ v_i ∇²c_i = ∇²L(λ = −v) − ∇²E
        u = jnp.asarray(u)
        return self._matrix(u, -jnp.asarray(v))[0] - self.hess_energy(u)

    def jac(self, u):
        return self._matrix(jnp.asarray(u), jnp.zeros(self.spec.m))[1]

    def kkt_residual(self, u) -> float:
        grad, J = np.asarray(self.grad(jnp.asarray(u))), self.jac(u)
        lam = scipy.sparse.linalg.lsqr(J.T, grad, atol=1e-15, btol=1e-15)[0]
        return max(np.abs(grad - J.T @ lam).max(), np.abs(np.asarray(self.g(jnp.asarray(u)))).max())

    def run(self):
        u0 = np.asarray(self.z0[self.spec.layout.free])
        constraint = scipy.optimize.NonlinearConstraint(
            lambda u: np.asarray(self.g(jnp.asarray(u))), 0.0, 0.0, jac=self.jac, hess=self.hess_constraints
        )
        return scipy.optimize.minimize(
            lambda u: float(self.f(jnp.asarray(u))), u0, jac=lambda u: np.asarray(self.grad(jnp.asarray(u))),
            hess=self.hess_energy, constraints=[constraint], method="trust-constr",
            options={"gtol": 1e-10, "xtol": 1e-14, "maxiter": 5000},
        )


def time_scipy(problem, repeats: int):
    runner = ScipyChain(problem)
    runner.run()  # warm-up: compiles the JAX derivative functions
    times, res = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = runner.run()
        times.append(time.perf_counter() - t0)
    return {"solve": statistics.median(times), "residual": runner.kkt_residual(res.x), "steps": int(res.nit)}


def ratio_text(ratio) -> str:
    if ratio is None:
        return "—"
    return f"{ratio:.1f}×" if ratio < 10 else f"{ratio:.0f}×"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--dense-max", type=int, default=1000, help="largest N for the dense path")
    parser.add_argument("--scipy-max", type=int, default=10000, help="largest N for trust-constr")
    parser.add_argument("--scipy-repeats", type=int, default=1)
    args = parser.parse_args(argv)

    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, scipy {scipy.__version__}")
    print("| N free | path | compile s | solve s (median) | steps | KKT residual | trust-constr s / this |")
    print("|---:|---|---:|---:|---:|---:|---:|")
    for N in args.sizes:
        problem = chain(N)
        n_free = spec_of(problem).n
        scipy_row = time_scipy(problem, args.scipy_repeats) if N <= args.scipy_max else None
        rows = [("sparse", time_ddgjax(problem, "sparse", args.repeats))]
        if N <= args.dense_max:
            rows.append(("dense", time_ddgjax(problem, "dense", args.repeats)))
        for path, r in rows:
            ratio = None if scipy_row is None else scipy_row["solve"] / r["solve"]
            print(f"| {n_free} | ddgjax {path} | {r['compile']:.2f} | {r['solve']:.4f} | {r['steps']} | "
                  f"{r['residual']:.1e} | {ratio_text(ratio)} |")
        if scipy_row is not None:
            print(f"| {n_free} | scipy trust-constr | — | {scipy_row['solve']:.3f} | {scipy_row['steps']} | "
                  f"{scipy_row['residual']:.1e} | 1× |")
        else:
            print(f"| {n_free} | scipy trust-constr | — | skipped (N > --scipy-max) | | | |")


if __name__ == "__main__":
    main()
