"""Flows on discrete arc-length curves (Section 2.2): the tangent flow (Prop 2.1) and the
Heisenberg flow (Prop 2.2), derived by automatic differentiation of the local bending energy,
checked against the closed forms, (2.5), (2.14), commutation and Remark 2.1's zig-zags.  The
smooth limits of Remark 2.3 and Remark 3.6 are `ddgjax verify` checks (`sec2_flows`)."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import curves
from ddgjax.errors import ArcLengthError, NonFiniteError, ShapeError, SingularVertexError

def closed_arc_length_curve(rng, n, noise=0.6):
    """A random closed regular curve with n unit edges: the tangents of a regular n-gon plus
    noise, projected onto {|T_k| = 1, Σ T_k = 0} by minimum-norm Gauss–Newton steps."""
    angles = 2 * np.pi * np.arange(n) / n
    T = np.stack([np.cos(angles), np.sin(angles), np.zeros(n)], axis=1) + noise * rng.normal(size=(n, 3))
    for _ in range(30):
        residual = np.concatenate([np.sum(T**2, axis=1) - 1, T.sum(axis=0)])
        J = np.vstack([np.kron(np.eye(n), np.ones((1, 3))) * 2 * T.ravel(), np.tile(np.eye(3), n)])
        T = T - (J.T @ np.linalg.solve(J @ J.T, residual)).reshape(n, 3)
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    assert np.max(np.abs(T.sum(axis=0))) <= 1e-14
    assert np.min(1 + np.sum(T * np.roll(T, 1, axis=0), axis=1)) > 0.05  # regular, not nearly singular
    return np.asarray(curves.from_tangents(T))[:-1]


@pytest.fixture(params=[(9, 0), (9, 1), (16, 2)], ids=lambda p: f"n={p[0]},seed={p[1]}")
def closed_curve(request):
    n, seed = request.param
    return jnp.asarray(closed_arc_length_curve(np.random.default_rng(seed), n))


# --- oracles: the closed forms of the reference (tests only) ---------------------------------


def neighbours(gamma, closed):
    """(T_{k−1}, T_k) at the vertices that move, T_k = Δγ_k (unit edges)."""
    E = curves.edge_vectors(gamma, closed)
    return (jnp.roll(E, 1, axis=0), E) if closed else (E[:-1], E[1:])


def pad_ends(v, closed):
    return v if closed else jnp.concatenate([jnp.zeros((1, 3)), v, jnp.zeros((1, 3))])


def tangent_flow_formula(gamma, closed=True):
    """Prop 2.1: v_k = (T_k + T_{k−1}) / (1 + <T_k, T_{k−1}>)."""
    T_prev, T = neighbours(gamma, closed)
    return pad_ends((T + T_prev) / (1 + jnp.sum(T * T_prev, axis=1, keepdims=True)), closed)


def heisenberg_flow_formula(gamma, closed=True, power=1):
    """(2.9): w_k = T_k × T_{k−1} / (1 + <T_k, T_{k−1}>)^power (power 1 is Prop 2.2)."""
    T_prev, T = neighbours(gamma, closed)
    return pad_ends(jnp.cross(T, T_prev) / (1 + jnp.sum(T * T_prev, axis=1, keepdims=True)) ** power, closed)


# --- the derived flows are the reference's flows ----------------------------------------------


@pytest.mark.parametrize("closed", [True, False])
def test_prop_2_1_2_2_derived_flows_equal_the_closed_forms(closed_curve, closed):
    gamma = closed_curve if closed else closed_curve[:-1]
    v = np.asarray(curves.tangent_flow(gamma, closed=closed))
    w = np.asarray(curves.heisenberg_flow(gamma, closed=closed))
    assert np.max(np.abs(v - tangent_flow_formula(gamma, closed))) <= 1e-14
    assert np.max(np.abs(w - heisenberg_flow_formula(gamma, closed))) <= 1e-14
    if not closed:
        assert not np.any(v[[0, -1]]) and not np.any(w[[0, -1]])  # the end vertices stay put


def test_flows_by_gradient_of_the_local_bending_energy(rng):
    """E_k = log 2 − log(1 + <T_k, T_{k−1}>) = log(1 + tan²(φ_k/2)) (Remark 3.6), and its
    gradients ∂E_k/∂T_k = −T_{k−1} / (1 + <T_k, T_{k−1}>) generate both flows."""
    T_prev, T_next = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 3)))
    phi = np.arccos(T_prev @ T_next)
    assert abs(float(curves.local_bending_energy(T_prev, T_next)) - np.log1p(np.tan(phi / 2) ** 2)) <= 1e-14
    grad_next = np.asarray(jax.grad(curves.local_bending_energy, argnums=1)(T_prev, T_next))
    assert np.max(np.abs(grad_next + T_prev / (1 + T_prev @ T_next))) <= 1e-15


# --- (2.5): both flows keep every edge length -------------------------------------------------


def edge_length_rates(flow, gamma, closed=True):
    """d/dt |γ_{k+1} − γ_k|² = 2 <v_{k+1} − v_k, Δγ_k> along ∂_t γ = v, by a JVP."""
    squared = lambda g: curves.edge_lengths(g, closed) ** 2  # noqa: E731
    return np.asarray(jax.jvp(squared, (gamma,), (flow(gamma, closed=closed),))[1])


def test_prop_2_1_tangent_flow_preserves_edge_lengths(closed_curve):
    assert np.max(np.abs(edge_length_rates(curves.tangent_flow, closed_curve))) <= 1e-13
    open_rates = edge_length_rates(curves.tangent_flow, closed_curve, closed=False)
    assert np.max(np.abs(open_rates[1:-1])) <= 1e-13  # interior edges of an open curve as well,
    assert np.min(np.abs(open_rates[[0, -1]])) > 1e-3  # but not the end edges (ends held fixed)


def test_prop_2_2_heisenberg_flow_preserves_edge_lengths(closed_curve):
    for closed in (True, False):
        assert np.max(np.abs(edge_length_rates(curves.heisenberg_flow, closed_curve, closed))) <= 1e-13


def test_prop_2_2_integrated_heisenberg_flow_keeps_edge_lengths():
    """Gauss–Legendre keeps quadratic invariants such as |Δγ_k|² to round-off along the flow."""
    gamma0 = jnp.asarray(closed_arc_length_curve(np.random.default_rng(3), 9))
    _, path = dg.integrate(lambda g: curves.heisenberg_flow(g), gamma0, 0.5, steps=10)
    lengths = jax.vmap(lambda g: curves.edge_lengths(g, closed=True))(path)
    assert float(jnp.max(jnp.abs(lengths - 1))) <= 1e-12
    assert float(jnp.max(jnp.abs(path[-1] - gamma0))) > 0.05  # it did move


# --- Prop 2.2: the Heisenberg flow commutes with the tangent flow -----------------------------


def bracket_max(f, g, gamma):
    return float(jnp.max(jnp.abs(dg.lie_bracket(f, g)(gamma))))


def test_prop_2_2_heisenberg_flow_commutes_with_tangent_flow(closed_curve):
    """[v, w] = Dw·v − Dv·w = 0 on closed arc-length curves (observed ≤ 1e-15).

    Both fields are tangent to the arc-length manifold, so their bracket there is that of the
    flows on it, and the ambient JVPs see no off-manifold terms."""
    assert bracket_max(curves.tangent_flow, curves.heisenberg_flow, closed_curve) <= 1e-12


@pytest.mark.parametrize("power", [0, 2])
def test_prop_2_2_other_binormal_flows_do_not_commute(closed_curve, power):
    """Uniqueness in Prop 2.2: β_k = (1 + <T_k, T_{k−1}>)^(−power) commutes only for power 1;
    power 0 is the naive flow T_k × T_{k−1} (Remark A.1)."""

    binormal = functools.partial(heisenberg_flow_formula, power=power)
    assert bracket_max(curves.tangent_flow, binormal, closed_curve) > 1e-2


# --- (2.14): the induced flow of the tangents ---------------------------------------------------


def test_eq_2_14_heisenberg_flow_of_the_tangents(closed_curve):
    """∂_t T_k = w_{k+1} − w_k = (T_{k+1}/(1 + <T_{k+1}, T_k>) + T_{k−1}/(1 + <T_k, T_{k−1}>)) × T_k."""
    w = curves.heisenberg_flow(closed_curve)
    dT = np.asarray(jax.jvp(lambda g: curves.edge_vectors(g, closed=True), (closed_curve,), (w,))[1])
    T = np.asarray(curves.edge_vectors(closed_curve, closed=True))
    T_next, T_prev = np.roll(T, -1, axis=0), np.roll(T, 1, axis=0)
    dot = lambda a, b: np.sum(a * b, axis=1, keepdims=True)  # noqa: E731
    formula = np.cross(T_next / (1 + dot(T_next, T)) + T_prev / (1 + dot(T, T_prev)), T)
    assert np.max(np.abs(dT - formula)) <= 1e-14


# --- Remark 2.1: zig-zags move rigidly under the tangent flow ---------------------------------


def rigid_motion_residual(gamma, v):
    """min over ω, c of max_k |v_k − (ω × γ_k + c)| (least squares), and ω."""
    cross_matrices = np.cross(gamma[:, None, :], np.eye(3)[None]).transpose(0, 2, 1)  # [γ_k]× e_j = γ_k × e_j
    A = np.concatenate([-cross_matrices, np.broadcast_to(np.eye(3), cross_matrices.shape)], axis=2).reshape(-1, 6)
    solution = np.linalg.lstsq(A, v.ravel(), rcond=None)[0]
    return np.max(np.abs(A @ solution - v.ravel())), solution[:3]


def test_remark_2_1_straight_zigzag_is_translated(rng):
    u, w = (x / np.linalg.norm(x) for x in rng.normal(size=(2, 3)))
    gamma = curves.from_tangents(np.array([u, w] * 5))
    v = np.asarray(curves.tangent_flow(gamma, closed=False))[1:-1]
    assert np.max(np.abs(v - (u + w) / (1 + u @ w))) <= 1e-14


def test_remark_2_1_circular_zigzag_is_rotated():
    """Vertices alternately on circles of radii 1 and 1.6 at angular steps 2π/12, scaled to unit
    edges: v_k = ω × γ_k exactly, ω along the axis; a generic curve is no rigid motion."""
    n, radii = 12, np.array([1.0, 1.6])
    angles = 2 * np.pi * np.arange(n) / n
    gamma = radii[np.arange(n) % 2, None] * np.stack([np.cos(angles), np.sin(angles), np.zeros(n)], axis=1)
    gamma /= np.linalg.norm(gamma[1] - gamma[0])
    residual, omega = rigid_motion_residual(gamma, np.asarray(curves.tangent_flow(gamma)))
    assert residual <= 1e-12
    assert abs(omega[2]) > 0.1 and np.max(np.abs(omega[:2])) <= 1e-12
    generic = closed_arc_length_curve(np.random.default_rng(5), 12)
    assert rigid_motion_residual(generic, np.asarray(curves.tangent_flow(generic)))[0] > 1e-2


# --- jit, bad input --------------------------------------------------------------------------


def test_flows_under_jit(closed_curve):
    for flow in (curves.tangent_flow, curves.heisenberg_flow):
        jitted = jax.jit(flow, static_argnames="closed")(closed_curve)
        assert float(jnp.max(jnp.abs(jitted - flow(closed_curve)))) <= 1e-15


def test_flows_name_bad_edges_and_vertices():
    gamma = closed_arc_length_curve(np.random.default_rng(7), 10)
    stretched = gamma.copy()
    stretched[4] += 1e-3 * (gamma[4] - gamma[3])  # edge 3 longer, edge 4 shorter
    for flow in (curves.tangent_flow, curves.heisenberg_flow):
        with pytest.raises(ArcLengthError, match="edge 3 has length"):
            flow(stretched)
    nan = gamma.copy()
    nan[6, 2] = np.nan
    with pytest.raises(NonFiniteError, match="vertex 6"):
        curves.tangent_flow(nan)
    hairpin = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    for flow in (curves.tangent_flow, curves.heisenberg_flow):
        with pytest.raises(SingularVertexError, match="vertex 2: the tangents T_1 and T_2 are anti-parallel"):
            flow(hairpin, closed=False)
    with pytest.raises(ShapeError, match="R³"):
        curves.heisenberg_flow(gamma[:, :2])
    copy = gamma.copy()
    curves.tangent_flow(gamma)
    curves.heisenberg_flow(gamma)
    assert np.array_equal(gamma, copy)
