"""The exact planar elastica (ddgjax.elastica_exact) against Thm 3.1, Thm 3.2 and Remark 3.2.

Derivatives are 8th-order central differences, so the tolerances are set by round-off (of
scipy's Jacobi functions, ~1e-15): `~1e-15·|f|/h` for first derivatives (h = 1e-3, observed
≤ 2e-11) and `~1e-15·|f|/h²` for second ones (h = 1e-2, observed ≤ 3e-10).
"""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipe, ellipj, ellipk

from ddgjax.smooth.elastica import elliptic_e, figure_eight, figure_eight_modulus, inflectional, non_inflectional
from ddgjax.errors import InvalidInputError

CURVES = {
    "inflectional-small-k": inflectional(0.3, lam=1.3, u0=0.4, length=5.0, load_angle=0.7),
    "inflectional-large-k": inflectional(0.95, lam=0.8, u0=-1.1, length=12.0, load_angle=-2.0),
    "non-inflectional": non_inflectional(0.5, lam=1.2, u0=0.3, length=7.0, load_angle=1.0),
    "non-inflectional-near-separatrix": non_inflectional(0.97, lam=0.9, u0=-0.6, length=9.0),
    "figure-eight": figure_eight(lam=2.0, load_angle=0.3),
}


@pytest.fixture(params=list(CURVES), ids=list(CURVES))
def curve(request):
    return CURVES[request.param]


def _samples(curve, n=23):
    return np.linspace(0.0, curve.length, n)


# 8th-order central stencils on the nodes s - 4h, ..., s + 4h
_D1 = (1 / 280, -4 / 105, 1 / 5, -4 / 5, 0.0, 4 / 5, -1 / 5, 4 / 105, -1 / 280)
_D2 = (-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560)


def _central(f, s, weights, order, h):
    return sum(w * f(s + (i - 4) * h) for i, w in enumerate(weights)) / h**order


def _d1(f, s):
    return _central(f, s, _D1, 1, 1e-3)


def _d2(f, s):
    return _central(f, s, _D2, 2, 1e-2)


def test_tangent_is_unit_and_derivative_of_gamma(curve):
    s = _samples(curve)
    t = curve.tangent(s)
    assert np.max(np.abs(np.linalg.norm(t, axis=-1) - 1.0)) < 1e-14
    assert np.max(np.abs(_d1(curve.gamma, s) - t)) < 1e-10


def test_gamma_is_integral_of_tangent(curve):
    s = _samples(curve, 7)
    integral = np.array([[quad(lambda x: curve.tangent(x)[i], 0.0, si, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
                          for i in range(3)] for si in s])
    assert np.max(np.abs(curve.gamma(s) - curve.gamma(0.0) - integral)) < 1e-10


def test_thm_3_2_tangent_euler_lagrange(curve):
    s = _samples(curve)
    t, t2 = curve.tangent(s), _d2(curve.tangent, s)
    assert np.max(np.abs(np.cross(t2, t) - np.cross(curve.a, t))) < 1e-8
    assert np.max(np.abs(t2 - curve.c(s)[:, None] * t - curve.a)) < 1e-8


def test_thm_3_2_curve_euler_lagrange(curve):
    s = _samples(curve)
    lhs = np.cross(_d2(curve.gamma, s), curve.tangent(s))
    rhs = np.cross(curve.a, curve.gamma(s)) + curve.b
    assert np.max(np.abs(lhs - rhs)) < 1e-8


def test_thm_3_1_pendulum_equation(curve):
    """θ'' = ⟨a, N⟩ = −|a| sin(θ − θ_a): the tangent is a pendulum pulled towards a."""
    s = _samples(curve)
    theta2 = _d2(curve.tangent_angle, s)
    assert np.max(np.abs(theta2 - curve.normal(s) @ curve.a)) < 1e-8
    assert np.max(np.abs(theta2 + curve.lam**2 * np.sin(curve.tangent_angle(s) - curve.load_angle))) < 1e-8


def test_curvature_is_turning_rate(curve):
    s = _samples(curve)
    theta = curve.tangent_angle(s)
    t = curve.tangent(s)
    assert np.max(np.abs(t[:, :2] - np.stack([np.cos(theta), np.sin(theta)], axis=-1))) < 1e-14
    assert np.max(np.abs(_d1(curve.tangent_angle, s) - curve.curvature(s))) < 1e-10
    assert np.max(np.abs(_d1(curve.tangent, s) - curve.curvature(s)[:, None] * curve.normal(s))) < 1e-10


def test_closed_form_curvature_and_angle():
    s = np.linspace(0.0, 5.0, 17)
    e = CURVES["inflectional-small-k"]
    sn, cn, _, _ = ellipj(e.lam * s + e.u0, e.k**2)
    assert np.max(np.abs(np.sin((e.tangent_angle(s) - e.load_angle) / 2) - e.k * sn)) < 1e-15
    assert np.max(np.abs(e.curvature(s) - 2 * e.k * e.lam * cn)) < 1e-15
    r = CURVES["non-inflectional"]
    _, _, dn, am = ellipj(r.lam * s / r.k + r.u0, r.k**2)
    assert np.max(np.abs(r.tangent_angle(s) - r.load_angle - 2 * am)) < 1e-15
    assert np.max(np.abs(r.curvature(s) - 2 * r.lam / r.k * dn)) < 1e-14


def test_bending_energy_matches_quadrature(curve):
    energy, _ = quad(lambda x: curve.curvature(x) ** 2, 0.0, curve.length, epsabs=0.0, epsrel=1e-13, limit=200)
    assert abs(curve.bending_energy() - energy) < 1e-13 * energy


def test_boundary_data_matches_curve(curve):
    bd = curve.boundary_data()
    assert np.max(np.abs(bd.start)) == 0.0
    assert np.max(np.abs(bd.chord - (curve.gamma(curve.length) - curve.gamma(0.0)))) == 0.0
    assert np.max(np.abs(bd.end_tangent - curve.tangent(curve.length))) == 0.0
    assert bd.length == curve.length


def test_remark_3_2_figure_eight_closes():
    k = figure_eight_modulus()
    assert abs(2 * ellipe(k**2) - ellipk(k**2)) < 1e-14
    assert abs(k - 0.908909) < 1e-6
    eight = CURVES["figure-eight"]
    bd = eight.boundary_data()
    assert np.linalg.norm(bd.chord) <= 1e-12
    assert np.linalg.norm(bd.end_tangent - bd.start_tangent) <= 1e-12


def test_remark_3_2_figure_eight_half_period_symmetry():
    """Half a period later the eight is mirrored in the load axis; the double point is u = K, 3K."""
    eight = CURVES["figure-eight"]
    half = eight.length / 2
    e_a = eight.a / np.linalg.norm(eight.a)
    e_perp = np.cross([0.0, 0.0, 1.0], e_a)
    mirror = np.outer(e_a, e_a) - np.outer(e_perp, e_perp) + np.diag([0.0, 0.0, 1.0])
    assert np.max(np.abs(eight.gamma(half) - 4 * eight.k / eight.lam * e_perp)) < 1e-12
    s = np.linspace(0.0, half, 11)
    assert np.max(np.abs(eight.gamma(s + half) - eight.gamma(half) - eight.gamma(s) @ mirror.T)) < 1e-12
    assert np.max(np.abs(eight.curvature(s + half) + eight.curvature(s))) < 1e-12
    quarter = eight.length / 4
    assert np.linalg.norm(eight.gamma(quarter) - eight.gamma(3 * quarter)) < 1e-12
    assert abs(eight.curvature(quarter)) < 1e-12


def _quadrature_e(phi, m):
    """∫₀^φ √(1 − m sin² t) dt by quad, split at the multiples of π/2 (kinks of |cos t| at m = 1)."""
    edges = np.concatenate([[0.0], np.sign(phi) * np.pi / 2 * np.arange(1, int(abs(phi) // (np.pi / 2)) + 1), [phi]])
    return sum(quad(lambda t: np.sqrt(1 - m * np.sin(t) ** 2), lo, hi, epsabs=3e-14, epsrel=3e-14)[0]
               for lo, hi in zip(edges[:-1], edges[1:]))


@pytest.mark.parametrize("m", [0.0, 0.3, figure_eight_modulus() ** 2, 0.99, 1.0, -0.5])
def test_elliptic_e_matches_quadrature(m):
    phis = np.array([-11.0, -3 * np.pi / 2, -2.0, -np.pi / 2, -0.3, 0.0, 1e-3, 1.2, np.pi / 2, 1.7,
                     np.pi, 4.0, 5 * np.pi / 2, 9.3, 17.0])
    expected = [_quadrature_e(phi, m) for phi in phis]
    assert np.max(np.abs(elliptic_e(phis, m) - expected)) < 1e-13
    assert abs(elliptic_e(np.pi / 2, m) - ellipe(m)) < 1e-15


@pytest.mark.parametrize("build", [inflectional, non_inflectional])
@pytest.mark.parametrize("k", [0.0, 1.0, 1.5, -0.2, float("nan")])
def test_invalid_modulus_raises(build, k):
    with pytest.raises(InvalidInputError, match="modulus k must lie in"):
        build(k)


@pytest.mark.parametrize("kwargs, match", [({"lam": 0.0}, "lam"), ({"length": -1.0}, "length"),
                                           ({"u0": float("inf")}, "u0")])
def test_invalid_parameters_raise(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        inflectional(0.5, **kwargs)


def test_elliptic_e_rejects_m_above_one():
    with pytest.raises(InvalidInputError, match="m = k"):
        elliptic_e(1.0, 1.2)


# --- non-planar elastica (ddgjax.smooth.space_elastica) ------------------------------------------


def test_space_elastica_reduces_to_the_exact_planar_one():
    """Started from the planar curve's T(0), T'(0) and load, the integrated pendulum is the
    elliptic elastica (an independent oracle for the integrator) to 1e-10."""
    from ddgjax.smooth.space_elastica import space_elastica

    planar = inflectional(0.7, lam=1.3, u0=0.4, length=3.0, load_angle=0.7)
    dT0 = planar.curvature(0.0) * planar.normal(0.0)  # T' = κN
    curve = space_elastica(planar.tangent(0.0), dT0, planar.a, length=planar.length)
    s = np.linspace(0.0, planar.length, 101)
    assert np.max(np.abs(curve.gamma(s) - (planar.gamma(s) - planar.gamma(0.0)))) <= 1e-10
    assert curve.spans_space() <= 1e-10  # planar: the negative case of Remark 3.2's span


def test_space_elastica_is_non_planar_and_unit_speed():
    from ddgjax.smooth.space_elastica import space_elastica

    curve = space_elastica([1.0, 0, 0], [0.0, 2.0, 1.5], [3.0, -4.0, 2.0])
    s = np.linspace(0.0, 1.0, 65)
    T = curve.state(s)[:, 3:6]
    assert np.max(np.abs(np.linalg.norm(T, axis=1) - 1)) <= 1e-11
    assert curve.spans_space() >= 0.1


@pytest.mark.parametrize("args, length, match", [
    (([1.0, 0, 0.1], [0, 1.0, 0], [0, 0, 1.0]), 1.0, "unit vector"),
    (([1.0, 0, 0], [0.5, 1.0, 0], [0, 0, 1.0]), 1.0, "orthogonal"),
    (([1.0, 0, 0], [0, 1.0, 0], [0, 0, np.nan]), 1.0, "finite"),
    (([1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]), 0.0, "positive length"),
])
def test_space_elastica_rejects_invalid_data(args, length, match):
    from ddgjax.smooth.space_elastica import space_elastica

    with pytest.raises(InvalidInputError, match=match):
        space_elastica(*args, length=length)


def test_space_elastica_is_not_evaluated_outside_its_arc():
    """The dense output would extrapolate silently: an arc length outside [0, L] (or NaN) raises."""
    from ddgjax.smooth.space_elastica import space_elastica

    curve = space_elastica([1.0, 0, 0], [0.0, 2.0, 1.5], [3.0, -4.0, 2.0])
    for s in (1.5, -0.1, np.nan):
        with pytest.raises(InvalidInputError, match="outside"):
            curve.gamma(np.array([0.5, s]))
    assert curve.gamma(1.0).shape == (3,) and curve.tangent(np.array([0.0, 1.0])).shape == (2, 3)
