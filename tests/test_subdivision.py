"""Subdivision (`dg.mesh.subdivide`, `dg.mesh.subdivision_matrix`) and solving on refined meshes
(`energies.refine.refine`).

Measured (2026-12): Loop on the tetrahedron brings the largest angle defect π down to 1.73, 0.562,
0.157, 0.0413 (ratios → 4); on the octahedron to 1.25, 0.663, 0.323, 0.150 (ratios 1.7 … 2.2, the
valence-4 vertices); midpoint subdivision keeps it at π (2π/3) exactly.  The soap bubble of volume
4π/3 refined from the icosahedron by Loop's scheme has pressures p = 2.129, 2.0312, 2.00769,
2.00191 (|p − 2| ratios 4.13, 4.06, 4.02: order 2) and areas 4π + 0.812, 0.196, 0.0483, 0.0120;
each level converges in 0, 4, 3, 3 Newton steps (tol 1e-10) from the subdivided solution.  From
the *midpoint* subdivision Newton stalls at level 2 (residual 3e-2 after 100 steps; `solve`'s L-BFGS retry
rescues it at ~4× the time): the new vertices sit on the flat faces of the coarse polyhedron.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import ddgjax as dg
from ddgjax.errors import InvalidInputError, MeshError, NonManifoldError, ShapeError
from ddgjax.mesh import subdivide, subdivision_matrix
from ddgjax.mesh.connectivity import glue_triangles

CLOSED = ["tetrahedron", "octahedron", "icosphere", "torus", "double_torus", "projective_plane", "klein_bottle"]
WITH_BOUNDARY = ["disk", "annulus", "mobius_strip"]
SCHEMES = ["midpoint", "loop"]


def mesh_of(name):
    V, F = getattr(dg.mesh, name)()
    return V, F


def edge_count(F) -> int:
    return dg.mesh.from_faces(F).n_edges


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("name", CLOSED + WITH_BOUNDARY)
def test_counts_euler_characteristic_and_manifold(name, scheme):
    """nv' = nv + ne, nf' = 4 nf, ne' = 2 ne + 3 nf, so χ is preserved; the result is a manifold
    with as many boundary loops, orientable iff the input is."""
    V, F = mesh_of(name)
    V2, F2 = subdivide(V, F, scheme=scheme)
    nv, ne, nf = len(V), edge_count(F), len(F)
    assert (len(V2), len(F2), edge_count(F2)) == (nv + ne, 4 * nf, 2 * ne + 3 * nf)
    assert V2.dtype == np.float64 and F2.dtype == np.int64
    assert dg.mesh.euler_characteristic(F2) == dg.mesh.euler_characteristic(F)
    assert dg.mesh.is_orientable(F2) == dg.mesh.is_orientable(F)
    assert len(dg.mesh.boundary_loops(F2)) == len(dg.mesh.boundary_loops(F))


@pytest.mark.parametrize("name", ["tetrahedron", "icosphere", "torus", "double_torus", "disk", "annulus"])
def test_orientation_preserved(name):
    """Each child runs like its parent: an oriented mesh stays consistently oriented (glue_triangles
    raises OrientationError otherwise) and the outward normals of the midpoint children are those
    of their parents."""
    V, F = mesh_of(name)
    V2, F2 = subdivide(V, F)
    glue_triangles(F2, len(V2))
    normal = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    child = np.cross(V2[F2[:, 1]] - V2[F2[:, 0]], V2[F2[:, 2]] - V2[F2[:, 0]])
    parent = np.tile(normal, (4, 1))
    assert np.allclose(child, parent / 4, rtol=0, atol=1e-14)  # a child has 1/4 of its parent's area vector


def test_vertex_order_old_first_then_edges():
    """Old vertex i is new vertex i; vertex nv + e is the midpoint of edge e of `dg.mesh.edges(F)`,
    exactly (round-off free: (a + b)/2 in binary)."""
    V, F = dg.mesh.torus(8, 5)
    V2, _ = subdivide(V, F)
    E = dg.mesh.edges(F)
    assert np.array_equal(V2[: len(V)], V)
    assert np.array_equal(V2[len(V):], 0.5 * (V[E[:, 0]] + V[E[:, 1]]))


def test_midpoint_keeps_the_polyhedron_and_its_boundary():
    """Midpoint subdivision cuts every face into four coplanar triangles: area and enclosed
    volume are unchanged to round-off, boundary vertices stay, and every new boundary vertex is
    the midpoint of an old boundary edge."""
    V, F = dg.mesh.icosphere(1)
    V2, F2 = subdivide(V, F)
    assert abs(dg.mesh.surface_area(V2, F2) - dg.mesh.surface_area(V, F)) < 1e-13
    volume = lambda V, F: np.linalg.det(V[F]).sum() / 6  # noqa: E731
    assert abs(volume(V2, F2) - volume(V, F)) < 1e-13
    V, F = dg.mesh.annulus(12, 3)
    V2, F2 = subdivide(V, F)
    old, new = dg.mesh.boundary_vertices(F), dg.mesh.boundary_vertices(F2)
    assert np.array_equal(new[new < len(V)], old) and np.array_equal(V2[old], V[old])
    E = dg.mesh.edges(F)
    edge = new[new >= len(V)] - len(V)
    assert np.all(np.isin(E[edge], old))  # both ends of each new boundary vertex's edge on the boundary


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("name", ["octahedron", "projective_plane", "disk", "mobius_strip"])
def test_prolongation_rows_are_affine_weights(name, scheme):
    """S (nv + ne, nv): nonnegative rows summing to 1 (so subdivision commutes with affine maps),
    and subdivide(V) = S V."""
    V, F = mesh_of(name)
    S = subdivision_matrix(F, len(V), scheme)
    assert sp.issparse(S) and S.shape == (len(V) + edge_count(F), len(V))
    assert np.max(np.abs(np.asarray(S.sum(axis=1)).ravel() - 1.0)) < 1e-15 and S.min() >= 0
    assert np.array_equal(subdivide(V, F, scheme=scheme)[0], S @ V)
    A, t = np.array([[1.0, 2.0, 0.5], [0.0, 1.0, -1.0], [0.3, 0.0, 2.0]]), np.array([1.0, -2.0, 3.0])
    assert np.allclose(subdivide(V @ A.T + t, F, scheme=scheme)[0], S @ V @ A.T + t, atol=1e-13)


def test_prolongation_carries_per_vertex_data():
    """The same S carries any per-vertex data: a fixed-vertex mask over the old vertices keeps
    its indices, and subdividing (V, u) together is subdividing each."""
    V, F = dg.mesh.disk(3, 8)
    u = np.random.default_rng(0).normal(size=(len(V), 2))
    S = subdivision_matrix(F, len(V), "loop")
    both, _ = subdivide(np.hstack([V, u]), F, scheme="loop")
    assert np.allclose(both[:, 3:], S @ u, rtol=0, atol=1e-15)


def test_loop_stencils():
    """Loop/Warren weights: valence 3 (tetrahedron) β = 3/16, centre 7/16; valence 4
    (octahedron) β = 3/32, centre 5/8; valence 6 (torus) β = 1/16, centre 5/8; an interior edge
    3/8, 3/8, 1/8, 1/8."""
    for name, beta in (("tetrahedron", 3 / 16), ("octahedron", 3 / 32), ("torus", 1 / 16)):
        V, F = mesh_of(name)
        S = subdivision_matrix(F, len(V), "loop").toarray()
        n = 6 if name == "torus" else {"tetrahedron": 3, "octahedron": 4}[name]
        row = S[0]
        neighbours = row[1:][row[1:] > 0]
        assert abs(row[0] - (1 - n * beta)) < 1e-15
        assert neighbours.size == n and np.allclose(neighbours, beta, rtol=0, atol=1e-16)
    V, F = dg.mesh.octahedron()
    S = subdivision_matrix(F, 6, "loop").toarray()
    i, j = dg.mesh.edges(F)[0]
    weights = S[6]
    assert weights[i] == weights[j] == 3 / 8 and np.sort(weights)[-4:-2].tolist() == [1 / 8, 1 / 8]


def test_loop_keeps_planes_and_boundary_curve_rule():
    """Loop's stencils are affine, so a planar mesh stays in its plane (tilted: no coordinate is
    trivially 0); the boundary follows the cubic B-spline rule of the boundary polygon alone: a
    regular m-gon of radius 1 becomes one of radius 3/4 + 1/4 cos(2π/m) at the old vertices and
    cos(π/m) at the edge midpoints; `boundary="fixed"` keeps the old boundary vertices."""
    V, F = dg.mesh.disk(3, 10)
    interior = np.linalg.norm(V, axis=1) < 0.99
    V[interior, :2] += 0.05 * np.random.default_rng(1).normal(size=(int(interior.sum()), 2))
    R = np.linalg.qr(np.random.default_rng(2).normal(size=(3, 3)))[0]
    V2, F2 = subdivide(V @ R.T, F, scheme="loop")
    assert np.max(np.abs((V2 @ R)[:, 2])) < 1e-15
    V2, F2 = subdivide(V, F, scheme="loop")
    old = dg.mesh.boundary_vertices(F)
    assert np.allclose(np.linalg.norm(V2[old], axis=1), 0.75 + 0.25 * np.cos(2 * np.pi / 10), rtol=0, atol=1e-15)
    new = dg.mesh.boundary_vertices(F2)
    new = new[new >= len(V)]
    assert np.allclose(np.linalg.norm(V2[new], axis=1), np.cos(np.pi / 10), rtol=0, atol=1e-15)
    fixed, _ = subdivide(V, F, scheme="loop", boundary="fixed")
    assert np.array_equal(fixed[old], V[old]) and np.array_equal(fixed[len(V):], V2[len(V):])
    assert not np.allclose(fixed[old], V2[old])


def test_loop_limit_is_smooth_and_midpoint_is_not():
    """Repeated Loop subdivision converges to a smooth surface: the largest angle defect (the
    curvature concentrated at a vertex) decreases at every level, by ≈ 4 at the tetrahedron's
    valence-3 vertices (at the octahedron's valence-4 ones by ≈ 2, module docstring).  Negative
    control: midpoint subdivision keeps the polyhedron, and its corners keep their defect π
    exactly."""
    V, F = dg.mesh.tetrahedron()
    defects = {}
    for scheme in SCHEMES:
        W, G, out = V, F, []
        for _ in range(5):
            out.append(np.abs(dg.mesh.angle_defect(W, G)).max())
            W, G = subdivide(W, G, scheme=scheme)
        defects[scheme] = np.array(out)
    assert np.allclose(defects["midpoint"], np.pi, atol=1e-13)
    ratios = defects["loop"][:-1] / defects["loop"][1:]
    assert np.all(ratios > 1.5) and abs(ratios[-1] - 4) < 0.3  # 1.82, 3.07, 3.58, 3.80


def _old_subdivide(V, F):
    """The private `builtin._subdivide` that `subdivide` replaced (verbatim), the reference of
    `test_icosphere_unchanged`."""
    nv = V.shape[0]
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    edges, mid = np.unique(np.sort(he, axis=1), axis=0, return_inverse=True)
    mid = mid.reshape(-1, 3) + nv
    V = np.vstack([V, 0.5 * (V[edges[:, 0]] + V[edges[:, 1]])])
    a, b, c = F.T
    ab, bc, ca = mid.T
    F = np.concatenate([np.stack(t, axis=1) for t in ([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca])])
    return V, F


@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_icosphere_unchanged(level):
    """`icosphere` now subdivides with `subdivide`: bit-for-bit the mesh of the former private
    implementation (vertices, faces and their order)."""
    V, F = dg.mesh.icosahedron()
    for _ in range(level):
        V, F = _old_subdivide(V, F)
        V = V / np.linalg.norm(V, axis=1, keepdims=True)
    V2, F2 = dg.mesh.icosphere(level)
    assert np.array_equal(V2, V) and np.array_equal(F2, F) and len(F2) == 20 * 4**level


@pytest.mark.parametrize(
    ("F", "nv", "error", "names"),
    [
        (np.array([[0, 1, 2, 3]]), 4, ShapeError, "(nf, 3)"),
        (np.array([[0, 1, 2], [0, 2, 7]]), 4, MeshError, "face 1"),
        (np.array([[0, 1, 2], [0, 2, 2]]), 4, MeshError, "face 1"),
        (np.array([[0, 1, 2], [0, -1, 2]]), 4, MeshError, "face 1"),
        (np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]), 5, NonManifoldError, "vertices (0, 1)"),
        (np.array([[0, 1, 2], [0, 3, 4]]), 5, NonManifoldError, "vertex 0"),
        (np.zeros((0, 3), dtype=int), 3, MeshError, "no faces"),
    ],
)
def test_bad_input_names_the_element(F, nv, error, names):
    V = np.zeros((nv, 3))
    for call in (lambda: subdivide(V, F), lambda: subdivision_matrix(F, nv, "loop")):
        with pytest.raises(error, match=names.replace("(", r"\(").replace(")", r"\)")):
            call()


def test_bad_options():
    V, F = dg.mesh.tetrahedron()
    with pytest.raises(InvalidInputError, match="scheme"):
        subdivide(V, F, scheme="butterfly")
    with pytest.raises(InvalidInputError, match="boundary"):
        subdivision_matrix(F, 4, "loop", boundary="free")
    with pytest.raises(ShapeError, match="V must be"):
        subdivide(V.ravel(), F)


# --- solving on refined meshes ---------------------------------------------------------------

SPHERE_VOLUME = 4.0 * np.pi / 3.0


def bubble_problem(V, F):
    from energies import area

    return area.with_volume(V, F, SPHERE_VOLUME)


def icosahedron_bubble():
    """The regular icosahedron scaled to the volume 4π/3: critical by symmetry (p = 2A/3vol)."""
    from energies import area

    V, F = dg.mesh.icosahedron()
    return V * (SPHERE_VOLUME / area.enclosed_volume(V, F)) ** (1 / 3), F


@pytest.fixture(scope="module")
def refined_bubble():
    """The soap bubble of volume 4π/3 solved from the icosahedron and two Loop subdivisions (a
    third gives the ratios 4.02 below, at twice the time of the test)."""
    from energies.refine import refine

    return refine(bubble_problem, *icosahedron_bubble(), levels=2, scheme="loop", tol=1e-10)


def test_refined_bubble_pressure_tends_to_two_at_order_two(refined_bubble):
    """Laplace–Young: the unit sphere has p = κ1 + κ2 = 2 and area 4π.  On the refined bubbles
    (h halves per level) |p − 2| and A − 4π fall by ≈ 4 per level (second order; measured 4.13,
    4.06, and 4.02 at a third level, the same for the area), the volume stays 4π/3, and each level converges from the
    subdivided coarse solution in a few Newton steps (measured 0, 4, 3, 3).  Negative control:
    midpoint subdivision of a solution alone gains nothing, its area is the coarse area to
    round-off, so the decrease is the re-solve's."""
    from energies import area

    assert [len(level.F) for level in refined_bubble] == [20, 80, 320]
    p = np.array([float(level.solution.multipliers["volume"][0]) for level in refined_bubble])
    A = np.array([level.energy for level in refined_bubble])
    for level in refined_bubble:
        assert bool(level.solution.converged) and level.steps <= 8
        assert abs(area.enclosed_volume(np.asarray(level.solution.x), level.F) - SPHERE_VOLUME) < 1e-10
    p_ratio = np.abs(p[:-1] - 2) / np.abs(p[1:] - 2)
    A_ratio = (A[:-1] - 4 * np.pi) / (A[1:] - 4 * np.pi)
    assert np.all(np.abs(p_ratio - 4) < 0.25) and np.all(np.abs(A_ratio - 4) < 0.25)
    assert abs(p[-1] - 2) < 1e-2 and np.all(A > 4 * np.pi)  # the sphere is the least area (isoperimetry)
    coarse = refined_bubble[1]
    V2, F2 = subdivide(np.asarray(coarse.solution.x), coarse.F)
    assert abs(dg.mesh.surface_area(V2, F2) - coarse.energy) < 1e-12
    assert A[2] < coarse.energy - 0.1


def test_refine_stops_at_rtol_and_applies_project(refined_bubble):
    """With rtol = 0.02 the energy changes 4.8 % from level 0 to 1 and 1.2 % from 1 to 2, so the
    refinement stops after level 2; `project` moves the subdivided start before the solve (here
    radially onto the unit sphere: the start of level 1 is the midpoint-subdivided icosahedron
    pushed out to the sphere, and the solution is that of the Loop run)."""
    from energies.refine import refine

    A = [level.energy for level in refined_bubble]
    assert abs(A[1] - A[0]) > 0.02 * A[1] and abs(A[2] - A[1]) < 0.02 * A[2]
    on_sphere = lambda V, F: V / np.linalg.norm(V, axis=1, keepdims=True)  # noqa: E731
    levels = refine(bubble_problem, *icosahedron_bubble(), levels=3, rtol=0.02, project=on_sphere, tol=1e-10)
    assert len(levels) == 3
    assert np.allclose(np.linalg.norm(levels[1].V, axis=1), 1.0, rtol=0, atol=1e-15)
    for ours, loop in zip(levels, refined_bubble[:3]):
        p, q = (float(s.solution.multipliers["volume"][0]) for s in (ours, loop))
        assert abs(ours.energy - loop.energy) < 1e-9 and abs(p - q) < 1e-8


def test_refine_rejects_bad_options():
    from energies.refine import refine

    V, F = icosahedron_bubble()
    with pytest.raises(InvalidInputError, match="levels"):
        refine(bubble_problem, V, F, levels=-1)
    with pytest.raises(InvalidInputError, match="rtol"):
        refine(bubble_problem, V, F, rtol=0.0)


# the catenoid between the unit circles at z = ±H: r(z) = a cosh(z/a), a cosh(H/a) = 1
H = 0.5


def catenoid_neck() -> float:
    from scipy.optimize import brentq

    return brentq(lambda a: a * np.cosh(H / a) - 1.0, 0.6, 1.0)  # the stable (outer) branch, a = 0.8483


def onto_circles(V, F):
    """Boundary vertices back onto the unit circles (the midpoints of their chords lie inside)."""
    V = V.copy()
    b = dg.mesh.boundary_vertices(F)
    V[b, :2] /= np.linalg.norm(V[b, :2], axis=1, keepdims=True)
    return V


def neck_radius(level) -> float:
    x = np.asarray(level.solution.x)
    ring = np.abs(x[:, 2]) < 1e-9  # the circle at z = 0 of cylinder(4), kept by symmetry
    return float(np.linalg.norm(x[ring, :2], axis=1).mean())


@pytest.fixture(scope="module")
def refined_catenoid():
    from energies import area
    from energies.refine import refine

    V, F = dg.mesh.builtin.cylinder(4, H=H)
    return refine(lambda V, F: area.simplicial(V, F), V, F, levels=2, project=onto_circles, tol=1e-10)


@pytest.mark.slow  # a convergence study (three levels, about 60 Newton steps); the quick runs have catenoid_neck_order
def test_refined_catenoid_neck_converges_at_order_two(refined_catenoid):
    """The minimal surface spanned by the unit circles at z = ±1/2, refined from cylinder(4) with
    the boundary vertices projected onto the circles: the neck radius tends to the catenoid's
    a = 0.84834 (a cosh(H/a) = 1) with error −1.25e-2, −2.99e-3, −7.40e-4 (ratios 4.17, 4.04), the
    area to π a (2H + a sinh(2H/a)) = 5.99180 from below with error 7.13e-2, 1.79e-2, 4.49e-3
    (ratios 3.98, 3.99); Newton steps 28, 30, 5 (the projected boundary vertices kink the first
    strip of the start).  Negative control: without `project` the boundary stays the coarse
    12-gon (new boundary vertices at its chords' midpoints), the surface tends to the one spanning
    the polygons, and the neck error grows (−1.25e-2 → −2.62e-2) instead of falling by 4; its old
    boundary vertices stay put exactly."""
    from energies import area
    from energies.refine import refine

    a = catenoid_neck()
    errors = np.array([neck_radius(level) - a for level in refined_catenoid])
    assert np.all(errors < 0) and np.all(np.abs(errors[:-1] / errors[1:] - 4) < 0.3)
    smooth_area = np.pi * a * (2 * H + a * np.sinh(2 * H / a))
    areas = np.array([level.energy for level in refined_catenoid])
    assert np.all(np.diff(areas) > 0) and np.all(areas < smooth_area)
    assert np.all(np.abs((smooth_area - areas[:-1]) / (smooth_area - areas[1:]) - 4) < 0.2)
    for level in refined_catenoid:
        assert bool(level.solution.converged)
        b = dg.mesh.boundary_vertices(level.F)
        assert np.allclose(np.linalg.norm(np.asarray(level.solution.x)[b, :2], axis=1), 1.0, rtol=0, atol=1e-15)
    V, F = dg.mesh.builtin.cylinder(4, H=H)
    unprojected = refine(lambda V, F: area.simplicial(V, F), V, F, levels=1, tol=1e-10)
    assert abs(neck_radius(unprojected[0]) - neck_radius(refined_catenoid[0])) < 1e-12
    assert neck_radius(unprojected[1]) - a < 1.5 * errors[0]
    # old vertex i is new vertex i: the fixed boundary of level 0 is fixed, bit for bit, at level 1
    b = dg.mesh.boundary_vertices(F)
    x0, x1 = (np.asarray(level.solution.x) for level in unprojected)
    assert np.array_equal(x1[b], x0[b])
    with pytest.raises(ShapeError, match="vertex positions"):
        refine(lambda V, F: dg.Problem(lambda x, p: (x**2).sum(), V[:, :2]), V, F)
