"""Halfedge arrays (connectivity): invariants, polygons, non-orientable input, and validation."""

import numpy as np
import pytest

from ddgjax import mesh
from ddgjax.errors import DDGError, MeshError, NonManifoldError, ShapeError

MESHES = ["tetrahedron", "cube", "octahedron", "icosphere", "torus", "projective_plane", "klein_bottle",
          "double_torus", "disk", "annulus", "mobius_strip"]


@pytest.mark.parametrize("name", MESHES)
def test_halfedge_invariants(name):
    """next is a permutation cycling within faces, twin an involution between halfedges of one
    edge, and 2|E| − |boundary halfedges| = number of halfedges (each corner is a halfedge).
    """
    V, F = getattr(mesh, name)()
    h = mesh.from_faces(F)
    nh = h.vertex.size
    assert np.array_equal(np.sort(h.next), np.arange(nh))
    assert np.array_equal(h.face[h.next], h.face)
    assert np.array_equal(h.prev[h.next], np.arange(nh))
    inner = h.twin >= 0
    assert np.array_equal(h.twin[h.twin[inner]], np.flatnonzero(inner))
    assert np.array_equal(h.edge[h.twin[inner]], h.edge[inner])
    assert 2 * h.n_edges - np.count_nonzero(~inner) == nh
    tail = np.where(h.sign > 0, h.vertex, h.head)
    assert np.array_equal(h.edges[h.edge, 0], tail)


def test_polygons_of_mixed_size():
    """A square pyramid given as a list (one quad, four triangles): 5 − 8 + 5 = 2."""
    F = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    h = mesh.from_faces(F)
    assert (h.vertex.size, h.n_edges, h.n_faces) == (16, 8, 5)
    assert mesh.euler_characteristic(F) == 2


def test_inputs_are_not_mutated():
    V, F = mesh.mobius_strip()
    F0 = F.copy()
    mesh.classify(F)
    mesh.angle_defect(V, F)
    assert np.array_equal(F, F0)


def test_out_of_range_index_names_the_face():
    V, F = mesh.tetrahedron()
    F = F.copy()
    F[2, 1] = 7
    with pytest.raises(MeshError, match="face 2 .* 7"):
        mesh.angle_defect(V, F)
    F[2, 1] = -1
    with pytest.raises(MeshError, match="face 2 .*negative"):
        mesh.from_faces(F)


def test_repeated_vertex_names_the_face():
    with pytest.raises(MeshError, match="face 1 repeats the vertex 3"):
        mesh.from_faces([[0, 1, 2], [3, 1, 3]])


def test_non_manifold_edge_names_vertices_and_faces():
    """Three triangles on the edge (0, 1)."""
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(NonManifoldError, match=r"\(0, 1\) lies in 3 faces \[0, 1, 2\]"):
        mesh.from_faces(F)


def test_non_manifold_vertex_is_named():
    """Two tetrahedra sharing only vertex 0 (a bow tie of two spheres)."""
    _, T = mesh.tetrahedron()
    F = np.vstack([T, np.where(T == 0, 0, T + 3)])
    with pytest.raises(NonManifoldError, match="vertex 0 is non-manifold: .* 2 fans"):
        mesh.from_faces(F)


def test_bow_tie_vertex_with_boundary_is_named():
    """Two triangles touching only at vertex 2."""
    with pytest.raises(NonManifoldError, match="vertex 2 is non-manifold"):
        mesh.from_faces(np.array([[0, 1, 2], [2, 3, 4]]))


def test_inconsistent_orientation_is_not_an_error():
    """A tetrahedron with one face reversed is still a sphere; `orient` repairs it."""
    _, F = mesh.tetrahedron()
    G = F.copy()
    G[1] = G[1, ::-1]
    assert mesh.classify(G) == mesh.classify(F)
    fixed = mesh.orient(G)
    h = mesh.from_faces(fixed)
    assert np.all(h.sign != h.sign[h.twin])


def test_errors_are_ddg_errors():
    with pytest.raises(DDGError):
        mesh.from_faces(np.zeros((3, 1), dtype=int))
    with pytest.raises(ShapeError):
        mesh.from_faces([[0, 1, 2], [3]])
    with pytest.raises(MeshError, match="non-integer"):
        mesh.from_faces(np.array([[0, 1, 2.5]]))
