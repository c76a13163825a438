"""KLU inside the caller's `jax.jit`: the pattern's analysis made in the program (what `solve`
does when `jit` traces it, so that the program is the same in every process and JAX's
persistent cache finds it) against the analysis made outside and its address passed as an
argument of the program (what the solver's own programs do), in one run.

The clamped elastica with chord (0.45, 0.2, 0), `linear_solver=KLU()`, `throw=False`, as
`jax.jit(lambda c: solve(problem.with_params(... chord=c ...)).x)`; columns: seconds to the
first result (trace, compile, run) and the median of `--repeats` runs after it, per way, and
their ratio (in the program ÷ passed).

    python benchmarks/klu_in_jit.py [--sizes 100 2000] [--repeats 7]

The machine may be shared: compare rows of one run only.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import jax.numpy as jnp

from energies import elastica
from solvers import KLU, solve
from solvers._kkt import spec_of


def timings(fn, args, repeats: int) -> tuple[float, float]:
    """`(first, median)`: seconds of the first call (compile included) and median of the rest."""
    start = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - start
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        runs.append(time.perf_counter() - start)
    return first, statistics.median(runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 2000])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    chord = jnp.array([0.45, 0.2, 0.0])
    print(f"{'n':>6} | {'in program: first':>17} {'run':>9} | {'passed: first':>13} {'run':>9} | run ratio")
    for n in args.sizes:
        problem = elastica.clamped(n, chord=(0.5, 0.2, 0.0), t_start=(1, 0, 0), t_end=(0, 1, 0))

        def curve(linear, c):
            return solve(problem.with_params({**problem.params, "chord": c}), linear_solver=linear, throw=False).x

        bound = KLU().bind(problem, spec_of(problem))  # analysed now; its address is a leaf
        assert "klu_symbolic" in bound.index
        inside = timings(jax.jit(lambda c: curve(KLU(), c)), (chord,), args.repeats)
        passed = timings(jax.jit(curve), (bound, chord), args.repeats)
        print(f"{n:6d} | {inside[0]:17.2f} {inside[1] * 1e3:7.2f}ms | {passed[0]:13.2f} {passed[1] * 1e3:7.2f}ms | "
              f"{inside[1] / passed[1]:9.2f}")


if __name__ == "__main__":
    main()
