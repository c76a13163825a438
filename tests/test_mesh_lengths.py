"""Geometry from edge lengths (Sec 5.3, 6.3, Lemma 7.17) and the one derived cotan Laplacian:
the autodiff Hessian of the Dirichlet energy on squared lengths, against the typed cotangent
formula as an independent oracle, extrinsically (Def 6.2), intrinsically and after edge flips
(Def 7.8)."""

import jax
import numpy as np
import pytest
import scipy.sparse as sp

import ddgjax as dg
from ddgjax.intrinsic import triangulation as T
from ddgjax.mesh import lengths
from ddgjax.mesh.builtin import grid_quads, icosphere, tall_dome, torus, triangulate


def _jittered_grid(m=12, n=12, seed=0):
    rng = np.random.default_rng(seed)
    X, Y = np.meshgrid(np.linspace(0, 1, m), np.linspace(0, 1, n), indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(m * n)])
    V[:, :2] += rng.uniform(-0.03, 0.03, (m * n, 2))
    V[:, 2] = 0.3 * np.sin(3 * V[:, 0]) * V[:, 1]
    return V, triangulate(grid_quads(m, n, False, False))


def _ellipsoid():
    V, F = icosphere(3)
    return V * np.array([12.0, 1.0, 0.5]), F


def _sheared_torus():
    V, F = torus(24, 8)
    return V @ np.array([[1.0, 0, 0], [0, 1.0, 0], [3.0, 0, 1.0]]).T * np.array([1.0, 0.3, 1.0]), F


MESHES = {
    "icosphere": lambda: icosphere(3),
    "torus": lambda: torus(24, 8),
    "jittered_grid": _jittered_grid,
    "ellipsoid": _ellipsoid,
    "sheared_torus": _sheared_torus,
    "tall_dome": lambda: tall_dome(0)[:2],
}


def _oracle_laplacian(n, I, J, cot):
    """L = Σ over corners of ½ cot α on the opposite side (i, j): the typed formula (6.2),
    loops dropped."""
    keep = I != J
    I, J, w = I[keep], J[keep], 0.5 * cot[keep]
    W = sp.coo_matrix((np.r_[w, w], (np.r_[I, J], np.r_[J, I])), shape=(n, n)).tocsr()
    return sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W


def _extrinsic_oracle(V, F):
    """cot α_k = (e · e') / |e × e'| with e, e' the sides at corner k, in positions."""
    cot = np.empty(F.shape)
    for k in range(3):
        u, w = V[F[:, (k + 1) % 3]] - V[F[:, k]], V[F[:, (k + 2) % 3]] - V[F[:, k]]
        cot[:, k] = np.einsum("ij,ij->i", u, w) / np.linalg.norm(np.cross(u, w), axis=1)
    return _oracle_laplacian(len(V), F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel(), cot.ravel())


def _intrinsic_oracle(tri):
    """cot α_k = (b² + c² − a²) / 4A from the lengths of `tri`, A by Heron in its plain form."""
    L = T.opposite_side_lengths(tri)
    a, b, c = L.T
    s = 0.5 * (a + b + c)
    A = np.sqrt(s * (s - a) * (s - b) * (s - c))
    cot = np.stack([(b * b + c * c - a * a), (c * c + a * a - b * b), (a * a + b * b - c * c)], 1) / (4 * A[:, None])
    F = tri.F
    return _oracle_laplacian(tri.n_vertices, F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel(), cot.ravel())


def _rel(A, B) -> float:
    return float(abs(A - B).max() / abs(B).max())


def test_polarised_cotangents_are_the_cotangents_of_the_corner_angles():
    """`corner_cotangents`, read off the Dirichlet energy by polarisation, equals cot of the
    angles computed from the positions (cos/sin from dot and cross products, the oracle); the
    same polarisation of a wrong energy (g11 and g22 exchanged) does not (negative control)."""
    rng = np.random.default_rng(5)
    P = rng.normal(size=(500, 3, 3))
    l2 = lengths.squared_side_lengths(P)
    l = np.sqrt(l2)
    A = lengths.triangle_area(l[:, 0], l[:, 1], l[:, 2])

    def cot_at(k):
        u, v = P[:, (k + 1) % 3] - P[:, k], P[:, (k + 2) % 3] - P[:, k]
        return np.sum(u * v, axis=1) / np.linalg.norm(np.cross(u, v), axis=1)

    oracle = np.stack([cot_at(k) for k in range(3)], axis=1)
    derived = np.stack(lengths.corner_cotangents(l2[:, 0], l2[:, 1], l2[:, 2], A), axis=1)
    scale = np.abs(oracle).max(axis=1, keepdims=True)
    assert np.max(np.abs(derived - oracle) / scale) < 1e-10
    wrong_form = lengths.polarised_cotangents(lambda d1, d2, a2, b2, c2: lengths.dirichlet_form(d1, d2, a2, c2, b2))
    wrong = np.stack(wrong_form(l2[:, 0], l2[:, 1], l2[:, 2], A), axis=1)
    assert np.max(np.abs(wrong - oracle) / scale) > 1e-2


def test_lemma_7_17_corner_cotangents_are_minus_twice_the_derived_stiffness():
    """The angle criterion's cotangents (`corner_cotangents`, polarisation of the Dirichlet
    energy) equal −2 × the off-diagonal of its autodiff Hessian on squared lengths (Thm 6.6)."""
    rng = np.random.default_rng(1)
    P = rng.normal(size=(500, 3, 3))
    l2 = lengths.squared_side_lengths(P)
    l = np.sqrt(l2)
    A = lengths.triangle_area(l[:, 0], l[:, 1], l[:, 2])
    cot = np.stack(lengths.corner_cotangents(l2[:, 0], l2[:, 1], l2[:, 2], A), axis=1)
    K = np.asarray(lengths.stiffness(l2))
    off = K[:, [1, 2, 0], [2, 0, 1]]
    scale = np.abs(cot).max(axis=1, keepdims=True)
    assert np.max(np.abs(cot + 2 * off) / scale) < 1e-12
    np.testing.assert_allclose(K.sum(axis=2), 0, atol=1e-12 * np.abs(K).max())  # constants in the kernel


def test_side_cotangent_columns_are_the_derived_stiffness_by_side():
    """The columnwise kernel (Hessian-vector products of the summed Dirichlet energies) gives
    the cotangents of `stiffness` (a `vmap` of `jax.hessian`) per side, padded or not, and
    `side_cotangents` the same per face with Heron's areas."""
    rng = np.random.default_rng(3)
    P = rng.normal(size=(500, 3, 3))
    l2 = lengths.squared_side_lengths(P)  # opposite corner k; side i is opposite corner i + 2
    s2 = l2[:, [2, 0, 1]]
    K = np.asarray(lengths.stiffness(l2))
    by_side = -2 * K[:, [0, 1, 2], [1, 2, 0]]  # cot(side i) = −2 K[i, i + 1]
    scale = np.abs(by_side).max(axis=1, keepdims=True)
    rows = np.stack(lengths.side_cotangent_columns(np.ascontiguousarray(s2.T)), axis=1)
    assert rows.shape == (500, 3) and np.max(np.abs(rows - by_side) / scale) < 1e-13
    width = lengths.padded_size(500)
    padded = np.ones((3, width))
    padded[:, :500] = s2.T
    np.testing.assert_array_equal(np.stack(lengths.side_cotangent_columns(padded, 500), axis=1), rows)
    cot, area = lengths.side_cotangents(s2)
    np.testing.assert_array_equal(cot, rows)
    l = np.sqrt(l2)
    np.testing.assert_array_equal(area, lengths.triangle_area(l[:, 0], l[:, 1], l[:, 2]))


def test_kernels_on_concrete_triangles_compile_two_programs_for_every_size():
    """Triangles padded to `padded_size` and run in blocks of `TRIANGLE_BLOCKS[-1]`: meshes of
    8 sizes from 10 to 5000 faces compile at most two programs of a kernel (one per size would
    be 8), and the blocked results equal the kernel on the unpadded rows (per-face arithmetic,
    to the last bit)."""
    from ddgjax import laplace

    kernel = laplace._corner_weights_of_squares
    rng = np.random.default_rng(4)
    sizes = (10, 100, 255, 256, 257, 1000, 2049, 5000)
    assert {lengths.padded_size(n) for n in sizes} == {256, 2048, 4096, 6144}
    triangles = [lengths.squared_side_lengths(rng.normal(size=(n, 3, 3))) for n in sizes]
    before = kernel._cache_size()
    blocked = [lengths.on_padded_rows(kernel, l2) for l2 in triangles]
    assert kernel._cache_size() - before <= 2
    reference = jax.jit(lengths.corner_weights)
    for l2, (w, sin2) in zip(triangles, blocked):
        expected = reference(l2)
        assert w.shape == (len(l2), 3) and sin2.shape == (len(l2),)
        np.testing.assert_array_equal(w, np.asarray(expected[0]))
        np.testing.assert_array_equal(sin2, np.asarray(expected[1]))


def test_dirichlet_energy_on_lengths_equals_the_cotangent_form():
    """E(f) = ¼ Σ_k cot α_k (f_{k+1} − f_{k+2})² (Sec 6.3), the energy written without angles."""
    rng = np.random.default_rng(2)
    for _ in range(20):
        P, f = rng.normal(size=(3, 3)), rng.normal(size=3)
        l2 = lengths.squared_side_lengths(P)
        cot = np.array([np.dot(P[(k + 1) % 3] - P[k], P[(k + 2) % 3] - P[k])
                        / np.linalg.norm(np.cross(P[(k + 1) % 3] - P[k], P[(k + 2) % 3] - P[k])) for k in range(3)])
        expected = 0.25 * sum(cot[k] * (f[(k + 1) % 3] - f[(k + 2) % 3]) ** 2 for k in range(3))
        assert abs(float(lengths.dirichlet_energy(f, l2)) - expected) < 1e-12 * (1 + abs(expected))


@pytest.mark.parametrize("name", list(MESHES))
def test_def_6_2_derived_laplacians_equal_the_typed_formula(name):
    """`laplace.cotan_laplacian(V, F)` (extrinsic composition) and `intrinsic.cotan_laplacian`
    (on the lengths of `from_mesh`) both equal the typed cotangent formula to 1e-12 max|L|."""
    V, F = MESHES[name]()
    L_oracle = _extrinsic_oracle(V, F)
    assert _rel(dg.laplace.cotan_laplacian(V, F), L_oracle) < 1e-12
    assert _rel(dg.intrinsic.cotan_laplacian(dg.intrinsic.from_mesh(V, F)), L_oracle) < 1e-12


@pytest.mark.parametrize("name", list(MESHES))
def test_def_7_8_laplace_beltrami_is_the_derived_laplacian_after_flips(name):
    """`laplace_beltrami(V, F)` equals the typed formula on the lengths of the intrinsic Delaunay
    triangulation; `FlipResult.cotan_weights()` (derived) equals ½ Σ of the cotangents cached
    by the flip loop's angle test (law of cosines) to 1e-12."""
    V, F = MESHES[name]()
    result = dg.intrinsic.flip_to_delaunay(dg.intrinsic.from_mesh(V, F))
    tri = result.triangulation
    assert _rel(dg.intrinsic.laplace_beltrami(V, F), _intrinsic_oracle(tri)) < 1e-12
    cached = 0.5 * np.bincount(tri.edge, result.halfedge_cotangents, minlength=tri.n_edges)
    nu = result.cotan_weights()
    assert np.max(np.abs(nu - cached)) < 1e-12 * np.abs(cached).max()


def test_multiple_edges_add_and_loops_drop_out():
    """After the flip of Example 5.5 the tetrahedron has two edges between one pair of vertices:
    their weights add in L; a self-glued triangle's loop drops out."""
    V, F = dg.mesh.tetrahedron()
    flipped = dg.intrinsic.flip(dg.intrinsic.from_mesh(V, F), 0)
    assert len(np.unique(np.sort(flipped.edges, 1), axis=0)) == 5
    assert _rel(dg.intrinsic.cotan_laplacian(flipped), _intrinsic_oracle(flipped)) < 1e-12
    cone = T.from_gluing([1, 0, -1], [[1.0, 1.0, 0.6]])
    L = dg.intrinsic.cotan_laplacian(cone)
    assert _rel(L, _intrinsic_oracle(cone)) < 1e-12
    assert abs(L @ np.ones(cone.n_vertices)).max() < 1e-15


def test_one_connectivity_type_for_meshes_and_intrinsic_triangulations():
    """`intrinsic.Triangulation` is a `mesh.Halfedges` plus lengths: the same edges as
    `mesh.from_faces`, and mesh topology accepts its connectivity."""
    V, F = torus(12, 6)
    tri = dg.intrinsic.from_mesh(V, F)
    h = dg.mesh.from_faces(F)
    assert isinstance(tri.connectivity, dg.mesh.Halfedges)
    np.testing.assert_array_equal(tri.edge, h.edge)
    np.testing.assert_array_equal(np.sort(tri.edges, 1), h.edges)
    assert dg.mesh.euler_characteristic(tri.connectivity) == 0
    stretched = dg.intrinsic.from_mesh(V * [6.0, 1, 1], F)
    result = dg.intrinsic.flip_to_delaunay(stretched)
    flipped = result.triangulation
    assert result.n_flips > 0
    assert dg.mesh.euler_characteristic(flipped.connectivity) == 0 and dg.mesh.is_orientable(flipped.connectivity)
    np.testing.assert_allclose(np.asarray(lengths.angle_defects(flipped.connectivity, T.opposite_side_lengths(flipped))),
                               np.asarray(dg.mesh.angle_defect(V * [6.0, 1, 1], F)), atol=1e-12)


@pytest.mark.parametrize("sides", [(1.0, 1.0, 1.0), (1.0, 1.0, 0.5), (0.5, 1.0, 1.0), (1.0, 0.5, 1.0), (1.2, 1.0, 0.7)])
def test_heron_gradient_is_right_at_ties_of_the_sorted_sides(sides):
    """∂A/∂a = a (b² + c² − a²) / (8A) (differentiate 16A² = 2a²b² + 2b²c² + 2c²a² − a⁴ − b⁴ − c⁴),
    also at the three-way tie of an equilateral triangle, where composing max/min split the
    derivative (weights 0.875, 0.875, 1.25 per side).  Negative control: the unequal case."""
    import jax
    import jax.numpy as jnp

    a, b, c = sides
    area = lengths.triangle_area(a, b, c)
    expected = np.array([s * (t**2 + u**2 - s**2) for s, t, u in ((a, b, c), (b, c, a), (c, a, b))]) / (8 * area)
    gradient = jax.grad(lambda l: lengths.triangle_area(l[0], l[1], l[2]))(jnp.array(sides))
    assert np.abs(np.asarray(gradient) - expected).max() < 1e-15


def test_simplicial_area_gradient_on_the_octahedron_with_exactly_equilateral_faces():
    """The octahedron ±e_k: every side is computed as √2 exactly (a three-way tie in every face).
    Moving vertex e_1 to s e_1 makes each of its 4 faces ½|(1, s, s)| = ½ √(1 + 2s²), so
    ∇_{v} A = (4/√3) v at every vertex (Thm 6.7's mean-curvature normal, here by symmetry)."""
    import jax
    import jax.numpy as jnp

    from energies import area

    V, F = dg.mesh.builtin.octahedron()
    sides = np.linalg.norm(V[F] - V[np.roll(F, 1, axis=1)], axis=2)
    assert np.all(sides == sides[0, 0])  # exact ties
    problem = area.simplicial(V, F)
    gradient = np.asarray(jax.grad(problem.energy)(jnp.asarray(V, dtype=jnp.float64), problem.params))
    assert np.abs(gradient - 4 / np.sqrt(3) * V).max() < 1e-14
