"""Define a functional and call solve(): Dido's problem, which the catalogue does not have.

Among closed polygons with n edges of length h, the area is critical at the regular n-gon,
area n h² / (4 tan(π/n)).  E = −(enclosed area), constraints |γ_{k+1} − γ_k|² = h².

    python examples/custom_energy.py [--out DIR] [--tiny]
"""

import jax.numpy as jnp
import numpy as np
from _common import output_dir, run

import ddgjax as dg
from solvers import solve


def minus_area(P, h):  # −½ Σ det(γ_k, γ_{k+1}) (shoelace formula)
    Q = jnp.roll(P, -1, axis=0)
    return -0.5 * jnp.sum(P[:, 0] * Q[:, 1] - P[:, 1] * Q[:, 0])


def edge_lengths(P, h):  # one constraint per edge: |γ_{k+1} − γ_k|² − h² = 0
    return jnp.sum((jnp.roll(P, -1, axis=0) - P) ** 2, axis=1) - h**2


def dido(n: int):
    """The solved problem for n edges of length 1/n, and the regular n-gon's area."""
    t = 2 * np.pi * np.arange(n) / n
    start = np.stack([1.3 * np.cos(t), np.sin(t)], axis=1) / n  # an ellipse, roughly the right size
    fixed = np.zeros((n, 2), bool)
    fixed[0] = True  # pin one vertex: translations would leave the critical point undetermined
    sol = solve(dg.Problem(minus_area, start, constraints=edge_lengths, params=1.0 / n, fixed=fixed))
    return sol, n * (1.0 / n) ** 2 / (4 * np.tan(np.pi / n))


def main(out=None, tiny: bool = False):
    n = 8 if tiny else 24
    sol, exact = dido(n)
    print(f"area {-float(sol.energy):.15f}, regular {n}-gon {exact:.15f}, KKT residual {float(sol.residual):.1e}")
    print(f"multipliers (the tension of every edge): {np.ptp(sol.multipliers):.1e} apart, "
          f"{float(sol.multipliers[0]):.12f} = −1/(4 tan(π/n)) = {-1 / (4 * np.tan(np.pi / n)):.12f}")
    return dg.plot.curve(np.asarray(sol.x), closed=True, path=output_dir(out) / "custom_energy.png")


if __name__ == "__main__":
    run(main, __doc__)
