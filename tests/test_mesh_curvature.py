"""Polyhedral curvature (Sec 5.2): angle defects (Def 5.2), Gauss–Bonnet (Thm 5.6, Remark 5.4),
Lemma 5.4, edge mean curvature (Def 5.3) and Steiner's formula (Thm 5.7, Example 5.1).  Gauss–Bonnet on
the built-in meshes and its gradient, the cube (Example 5.1), Steiner on the cube and the limit of
H(S) on the icosphere are `ddgjax verify` checks (`sec5_curvature`).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from ddgjax import mesh
from ddgjax.errors import OrientationError


def test_gauss_bonnet_on_a_polygon_list_and_random_positions(rng):
    """The identity is combinatorial: it holds for any non-degenerate positions (here random
    vertices of a torus's combinatorics) and for polygon lists (a pyramid with a square base).
    """
    _, F = mesh.torus(8, 5)
    V = rng.normal(size=(40, 3))
    assert abs(float(mesh.angle_defect(V, F).sum())) < 1e-12
    Vp = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.3, 0.4, 0.8]])
    Fp = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    assert abs(float(mesh.angle_defect(Vp, Fp).sum()) - 4 * np.pi) < 1e-12


def test_boundary_turning_angles_remark_5_4():
    """A flat disk: interior vertices are flat (K = 0); the boundary turning angles of the
    regular m-gon are 2π/m and sum to 2π = 2πχ.
    """
    V, F = mesh.disk(rings=3, m=12)
    K = np.asarray(mesh.angle_defect(V, F))
    boundary = mesh.boundary_loops(F)[0]
    interior = np.setdiff1d(np.arange(V.shape[0]), boundary)
    assert np.max(np.abs(K[interior])) < 1e-14
    assert np.allclose(K[boundary], 2 * np.pi / 12, atol=1e-14, rtol=0)
    assert np.all(np.asarray(mesh.vertex_kind(V, F))[interior] == 0)


def _star(p, q):
    """A vertex star: vertex 0 at p, neighbours 1..n in cyclic order."""
    n = q.shape[0]
    F = np.stack([np.zeros(n, dtype=int), 1 + np.arange(n), 1 + (np.arange(n) + 1) % n], axis=1)
    return np.vstack([p, q]), F


def _is_convex(p, q):
    """All neighbours strictly on one side of every face plane of the star (the star lies on the
    boundary of its convex hull, so the normals' spherical polygon is convex)."""
    n = q.shape[0]
    normals = np.cross(q - p, np.roll(q, -1, axis=0) - p)
    side = np.einsum("fi,ji->fj", normals, q - p)
    mask = (np.arange(n)[None] != np.arange(n)[:, None]) & (np.arange(n)[None] != (np.arange(n)[:, None] + 1) % n)
    s = side[mask]
    return bool(np.all(s < -1e-9) or np.all(s > 1e-9))


def _is_saddle(p, q):
    """p in the interior of the convex hull of its neighbours."""
    hull = ConvexHull(q)
    return bool(np.all(hull.equations[:, :3] @ p + hull.equations[:, 3] < -1e-9))


def test_lemma_5_4_random_vertex_stars(rng):
    """convex ⇒ K > 0, planar ⇒ K = 0, saddle ⇒ K < 0 on random stars; each class is hit."""
    seen = {"convex": 0, "saddle": 0, "planar": 0}
    for _ in range(120):
        n = rng.integers(4, 9)
        t = np.sort(rng.uniform(0, 2 * np.pi, n))
        if np.max(np.diff(np.append(t, t[0] + 2 * np.pi))) >= np.pi * 0.95:
            continue
        r = rng.uniform(0.5, 1.5, n)
        q = np.stack([r * np.cos(t), r * np.sin(t), rng.normal(0, 0.3, n)], axis=1)
        p = np.array([0, 0, rng.normal(0, 0.6)])
        V, F = _star(p, q)
        K = float(mesh.angle_defect(V, F)[0])
        if _is_convex(p, q):
            seen["convex"] += 1
            assert K > 0
        if _is_saddle(p, q):
            seen["saddle"] += 1
            assert K < 0
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # a random rotation of a planar star
        flat = q * np.array([1, 1, 0])
        V, F = _star(np.ones(3), flat @ Q.T + 1.0)
        seen["planar"] += 1
        assert abs(float(mesh.angle_defect(V, F)[0])) < 1e-13
    assert min(seen.values()) >= 8, seen


def test_vertex_kinds():
    """The icosphere is elliptic everywhere; the torus has elliptic outer and hyperbolic inner
    vertices; a cube corner pushed in stays elliptic (K is intrinsic) while its edges turn concave.
    """
    assert np.all(np.asarray(mesh.vertex_kind(*mesh.icosphere(2))) == 1)
    V, F = mesh.torus(16, 8)
    kind = np.asarray(mesh.vertex_kind(V, F))
    rho = np.hypot(V[:, 0], V[:, 1])
    assert np.all(kind[rho > 1 + 1e-9] == 1) and np.all(kind[rho < 1 - 1e-9] == -1)


def test_dihedral_sign_convention():
    """θ = +π/2 at convex and −π/2 at concave edges of the outward polycube double torus, 0 on its
    flat diagonals; reversing all faces flips every sign.
    """
    V, F = mesh.double_torus()
    theta = np.asarray(mesh.dihedral_angles(V, F))
    values = np.unique(np.round(theta / (np.pi / 2), 12))
    assert set(values.tolist()) == {-1.0, 0.0, 1.0}
    assert np.allclose(mesh.dihedral_angles(V, F[:, ::-1]), -theta, atol=1e-15, rtol=0)
    with pytest.raises(OrientationError, match="edge"):
        mesh.edge_mean_curvature(*mesh.mobius_strip())


def _distance_to_triangle(X, a, b, c):
    """Euclidean distance from the rows of X to the triangle abc (vectorised over X)."""
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n)
    h = (X - a) @ n
    P = X - h[:, None] * n
    inside = np.ones(X.shape[0], dtype=bool)
    for u, w in ((a, b), (b, c), (c, a)):
        inside &= np.cross(w - u, P - u) @ n >= 0
    d = np.full(X.shape[0], np.inf)
    for u, w in ((a, b), (b, c), (c, a)):
        s = np.clip((X - u) @ (w - u) / ((w - u) @ (w - u)), 0, 1)
        d = np.minimum(d, np.linalg.norm(X - (u + s[:, None] * (w - u)), axis=1))
    return np.where(inside, np.abs(h), d)


def test_theorem_5_7_steiner_volume_monte_carlo(rng):
    """Integrating Thm 5.7 in ρ: vol(P_ρ) = vol(P) + A ρ + H ρ² + (4π/3) ρ³ for random convex
    hulls, against a Monte Carlo estimate within 4 standard errors; the H term is resolved
    (dropping it would miss by far more than 4 standard errors).
    """
    for _ in range(2):
        hull = ConvexHull(rng.normal(size=(12, 3)))
        V = hull.points[hull.vertices]
        hull = ConvexHull(V)
        F = hull.simplices.copy()
        normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        flip = np.einsum("ij,ij->i", normals, hull.equations[:, :3]) < 0
        F[flip] = F[flip][:, ::-1]
        rho = 0.3
        A, H = float(mesh.surface_area(V, F)), float(mesh.total_mean_curvature(V, F))
        assert abs(A - hull.area) < 1e-12 * A
        predicted = hull.volume + A * rho + H * rho**2 + 4 * np.pi / 3 * rho**3
        lo, hi = V.min(0) - rho, V.max(0) + rho
        N = 100_000
        X = lo + (hi - lo) * rng.uniform(size=(N, 3))
        outside = np.any(X @ hull.equations[:, :3].T + hull.equations[:, 3] > 0, axis=1)
        Y = X[outside]
        dist = np.min([_distance_to_triangle(Y, *V[f]) for f in F], axis=0)
        hits = (N - outside.sum()) + np.count_nonzero(dist <= rho)
        box = np.prod(hi - lo)
        estimate = box * hits / N
        sigma = box * np.sqrt(hits / N * (1 - hits / N) / N)
        assert abs(estimate - predicted) < 4 * sigma
        assert H * rho**2 > 8 * sigma


def test_jit_matches_eager():
    """`angle_defect` (with a traced F) and `edge_mean_curvature` under jit match eager."""
    V, F = mesh.torus(12, 6)
    K = mesh.angle_defect(V, F)
    assert np.allclose(jax.jit(mesh.angle_defect)(V, jnp.asarray(F)), K, atol=1e-14, rtol=0)
    H = jax.jit(lambda X: mesh.edge_mean_curvature(X, F))(V)
    assert np.allclose(H, mesh.edge_mean_curvature(V, F), atol=1e-14, rtol=0)


def test_concrete_and_traced_angle_defects_agree():
    """Def 5.2 / Remark 5.4 (and the corner angles) two ways: concrete triangle meshes in NumPy (corner angles in blocks,
    sums per vertex by `bincount`), traced ones in one jitted kernel; the same numbers to
    round-off on closed meshes of genus 0 and 1 and on a disk (boundary vertices: π − Σ α)."""
    for V, F in (mesh.icosphere(2), mesh.torus(12, 6), mesh.builtin.disk(4, 12)):
        concrete = mesh.angle_defect(V, F)
        traced = jax.jit(lambda X, F=F: mesh.angle_defect(X, jnp.asarray(F)))(jnp.asarray(V))
        assert isinstance(concrete, np.ndarray) and concrete.shape == (len(V),)
        assert np.max(np.abs(concrete - np.asarray(traced))) < 1e-14
        angles = mesh.corner_angles(V, F)  # the corner angles they sum, the same two ways
        traced_angles = jax.jit(lambda X, F=F: mesh.corner_angles(X, jnp.asarray(F)))(jnp.asarray(V))
        assert angles.shape == np.shape(F) and np.max(np.abs(angles - np.asarray(traced_angles))) < 1e-14
