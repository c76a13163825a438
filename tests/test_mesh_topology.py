"""Topology of cell decompositions (Sec 4): χ, orientability, boundary, classification (Thm 4.1,
Cor 4.2, Remark 4.6), regularity (Def 4.4), polygon words and connected sums.  The classification
of the built-in meshes and χ of connected sums are `ddgjax verify` checks (`sec4_topology`).
"""

import numpy as np
import pytest

from ddgjax import mesh
from ddgjax.errors import MeshError, NonManifoldError, OrientationError


def test_hemi_icosahedron_counts():
    """The 6-vertex projective plane: 6 − 15 + 10 = 1, and it is strongly regular."""
    V, F = mesh.projective_plane()
    h = mesh.from_faces(F)
    assert (V.shape[0], h.n_edges, h.n_faces) == (6, 15, 10)
    assert mesh.is_strongly_regular(F)


def test_classify_strings():
    assert mesh.classify(mesh.torus()[1]) == "orientable surface of genus 1 with 0 boundary components (torus)"
    assert mesh.classify(mesh.klein_bottle()[1]) == (
        "non-orientable surface with 2 cross-caps and 0 boundary components (Klein bottle)")


def test_boundary_loops_are_vertex_cycles():
    """The annulus boundary: two loops of m vertices, consecutive ones joined by an edge of F."""
    V, F = mesh.annulus(m=16, n=3)
    loops = mesh.boundary_loops(F)
    assert sorted(len(l) for l in loops) == [16, 16]
    E = {tuple(e) for e in mesh.edges(F).tolist()}
    for loop in loops:
        pairs = zip(loop.tolist(), np.roll(loop, -1).tolist())
        assert all(tuple(sorted(p)) in E for p in pairs)
        radii = np.linalg.norm(V[loop], axis=1)
        assert np.ptp(radii) < 1e-15
    # The Möbius strip has one boundary loop that runs twice around: 2m vertices.
    loops = mesh.boundary_loops(mesh.mobius_strip(m=24, n=4)[1])
    assert [len(l) for l in loops] == [48]


def test_several_components_are_refused_with_their_first_faces():
    _, T = mesh.tetrahedron()
    F = np.vstack([T, T + 4])
    assert mesh.euler_characteristic(F) == 4
    assert [c.tolist() for c in mesh.connected_components(F)] == [[0, 1, 2, 3], [4, 5, 6, 7]]
    with pytest.raises(MeshError, match="2 connected components .*first faces \\[0, 4\\]"):
        mesh.classify(F)
    assert mesh.classify(F[mesh.connected_components(F)[1]] - 4).endswith("(sphere)")


def test_orient_refuses_non_orientable():
    with pytest.raises(OrientationError, match="face"):
        mesh.orient(mesh.mobius_strip()[1])


# word -> (χ, orientable, name)
WORDS = {
    "aA": (2, True, "sphere"),
    "aa": (1, False, "projective plane"),
    "abAB": (0, True, "torus"),
    "abaB": (0, False, "Klein bottle"),
    "aabb": (0, False, "Klein bottle"),
    "abab": (1, False, "projective plane"),
    "abcabc": (1, False, "projective plane"),
    "abcABC": (0, True, "torus"),
    "abABcdCD": (-2, True, "double torus"),
    "aabbcc": (-1, False, "Dyck's surface"),
    "abAcdC": (0, True, "annulus"),
    "ab": (1, True, "disk"),
}


@pytest.mark.parametrize("word", WORDS)
def test_polygon_words(word):
    chi, orientable, name = WORDS[word]
    c = mesh.classification(word)
    assert (c.euler_characteristic, c.orientable, c.name) == (chi, orientable, name)


def test_word_cell_counts_bigon_and_square():
    """Fig 4.6: χ(S²) = 2 − 1 + 1, χ(RP²) = 1 − 1 + 1, χ(T²) = χ(K) = 1 − 2 + 1."""
    for word, counts in {"aA": (2, 1, 1), "aa": (1, 1, 1), "abAB": (1, 2, 1), "abaB": (1, 2, 1)}.items():
        h = mesh.from_word(word)
        assert (h.n_vertices, h.n_edges, h.n_faces) == counts


def test_rp2_sums():
    """RP² # RP² = K and K # RP² = T² # RP² (Sec 4.2), decided by Cor 4.2."""
    assert mesh.classification(mesh.connected_sum("aa", "aa")) == mesh.classification("abaB")
    assert mesh.classification(mesh.connected_sum("abaB", "aa")) == mesh.classification(mesh.connected_sum("abAB", "aa"))
    assert mesh.classification(mesh.connected_sum("abAB", "aa")).genus == 3
    assert mesh.classification("aA" + "bcBC").name == "torus"  # the sphere is the identity


@pytest.mark.parametrize("g", [0, 1, 2, 3])
def test_normal_forms(g):
    """Thm 4.1: (T²)#g has χ = 2 − 2g; (RP²)#k has χ = 2 − k."""
    assert mesh.euler_characteristic(mesh.normal_form(g)) == 2 - 2 * g
    assert mesh.genus(mesh.normal_form(g)) == g
    if g:
        assert mesh.euler_characteristic(mesh.normal_form(g, orientable=False)) == 2 - g
        assert mesh.crosscaps(mesh.normal_form(g, orientable=False)) == g


def test_bad_words():
    with pytest.raises(NonManifoldError, match="label 0 is used 3 times"):
        mesh.from_word("aaa")
    with pytest.raises(MeshError, match="non-letter '1' at side 1"):
        mesh.from_word("a1A")


def test_regularity_def_4_4():
    """Words give non-regular decompositions (one vertex, self-touching faces); a bigon disk is
    regular but its two edges share both endpoints; a two-triangle 'pillow' is regular, not
    strongly regular; so is a quad capped by two triangles whose diagonal (0, 2) meets the quad in
    two vertices only.  The built-in triangulations are strongly regular.
    """
    assert not mesh.is_regular("abAB") and not mesh.is_strongly_regular("abAB")
    assert mesh.is_regular("ab") and not mesh.is_strongly_regular("ab")
    pillow = np.array([[0, 1, 2], [0, 2, 1]])
    assert mesh.classify(pillow).endswith("(sphere)")
    assert mesh.is_regular(pillow) and not mesh.is_strongly_regular(pillow)
    capped = [[0, 3, 2, 1], [0, 1, 2], [0, 2, 3]]
    assert mesh.euler_characteristic(capped) == 2
    assert mesh.is_regular(capped) and not mesh.is_strongly_regular(capped)
    for name in ["tetrahedron", "cube", "torus", "projective_plane", "klein_bottle", "mobius_strip"]:
        assert mesh.is_strongly_regular(getattr(mesh, name)()[1]), name
