"""The solver: constrained critical points and their derivatives."""

from __future__ import annotations

import jax
import numpy as np

from ddgjax.problem import flatten_multipliers
from ddgjax.verify import check
from energies import elastica
from solvers import solve
from solvers.problems import random_symmetric, rayleigh


@check("Lagrange multipliers", "the Rayleigh quotient xᵀAx on |x| = 1: the multiplier is an eigenvalue and x its eigenvector",
       quantity="|λ − nearest eigenvalue| + |Ax − λx|∞", at_most=1e-10, quick=dict(n=20), full=dict(n=200))
def rayleigh_multiplier_is_eigenvalue(ctx, n):
    A = random_symmetric(n, 0)
    sol = solve(rayleigh(A, np.random.default_rng(1).normal(size=n)))
    lam, x = float(sol.multipliers[0]), np.asarray(sol.x)
    return float(np.min(np.abs(np.linalg.eigvalsh(A) - lam)) + np.max(np.abs(A @ x - lam * x)))


@check("implicit function theorem", "the derivative of the eigenvalue through solve is ∂λ/∂A = x xᵀ (Hellmann–Feynman)",
       quantity="max |∂λ/∂A − x xᵀ|", at_most=1e-8, quick=dict(n=20), full=dict(n=200))
def rayleigh_eigenvalue_derivative(ctx, n):
    A = random_symmetric(n, 0)
    x0 = np.random.default_rng(1).normal(size=n)
    sol = solve(rayleigh(A, x0))
    gradient = jax.grad(lambda B: solve(rayleigh(B, x0)).multipliers[0])(A)
    x = np.asarray(sol.x)
    # A is used symmetrically (xᵀAx), so the derivative with respect to the entries is x xᵀ
    return float(np.max(np.abs(np.asarray(gradient) - np.outer(x, x))))


@check("linear algebra paths", "dense LU, sparse KLU and matrix-free Krylov (MINRES on the constraints' tangent space) "
       "reach the same clamped elastica and multipliers",
       quantity="max |x − x_dense| + |λ − λ_dense| over sparse, Krylov", at_most=1e-10, quick=dict(n=12), full=dict(n=40))
def linear_algebra_paths_agree(ctx, n):
    problem = elastica.clamped(n, chord=(0.5, 0.3, 0.1), t_start=(1, 0, 0), t_end=(0, 1, 0), clamp="vertex")
    dense = solve(problem, method="dense", tol=1e-11)
    gaps = []
    for method in ("sparse", "krylov"):
        other = solve(problem, method=method, tol=1e-11)
        gaps.append(float(np.max(np.abs(np.asarray(other.x) - np.asarray(dense.x))))
                    + float(np.max(np.abs(flatten_multipliers(problem, other.multipliers)
                                          - flatten_multipliers(problem, dense.multipliers)))))
    return max(gaps)
