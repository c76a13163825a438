"""Quaternions and Euclidean motions (Section 3.2): the identities, as hypothesis properties.

Tolerances: every identity is exact in exact arithmetic and each side costs O(10) flops on
entries of size ≤ 10, so 1e-12 (a few hundred ulps at that scale) is machine precision.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ddgjax as dg
from ddgjax import quaternion as qt
from ddgjax.errors import InvalidInputError, NonFiniteError, ShapeError

TOL = 1e-12
SETTINGS = settings(max_examples=50, deadline=None)

coordinate = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)
vectors = st.lists(coordinate, min_size=3, max_size=3).map(np.array)
quaternions = st.lists(coordinate, min_size=4, max_size=4).map(np.array).filter(lambda q: np.linalg.norm(q) > 1e-3)
units = quaternions.map(lambda q: q / np.linalg.norm(q))
axes = vectors.filter(lambda v: np.linalg.norm(v) > 1e-3).map(lambda v: v / np.linalg.norm(v))
angles = st.floats(-np.pi, np.pi, allow_nan=False)


def close(x, y, tol=TOL):
    return float(np.max(np.abs(np.asarray(x) - np.asarray(y)))) <= tol


def rodrigues(v, n, theta):
    """v turned by θ about the unit n (right-hand rule)."""
    return v * np.cos(theta) + np.cross(n, v) * np.sin(theta) + n * (n @ v) * (1 - np.cos(theta))


def test_relations_3_1_on_the_basis():
    """i² = j² = k² = ijk = −1, ij = k, jk = i, ki = j."""
    one, i, j, k = np.eye(4)
    for x in (i, j, k):
        assert close(qt.mul(x, x), -one, 0)
    assert close(qt.mul(qt.mul(i, j), k), -one, 0)
    assert close(qt.mul(i, j), k, 0) and close(qt.mul(j, k), i, 0) and close(qt.mul(k, i), j, 0)
    assert close(qt.mul(j, i), -k, 0)


@SETTINGS
@given(vectors, vectors)
def test_lemma_3_4_product_of_imaginary_quaternions(v, w):
    """vw = −<v, w> + v × w; hence v × w = ½[v, w] and <v, w> = −½(vw + wv)."""
    vw = qt.mul(qt.from_vector(v), qt.from_vector(w))
    assert close(vw, np.concatenate([[-v @ w], np.cross(v, w)]))
    wv = qt.mul(qt.from_vector(w), qt.from_vector(v))
    assert close(0.5 * (vw - wv), np.concatenate([[0.0], np.cross(v, w)]))


@SETTINGS
@given(vectors, vectors, quaternions)
def test_cross_and_rotation_are_the_contractions_of_their_structure_constants(v, w, q):
    """`cross` is Im(vw) (Lemma 3.4) and broadcasts; `rotate` equals the expanded sandwich
    `((q0² − |u|²) v + 2<u, v> u + 2 q0 u × v) / |q|²`, u = Im q (Prop 3.6) that the
    contraction with `SANDWICH` replaces."""
    assert close(qt.cross(v, w), np.cross(v, w))
    assert close(qt.cross(v, np.stack([w, v, -w])), np.cross(v, np.stack([w, v, -w])))
    q0, u = q[0], q[1:]
    expanded = ((q0**2 - u @ u) * v + 2 * (u @ v) * u + 2 * q0 * np.cross(u, v)) / (q @ q)
    assert close(qt.rotate(q, v), expanded)


def test_structure_constants_are_the_tables_of_h_and_r3():
    """`HAMILTON` has 1 as its unit and e_a e_b = −δ_ab + ε_cab e_c; `LEVI_CIVITA` is
    antisymmetric with ε_012 = 1; a componentwise check with the sign of k flipped fails."""
    C, eps = qt.HAMILTON, qt.LEVI_CIVITA
    assert np.array_equal(C[:, 0, :], np.eye(4)) and np.array_equal(C[:, :, 0], np.eye(4))
    assert eps[0, 1, 2] == 1 and np.array_equal(eps, -eps.transpose(0, 2, 1))
    one, i, j, k = np.eye(4)
    assert close(np.einsum("ijk,j,k->i", C, i, j), k, 0)
    assert not close(np.einsum("ijk,j,k->i", C, i, j), -k, 0)  # negative control
    with pytest.raises(ShapeError):
        qt.cross(np.ones(4), np.ones(3))


@SETTINGS
@given(quaternions, quaternions, quaternions)
def test_algebra_norm_multiplicative_associative_inverse(p, q, r):
    """|pq| = |p||q|, (pq)r = p(qr), q q⁻¹ = 1, conj(pq) = q̄ p̄."""
    assert abs(float(qt.norm(qt.mul(p, q))) - np.linalg.norm(p) * np.linalg.norm(q)) <= TOL * 10
    assert close(qt.mul(qt.mul(p, q), r), qt.mul(p, qt.mul(q, r)), 1e-11)
    assert close(qt.mul(q, qt.inv(q)), qt.ONE)
    assert close(qt.conj(qt.mul(p, q)), qt.mul(qt.conj(q), qt.conj(p)))


@SETTINGS
@given(axes, st.floats(0.0, np.pi), vectors)
def test_prop_3_6_rotation_by_twice_alpha(n, alpha, v):
    """q = cos α + sin α n: q v q⁻¹ is v turned by 2α about n; from_axis_angle(n, θ) has α = θ/2."""
    q = np.concatenate([[np.cos(alpha)], np.sin(alpha) * n])
    assert close(qt.rotate(q, v), rodrigues(v, n, 2 * alpha))
    assert close(qt.from_axis_angle(n, 2 * alpha), q)
    # |q| cancels (footnote 17)
    assert close(qt.rotate(3.5 * q, v), rodrigues(v, n, 2 * alpha))


@SETTINGS
@given(units, units, vectors)
def test_remark_3_5_double_cover_and_composition(q1, q2, v):
    """R_{−q} = R_q and R_{q2 q1} = R_{q2} ∘ R_{q1}."""
    assert close(qt.rotate(-q1, v), qt.rotate(q1, v))
    assert close(qt.rotate(qt.mul(q2, q1), v), qt.rotate(q2, qt.rotate(q1, v)))


@SETTINGS
@given(quaternions)
def test_to_matrix_in_so3_and_from_matrix_inverts_up_to_sign(q):
    R = np.asarray(qt.to_matrix(q))
    assert close(R.T @ R, np.eye(3)) and abs(np.linalg.det(R) - 1) <= TOL
    u = q / np.linalg.norm(q)
    back = np.asarray(qt.from_matrix(R))
    assert min(np.max(np.abs(back - u)), np.max(np.abs(back + u))) <= 1e-12
    assert back[0] >= 0


@SETTINGS
@given(axes, angles)
def test_axis_angle_round_trip_and_exp_log(n, theta):
    """exp(θ/2 n) = from_axis_angle(n, θ); log inverts exp; to_axis_angle recovers |θ|, ±n."""
    q = qt.from_axis_angle(n, theta)
    assert close(qt.exp(0.5 * theta * n), q)
    assert close(qt.log(q), 0.5 * theta * n)
    axis, angle = qt.to_axis_angle(q)
    assert abs(float(angle) - abs(theta)) <= 1e-12
    if abs(theta) > 1e-6:
        assert close(np.sign(theta) * np.asarray(axis), n, 1e-10)


def test_from_matrix_branches_and_broadcasting():
    """Shepperd's selection: rotations by π about each axis (q0 = 0) and about a diagonal."""
    n = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -2, 0.5]]) * 1.0
    thetas = np.array([np.pi, np.pi, np.pi, 2.5, np.pi - 1e-9])
    q = qt.from_axis_angle(n, thetas)
    assert q.shape == (5, 4)
    R = qt.to_matrix(q)
    assert R.shape == (5, 3, 3)
    back = qt.from_matrix(R)
    sign = np.sign(np.sum(np.asarray(back) * np.asarray(q), axis=-1))[:, None]
    assert close(back, sign * np.asarray(q))
    assert close(jax.jit(qt.from_matrix)(R), back)


def test_gradients_are_finite_at_the_identity():
    """exp, log, from_matrix are differentiable at the identity (no NaN from |v| = 0)."""
    J = jax.jacfwd(qt.exp)(jnp.zeros(3))
    assert close(J, np.eye(4)[:, 1:])  # d exp(v) at 0 = v
    J = jax.jacfwd(qt.log)(jnp.asarray(qt.ONE))
    assert close(J, np.eye(4)[1:])
    J = jax.jacfwd(qt.from_matrix)(jnp.eye(3))
    assert np.all(np.isfinite(np.asarray(J)))


# ---------------------------------------------------------------------------------------------
# Euclidean motions


motions = st.tuples(units, vectors).map(lambda t: qt.Motion(*t))


@SETTINGS
@given(motions, motions, vectors)
def test_euclidean_motion_composition_and_inverse(m2, m1, v):
    """(m2 ∘ m1)(v) = m2(m1(v)); m⁻¹(m(v)) = v; distances are kept."""
    assert close(qt.apply(qt.compose(m2, m1), v), qt.apply(m2, qt.apply(m1, v)), 1e-11)
    assert close(qt.apply(qt.inverse(m1), qt.apply(m1, v)), v, 1e-11)
    assert abs(float(np.linalg.norm(qt.apply(m1, v) - qt.apply(m1, 2 * v))) - np.linalg.norm(v)) <= 1e-11


@jax.jit
def _flow_derivatives(a, b, m0, t, v):
    """At m(t) = motion_exp(a, b, t) ∘ m0: the generator of (m, m'), the ODE right-hand side,
    and the velocity of the point m(t)(v) next to the infinitesimal motion there."""

    def m(t):
        return qt.compose(qt.motion_exp(a, b, t), m0)

    mt, m_dot = jax.jvp(m, (t,), (jnp.ones_like(t),))
    velocity = jax.jvp(lambda s: qt.apply(m(s), v), (t,), (jnp.ones_like(t),))[1]
    return qt.generator(mt, m_dot), (qt.motion_ode(a, b, mt), m_dot), (velocity, qt.infinitesimal_motion(a, b, qt.apply(mt, v)))


@SETTINGS
@given(vectors, vectors, motions, st.floats(0.0, 2.0), vectors)
def test_cor_3_7_generator_of_the_closed_form_flow(a, b, m0, t, v):
    """m(t) = motion_exp(a, b, t) ∘ m0: its generator (2q'q⁻¹, p' − a × p) is the constant (a, b),
    (q', p') solves q' = ½ a q, p' = b + ½[a, p], and d/dt m(t)(v) = a × m(t)(v) + b."""
    (ga, gb), (ode, m_dot), (velocity, field) = _flow_derivatives(a, b, m0, jnp.asarray(t), v)
    scale = 1 + np.abs(a).max() * (1 + np.abs(b).max() + np.abs(m0.p).max())
    assert close(ga, a, 1e-11 * scale) and close(gb, b, 1e-11 * scale)
    assert close(ode.q, m_dot.q, 1e-11 * scale) and close(ode.p, m_dot.p, 1e-11 * scale)
    assert close(velocity, field, 1e-10 * scale * (1 + np.abs(v).max()))


def test_motion_exp_small_angle_branch_is_continuous():
    """The Taylor branch (|a|t < 0.1) and the closed form agree at the switch, and a = 0 is a
    pure translation by t b."""
    b = np.array([0.3, -1.0, 2.0])
    n = np.array([2.0, 1.0, -2.0]) / 3
    below = qt.motion_exp(n * (0.1 - 1e-12), b, 1.0)
    above = qt.motion_exp(n * (0.1 + 1e-12), b, 1.0)
    assert close(below.p, above.p, 1e-11) and close(below.q, above.q, 1e-11)
    m = qt.motion_exp(np.zeros(3), b, 2.0)
    assert close(m.p, 2 * b, 0) and close(m.q, qt.ONE, 0)


def test_motion_ode_integrated_by_gauss6_matches_closed_form():
    """q' = ½ a q, p' = b + ½[a, p] integrated by ddgjax.integrate (Gauss6, 200 steps to t = 4)
    agrees with motion_exp ∘ m0; the local error is O(h⁷) with h = 0.02, |a| = 1.5: ≤ 1e-11."""
    a, b = np.array([0.5, -1.0, 1.0]), np.array([1.0, 0.2, -0.3])
    m0 = qt.Motion(qt.from_axis_angle(np.array([0.0, 1.0, 1.0]), 0.7), np.array([0.5, 0.0, -1.0]))
    ts, ms = dg.integrate(lambda m: qt.motion_ode(a, b, m), m0, 4.0, steps=200, method="gauss6")
    exact = qt.compose(qt.motion_exp(a, b, ts), m0)
    assert close(ms.q, exact.q, 1e-11) and close(ms.p, exact.p, 1e-11)
    assert close(np.linalg.norm(ms.q, axis=-1), 1.0, 1e-13)  # |q|² is a quadratic invariant


# ---------------------------------------------------------------------------------------------
# bad input


def test_shape_errors_name_the_last_axis():
    with pytest.raises(ShapeError, match=r"\[\.\.\., 4\]"):
        qt.mul(np.ones(3), np.ones(4))
    with pytest.raises(ShapeError, match=r"\[\.\.\., 3\]"):
        qt.rotate(np.ones(4), np.ones(4))
    with pytest.raises(ShapeError, match=r"3, 3"):
        qt.from_matrix(np.eye(4))


def test_from_matrix_rejects_non_rotations():
    R = np.stack([np.eye(3), np.diag([1.0, 1.0, -1.0])])
    with pytest.raises(InvalidInputError, match=r"index \(1,\).*det R"):
        qt.from_matrix(R)
    with pytest.raises(InvalidInputError, match=r"RᵀR − I"):
        qt.from_matrix(2 * np.eye(3))


def test_unit_required_zero_and_nonfinite_rejected():
    with pytest.raises(InvalidInputError, match=r"unit quaternion.*entry \(1,\)"):
        qt.log(np.array([qt.ONE, [1.0, 1.0, 0.0, 0.0]]))
    with pytest.raises(InvalidInputError, match="zero quaternion"):
        qt.inv(np.zeros(4))
    with pytest.raises(InvalidInputError, match="zero vector"):
        qt.from_axis_angle(np.zeros(3), 1.0)
    with pytest.raises(NonFiniteError):
        qt.mul(np.array([1.0, np.nan, 0, 0]), qt.ONE)
