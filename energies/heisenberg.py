"""The Heisenberg magnet chain (Appendix A, eq (A.2), Remark A.1, eq (2.14)): declared by its
Hamiltonians only; the equations of motion are `dg.hamiltonian_flow(H, dg.spin_poisson)`.

A closed chain of N unit spins S_1 … S_N (periodic, S_{N+1} = S_1) with the Lie–Poisson
bracket {S_i^α, S_j^β} = ε^{αβγ} δ_ij S_j^γ, so that `∂_t S_i = ∇_i H × S_i`:

- **naive** (Sec A):  `H = −J Σ <S_i, S_{i+1}>`  ⟹  `∂_t S_i = J S_i × (S_{i+1} + S_{i−1})` (A.2);
- **integrable** (Remark A.1):  `H = −2J Σ log((1 + <S_i, S_{i+1}>)/2)`  ⟹
  `∂_t S_i = 2J S_i × (S_{i+1}/(1 + <S_{i+1}, S_i>) + S_{i−1}/(1 + <S_i, S_{i−1}>))`.
  With J = −½ and S = T this is the discrete Heisenberg flow (2.14) on the tangents of a
  discrete curve; it commutes with the discrete tangent flow (Prop 2.2), the naive one does not.

**Smooth limit** (Sec A).  With spins S_i = S(εi) of a smooth periodic field, `H/ε` (after
adding the constant JN) tends to `(J/2) ∫ |S'|² dx` and the flow of `H/ε`, with time rescaled
by 1/ε, tends to `∂_t S = J S × S''` (A.3): `scaled_hamiltonian`, `scaled_flow`.
"""

from __future__ import annotations

from typing import Callable

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

import ddgjax as dg
from ddgjax._checks import check_finite, check_positive, checked_shape, when_concrete
from ddgjax.errors import InvalidInputError, ShapeError, SingularVertexError

__all__ = [
    "hamiltonian", "flow", "tangent_flow_on_tangents", "ground_energy", "scaled_hamiltonian", "scaled_flow", "check_spins", "check_neighbours",
    "NonUnitSpinError",
]

KINDS = ("naive", "integrable")


class NonUnitSpinError(InvalidInputError):
    """A spin of the chain is not a unit vector."""


def _neighbour_products(S):
    """`<S_i, S_{i+1}>` around the closed chain."""
    return jnp.sum(S * jnp.roll(S, -1, axis=0), axis=1)


def naive_energy(S: Float[Array, "n 3"], J) -> Float[Array, ""]:
    """`H = −J Σ <S_i, S_{i+1}>` (Sec A)."""
    return -J * jnp.sum(_neighbour_products(S))


def integrable_energy(S: Float[Array, "n 3"], J) -> Float[Array, ""]:
    """`H = −2J Σ log((1 + <S_i, S_{i+1}>)/2)` (Remark A.1)."""
    return -2.0 * J * jnp.sum(jnp.log1p(_neighbour_products(S)) - jnp.log(2.0))


def check_spins(S, tol: float = 1e-10) -> None:
    """Raise unless S is an (N, 3) array, N ≥ 3 (`ShapeError`, always), of finite unit spins
    (`NonFiniteError` / `NonUnitSpinError` naming the spin, when S is concrete)."""
    shape = np.shape(S)
    if len(shape) != 2 or shape[1] != 3 or shape[0] < 3:
        raise ShapeError(f"spins must be an (N, 3) array with N >= 3 on a closed chain, got shape {shape}")
    _check_unit_spins(S, tol)


@when_concrete
def _check_unit_spins(S, tol: float) -> None:
    arr = np.asarray(S)
    check_finite(arr, "spins")
    defect = np.abs(np.linalg.norm(arr, axis=1) - 1.0)
    if np.any(defect > tol):
        i = int(np.argmax(defect > tol))
        raise NonUnitSpinError(f"spin {i} has length {np.linalg.norm(arr[i]):.15g}, not 1 (spins live on S²)")


@when_concrete
def check_neighbours(S) -> None:
    """Raise `SingularVertexError` naming the first pair of neighbouring spins with
    `1 + <S_i, S_{i+1}> <= dg.curves.SINGULAR_TOL` (anti-parallel): there the integrable
    Hamiltonian `−2J log((1 + <S_i, S_{i+1}>)/2)` and its flow are singular (Remark A.1).
    Concrete S only."""
    arr = np.asarray(S, dtype=float)
    gap = 1.0 + np.sum(arr * np.roll(arr, -1, axis=0), axis=1)
    bad = np.flatnonzero(gap <= dg.curves.SINGULAR_TOL)
    if bad.size:
        i = int(bad[0])
        j = (i + 1) % len(arr)
        raise SingularVertexError(
            f"spins {i} and {j} are anti-parallel (1 + <S_{i}, S_{j}> = {gap[i]:.3g}): the integrable "
            "Hamiltonian −2J log((1 + <S_i, S_{i+1}>)/2) is singular there (Remark A.1)"
        )


def check_chain(S, kind: str) -> None:
    """The checks of `check_spins`, and for the integrable chain those of `check_neighbours`."""
    check_spins(S)
    if kind == "integrable":
        check_neighbours(S)


@when_concrete
def _check_coupling(J) -> None:
    if not (np.isfinite(J) and J != 0):
        raise InvalidInputError(f"the coupling J must be finite and non-zero (J = 0 is no interaction), got {J}")


def checked_coupling(J) -> Float[Array, ""]:
    """The coupling J as a traceable scalar (so `jax.grad` in J works); when concrete,
    `InvalidInputError` unless it is finite and non-zero."""
    J = jnp.asarray(J, dtype=float)
    checked_shape(J, (), "the coupling J")
    _check_coupling(J)
    return J


def hamiltonian(kind: str, J: float = 1.0) -> Callable:
    """`H(S)` of the naive or integrable closed chain (periodic, S_{N+1} = S_1, Sec A) with
    coupling J ≠ 0 (traceable: `H` is differentiable in J).

    **Raises:** `InvalidInputError` for an unknown kind, J = 0 or non-finite; when called on
    concrete spins, `NonUnitSpinError` / `NonFiniteError` naming the spin, `SingularVertexError`
    naming two anti-parallel neighbours (integrable chain); `ShapeError`.
    """
    if kind not in KINDS:
        raise InvalidInputError(f"kind must be one of {KINDS}, got {kind!r}")
    J = checked_coupling(J)
    energy = naive_energy if kind == "naive" else integrable_energy

    def H(S):
        check_chain(S, kind)
        return energy(S, J)

    return H


def flow(kind: str, J: float = 1.0) -> Callable:
    """The equations of motion `∂_t S = ∇H × S` of `hamiltonian(kind, J)`, by autodiff (the same
    errors, raised before differentiating)."""
    f = dg.hamiltonian_flow(hamiltonian(kind, J), dg.spin_poisson)

    def checked(S):
        check_chain(S, kind)
        return f(S)

    return checked


def tangent_flow_on_tangents(T: Float[Array, "n 3"]) -> Float[Array, "n 3"]:
    """The discrete tangent flow (Prop 2.1) acting on the tangents of a closed curve:
    `∂_x T_k = v_{k+1} − v_k`, `v_k = (T_k + T_{k−1})/(1 + <T_k, T_{k−1}>)`, with v_k obtained by
    autodiff from the local bending energy as in `dg.curves.tangent_flow`."""
    v = dg.curves.tangent_velocity(jnp.roll(T, 1, axis=0), T)
    return jnp.roll(v, -1, axis=0) - v


def ground_energy(kind: str, J: float, N: int) -> float:
    """H of the aligned chain: −JN (naive), 0 (integrable)."""
    return -J * N if kind == "naive" else 0.0


def scaled_hamiltonian(kind: str, J: float, eps: float) -> Callable:
    """`(H − H_aligned)/ε`: tends to `(J/2) ∫ |S'|² dx` for spins S_i = S(εi) (Sec A; the text's
    "replacing H by H + N" for the naive chain).  **Raises:** as `hamiltonian`, and
    `InvalidInputError` unless the spacing ε is finite and positive (when concrete)."""
    H = hamiltonian(kind, J)
    check_positive(eps, "the spacing eps")

    def H_eps(S):
        return (H(S) - ground_energy(kind, J, S.shape[0])) / eps

    return H_eps


def scaled_flow(kind: str, J: float, eps: float) -> Callable:
    """The flow of `H/ε` with time rescaled by 1/ε: tends to `∂_t S = J S × S''` (A.3)."""
    f = flow(kind, J)
    check_positive(eps, "the spacing eps")
    return lambda S: f(S) / eps**2
