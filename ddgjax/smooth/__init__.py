"""Smooth reference solutions: the oracles that discrete solutions converge to.

- `elastica`: exact planar elastica from Jacobi elliptic functions (Thm 3.1, 3.2, Remark 3.2);
- `curve_flows`: the tangent and mKdV flows of planar arc-length curves and a closed test
  curve with exact curvature (Ex 2.2, Ex 2.3);
- `top`: the Lagrange top, its action (3.10) and equations of motion by autodiff (Sec 3.4.1);
- `kirchhoff`: smooth clamped rods by shooting with the top (Thm 3.11, 3.13); imported on first
  use (it loads diffrax and optimistix);
- `space_elastica`: non-planar elastic curves, the tangent a spherical pendulum integrated by
  scipy (Thm 3.1, 3.2); imported on first use.

Nothing here uses a discrete energy of `energies/`: these are independent computations.
"""

import importlib as _importlib

from . import curve_flows as curve_flows
from . import elastica as elastica
from . import top as top


def __getattr__(name: str):
    if name in ("kirchhoff", "space_elastica"):
        return _importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
