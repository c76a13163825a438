"""Discrete surfaces: connectivity, topology (Sec 4) and polyhedral curvature (Sec 5.2, 5.3).

Faces `F` are an (nf, k) int array or a list of polygons (vertex index lists); topology also takes
a gluing word ("abAB") or `Halfedges`.  Surfaces may be non-orientable and have boundary.

- connectivity: `Halfedges` (the one connectivity type, also of the intrinsic triangulations),
  `from_faces`, `from_gluing`, `from_twins`, `edges`, `boundary_vertices`, `boundary_indices`
- topology: `euler_characteristic`, `connected_components`, `is_orientable`, `orient`,
  `boundary_loops`, `genus`, `crosscaps`, `classification`, `classify`, `is_regular`,
  `is_strongly_regular`
- gluing: `from_word`, `connected_sum`, `normal_form`
- builtin: `saddle_grid`, `tetrahedron`, `cube`, `octahedron`, `icosahedron`, `icosphere`, `torus`,
  `projective_plane`, `klein_bottle`, `double_torus`, `disk`, `annulus`, `mobius_strip`,
  `double_bubble` (with its chambers)
- curvature: `corner_angles`, `angle_defect`, `vertex_kind`, `surface_area`, `dihedral_angles`,
  `edge_mean_curvature`, `total_mean_curvature`, `steiner_area`
- lengths (geometry from edge lengths alone): `edge_lengths`, `triangle_area`,
  `corner_angles_from_lengths`, `angle_defect_from_lengths`, `corner_cotangents`,
  `dirichlet_energy`, `stiffness`
- io: `read`, `write` (meshio)
- subdivision: `subdivide` (midpoint or Loop, old vertices first), `subdivision_matrix` (the
  sparse prolongation S, V' = S V, also for warm starts)
- cleanup (each returns `(V, F, CleanupReport)`): `remove_unreferenced_vertices`, `weld_vertices`,
  `split_nonmanifold_vertices`, `drop_degenerate_faces`
"""

from . import lengths as lengths
from .builtin import (
    annulus as annulus,
)
from .builtin import (
    cube as cube,
)
from .builtin import (
    disk as disk,
)
from .builtin import (
    double_bubble as double_bubble,
)
from .builtin import (
    double_torus as double_torus,
)
from .builtin import (
    icosahedron as icosahedron,
)
from .builtin import (
    icosphere as icosphere,
)
from .builtin import (
    klein_bottle as klein_bottle,
)
from .builtin import (
    mobius_strip as mobius_strip,
)
from .builtin import (
    octahedron as octahedron,
)
from .builtin import (
    projective_plane as projective_plane,
)
from .builtin import (
    saddle_grid as saddle_grid,
)
from .builtin import (
    tetrahedron as tetrahedron,
)
from .builtin import (
    torus as torus,
)
from .builtin import (
    triangulate as triangulate,
)
from .cleanup import (
    CleanupReport as CleanupReport,
)
from .cleanup import (
    drop_degenerate_faces as drop_degenerate_faces,
)
from .cleanup import (
    remove_unreferenced_vertices as remove_unreferenced_vertices,
)
from .cleanup import (
    split_nonmanifold_vertices as split_nonmanifold_vertices,
)
from .cleanup import (
    weld_vertices as weld_vertices,
)
from .connectivity import (
    Halfedges as Halfedges,
)
from .connectivity import (
    boundary_indices as boundary_indices,
)
from .connectivity import (
    boundary_vertices as boundary_vertices,
)
from .connectivity import (
    edges as edges,
)
from .connectivity import (
    from_faces as from_faces,
)
from .connectivity import (
    from_gluing as from_gluing,
)
from .connectivity import (
    from_twins as from_twins,
)
from .curvature import (
    angle_defect as angle_defect,
)
from .curvature import (
    corner_angles as corner_angles,
)
from .curvature import (
    dihedral_angles as dihedral_angles,
)
from .curvature import (
    edge_mean_curvature as edge_mean_curvature,
)
from .curvature import (
    face_area_vectors as face_area_vectors,
)
from .curvature import (
    steiner_area as steiner_area,
)
from .curvature import (
    surface_area as surface_area,
)
from .curvature import (
    total_mean_curvature as total_mean_curvature,
)
from .curvature import (
    vertex_kind as vertex_kind,
)
from .gluing import connected_sum as connected_sum
from .gluing import from_word as from_word
from .gluing import normal_form as normal_form
from .io import read as read
from .io import write as write
from .lengths import (
    angle_defect_from_lengths as angle_defect_from_lengths,
)
from .lengths import (
    corner_angles_from_lengths as corner_angles_from_lengths,
)
from .lengths import (
    edge_lengths as edge_lengths,
)
from .subdivision import subdivide as subdivide
from .subdivision import subdivision_matrix as subdivision_matrix
from .topology import (
    Classification as Classification,
)
from .topology import (
    boundary_loops as boundary_loops,
)
from .topology import (
    classification as classification,
)
from .topology import (
    classify as classify,
)
from .topology import (
    connected_components as connected_components,
)
from .topology import (
    crosscaps as crosscaps,
)
from .topology import (
    euler_characteristic as euler_characteristic,
)
from .topology import (
    genus as genus,
)
from .topology import (
    is_orientable as is_orientable,
)
from .topology import (
    is_regular as is_regular,
)
from .topology import (
    is_strongly_regular as is_strongly_regular,
)
from .topology import (
    orient as orient,
)
