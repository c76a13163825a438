"""Flows and Euclidean motions: geometric flows (Sec 2.2, (2.6)–(2.8)), invariant curvatures and
bending energy (Remark 3.1, 3.6), and the elastica moved by the Heisenberg flow ((3.3), Remark 3.8)."""

from __future__ import annotations

import jax
import numpy as np

from ddgjax import curves
from ddgjax.verify import check
from energies import elastica

from ._shared import space_elastica, vertex_field
from .sec1_curves import random_polygon
from .sec2_flows import closed_curve

GROUP = "clamped elastica"  # (3.3) is checked on the shared solved elastica (one compilation)

SCALES = (1.0, 1e-3, 250.0)  # x ↦ s R x + b: the flows see T_k = Δγ_k / ε (Sec 1.2), so any s
SHEAR = np.array([[1.0, 0.6, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
REFLECTION = np.diag([1.0, 1.0, -1.0])


def _curves():
    """`(γ, closed)`: an open random arc-length polygon and the closed test curve of Sec 2 (unit edges)."""
    return (random_polygon(16, seed=4), False), (np.asarray(closed_curve(24)[0]), True)


def _rotation(rng) -> np.ndarray:
    """A uniformly random rotation, det +1."""
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else Q @ REFLECTION


def _similarities(seed: int = 0):
    """`(A, s, b)` for x ↦ A x + b with A = s R, R a random rotation, s in SCALES, |b| = O(s)."""
    rng = np.random.default_rng(seed)
    return [(s * _rotation(rng), s, s * rng.normal(size=3)) for s in SCALES]


_energy_of_tangents = jax.jit(elastica.bending_energy, static_argnames="closed")  # one compilation per shape


def _bending_energy(gamma, closed: bool) -> float:
    """`Σ_k E_k`, E_k = log(1 + tan²(φ_k/2)) of the unit tangents (Remark 3.6)."""
    return float(_energy_of_tangents(curves.tangents(gamma, closed=closed), closed=closed))


def _flows(gamma, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    """`(v, w)`: the tangent flow (Prop 2.1) and the Heisenberg flow (Prop 2.2) of γ."""
    return (np.asarray(curves.tangent_flow(gamma, closed=closed)),
            np.asarray(curves.heisenberg_flow(gamma, closed=closed)))


@check("(2.6)–(2.8), Prop 2.1, 2.2", "the tangent and Heisenberg flows are geometric: v[sRγ + b] = R v[γ], "
       "w[sRγ + b] = R w[γ] (R ∈ SO(3), any scale s); under a reflection Q the tangent flow is equivariant and "
       "the Heisenberg flow, a cross product, changes sign: w[Qγ] = −Q w[γ]",
       quantity="max |F[Aγ + b] − (±)R F[γ]| over both flows, both curves, three similarities and a reflection",
       at_most=1e-12, quick={})
def flows_are_equivariant(ctx):
    """(2.6)–(2.8): v_k = α(T_k + T_(k−1)), w_k = α T_k × T_(k−1) with α = 1/(1 + <T_k, T_(k−1)>)
    depend on the tangents only (translations drop out), α is rotation invariant, and under an
    orthogonal Q, T_k × T_(k−1) ↦ det(Q) Q (T_k × T_(k−1))."""
    worst = 0.0
    for gamma, closed in _curves():
        v, w = _flows(gamma, closed)
        motions = [(A / s, A, b, 1.0) for A, s, b in _similarities()] + [(REFLECTION, REFLECTION, 0.0, -1.0)]
        for R, A, b, orientation in motions:
            v_moved, w_moved = _flows(gamma @ A.T + b, closed)
            worst = max(worst, float(np.max(np.abs(v_moved - v @ R.T))),
                        float(np.max(np.abs(w_moved - orientation * w @ R.T))))
    return worst


@check("Remark 3.1, 3.6", "the curvature κ_k = 2 tan(φ_k/2)/ε and the bending energy Σ log(1 + κ_k²ε²/4) are "
       "invariant under Euclidean motions (reflections included); under scaling by s, κ scales by 1/s and the energy "
       "not at all",
       quantity="max relative change of s·κ and of Σ E_k, both curves, three similarities and a reflection",
       at_most=1e-12, quick={})
def curvature_and_energy_are_invariant(ctx):
    """Remark 3.1 (smooth) and 3.6 (discrete): E_k = log(1 + κ_k²/4) = log 2 − log(1 + <T_k, T_(k−1)>) depends
    on <T_k, T_(k−1)> only; the scaling is that of Sec 1.2 (T_k = Δγ_k/ε)."""
    worst = 0.0
    for gamma, closed in _curves():
        kappa, energy = np.asarray(curves.curvature(gamma, "arclength", closed=closed)), _bending_energy(gamma, closed)
        for A, s, b in _similarities(1) + [(REFLECTION, 1.0, 0.0)]:
            moved = gamma @ A.T + b
            kappa_moved = s * np.asarray(curves.curvature(moved, "arclength", closed=closed))
            worst = max(worst, float(np.max(np.abs(kappa_moved - kappa)) / np.max(np.abs(kappa))),
                        abs(_bending_energy(moved, closed) - energy) / energy)
    return worst


@check("Remark 3.6, (2.6)–(2.8)", "negative control: a shear (not a similarity) changes the bending energy, and a "
       "reflection does not commute with the Heisenberg flow (w[Qγ] ≠ Q w[γ])",
       quantity="min over both curves of |ΔE|/E (shear) and max|w[Qγ] − Q w[γ]|/max|w| (reflection)",
       at_least=1e-2, quick={})
def shear_and_reflection_break_invariance(ctx):
    """Shows that the two checks above would see a non-geometric map: each change must be O(1)."""
    changes = []
    for gamma, closed in _curves():
        energy = _bending_energy(gamma, closed)
        changes.append(abs(_bending_energy(gamma @ SHEAR.T, closed) - energy) / energy)
        w = _flows(gamma, closed)[1]
        w_reflected = _flows(gamma @ REFLECTION.T, closed)[1]
        changes.append(float(np.max(np.abs(w_reflected - w @ REFLECTION.T)) / np.max(np.abs(w))))
    return min(changes)


# --- (3.3): on a discrete elastica the Heisenberg flow rotates every tangent, ∂_t T_k = a × T_k --


def _tangent_form(n: int):
    """`(T, a, W)` of the shared clamped space elastica with unit edges: its tangents, the vector
    a of (3.2)/(3.3) (the pendulum gravity (h²/2)λ: a of Thm 3.8 for the curve scaled to unit
    edges) and the vertex field W_k = T_k × T_(k−1)/(1 + <T_k, T_(k−1)>) at the interior vertices."""
    problem, sol = space_elastica(n, "edge")
    T = np.asarray(sol.x)
    return T, np.asarray(elastica.pendulum_gravity(sol, problem)), vertex_field(T)


@check("eq (3.3), Remark 3.8", "on a clamped discrete space elastica, at every free edge k = 1 … n−2, "
       "T_(k+1) × T_k/(1 + <T_(k+1), T_k>) + T_(k−1) × T_k/(1 + <T_k, T_(k−1)>) = a × T_k (the reference prints "
       "− before the second term: a sign typo, see the negative control), and this is ∂_t T_k = a × T_k for the "
       "library's Heisenberg flow of the unit-edge curve",
       quantity="max_k |LHS_k − a × T_k| + max_k |∂_t T_k − a × T_k|", at_most=1e-10, quick=dict(n=32),
       full=dict(n=256))
def elastica_tangent_form(ctx, n):
    """Thm 3.8's proof: (3.2) T_(k−1)/(1 + <T_k, T_(k−1)>) + T_(k+1)/(1 + <T_(k+1), T_k>) − 2c_k T_k
    − a = 0, crossed with T_k, gives W_(k+1) − W_k = a × T_k (the unit-length multipliers c_k drop
    out, so the check does not depend on how the solver extends the energy off the sphere); with
    ∂_t γ_k = W_k (Prop 2.2) this is ∂_t T_k = a × T_k (Remark 3.8), a = (h²/2)λ from the solver's
    chord multipliers λ."""
    T, a, W = _tangent_form(n)
    target = np.cross(a, T[1:-1])
    explicit = np.diff(W, axis=0)  # W_(k+1) − W_k: the left side of (3.3) with its sign fixed
    gamma = np.asarray(curves.from_tangents(T))
    flowed = np.asarray(curves.edge_vectors(curves.heisenberg_flow(gamma, closed=False)))[1:-1]  # Δw_k, interior ends
    return float(np.max(np.abs(explicit - target)) + np.max(np.abs(flowed - target)))


@check("eq (3.3)", "negative control: (3.3) as printed, T_(k+1) × T_k/(1 + …) − T_(k−1) × T_k/(1 + …) "
       "= a × T_k, fails on the same elastica", quantity="max_k |W_(k+1) + W_k − a × T_k|", at_least=1e-3, quick=dict(n=32),
       full=dict(n=256))
def elastica_tangent_form_as_printed_fails(ctx, n):
    """As printed, the left side of (3.3) is W_(k+1) + W_k (T_(k−1) × T_k = −T_k × T_(k−1)): O(κh) off."""
    T, a, W = _tangent_form(n)
    return float(np.max(np.abs(W[1:] + W[:-1] - np.cross(a, T[1:-1]))))
