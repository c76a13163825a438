"""Discrete surfaces: connectivity, topology (Sec 4) and polyhedral curvature (Sec 5.2, 5.3).

Faces `F` are an (nf, k) int array or a list of polygons (vertex index lists); topology also takes
a gluing word ("abAB") or `Halfedges`.  Surfaces may be non-orientable and have boundary.

- connectivity: `Halfedges`, `from_faces`, `from_gluing`, `edges`
- topology: `euler_characteristic`, `connected_components`, `is_orientable`, `orient`,
  `boundary_loops`, `genus`, `crosscaps`, `classification`, `classify`, `is_regular`,
  `is_strongly_regular`
- gluing: `from_word`, `connected_sum`, `normal_form`
- builtin: `tetrahedron`, `cube`, `octahedron`, `icosahedron`, `icosphere`, `torus`,
  `projective_plane`, `klein_bottle`, `double_torus`, `disk`, `annulus`, `mobius_strip`
- curvature: `corner_angles`, `angle_defect`, `vertex_kind`, `surface_area`, `dihedral_angles`,
  `edge_mean_curvature`, `total_mean_curvature`, `steiner_area`
- intrinsic_angles: `edge_lengths`, `corner_angles_from_lengths`, `angle_defect_from_lengths`
- io: `read`, `write` (meshio)
"""

from .builtin import (
    annulus as annulus,
    cube as cube,
    disk as disk,
    double_torus as double_torus,
    icosahedron as icosahedron,
    icosphere as icosphere,
    klein_bottle as klein_bottle,
    mobius_strip as mobius_strip,
    octahedron as octahedron,
    projective_plane as projective_plane,
    tetrahedron as tetrahedron,
    torus as torus,
    triangulate as triangulate,
)
from .connectivity import Halfedges as Halfedges, edges as edges, from_faces as from_faces, from_gluing as from_gluing
from .curvature import (
    angle_defect as angle_defect,
    corner_angles as corner_angles,
    dihedral_angles as dihedral_angles,
    edge_mean_curvature as edge_mean_curvature,
    face_area_vectors as face_area_vectors,
    steiner_area as steiner_area,
    surface_area as surface_area,
    total_mean_curvature as total_mean_curvature,
    vertex_kind as vertex_kind,
)
from .gluing import connected_sum as connected_sum, from_word as from_word, normal_form as normal_form
from .intrinsic_angles import (
    angle_defect_from_lengths as angle_defect_from_lengths,
    corner_angles_from_lengths as corner_angles_from_lengths,
    edge_lengths as edge_lengths,
)
from .io import read as read, write as write
from .topology import (
    Classification as Classification,
    boundary_loops as boundary_loops,
    classification as classification,
    classify as classify,
    connected_components as connected_components,
    crosscaps as crosscaps,
    euler_characteristic as euler_characteristic,
    genus as genus,
    is_orientable as is_orientable,
    is_regular as is_regular,
    is_strongly_regular as is_strongly_regular,
    orient as orient,
)
