"""Scale-free geometry, as hypothesis properties: every quantity of Sec 1.3, 5.2, 5.3, 6.2 and 7
is invariant or covariant under x ↦ s x, and invariant under Euclidean motions, for coordinates
and lengths from 1e-150 to 1e150 (far beyond where |x|² or Heron's fourth powers leave float64).

    angles, angle defects (Def 5.2), dihedral angles, cotan weights and Laplacians (Def 6.2,
    Thm 6.6), the Laplace–Beltrami operator (Def 7.8), Delaunay flips (Fig 7.13), the harmonic
    index (Def 7.7), turning angles (Sec 1.3)            ~ s⁰
    lengths, edge mean curvature H(e) = ½ θ l (Def 5.3)  ~ s
    areas, vertex masses                                 ~ s²
    curvature of a curve (Def 1.4)                       ~ 1/s

Tolerances: the scaled coordinates are the unit ones times s rounded once (relative 1.1e-16),
and the library divides by a power of two (exact), so each quantity agrees with its unit-scale
value up to the conditioning of its formula on these small, well-shaped meshes: 1e-12 relative
to the largest entry leaves a margin of about 100 over what is observed.  Gauss–Bonnet sums
~10² angles, each correct to a few ulps: 1e-10.
"""

from __future__ import annotations

import math
from functools import cache

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import ddgjax as dg
from ddgjax import curves, intrinsic, laplace, mesh
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh import lengths
from ddgjax.mesh.builtin import triangulate

TOL = 1e-12
SETTINGS = settings(max_examples=20, deadline=None)

# s = m · 2^k with m in [1, 2): from 6e-151 to 1.6e150
scales = st.builds(math.ldexp, st.floats(1.0, 2.0, exclude_max=True), st.integers(-499, 498))
seeds = st.integers(0, 2**32 - 1)


def assert_scales(value, reference, s: float, power: int, tol: float = TOL, what: str = "") -> None:
    """value = reference · s^power up to `tol` relative to the largest entry."""
    expected = np.asarray(reference, dtype=np.float64) * s**power
    value = np.asarray(value, dtype=np.float64)
    assert value.shape == expected.shape, what
    assert np.all(np.isfinite(value)), f"{what}: non-finite entries"
    deviation, size = np.max(np.abs(value - expected), initial=0.0), np.max(np.abs(expected), initial=0.0)
    assert deviation <= tol * size, f"{what}: max deviation {deviation:.3g} from s^{power} × reference, of size {size:.3g}"


@cache
def surface():
    """A perturbed, stretched icosphere (80 faces): not Delaunay, no symmetry."""
    V, F = mesh.icosphere(1)
    V = V * np.array([2.5, 1.0, 0.6]) + 0.03 * np.random.default_rng(7).standard_normal(V.shape)
    return V, F


@cache
def curve(d: int = 2):
    """A closed curve of 11 vertices: an ellipse (d = 2) or a knotted-looking space curve (d = 3)."""
    t = 2 * np.pi * np.arange(11) / 11
    if d == 2:
        return np.stack([np.cos(t), 0.4 * np.sin(t)], axis=1)
    return np.stack([np.cos(t) + 0.3 * np.cos(3 * t), np.sin(t), 0.5 * np.sin(2 * t)], axis=1)


def dense(L):
    return L.toarray()


# quantity name -> (function of V (and F), power of s)
SURFACE_QUANTITIES = {
    "angle_defect": (lambda V, F: mesh.angle_defect(V, F), 0),
    "corner_angles": (lambda V, F: mesh.corner_angles(V, F), 0),
    "dihedral_angles": (lambda V, F: mesh.dihedral_angles(V, F), 0),
    "edge_mean_curvature": (lambda V, F: mesh.edge_mean_curvature(V, F), 1),
    "total_mean_curvature": (lambda V, F: mesh.total_mean_curvature(V, F), 1),
    "edge_lengths": (lambda V, F: mesh.edge_lengths(V, F), 1),
    "surface_area": (lambda V, F: mesh.surface_area(V, F), 2),
    "cotan_laplacian": (lambda V, F: dense(laplace.cotan_laplacian(V, F)), 0),
    "barycentric_areas": (lambda V, F: laplace.barycentric_areas(V, F), 2),
    "laplace_beltrami": (lambda V, F: dense(intrinsic.laplace_beltrami(V, F)), 0),
    "intrinsic_angle_defects": (lambda V, F: intrinsic.angle_defects(T.from_mesh(V, F)), 0),
}

CURVE_QUANTITIES = {
    "turning_angles": (lambda g: curves.turning_angles(g, closed=True), 0),
    "tangents": (lambda g: curves.tangents(g, closed=True), 0),
    "vertex_curvature": (lambda g: curves.curvature(g, "vertex", closed=True), -1),
    "edge_curvature": (lambda g: curves.curvature(g, "edge", closed=True), -1),
    "edge_lengths": (lambda g: curves.edge_lengths(g, closed=True), 1),
}


@cache
def surface_reference():
    V, F = surface()
    return {name: np.asarray(f(V, F)) for name, (f, _) in SURFACE_QUANTITIES.items()}


@cache
def curve_reference():
    return {name: np.asarray(f(curve())) for name, (f, _) in CURVE_QUANTITIES.items()}


@SETTINGS
@given(scales)
@example(math.ldexp(1.0, -499))
@example(math.ldexp(1.999, 498))
def test_surface_quantities_scale_covariantly(s):
    """Def 5.2, 5.3, 6.2, 7.8: each quantity at V s is its value at V times s^p; the inputs are
    not changed."""
    V, F = surface()
    V_s, F_copy = V * s, F.copy()
    V_copy = V_s.copy()
    reference = surface_reference()
    for name, (f, power) in SURFACE_QUANTITIES.items():
        assert_scales(f(V_s, F), reference[name], s, power, what=name)
    assert np.array_equal(V_s, V_copy) and np.array_equal(F, F_copy)


@SETTINGS
@given(scales)
@example(math.ldexp(1.0, -499))
@example(math.ldexp(1.999, 498))
def test_curve_quantities_scale_covariantly(s):
    """Sec 1.3: turning angles and tangents are invariant, curvature (an inverse radius, Def 1.4,
    1.5) scales by 1/s, edge lengths by s."""
    gamma = curve() * s
    copy = gamma.copy()
    reference = curve_reference()
    for name, (f, power) in CURVE_QUANTITIES.items():
        assert_scales(f(gamma), reference[name], s, power, what=name)
    assert np.array_equal(gamma, copy)


@cache
def flip_reference():
    V, F = surface()
    l = np.asarray(mesh.edge_lengths(V, F))
    return l, intrinsic.flip_to_delaunay(F, l)


@SETTINGS
@given(scales)
@example(math.ldexp(1.0, -499))
@example(math.ldexp(1.999, 498))
def test_fig_7_13_flips_do_not_depend_on_the_scale(s):
    """Prop 7.9, Fig 7.13: the angle test is scale-invariant, so the flips at lengths l s are
    those at l: the same count, the same triangulation, lengths l' s, the same harmonic index
    and cotan weights; the result is Delaunay and the input is not changed."""
    _, F = surface()
    l, unit = flip_reference()
    assert unit.n_flips > 0
    l_s = l * s
    copy = l_s.copy()
    result = intrinsic.flip_to_delaunay(F, l_s)
    assert result.n_flips == unit.n_flips
    assert np.array_equal(result.F, unit.F) and np.array_equal(result.triangulation.halfedges, unit.triangulation.halfedges)
    assert_scales(result.lengths, unit.lengths, s, 1)
    assert_scales(result.harmonic_index, unit.harmonic_index, s, 0)
    assert_scales(result.cotan_weights(), unit.cotan_weights(), s, 0)
    assert intrinsic.is_delaunay(result)
    assert intrinsic.is_delaunay(F, l_s) == intrinsic.is_delaunay(F, l) is False
    assert_scales(intrinsic.harmonic_index(F, l_s), intrinsic.harmonic_index(F, l), s, 0)
    assert np.array_equal(l_s, copy)


def random_rotation(rng) -> np.ndarray:
    """A uniformly random rotation (det +1): a reflection reverses the orientation and with it
    the sign of dihedral angles."""
    Q, R = np.linalg.qr(rng.standard_normal((3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else Q * np.array([-1.0, 1.0, 1.0])


@SETTINGS
@given(seeds, scales)
def test_euclidean_motions_change_nothing(seed, s):
    """Every quantity of a surface and of a space curve is invariant under x ↦ R x + t (R a
    rotation), also at scale s (t of size s)."""
    rng = np.random.default_rng(seed)
    R, t = random_rotation(rng), rng.uniform(-2, 2, 3)
    V, F = surface()
    moved = (V @ R.T + t) * s
    reference = surface_reference()
    for name, (f, power) in SURFACE_QUANTITIES.items():
        assert_scales(f(moved, F), reference[name], s, power, tol=1e-11, what=name)
    gamma = (curve(3) @ R.T + t) * s
    for name in ("turning_angles", "vertex_curvature", "edge_lengths"):
        f, power = CURVE_QUANTITIES[name]
        assert_scales(f(gamma), f(curve(3)), s, power, tol=1e-11, what=name)


# χ = 2, 0, −2 (orientable, closed), 1 (non-orientable, closed), 0 (non-orientable, a boundary)
MESHES = {"icosphere": lambda: mesh.icosphere(1), "torus": lambda: mesh.torus(8, 4), "double_torus": mesh.double_torus,
          "projective_plane": mesh.projective_plane, "mobius_strip": lambda: mesh.mobius_strip(8, 2)}


@cache
def small_mesh(name: str):
    """`(V, F, shortest edge length, χ)` of a small builtin mesh, triangulated."""
    V, F = MESHES[name]()
    F = triangulate(F) if F.shape[1] > 3 else F
    E = mesh.edges(F)
    shortest = float(np.min(np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)))
    return V, F, shortest, mesh.euler_characteristic(F)


@SETTINGS
@given(st.sampled_from(sorted(MESHES)), seeds, st.floats(0.0, 0.2), scales)
def test_thm_5_6_gauss_bonnet_on_perturbed_meshes(name, seed, amplitude, s):
    """Σ_p K(p) = 2πχ (Thm 5.6, with the boundary turning angles of Remark 5.4) on randomly
    perturbed meshes, orientable or not, at scale s."""
    V, F, shortest, chi = small_mesh(name)
    rng = np.random.default_rng(seed)
    V = (V + amplitude * shortest * rng.uniform(-1, 1, V.shape)) * s
    K = np.asarray(mesh.angle_defect(V, F))
    assert abs(K.sum() - 2 * np.pi * chi) <= 1e-10


@SETTINGS
@given(seeds, st.lists(st.floats(0.2, 5.0), min_size=3, max_size=3), scales)
def test_cor_7_19_flips_lower_the_harmonic_index_and_are_idempotent(seed, stretch, s):
    """Each flip of Fig 7.13 lowers the harmonic index (Cor 7.16, 7.19), and the result is
    Delaunay: flipping it again does nothing (Thm 7.12).  Flips keep the metric (Lemma 5.8), so
    the intrinsic angle defects stay those of the mesh, and sum to 4π (Thm 5.6)."""
    V, F = mesh.icosphere(1)
    V = (V * np.array(stretch) + 0.05 * np.random.default_rng(seed).standard_normal(V.shape)) * s
    l = np.asarray(mesh.edge_lengths(V, F))
    result = intrinsic.flip_to_delaunay(F, l)
    K = np.asarray(mesh.angle_defect(V, F))
    assert np.max(np.abs(intrinsic.angle_defects(result.triangulation) - K)) <= 1e-11
    assert abs(K.sum() - 4 * np.pi) <= 1e-10
    h = result.harmonic_index
    assert h.shape == (result.n_flips + 1,)
    assert np.all(np.diff(h) < 0) and np.all(result.harmonic_index_steps < 0)
    assert_scales(h[-1], intrinsic.harmonic_index(result), 1.0, 0, tol=1e-12)
    assert intrinsic.is_delaunay(result)
    again = intrinsic.flip_to_delaunay(result)
    assert again.n_flips == 0
    assert np.array_equal(again.lengths, result.lengths) and np.array_equal(again.F, result.F)


def test_derivatives_scale_covariantly():
    """jax.grad works at every scale: ∂/∂V of a quantity of degree p scales by s^(p−1)."""
    V, F = surface()
    V = jnp.asarray(V)
    cases = {
        "angle_defect": (lambda X: jnp.sum(mesh.angle_defect(X, F) ** 2), 0),
        "total_mean_curvature": (lambda X: mesh.total_mean_curvature(X, F), 1),
        "turning_angles": (lambda X: jnp.sum(curves.turning_angles(X[:11, :2], closed=True) ** 2), 0),
    }
    for name, (f, power) in cases.items():
        grad = jax.jit(jax.grad(f))
        unit = grad(V)
        for s in (math.ldexp(1.3, -497), math.ldexp(1.7, 497)):
            assert_scales(grad(V * s), unit, s, power - 1, what=name)


def test_negative_control_naive_formulas_leave_float64():
    """The properties above catch the failure they are written for: squared lengths and Heron's
    product of a mesh at 1e160 overflow (the old formulas), and the covariance check rejects
    lengths computed from them, while the library's pass it."""
    V, F = surface()
    s = 1e160
    E = mesh.edges(F)

    def naive_lengths(X):
        d = X[E[:, 1]] - X[E[:, 0]]
        with np.errstate(over="ignore"):
            return np.sqrt(np.sum(d * d, axis=1))

    assert np.all(np.isinf(naive_lengths(V * s)))
    with pytest.raises(AssertionError, match="non-finite"):
        assert_scales(naive_lengths(V * s), naive_lengths(V), s, 1)
    assert_scales(mesh.edge_lengths(V * s, F), naive_lengths(V), s, 1)
    a = b = c = np.float64(1e80)
    with np.errstate(over="ignore"):
        assert np.isinf(0.25 * np.sqrt((a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c))))
    assert_scales(lengths.triangle_area(a, b, c), math.sqrt(3) / 4, 1e80, 2)
    # and a covariant result that is not a float64 is an error, never inf or 0
    with pytest.raises(dg.errors.InvalidInputError, match="outside the normal range of float64"):
        laplace.face_areas(V * 1e160, F)
    with pytest.raises(dg.errors.InvalidInputError, match="the surface area"):
        mesh.surface_area(V * 1e-160, F)
