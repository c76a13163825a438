"""The worked example run by `make demo`: declare constrained problems, solve, print.

1. The Rayleigh quotient `E(x) = xᵀAx` on the unit sphere `|x|² = 1`: its critical points are
   the eigenvectors of A and the Lagrange multiplier is the eigenvalue (∇E = 2Ax = λ·2x).
2. Six unit charges on the sphere (Thomson problem): a critical point of the Coulomb energy
   with three continuous symmetries (rotations), so the KKT matrix is singular at the answer;
   the minimum is the octahedron with energy 3/2 + 12/√2.
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


def main() -> None:
    rayleigh_demo()
    thomson_demo()


if __name__ == "__main__":
    main()
