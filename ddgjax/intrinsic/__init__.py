"""Piecewise flat surfaces and intrinsic Delaunay triangulations (Sec 5.3, 7 of the reference).

- triangulation: `Triangulation` = connectivity (`ddgjax.mesh.Halfedges`: a gluing of triangles
  admitting loops, multiple edges and self-glued triangles) + edge lengths; `from_faces`,
  `from_mesh`, `from_gluing`, `corner_angles`, `cone_angles`, `angle_defects`, `cotan_weights`,
  `unfold` (the geometry is `ddgjax.mesh.lengths`)
- geometry: unfolding two triangles into the plane (the length of a flipped edge)
- flips: `flip` (Lemma 5.8), `is_flippable`
- delaunay: `is_delaunay`, `delaunay_edges` (Prop 7.9), `harmonic_index` (Def 7.7),
  `flip_to_delaunay` (Fig 7.13) -> `FlipResult`
- rippa: Rippa's formula (Lemma 7.14), circularity (Lemma 7.15)
- laplace_beltrami: `laplace_beltrami(V, F)` (Def 7.8), `cotan_laplacian`, `delaunay_tessellation`

Minimal surfaces in the narrow sense (Def 7.9, Fig 7.23) are computed by
`energies.area.minimal_surface(..., method="delaunay")` / `energies.area.harmonic_iteration`.
"""

from . import rippa as rippa
from .delaunay import (
    FlipResult as FlipResult,
)
from .delaunay import (
    delaunay_edges as delaunay_edges,
)
from .delaunay import (
    edge_cotangent_sums as edge_cotangent_sums,
)
from .delaunay import (
    flip_to_delaunay as flip_to_delaunay,
)
from .delaunay import (
    harmonic_index as harmonic_index,
)
from .delaunay import (
    is_delaunay as is_delaunay,
)
from .flips import flip as flip
from .flips import is_flippable as is_flippable
from .laplace_beltrami import (
    Tessellation as Tessellation,
)
from .laplace_beltrami import (
    cotan_laplacian as cotan_laplacian,
)
from .laplace_beltrami import (
    cotan_weights as cotan_weights,
)
from .laplace_beltrami import (
    delaunay_tessellation as delaunay_tessellation,
)
from .laplace_beltrami import (
    laplace_beltrami as laplace_beltrami,
)
from .laplace_beltrami import (
    laplace_beltrami_from_lengths as laplace_beltrami_from_lengths,
)
from .triangulation import (
    Triangulation as Triangulation,
)
from .triangulation import (
    angle_defects as angle_defects,
)
from .triangulation import (
    cone_angles as cone_angles,
)
from .triangulation import (
    corner_angles as corner_angles,
)
from .triangulation import (
    from_faces as from_faces,
)
from .triangulation import (
    from_gluing as from_gluing,
)
from .triangulation import (
    from_mesh as from_mesh,
)
from .triangulation import (
    unfold as unfold,
)
