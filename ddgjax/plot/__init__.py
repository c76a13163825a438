"""Output: every figure ddgjax draws (matplotlib, Agg backend, loaded on first use).

- lines: `curve`, `curves`, `convergence`, `spin_chain`, `animate_spin_chain`;
- surface: `surface`, `face_values` (polyhedral surfaces coloured by curvature, Sec 5.2);
- laplace: `harmonic_function`, `minimal_surface` (Sec 6);
- intrinsic: `triangulation`, `before_after` (non-Delaunay edges highlighted, Sec 7);
- sweep: `family` (a stored `ddgjax.sweep` file: energy, residual, steps, shapes);
- `save_figure`: the one place that lays out, writes and closes a figure.

Every drawing function returns the matplotlib Figure when `path` is None, and when `path` is
given saves the figure there (by `save_figure`), closes it and returns `path`.  The exceptions:
`animate_spin_chain` always writes its `path`; `intrinsic.before_after` returns its flip result,
with the figure beside it, `(result, fig)`, when `path` is None.
"""

from . import intrinsic as intrinsic
from . import lines as lines
from . import laplace as laplace
from . import surface as surface
from . import sweep as sweep
from ._figure import save_figure as save_figure
from .lines import (
    animate_spin_chain as animate_spin_chain,
    convergence as convergence,
    curve as curve,
    curves as curves,
    spin_chain as spin_chain,
)

__all__ = ["animate_spin_chain", "convergence", "curve", "curves", "save_figure", "spin_chain", "intrinsic", "laplace",
           "lines", "surface", "sweep"]
