"""Discrete curves (Sections 1.1–1.3): curvatures against geometric oracles, the smooth limit on
a space curve, reconstruction, sampling, bad input, plots.  The statements with exact values on
circles and the plane smooth limits are `ddgjax verify` checks (`sec1_curves`, run by
`test_verify_checks.py`)."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ddgjax as dg
from ddgjax import curves
from ddgjax.errors import ArcLengthError, InvalidInputError, NonFiniteError, ShapeError, SingularVertexError

RESOLUTIONS = (16, 32, 64, 128, 256, 512)


def circle(R):
    """The counterclockwise circle of radius R, parametrised by arc length."""
    return lambda s: R * jnp.array([jnp.cos(s / R), jnp.sin(s / R)])


def catenary(s):
    """(asinh s, √(1 + s²)): arc-length parametrised, signed curvature κ(s) = 1 / (1 + s²)."""
    return jnp.array([jnp.arcsinh(s), jnp.sqrt(1 + s**2)])


def helix(s, r=1.0, h=0.5):
    """Arc-length helix of radius r and pitch 2πh: curvature r / (r² + h²)."""
    c = np.hypot(r, h)
    return jnp.array([r * jnp.cos(s / c), r * jnp.sin(s / c), h * s / c])


@functools.cache
def derivative(curve):
    """s ↦ γ'(s) at an array of parameters, by forward-mode AD (compiled once per size)."""
    return jax.jit(jax.vmap(jax.jacfwd(curve)))


def random_tangents(rng, n, dim=3, max_turn=1.0):
    """n unit tangents, each turned from the last by an angle uniform in [−max_turn, max_turn]."""
    T = [np.eye(dim)[0]]
    for _ in range(n - 1):
        axis = rng.normal(size=dim)
        axis -= (axis @ T[-1]) * T[-1]
        phi = rng.uniform(-max_turn, max_turn)
        T.append(np.cos(phi) * T[-1] + np.sin(phi) * axis / np.linalg.norm(axis))
    return np.array(T)


def random_arc_length_curve(rng, n, dim=3, max_turn=1.0):
    """Open curve with n unit edges (n + 1 vertices)."""
    return np.asarray(curves.from_tangents(random_tangents(rng, n, dim, max_turn)))


# --- exact values on circles and regular polygons ------------------------------------------


def test_turning_angles_signed_in_the_plane_unsigned_in_space():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert np.allclose(curves.turning_angles(square, closed=True), np.pi / 2, atol=1e-15)
    assert np.allclose(curves.turning_angles(square[::-1], closed=True), -np.pi / 2, atol=1e-15)
    spatial = np.column_stack([square[::-1], np.zeros(4)])
    assert np.allclose(curves.turning_angles(spatial, closed=True), np.pi / 2, atol=1e-15)


# --- geometric oracles: the osculating circles of Defs 1.4–1.6, constructed directly -------


def test_def_1_4_vertex_curvature_is_inverse_circumradius(rng):
    """1/R of the triangle γ_{k−1} γ_k γ_{k+1} is 4·area / (product of the sides)."""
    gamma = rng.normal(size=(9, 3))
    a, b, c = gamma[:-2], gamma[1:-1], gamma[2:]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 2
    sides = np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - b, axis=1) * np.linalg.norm(c - a, axis=1)
    np.testing.assert_allclose(curves.curvature(gamma, "vertex"), 4 * area / sides, rtol=1e-12)


def test_def_1_5_edge_curvature_is_the_circle_touching_three_oriented_lines(rng):
    """Solve for the centre c and signed radius ρ with <c − γ_i, J T_i> = ρ on the lines of the
    edges i = k − 1, k, k + 1 (J = rotation by +π/2): ρ > 0 is a counterclockwise circle left of
    every edge.  κ_k = 1/ρ, for convex and non-convex (sign-changing) curves alike."""
    lengths = rng.uniform(0.5, 2.0, size=(10, 1))
    gamma = np.asarray(curves.from_tangents(lengths * random_tangents(rng, 10, dim=2, max_turn=2.0)))
    T = np.asarray(curves.tangents(gamma))
    normals = T @ np.array([[0.0, 1.0], [-1.0, 0.0]])  # J T
    oracle = []
    for k in range(1, len(T) - 1):
        rows = [k - 1, k, k + 1]
        A = np.column_stack([normals[rows], -np.ones(3)])
        rhs = np.sum(normals[rows] * gamma[rows], axis=1)
        oracle.append(1 / np.linalg.solve(A, rhs)[2])
    kappa = np.asarray(curves.curvature(gamma, "edge"))
    assert np.min(kappa) < 0 < np.max(kappa)  # the test curve is not convex
    np.testing.assert_allclose(kappa, oracle, rtol=1e-10)


def test_def_1_6_arclength_curvature_is_the_circle_touching_edges_at_midpoints(rng):
    """Centre c: in the plane of T_{k−1}, T_k and on the normal planes of both edge midpoints;
    it is equidistant from the two midpoints and κ_k = 1 / |c − midpoint| = 2 tan(φ_k/2)/ε."""
    eps = 0.3
    gamma = eps * random_arc_length_curve(rng, 9)
    T = np.asarray(curves.tangents(gamma))
    mid = (gamma[1:] + gamma[:-1]) / 2
    oracle = []
    for k in range(1, len(T)):
        A = np.stack([T[k - 1], T[k], np.cross(T[k - 1], T[k])])
        centre = np.linalg.solve(A, [T[k - 1] @ mid[k - 1], T[k] @ mid[k], A[2] @ gamma[k]])
        radii = np.linalg.norm(centre - mid[k - 1 : k + 1], axis=1)
        assert abs(radii[0] - radii[1]) <= 1e-12 * radii[0]
        oracle.append(1 / radii[0])
    np.testing.assert_allclose(curves.curvature(gamma, "arclength"), oracle, rtol=1e-10)
    phi = np.asarray(curves.turning_angles(gamma))
    np.testing.assert_allclose(curves.curvature(gamma / eps, "arclength"), 2 * np.tan(phi / 2), rtol=1e-13)  # (1.1)


def test_remark_1_4_vertex_curvature_of_unit_edges_is_2_sin_half_angle_at_most_2(rng):
    gamma = random_arc_length_curve(rng, 30, max_turn=2.8)
    kappa = np.asarray(curves.curvature(gamma, "vertex"))
    phi = np.asarray(curves.turning_angles(gamma))
    np.testing.assert_allclose(kappa, 2 * np.sin(phi / 2), rtol=1e-12)
    assert np.max(kappa) <= 2.0 and np.max(phi) > 2.0  # sharp turns, still bounded


# --- smooth limits (Section 1.2) -----------------------------------------------------------


@functools.lru_cache(maxsize=None)
def sampled(curve, length, start, n):
    """Discrete arc-length curve inscribed in `curve` with n equal edges, and its parameters."""
    gamma, s = curves.sample(curve, n, length=length, start=start, equal_chords=True, return_parameters=True)
    return np.asarray(gamma), np.asarray(s)


CATENARY = (catenary, 4.0, -2.0)  # s ∈ [−2, 2]: κ from 1/5 to 1
HELIX = (helix, 8.0, 0.0)


def curvature_error(kind, curve, length, start, exact_kappa, n):
    """max over the curve's vertices (edges for "edge") of |κ_discrete − κ(s)|."""
    gamma, s = sampled(curve, length, start, n)
    at = ((s[1:] + s[:-1]) / 2)[1:-1] if kind == "edge" else s[1:-1]
    return np.max(np.abs(np.asarray(curves.curvature(gamma, kind)) - exact_kappa(at)))


def assert_order(table, order, tol=0.1):
    print("\n" + table.to_markdown())
    assert abs(table.fitted_order - order) <= tol, table.to_markdown()
    assert abs(table.orders[-1] - order) <= tol / 2, table.to_markdown()


@pytest.mark.parametrize("kind", ["vertex", "arclength"])
def test_section_1_3_space_curvatures_converge_on_a_helix(kind):
    table = dg.limits.convergence(
        functools.partial(curvature_error, kind, *HELIX, lambda s: np.full_like(s, 1 / 1.25)),
        RESOLUTIONS, label=f"max |κ_{kind} − κ| (helix)",
    )
    assert_order(table, 2.0)


# --- reconstruction and sampling -------------------------------------------------------------


def test_from_tangents_round_trips_tangents(rng):
    T = rng.normal(size=(15, 3))
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    gamma = curves.from_tangents(T, start=(1.0, 2.0, 3.0), edge_length=0.1)
    assert gamma.shape == (16, 3) and np.allclose(gamma[0], [1, 2, 3])
    assert np.max(np.abs(np.asarray(curves.tangents(gamma)) - T)) <= 1e-14
    np.testing.assert_allclose(curves.edge_lengths(gamma), 0.1, rtol=1e-13)
    planar = curves.from_tangents(T[:, :2])  # default start: the origin of the plane
    assert planar.shape == (16, 2) and np.all(planar[0] == 0)
    square = np.array([[1.0, 0], [0, 1], [-1, 0], [0, -1]])
    assert np.max(np.abs(np.asarray(curves.from_tangents(square))[-1])) == 0  # closes up


def test_sample_at_spacing_eps_and_with_equal_chords():
    gamma = curves.sample(catenary, 8, eps=0.25, start=-1.0)
    s = -1.0 + 0.25 * np.arange(9)
    np.testing.assert_allclose(gamma, jax.vmap(catenary)(jnp.asarray(s)), rtol=1e-15)
    assert curves.sample(catenary, eps=0.25, length=2.0, start=-1.0).shape == (9, 2)
    closed = curves.sample(helix, 40, length=8.0, closed=True, equal_chords=False)
    assert closed.shape == (40, 3)
    equal = np.asarray(curves.sample(catenary, 20, length=4.0, start=-2.0, equal_chords=True))
    lengths = np.asarray(curves.edge_lengths(equal))
    assert np.ptp(lengths) <= 1e-13 * lengths[0] and curves.is_arc_length(equal)
    assert not curves.is_arc_length(curves.sample(catenary, 20, length=4.0, start=-2.0))
    np.testing.assert_allclose(equal[[0, -1]], jax.vmap(catenary)(jnp.array([-2.0, 2.0])), rtol=1e-15)
    with pytest.raises(InvalidInputError, match="exactly two of n, eps, length"):
        curves.sample(catenary, 8, eps=0.25, length=2.0)
    with pytest.raises(InvalidInputError, match="integer"):
        curves.sample(catenary, eps=0.3, length=2.0)


# --- works under jit and grad ----------------------------------------------------------------


def test_curvatures_under_jit_and_grad(rng):
    T = random_tangents(rng, 10)
    T[5] = T[4]
    gamma = np.asarray(curves.from_tangents(T))  # straight at vertex 5, where |T_5 × T_4| = 0
    for kind in ("vertex", "arclength"):
        jitted = jax.jit(curves.curvature, static_argnames=("kind", "closed"))(gamma, kind)
        assert np.max(np.abs(np.asarray(jitted) - np.asarray(curves.curvature(gamma, kind)))) <= 1e-15
        grad = jax.grad(lambda g: jnp.sum(curves.curvature(g, kind) ** 2))(jnp.asarray(gamma))
        assert np.all(np.isfinite(np.asarray(grad)))
    assert float(jnp.abs(curves.turning_angles(gamma)[4])) <= 1e-7


# --- bad input -----------------------------------------------------------------------------


def test_nan_vertex_is_named():
    gamma = np.zeros((6, 3))
    gamma[:, 0] = np.arange(6)
    gamma[3, 1] = np.nan
    calls = (curves.tangents, curves.turning_angles, curves.vertex_tangent, lambda g: curves.curvature(g, "vertex"))
    for call in calls:
        with pytest.raises(NonFiniteError, match=r"vertex 3 has the non-finite coordinate nan"):
            call(gamma)
    with pytest.raises(NonFiniteError, match="tangent 2"):
        curves.from_tangents(np.array([[1.0, 0], [0, 1], [np.inf, 0]]))


def test_irregular_and_singular_vertices_are_named():
    zigzag = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0, 0], [3, 0, 0]])
    with pytest.raises(SingularVertexError, match="vertices 2 and 3 coincide"):
        curves.tangents(zigzag)
    hairpin = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]])  # T_2 = −T_1
    assert curves.is_regular(hairpin[:3]) and not curves.is_regular(hairpin)
    with pytest.raises(SingularVertexError, match="at vertex 2 the neighbours 1 and 3 coincide"):
        curves.check_regular(hairpin)
    with pytest.raises(SingularVertexError, match="vertex 2: the tangents T_1 and T_2 are anti-parallel"):
        curves.curvature(hairpin, "arclength")
    with pytest.raises(SingularVertexError, match="vertex 2: .*anti-parallel.*vertex tangent"):
        curves.vertex_tangent(hairpin)
    with pytest.raises(SingularVertexError, match="vertex 2"):
        curves.curvature(hairpin[:, :2], "edge")
    # unequal edges with anti-parallel tangents are regular (Def 1.2) but still singular
    spike = np.array([[0.0, 0], [2, 0], [1, 0], [1, 1]])
    assert curves.is_regular(spike)
    with pytest.raises(SingularVertexError, match="vertex 1"):
        curves.vertex_tangent(spike)


def test_arc_length_violations_name_the_edge():
    gamma = np.column_stack([np.arange(8.0), np.zeros(8)])
    gamma[5:, 0] += 0.01  # edge 4 is 1.01 long
    assert not curves.is_arc_length(gamma)
    with pytest.raises(ArcLengthError, match=r"edge 4 has length 1.01.*median edge length 1"):
        curves.check_arc_length(gamma)
    with pytest.raises(ArcLengthError, match="edge 4"):
        curves.curvature(gamma, "arclength")
    assert curves.is_arc_length(gamma, tol=0.02)
    with pytest.raises(ArcLengthError, match=r"edge 0 has length 1, not length 0.5"):
        curves.check_arc_length(gamma, length=0.5)


def test_shapes_and_kinds_are_checked():
    with pytest.raises(ShapeError, match="planar curves only"):
        curves.curvature(np.eye(3), "edge")
    with pytest.raises(InvalidInputError, match="kind must be one of"):
        curves.curvature(np.eye(3), "gauss")
    with pytest.raises(ShapeError, match=r"got shape \(5,\)"):
        curves.tangents(np.arange(5.0))
    with pytest.raises(ShapeError, match="at least 3 vertices"):
        curves.tangents(np.eye(2), closed=True)


def test_inputs_are_not_mutated(rng):
    gamma = random_arc_length_curve(rng, 8)
    T = rng.normal(size=(5, 3))
    copies = gamma.copy(), T.copy()
    for closed in (False, True):
        curves.tangents(gamma, closed)
        curves.turning_angles(gamma, closed)
        curves.vertex_tangent(gamma, closed)
        curves.curvature(gamma, "vertex", closed)
        curves.curvature(gamma[:, :2], "edge", closed)
        curves.is_regular(gamma, closed)
    curves.curvature(gamma, "arclength")
    curves.from_tangents(T)
    assert np.array_equal(gamma, copies[0]) and np.array_equal(T, copies[1])


# --- plots -----------------------------------------------------------------------------------


def test_plots_draw_the_polylines(tmp_path, rng):
    """The figures show the data: one line per curve with the curve's vertices, a closed curve
    repeats its first vertex, 3-D axes for space curves, one legend entry per label."""
    gamma = random_arc_length_curve(rng, 12)
    fig = dg.plot.curve(gamma)
    (line,) = fig.axes[0].lines
    assert fig.axes[0].name == "3d"
    np.testing.assert_allclose(np.stack(line.get_data_3d(), axis=1), gamma, rtol=0, atol=1e-15)
    fig = dg.plot.curve(gamma[:, :2], closed=True, color="k")
    x, y = fig.axes[0].lines[0].get_data()
    assert len(x) == len(gamma) + 1 and (x[0], y[0]) == (x[-1], y[-1])
    family = [gamma[:, :2] * a for a in (1.0, 1.5, 2.0)]
    fig = dg.plot.curves(family, labels=["a", "b", "c"])
    assert [line.get_xdata().max() for line in fig.axes[0].lines] == pytest.approx([f[:, 0].max() for f in family])
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["a", "b", "c"]
    path = dg.plot.curve(gamma, path=tmp_path / "space.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_curvatures_of_concrete_curves_are_computed_in_numpy_like_traced_ones():
    """Defs 1.4–1.6 on concrete curves run the formulas in NumPy (no program compiled for each
    number of vertices: the compiled calls' caches do not grow over 5 sizes) and agree to
    round-off with the same formulas traced under `jit`."""
    compiled = {kind: entry[2] for kind, entry in curves._CURVATURES.items()}
    cases = []
    for n in (9, 17, 33, 65, 129):
        t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
        planar = np.stack([np.cos(t), 2.0 * np.sin(t)], axis=1)
        unit = np.cumsum(np.stack([np.cos(0.3 * np.sin(t)), np.sin(0.3 * np.sin(t))], axis=1), axis=0)
        cases += [("vertex", planar, True), ("vertex", planar, False), ("edge", planar, True),
                  ("edge", planar, False), ("arclength", unit, False)]
    before = {kind: fn._cache_size() for kind, fn in compiled.items()}
    values = [curves.curvature(gamma, kind, closed) for kind, gamma, closed in cases]
    assert {kind: fn._cache_size() for kind, fn in compiled.items()} == before
    for (kind, gamma, closed), value in zip(cases, values):
        assert np.max(np.abs(np.asarray(value) - np.asarray(compiled[kind](jnp.asarray(gamma), closed)))) < 1e-13
