"""Reference problems with known answers, for tests and benchmarks of `solve`.

They are generic (vectors on spheres, quadratic forms), not objects of the catalogue."""

import jax.numpy as jnp
import numpy as np

import ddgjax as dg


def random_symmetric(n: int, seed: int) -> np.ndarray:
    B = np.random.default_rng(seed).normal(size=(n, n))
    return (B + B.T) / 2


# Energies are module-level functions, so that every problem built from them shares one
# compiled solver (jit caches on the functions' identity).


def quadratic_form(x, A):
    return x @ A @ x


def unit_sphere(x, _):
    return jnp.array([x @ x - 1.0])


def rayleigh(A, x0, **kw) -> dg.Problem:
    """E(x) = xᵀAx on |x|² = 1: critical points are eigenvectors, the multiplier is the eigenvalue."""
    return dg.Problem(quadratic_form, x0, constraints=unit_sphere, params=A, **kw)


def squared_distance(x, p):
    return jnp.sum((x - p["c"]) ** 2)


def sphere_of_radius(x, p):
    return jnp.array([x @ x - p["r"] ** 2])


def nearest_point_on_sphere(c, r) -> dg.Problem:
    """min |x − c|² on |x| = r: x* = r c/|c|, E* = (|c| − r)², λ* = 1 − |c|/r."""
    return dg.Problem(
        squared_distance,
        np.array([0.3, 0.4, 0.5]),
        constraints=sphere_of_radius,
        params={"c": jnp.asarray(c, float), "r": jnp.asarray(r, float)},
    )


def unit_chain(n: int, *, field=(1.0, -0.5, 2.0), chord=None, local=True, seed=0, noise=0.05,
               turn=1.0) -> dg.Problem:
    """Unit vectors X_0..X_{n-1} with a nearest-neighbour coupling and a weak field.

    E = n Σ_k (1 − <X_k, X_{k+1}>) + (1/n) Σ_k <f, X_k>  (h = 1/n: a discretisation of
    ∫|X'|²/2 + <f, X>, so the answer has a smooth limit and Newton's step count does not grow),  |X_k|² = 1 for the free k, and optionally
    Σ_k X_k = chord.  X_0 = e1 and X_{n-1} = (cos turn, sin turn, 0) are fixed; the start is
    the normalised linear interpolation plus noise.  Declared local (dg.local_sum /
    dg.local_map) or as plain functions.  Constraints: `|X_k|² − 1` (n − 2,) alone, or with a
    chord the named `{"unit": (n − 2,), "chord": (3,)}`.
    """
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.0, n)[:, None]
    end = np.array([np.cos(turn), np.sin(turn), 0.0])
    X0 = (1 - s) * np.array([1.0, 0.0, 0.0]) + s * end + noise * rng.normal(size=(n, 3))
    X0[[0, -1]] = [[1.0, 0.0, 0.0], end]
    X0 /= np.linalg.norm(X0, axis=1, keepdims=True)
    f = jnp.asarray(field)
    edges = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    interior = np.arange(1, n - 1)
    fixed = np.zeros((n, 3), bool)
    fixed[[0, -1]] = True

    def bond(X2, _):
        return n * (1.0 - X2[0] @ X2[1])

    def potential(X1, _):
        return f @ X1[0] / n

    def unit(X1, _):
        return X1[0] @ X1[0] - 1.0

    def chord_term(X1, c):
        return X1[0] - c / n

    if local:
        energy = dg.local_sum(bond, edges) + dg.local_sum(potential, np.arange(n)[:, None])
        cons = dg.local_map(unit, interior[:, None])
        if chord is not None:
            cons = dg.concat(unit=cons, chord=dg.local_sum(chord_term, np.arange(n)[:, None]))
    else:
        def energy(X, _):
            return n * jnp.sum(1.0 - jnp.sum(X[:-1] * X[1:], axis=1)) + jnp.sum(X @ f) / n

        def cons(X, c):
            unit_part = jnp.sum(X[1:-1] ** 2, axis=1) - 1.0
            return unit_part if chord is None else {"unit": unit_part, "chord": X.sum(0) - c}

    return dg.Problem(energy, X0, constraints=cons, params=None if chord is None else jnp.asarray(chord), fixed=fixed)
