"""The worked example run by `make demo`: declare constrained problems, solve, print.

1. The Rayleigh quotient `E(x) = xᵀAx` on the unit sphere `|x|² = 1`: its critical points are
   the eigenvectors of A and the Lagrange multiplier is the eigenvalue (∇E = 2Ax = λ·2x).
2. Six unit charges on the sphere (Thomson problem): a critical point of the Coulomb energy
   with three continuous symmetries (rotations), so the KKT matrix is singular at the answer;
   the minimum is the octahedron with energy 3/2 + 12/√2.
3. A family of clamped discrete elastica (Def 3.2) with decreasing chord, its loads and
   Thm 3.8's residual, drawn to `report/elastica_family.png`.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

import ddgjax as dg
from solvers import solve


def rayleigh_demo(n: int = 6, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(n, n))
    A = (B + B.T) / 2
    problem = dg.Problem(
        energy=lambda x, A: x @ A @ x,
        x0=rng.normal(size=n),
        constraints=lambda x, A: jnp.array([x @ x - 1.0]),
        params=A,
        name="Rayleigh quotient",
    )
    sol = solve(problem)
    eigenvalues = np.linalg.eigvalsh(A)
    nearest = eigenvalues[np.argmin(np.abs(eigenvalues - float(sol.multipliers[0])))]
    print("1. Rayleigh quotient x^T A x on |x| = 1, A random symmetric", f"{n}x{n}")
    print("   critical point x  =", np.array2string(np.asarray(sol.x), precision=6))
    print(f"   multiplier lambda = {float(sol.multipliers[0]):.12f}")
    print(f"   nearest eigenvalue= {nearest:.12f}  (|difference| = {abs(nearest - float(sol.multipliers[0])):.1e})")
    print(f"   KKT residual      = {float(sol.residual):.2e} after {int(sol.steps)} Newton steps")


def thomson_demo(seed: int = 1) -> None:
    import jax.numpy as jnp

    def coulomb(X, _):
        i, j = np.triu_indices(len(X), 1)
        return jnp.sum(1.0 / jnp.linalg.norm(X[i] - X[j], axis=1))

    rng = np.random.default_rng(seed)
    X0 = rng.normal(size=(6, 3))
    X0 /= np.linalg.norm(X0, axis=1, keepdims=True)
    problem = dg.Problem(coulomb, X0, constraints=lambda X, _: jnp.sum(X**2, axis=1) - 1.0, name="Thomson")
    sol = solve(problem, warm_start="lbfgs")
    print("2. Six charges on the unit sphere (rotation-invariant: singular KKT matrix)")
    print(f"   energy            = {float(sol.energy):.12f}")
    print(f"   octahedron        = {1.5 + 12 / np.sqrt(2):.12f}")
    print("   multipliers       =", np.array2string(np.asarray(sol.multipliers), precision=8))
    print(f"   KKT residual      = {float(sol.residual):.2e} after {int(sol.steps)} Newton steps")


def elastica_demo(n: int = 100, out: str = "report") -> None:
    import os

    from energies import elastica

    print(f"3. Clamped discrete elastica, n = {n} edges, T_0 = (0,1,0), T_n-1 = (0,-1,0)")
    curves, T = [], None
    for chord in (0.8, 0.6, 0.4, 0.2):
        problem = elastica.clamped(
            n, chord=[chord, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0],
            x0=None if T is None else np.asarray(T),
        )
        sol = solve(problem)
        T = sol.x
        gamma = np.asarray(elastica.curve(sol.x, problem))
        Tn = np.asarray(sol.x)
        W = np.cross(Tn[1:], Tn[:-1]) / (1 + np.sum(Tn[1:] * Tn[:-1], axis=1))[:, None]
        b = W - np.cross(np.asarray(elastica.theorem_3_8_a(sol, problem)), gamma[1:-1])
        print(f"   chord {chord:.1f}: energy {float(sol.energy):9.5f}, load a = {np.asarray(elastica.load(sol)).round(5)}, "
              f"Thm 3.8 residual {np.max(np.abs(b - b[0])):.1e}, KKT residual {float(sol.residual):.1e}")
        curves.append(gamma[:, :2])
    os.makedirs(out, exist_ok=True)
    path = dg.plot.curves(curves, path=os.path.join(out, "elastica_family.png"), labels=["0.8", "0.6", "0.4", "0.2"])
    print(f"   drawn to {path}")


def main() -> None:
    rayleigh_demo()
    thomson_demo()
    elastica_demo()


if __name__ == "__main__":
    main()
