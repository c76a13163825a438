"""Built-in polyhedral surfaces: each function returns `(V, F)`, V (nv, 3) float64, F int64, and
those made as starts of minimal-surface problems with a fixed boundary (`unit_square`,
`tall_dome`) `(V, F, boundary)`, the boundary vertices' indices.

Closed orientable ones are oriented with outward normals (faces counter-clockwise seen from
outside).  Non-orientable ones are immersed or, for the projective plane, only combinatorially
meaningful (its six vertices are representatives of antipodal icosahedron vertices; the
straight triangles between them intersect, which does not affect angle sums).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from .subdivision import subdivide

__all__ = [
    "tetrahedron",
    "cube",
    "octahedron",
    "icosahedron",
    "icosphere",
    "torus",
    "projective_plane",
    "klein_bottle",
    "double_torus",
    "disk",
    "saddle_grid",
    "annulus",
    "mobius_strip",
    "grid_quads",
    "triangulate",
    "unit_square",
    "cylinder",
    "stretched_sphere",
    "tall_dome",
    "double_bubble",
]


def _mesh(V, F):
    return np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)


def tetrahedron():
    """The regular tetrahedron inscribed in the cube [-1, 1]³ (4 vertices, 4 faces)."""
    V = [[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]
    F = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]
    return _mesh(V, F)


def triangulate(F) -> np.ndarray:
    """Split each convex k-gon into k − 2 triangles by a fan from its first corner, keeping the
    orientation.  `F` is an (nf, k) array or a list of polygons of any sizes (what `read` returns
    for a file mixing triangles and quads); the triangles of each face stay together, in face order.
    """
    if not hasattr(F, "shape"):
        fans = [[f[0], f[i], f[i + 1]] for f in F for i in range(1, len(f) - 1)]
        return np.asarray(fans, dtype=np.int64).reshape(-1, 3)
    F = np.asarray(F)
    k = F.shape[1]
    fans = [F[:, [0, i, i + 1]] for i in range(1, k - 1)]
    return np.stack(fans, axis=1).reshape(-1, 3)


def cube(triangulated: bool = False):
    """The unit cube [0, 1]³: 6 squares (Example 5.1), or 12 triangles when `triangulated`."""
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    F = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    return _mesh(V, triangulate(F) if triangulated else F)


def octahedron():
    """The regular octahedron with vertices ±e_i."""
    V = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return _mesh(V, F)


def icosahedron():
    """The regular icosahedron on the unit sphere; vertex i + 6 is the antipode of vertex i."""
    t = (1 + 5**0.5) / 2
    half = np.array([[-1, t, 0], [1, t, 0], [0, 1, t], [0, 1, -t], [t, 0, 1], [-t, 0, 1]], dtype=float)
    V = np.vstack([half, -half]) / np.sqrt(1 + t * t)
    F = _hull_faces(V)
    return _mesh(V, F)


def _hull_faces(V) -> np.ndarray:
    """Faces of the convex hull of points in convex position, oriented outward."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(V)
    F = hull.simplices.copy()
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    flip = np.einsum("ij,ij->i", normals, hull.equations[:, :3]) < 0
    F[flip] = F[flip][:, ::-1]
    return F


def icosphere(level: int = 1):
    """The icosahedron subdivided `level` times (20·4^level faces, `subdivide`, midpoints),
    each time projected to the unit sphere."""
    V, F = icosahedron()
    for _ in range(level):
        V, F = subdivide(V, F)
        V = V / np.linalg.norm(V, axis=1, keepdims=True)
    return _mesh(V, F)


def grid_quads(m: int, n: int, wrap_u: bool, wrap_v: bool, twist: bool = False) -> np.ndarray:
    """Quads (i, j), (i+1, j), (i+1, j+1), (i, j+1) of an m × n vertex grid, vertex i·n + j.

    `wrap_u` glues row m to row 0; with `twist` it glues (m, j) to (0, n − 1 − j) (Möbius strip,
    Klein bottle).  `wrap_v` glues column n to column 0.
    """
    i, j = np.meshgrid(np.arange(m if wrap_u else m - 1), np.arange(n if wrap_v else n - 1), indexing="ij")
    i, j = i.reshape(-1), j.reshape(-1)

    def index(a, b):
        b = b % n
        wrapped = a >= m
        b = np.where(wrapped & twist, n - 1 - b, b)
        return (a % m) * n + b

    return np.stack([index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)], axis=1)


def _check_grid(**sizes):
    for name, (value, least) in sizes.items():
        if value < least:
            raise InvalidInputError(f"{name} must be at least {least}, got {value}")


def torus(m: int = 16, n: int = 8, R: float = 1.0, r: float = 0.4):
    """Torus of revolution, m × n vertices, triangulated, outward oriented (genus 1)."""
    _check_grid(m=(m, 3), n=(n, 3))
    u, v = np.meshgrid(2 * np.pi * np.arange(m) / m, 2 * np.pi * np.arange(n) / n, indexing="ij")
    V = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1)
    return _mesh(V.reshape(-1, 3), triangulate(grid_quads(m, n, True, True)))


def projective_plane():
    """The hemi-icosahedron: the icosahedron modulo the antipodal map (6 vertices, 15 edges,
    10 faces, χ = 1), a triangulation of RP²; V holds one representative per antipodal pair.
    """
    V, F = icosahedron()
    F6 = F % 6
    key = np.sort(F6, axis=1)
    _, first = np.unique(key, axis=0, return_index=True)
    return _mesh(V[:6], F6[np.sort(first)])


def klein_bottle(m: int = 24, n: int = 12, R: float = 2.0):
    """The figure-8 immersion of the Klein bottle, m × n vertices (n even), triangulated.

    (u, v) ~ (u + 2π, −v); vertex columns sit at v_j = 2π (j + ½)/n so that the identification
    maps column j to n − 1 − j and no two vertices coincide on the self-intersection circle.
    """
    _check_grid(m=(m, 3), n=(n, 4))
    u, v = np.meshgrid(2 * np.pi * np.arange(m) / m, 2 * np.pi * (np.arange(n) + 0.5) / n, indexing="ij")
    w = np.cos(u / 2) * np.sin(v) - np.sin(u / 2) * np.sin(2 * v)
    V = np.stack([(R + w) * np.cos(u), (R + w) * np.sin(u),
                  np.sin(u / 2) * np.sin(v) + np.cos(u / 2) * np.sin(2 * v)], -1)
    return _mesh(V.reshape(-1, 3), triangulate(grid_quads(m, n, True, True, twist=True)))


def _voxel_boundary(occupied: np.ndarray):
    """Outward-oriented boundary squares of a union of unit voxels, triangulated."""
    padded = np.pad(occupied, 1)
    quads = []
    corners = {  # square of the face in direction ±axis, counter-clockwise seen from outside
        (0, 1): [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)], (0, -1): [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],
        (1, 1): [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)], (1, -1): [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],
        (2, 1): [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], (2, -1): [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],
    }
    cells = np.argwhere(padded)
    for (axis, step), square in corners.items():
        shift = np.zeros(3, dtype=int)
        shift[axis] = step
        nb = cells + shift
        open_side = ~padded[nb[:, 0], nb[:, 1], nb[:, 2]]
        quads.append(cells[open_side][:, None, :] + np.array(square)[None])
    points = np.concatenate(quads).reshape(-1, 3)
    V, F = np.unique(points, axis=0, return_inverse=True)
    return _mesh(V - 1.0, triangulate(F.reshape(-1, 4)))


def double_torus():
    """A genus-2 polycube: the boundary of a 3 × 5 × 1 slab of unit cubes with two cubes
    removed, triangulated (χ = −2).
    """
    occupied = np.ones((3, 5, 1), dtype=bool)
    occupied[1, 1, 0] = occupied[1, 3, 0] = False
    return _voxel_boundary(occupied)


def saddle_grid(k: int, *, noise: float = 0.1, seed: int = 0):
    """`(V, F, boundary)`: a k×k grid on [−1, 1]², two triangles per square, on the saddle
    z = (x² − y²)/4, the interior vertices' z moved by `noise` × h × N(0, 1) (h = 2/(k − 1),
    generator `seed`); `boundary` the indices of the border vertices.  The test surface of the
    minimal-surface solves (Fig 6.5)."""
    _check_grid(k=(k, 2))
    x = np.linspace(-1.0, 1.0, k)
    X, Y = np.meshgrid(x, x, indexing="ij")
    V = np.stack([X, Y, 0.25 * (X**2 - Y**2)], -1).reshape(-1, 3)
    F = _grid_triangles(k)
    border = np.zeros((k, k), bool)
    border[[0, -1], :] = border[:, [0, -1]] = True
    interior = ~border.ravel()
    V[interior, 2] += noise * (2.0 / (k - 1)) * np.random.default_rng(seed).normal(size=int(interior.sum()))
    return V, F, np.arange(k * k).reshape(k, k)[border]


def _grid_triangles(k: int) -> np.ndarray:
    """The k×k vertex grid's squares (a, b, c, d) split into (a, b, c) and (a, c, d)."""
    idx = np.arange(k * k).reshape(k, k)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def disk(rings: int = 4, m: int = 12):
    """The unit disk: a centre vertex and `rings` concentric rings of m vertices, triangulated."""
    _check_grid(rings=(rings, 1), m=(m, 3))
    t, r = np.meshgrid(2 * np.pi * np.arange(m) / m, np.arange(1, rings + 1) / rings, indexing="ij")
    V = np.vstack([[0.0, 0.0, 0.0], np.stack([r * np.cos(t), r * np.sin(t), 0 * r], -1).reshape(-1, 3)])
    first_ring = 1 + np.arange(m) * rings
    fan = np.stack([np.zeros(m, dtype=int), first_ring, np.roll(first_ring, -1)], 1)
    rings_ = 1 + grid_quads(m, rings, True, False)[:, ::-1]
    return _mesh(V, np.vstack([fan, triangulate(rings_)]))


def annulus(m: int = 16, n: int = 3, r_in: float = 0.5, r_out: float = 1.0):
    """The planar annulus r_in ≤ |x| ≤ r_out, m × n vertices, triangulated (two boundary loops)."""
    _check_grid(m=(m, 3), n=(n, 2))
    t, r = np.meshgrid(2 * np.pi * np.arange(m) / m, np.linspace(r_in, r_out, n), indexing="ij")
    V = np.stack([r * np.cos(t), r * np.sin(t), 0 * r], -1).reshape(-1, 3)
    return _mesh(V, triangulate(grid_quads(m, n, True, False)[:, ::-1]))


def mobius_strip(m: int = 24, n: int = 4, width: float = 0.6):
    """A Möbius strip of centre radius 1: m × n vertices, (m, j) glued to (0, n − 1 − j)."""
    _check_grid(m=(m, 3), n=(n, 2))
    u, w = np.meshgrid(2 * np.pi * np.arange(m) / m, np.linspace(-width / 2, width / 2, n), indexing="ij")
    V = np.stack([(1 + w * np.cos(u / 2)) * np.cos(u), (1 + w * np.cos(u / 2)) * np.sin(u), w * np.sin(u / 2)], -1)
    return _mesh(V.reshape(-1, 3), triangulate(grid_quads(m, n, True, False, twist=True)))


def unit_square(n: int):
    """`(V, F, boundary)`: the unit square in the plane z = 0 cut into n × n squares, each split
    into two right triangles (a Delaunay triangulation: every cotan weight is ≥ 0)."""
    s = np.linspace(0.0, 1.0, n + 1)
    x, y = np.repeat(s, n + 1), np.tile(s, n + 1)
    V = np.stack([x, y, np.zeros_like(x)], 1)
    F = triangulate(grid_quads(n + 1, n + 1, False, False))
    return V, F, np.flatnonzero((x == 0) | (x == 1) | (y == 0) | (y == 1))


def cylinder(n: int, R: float = 1.0, H: float = 0.5):
    """`(V, F)`: n + 1 circles of 3n vertices on the cylinder of radius R over |z| ≤ H, the start
    of Fig 6.5 for the catenoid spanned by its two boundary circles (edge length h ∝ 1/n)."""
    V, F = annulus(3 * n, n + 1, 1.0, 2.0)
    angle, s = np.arctan2(V[:, 1], V[:, 0]), np.linalg.norm(V[:, :2], axis=1) - 1.0
    return np.stack([R * np.cos(angle), R * np.sin(angle), H * (2.0 * s - 1.0)], 1), F


def stretched_sphere(level: int = 2, stretch=(6.0, 1.0, 0.5), bumps: float = 0.0, seed: int = 0):
    """`(V, F)`: the icosphere stretched into a skinny ellipsoid (many non-Delaunay edges), its
    radii scaled by 1 + `bumps` · N(0, 1) (bumps > 0 breaks the symmetries that make quadrilaterals
    cocircular)."""
    V, F = icosphere(level)
    noise = 1.0 + bumps * np.random.default_rng(seed).standard_normal((len(V), 1))
    return V * np.asarray(stretch) * noise, F


def tall_dome(seed: int = 0, n_inner: int = 150, m: int = 32, stretch: float = 5.0, height: float = 3.0,
              wave: float = 0.0):
    """`(V, F, boundary)`: a start unsuited to its minimal surface (Fig 7.26).  Points in the unit
    disk (m on the circle, `n_inner` random inside), triangulated by the planar Delaunay
    triangulation of the points squeezed by `stretch` in y (long skinny triangles), lifted to the
    dome z = height (1 − r²) + wave r² cos 2φ over the boundary curve z = wave cos 2φ, which
    stays fixed (for wave = 0 the minimal surface is the flat m-gon)."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(m) / m
    r, a = np.sqrt(rng.uniform(0, 0.8, n_inner)), rng.uniform(0, 2 * np.pi, n_inner)
    P = np.vstack([np.stack([np.cos(t), np.sin(t)], 1), np.stack([r * np.cos(a), r * np.sin(a)], 1)])
    F = Delaunay(P * np.array([1.0, stretch])).simplices
    u, w = P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]
    clockwise = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0] < 0
    F[clockwise] = F[clockwise][:, [0, 2, 1]]
    rho2, phi = np.sum(P**2, axis=1), np.arctan2(P[:, 1], P[:, 0])
    return np.column_stack([P, height * (1 - rho2) + wave * rho2 * np.cos(2 * phi)]), F, np.arange(m)


def _ring_band(inner: np.ndarray, outer: np.ndarray) -> np.ndarray:
    """The triangles of the band between two rings of m vertex indices (inner → outer)."""
    i = np.arange(inner.size)
    j = np.roll(i, -1)
    return np.concatenate([np.stack([inner[i], outer[i], outer[j]], 1), np.stack([inner[i], outer[j], inner[j]], 1)])


def _capped_rings(centre: int, rings: list) -> np.ndarray:
    """A fan around `centre` to the first ring, then the bands between consecutive rings."""
    first = rings[0]
    fan = np.stack([np.full(first.size, centre), first, np.roll(first, -1)], 1)
    return np.concatenate([fan] + [_ring_band(a, b) for a, b in zip(rings[:-1], rings[1:])])


def double_bubble(m: int = 24, k: int = 6, k_wall: int = 4, radius: float = 1.0):
    """The standard double bubble of two equal chambers, sampled: `(V, F, chambers)`.

    Two spheres of radius r = `radius` with centres (∓r/2, 0, 0), each without the cap beyond
    the plane x = 0, and the flat disk of radius (√3/2) r in that plane (the wall): three sheets
    meeting at 120° along the junction circle (Plateau's laws), each chamber of volume 9πr³/8.
    Each cap is a pole, k − 1 rings at polar angles 120° j/k about its centre and the junction
    ring; the wall a centre and k_wall − 1 rings; every ring has m vertices.  The edges on the
    junction lie in three faces: the mesh is not a manifold there.

    `chambers` (nf, 2): +1 where the face's normal (v1 − v0) × (v2 − v0) points out of chamber
    c, −1 where into it, 0 where the face does not bound it (the caps' normals point outwards,
    the wall's along +x: out of chamber 0, into chamber 1), so that the volume of chamber c is
    Σ_f chambers[f, c] det(V[F[f]])/6 (`energies.area.with_volumes`).
    """
    _check_grid(m=(m, 3), k=(k, 2), k_wall=(k_wall, 1))
    theta = 2 * np.pi * np.arange(m) / m
    circle = np.stack([np.zeros(m), np.cos(theta), np.sin(theta)], 1)
    points, count = [], [0]

    def add(P):
        points.append(np.atleast_2d(P))
        count[0] += len(points[-1])
        return np.arange(count[0] - len(points[-1]), count[0])

    junction = add(np.sqrt(3.0) / 2.0 * radius * circle)
    faces, chambers = [], []
    for side, chamber in ((-1.0, (1, 0)), (1.0, (0, 1))):
        centre = np.array([side * radius / 2.0, 0.0, 0.0])
        pole = add(centre + [side * radius, 0.0, 0.0])[0]
        rings = []
        for j in range(1, k):
            phi = (2.0 * np.pi / 3.0) * j / k
            rings.append(add(centre + radius * (np.cos(phi) * np.array([side, 0.0, 0.0]) + np.sin(phi) * circle)))
        cap = _capped_rings(pole, rings + [junction])
        faces.append(cap[:, ::-1] if side < 0 else cap)  # normals away from the centre
        chambers.append(np.tile(chamber, (len(cap), 1)))
    centre = add(np.zeros(3))[0]
    rings = [add(np.sqrt(3.0) / 2.0 * radius * j / k_wall * circle) for j in range(1, k_wall)]
    wall = _capped_rings(centre, rings + [junction])  # normals along +x
    faces.append(wall)
    chambers.append(np.tile((1, -1), (len(wall), 1)))
    V, F = _mesh(np.concatenate(points), np.concatenate(faces))
    return V, F, np.concatenate(chambers).astype(np.float64)
