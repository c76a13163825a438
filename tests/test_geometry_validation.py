"""Bad geometric input is an error that names what is wrong, never a silent NaN or a wrong answer:
tolerances that are NaN, infinite or ≤ 0; empty meshes; coincident vertices and faces of zero
area in the curvature functions (Def 5.2, 5.3, 6.2); NaN, infinite, zero or negative edge
lengths in the functions of edge lengths (Def 5.5); results that are not float64 numbers."""

from __future__ import annotations

import numpy as np
import pytest

from ddgjax import curves, intrinsic, laplace, mesh
from ddgjax.errors import (
    DegenerateFaceError,
    InvalidInputError,
    MeshError,
    NonFiniteError,
    SingularVertexError,
    TriangleInequalityError,
)
from ddgjax.intrinsic import rippa
from ddgjax.intrinsic import triangulation as T
from ddgjax.intrinsic.flips import is_flippable

V, F = mesh.octahedron()
LENGTHS = np.linalg.norm(V[mesh.edges(F)[:, 1]] - V[mesh.edges(F)[:, 0]], axis=1)
BAD_TOLERANCES = [np.nan, np.inf, -np.inf, 0.0, -1e-12]

TOLERANCE_CASES = {
    "flip_to_delaunay": lambda tol: intrinsic.flip_to_delaunay(F, LENGTHS, tol=tol),
    "is_delaunay": lambda tol: intrinsic.is_delaunay(F, LENGTHS, tol=tol),
    "delaunay_edges": lambda tol: intrinsic.delaunay_edges(T.from_faces(F, LENGTHS), tol),
    "laplace_beltrami": lambda tol: intrinsic.laplace_beltrami(V, F, tol=tol),
    "laplace_beltrami_from_lengths": lambda tol: intrinsic.laplace_beltrami_from_lengths(F, LENGTHS, tol=tol),
    "delaunay_tessellation": lambda tol: intrinsic.delaunay_tessellation(T.from_faces(F, LENGTHS), zero_tol=tol),
    "vertex_kind": lambda tol: mesh.vertex_kind(V, F, atol=tol),
    "is_arc_length": lambda tol: curves.is_arc_length(V[:4], tol=tol),
    "check_arc_length": lambda tol: curves.check_arc_length(V[:4], tol=tol),
    "is_circular": lambda tol: rippa.is_circular([1.0, 1.0, 1.0, 1.0], rtol=tol),
}


@pytest.mark.parametrize("tol", BAD_TOLERANCES)
@pytest.mark.parametrize("name", sorted(TOLERANCE_CASES))
def test_bad_tolerances_are_rejected(name, tol):
    """`flip_to_delaunay(tol=nan)` used to report "Delaunay" after 0 flips."""
    with pytest.raises(InvalidInputError, match="tol must be finite and positive"):
        TOLERANCE_CASES[name](tol)


@pytest.mark.parametrize("margin", [np.nan, -0.1, 0.5])
def test_flip_margin_is_checked(margin):
    with pytest.raises(InvalidInputError, match="margin"):
        is_flippable(T.from_faces(F, LENGTHS), 0, margin=margin)


EMPTY_V, EMPTY_F = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
EMPTY_CASES = {
    "classify": lambda: mesh.classify([]),
    "classify (nf, 3)": lambda: mesh.classify(EMPTY_F),
    "genus": lambda: mesh.genus([]),
    "crosscaps": lambda: mesh.crosscaps([]),
    "angle_defect": lambda: mesh.angle_defect(EMPTY_V, EMPTY_F),
    "total_mean_curvature": lambda: mesh.total_mean_curvature(EMPTY_V, EMPTY_F),
    "cotan_laplacian": lambda: laplace.cotan_laplacian(EMPTY_V, EMPTY_F),
    "triangulation": lambda: T.from_faces(EMPTY_F, []),
    "laplace_beltrami": lambda: intrinsic.laplace_beltrami(EMPTY_V, EMPTY_F),
}


@pytest.mark.parametrize("name", sorted(EMPTY_CASES))
def test_empty_meshes_are_not_surfaces(name):
    """Def 4.1: `classify([])` used to answer "torus" (χ = 0, no boundary)."""
    with pytest.raises(MeshError, match="no faces"):
        EMPTY_CASES[name]()


def _with(vertex: int, position) -> np.ndarray:
    W = V.copy()
    W[vertex] = position
    return W


COINCIDENT = _with(0, V[2])  # vertices 0 and 2 share edge 0 and face 0
COLLINEAR = _with(4, 0.5 * (V[0] + V[2]))  # face 0 = [0, 2, 4] becomes a segment
CURVATURE = {
    "corner_angles": mesh.corner_angles,
    "angle_defect": mesh.angle_defect,
    "vertex_kind": mesh.vertex_kind,
    "dihedral_angles": mesh.dihedral_angles,
    "edge_mean_curvature": mesh.edge_mean_curvature,
    "total_mean_curvature": mesh.total_mean_curvature,
    "steiner_area": lambda V, F: mesh.steiner_area(V, F, 0.1),
}
NEEDS_NORMALS = ["dihedral_angles", "edge_mean_curvature", "total_mean_curvature", "steiner_area"]


@pytest.mark.parametrize("name", sorted(CURVATURE))
def test_coincident_vertices_are_named(name):
    """Two vertices of an edge at one point: the angles there are undefined (NaN before)."""
    with pytest.raises(SingularVertexError, match=r"vertices 0 and 2 coincide \(edge 0 of face 0"):
        CURVATURE[name](COINCIDENT, F)


def test_coincident_vertices_of_polygons_are_named():
    Vc, Fc = mesh.cube()
    Vc[1] = Vc[0]
    with pytest.raises(SingularVertexError, match="vertices 0 and 1 coincide"):
        mesh.angle_defect(Vc, [list(f) for f in Fc])


@pytest.mark.parametrize("name", NEEDS_NORMALS)
def test_faces_of_zero_area_are_named_where_normals_are_used(name):
    """A collinear triangle has no normal: the dihedral angles of its edges are undefined."""
    with pytest.raises(DegenerateFaceError, match=r"face 0 \[0, 2, 4\] has zero area"):
        CURVATURE[name](COLLINEAR, F)


def test_collinear_triangles_have_the_limit_angles():
    """Angles need no normal: a collinear triangle with distinct vertices has the angles 0, 0, π
    (the limit of flattening triangles), so angle defects are defined and Gauss–Bonnet holds."""
    angles = np.asarray(mesh.corner_angles(COLLINEAR, F))
    assert np.allclose(angles[0], [0.0, 0.0, np.pi], rtol=0, atol=1e-15)
    K = np.asarray(mesh.angle_defect(COLLINEAR, F))
    assert np.all(np.isfinite(K)) and abs(K.sum() - 4 * np.pi) <= 1e-12


@pytest.mark.parametrize("W", [COINCIDENT, COLLINEAR], ids=["coincident", "collinear"])
def test_cotan_laplacian_names_the_degenerate_face(W):
    """Sec 6.3: the cotangents of a face of zero area are undefined."""
    with pytest.raises(DegenerateFaceError, match=r"face 0 \[0, 2, 4\] has zero area"):
        laplace.cotan_laplacian(W, F)


NON_FINITE_V = _with(3, [0.0, np.nan, 0.0])


@pytest.mark.parametrize("name", sorted(CURVATURE) + ["surface_area", "face_area_vectors"])
def test_non_finite_coordinates_are_named(name):
    f = CURVATURE.get(name, getattr(mesh, name))
    with pytest.raises(NonFiniteError, match=r"index \(3, 1\)"):
        f(NON_FINITE_V, F)


LENGTH_CASES = {
    "corner_angles_from_lengths": lambda l: mesh.corner_angles_from_lengths(F, l),
    "angle_defect_from_lengths": lambda l: mesh.angle_defect_from_lengths(F, l),
    "triangulation": lambda l: T.from_faces(F, l),
    "flip_to_delaunay": lambda l: intrinsic.flip_to_delaunay(F, l),
    "is_delaunay": lambda l: intrinsic.is_delaunay(F, l),
    "laplace_beltrami_from_lengths": lambda l: intrinsic.laplace_beltrami_from_lengths(F, l),
}


@pytest.mark.parametrize("bad, error", [(np.nan, NonFiniteError), (np.inf, NonFiniteError),
                                        (0.0, TriangleInequalityError), (-1.0, TriangleInequalityError)])
@pytest.mark.parametrize("name", sorted(LENGTH_CASES))
def test_bad_edge_lengths_are_named(name, bad, error):
    """A NaN or negative length used to give NaN angles (or pass as a triangle)."""
    lengths = LENGTHS.copy()
    lengths[5] = bad
    with pytest.raises(error, match="edge 5 has the non"):
        LENGTH_CASES[name](lengths)


@pytest.mark.parametrize("s, name", [(1e160, "face_areas"), (1e-160, "face_areas"), (1e160, "surface_area"),
                                     (1e-200, "barycentric_areas"), (1e200, "face_area_vectors")])
def test_areas_that_are_not_float64_numbers_are_errors(s, name):
    """Areas scale by s² (Sec 6.3): at coordinates beyond ~1e±154 they over- or underflow; the
    answer is an error, never inf or 0."""
    f = getattr(laplace, name, None) or getattr(mesh, name)
    with pytest.raises(InvalidInputError, match="outside the normal range of float64"):
        f(V * s, F)


def test_scale_invariant_results_at_the_same_scales_are_fine():
    """The same meshes' angles and cotan weights are the unit-scale ones (no error)."""
    for s in (1e160, 1e-160, 1e300, 1e-300):
        assert np.allclose(np.asarray(mesh.angle_defect(V * s, F)), 2 * np.pi / 3, rtol=0, atol=1e-14)
        assert np.allclose(laplace.cotan_laplacian(V * s, F).toarray(), laplace.cotan_laplacian(V, F).toarray(),
                           rtol=0, atol=1e-14)
