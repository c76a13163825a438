"""Exceptions raised by ddgjax.

Every error a user can trigger with bad input is a subclass of :class:`DDGError`, and its
message names the offending element: the pytree leaf and index of a bad value, the vertex,
edge or face of a bad mesh, the counts that make a problem over-constrained.  The subclasses
that describe bad *values* also derive from :class:`ValueError`, so generic handlers work.
"""

from __future__ import annotations

__all__ = [
    "DDGError",
    "InvalidInputError",
    "NonFiniteError",
    "ShapeError",
    "NotScalarError",
    "OverconstrainedError",
    "ConvergenceError",
    "ArcLengthError",
    "SingularVertexError",
    "MeshError",
    "MeshFileError",
    "NonManifoldError",
    "OrientationError",
    "TriangleInequalityError",
    "GluingError",
    "FlipBudgetError",
    "DegenerateFaceError",
    "NonUniqueSolutionError",
]


class DDGError(Exception):
    """Base class of every error ddgjax raises on purpose."""


class InvalidInputError(DDGError, ValueError):
    """An argument has the right type but a value the mathematics does not allow."""


class NonFiniteError(InvalidInputError):
    """An input contains NaN or infinity; the message names the leaf and the index."""


class ShapeError(InvalidInputError):
    """An array has the wrong shape, or two pytrees that must match do not."""


class NotScalarError(ShapeError):
    """An energy returned something other than a scalar."""


class OverconstrainedError(InvalidInputError):
    """A problem has more constraints than free unknowns."""


class ConvergenceError(DDGError, RuntimeError):
    """`solve` stopped before the KKT residual reached `tol`.

    **Attributes:**
    - `residual`: the last (scaled) max-norm KKT residual.
    - `steps`: the number of steps taken.
    - `solution`: the last iterate as a `Solution` (not converged), for inspection.
    """

    def __init__(self, message: str, *, residual: float, steps: int, solution=None):
        super().__init__(message)
        self.residual = residual
        self.steps = steps
        self.solution = solution


class ArcLengthError(InvalidInputError):
    """A curve that must be arc-length parametrised (Def 1.2) has an edge of another length.

    The message names the first offending edge and its length.
    """


class SingularVertexError(InvalidInputError):
    """A curve is singular at a vertex: successive points coincide (not regular, Def 1.2) or
    consecutive tangents are anti-parallel (turning angle π), where a formula divides by
    `1 + <T_k, T_{k-1}> = 0`.  The message names the vertex (or the coinciding vertices).
    """


class MeshError(InvalidInputError):
    """A face list or cell decomposition is not a valid surface (Def 4.3); the message names the
    offending vertex, edge or face index.
    """


class MeshFileError(MeshError):
    """A mesh file cannot be read as a surface: it is missing or unreadable, malformed or
    truncated, its header promises more data than the file holds, a coordinate is NaN or
    infinite, or a face refers to a vertex that is not there.  The message names the file and
    the offending line, vertex or face.

    **Attributes:** `path`: the file; `reason`: what is wrong with it.
    """

    def __init__(self, path, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path, self.reason = path, reason

    def __reduce__(self):
        return type(self), (self.path, self.reason)


class NonManifoldError(MeshError):
    """An edge lies in more than two faces, or the faces around a vertex form more than one fan
    (the vertex's neighbourhood is not a disk or half-disk).  The message names the edge's
    vertices and faces, or the vertex.
    """


class OrientationError(MeshError):
    """An operation needs a consistently oriented surface and the faces at an edge traverse it in
    the same direction (or the surface is not orientable).  The message names the edge.
    """


class TriangleInequalityError(MeshError):
    """Edge lengths violate a triangle inequality on some face (Sec 5.3); the message names the
    face and its three lengths.
    """


class GluingError(MeshError):
    """A gluing of triangles is inconsistent (Def 5.6): a halfedge glued to itself or to a side
    that is not glued back, an index out of range, or two glued sides of different lengths.  The
    message names the halfedge (side `i` of face `f` is halfedge `3 f + i`).
    """


class FlipBudgetError(DDGError, RuntimeError):
    """The edge-flip algorithm (Fig 7.13) used up its flip budget before every edge was Delaunay.

    Theorem 7.12 guarantees termination in exact arithmetic; the budget only guards against a
    hang.  The message names the number of flips done and an edge that is still not Delaunay.
    """



class DegenerateFaceError(MeshError):
    """A triangle has zero area (up to round-off): its cotangents and the gradient of an affine
    function on it are undefined (Sec 6.3).  The message names the face and its vertices.
    """


class NonUniqueSolutionError(InvalidInputError):
    """A discrete Dirichlet boundary value problem has no unique solution: a connected component
    of the graph holds no boundary vertex, so constants can be added there (Cor 6.3, Thm 6.5).
    The message names a vertex of that component.
    """

