"""Topology of surfaces (Sec 4: Thm 4.1, Cor 4.2)."""

from __future__ import annotations

from ddgjax import mesh
from ddgjax.verify import check

# built-in mesh -> (χ, orientable, genus or number of cross-caps, boundary components, name)
BUILTIN = {
    "tetrahedron": (2, True, 0, 0, "sphere"), "cube": (2, True, 0, 0, "sphere"),
    "octahedron": (2, True, 0, 0, "sphere"), "icosahedron": (2, True, 0, 0, "sphere"),
    "icosphere": (2, True, 0, 0, "sphere"), "torus": (0, True, 1, 0, "torus"),
    "projective_plane": (1, False, 1, 0, "projective plane"), "klein_bottle": (0, False, 2, 0, "Klein bottle"),
    "double_torus": (-2, True, 2, 0, "double torus"), "disk": (1, True, 0, 1, "disk"),
    "annulus": (0, True, 0, 2, "annulus"), "mobius_strip": (0, False, 1, 1, "Möbius strip"),
}


@check("Thm 4.1, Cor 4.2", "every built-in mesh is classified as the surface it is (χ, orientability, genus, boundary)",
       quantity="number of misclassified meshes (by `classification` or by any of the single invariants)", at_most=0,
       quick=dict())
def builtin_meshes_classified(ctx):
    wrong = 0
    for name, expected in BUILTIN.items():
        F = getattr(mesh, name)()[1]
        c = mesh.classification(F)
        single = (mesh.euler_characteristic(F), mesh.is_orientable(F), mesh.genus(F), len(mesh.boundary_loops(F)))
        wrong += ((c.euler_characteristic, c.orientable, c.genus, c.boundary_components, c.name) != expected
                  or single != expected[:4] or expected[4] not in mesh.classify(F))
    return wrong


@check("Thm 4.1", "χ = 2 − 2g − b (orientable) and χ = 2 − g − b (non-orientable) on every built-in mesh",
       quantity="max |χ − formula|", at_most=0, quick=dict())
def euler_characteristic_formula(ctx):
    worst = 0
    for name, (_, orientable, g, b, _) in BUILTIN.items():
        F = getattr(mesh, name)()[1]
        formula = 2 - 2 * g - b if orientable else 2 - g - b
        worst = max(worst, abs(mesh.euler_characteristic(F) - formula))
    return worst


@check("Sec 4.2", "the connected sum of polygon words has χ(M # N) = χ(M) + χ(N) − 2 and is orientable iff M and N are",
       quantity="max |χ(M # N) − χ(M) − χ(N) + 2| over pairs of words + number of pairs with the wrong orientability",
       at_most=0, quick=dict())
def connected_sum_euler_characteristic(ctx):
    words = ["aA", "aa", "abAB", "abaB", "abcabc"]
    chi = {w: mesh.euler_characteristic(mesh.from_word(w)) for w in words}
    orientable = {w: mesh.is_orientable(w) for w in words}
    sums = {(u, w): mesh.connected_sum(u, w) for u in words for w in words}
    defect = max(abs(mesh.euler_characteristic(mesh.from_word(s)) - chi[u] - chi[w] + 2) for (u, w), s in sums.items())
    return defect + sum(mesh.is_orientable(s) != (orientable[u] and orientable[w]) for (u, w), s in sums.items())
