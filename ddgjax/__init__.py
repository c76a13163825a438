"""ddgjax: variational discrete differential geometry in JAX.

Declare a discrete object as an energy with constraints (`Problem`), and get its critical
points (`solvers.solve`), Euler–Lagrange equations (`euler_lagrange`), flows
(`gradient_flow`, `hamiltonian_flow`) and smooth limits (`limits.convergence`) by automatic
differentiation.  Importing ddgjax switches JAX to float64 (the only global setting).

The package is layered; each layer imports only the layers above it in this list (a test,
`tests/test_layering.py`, keeps it so):

1. the language: `problem`, `locality`, `flows`, `limits`, `errors`;
2. geometry: `curves`, `quaternion`, `frames`, `mesh`, `intrinsic`, `laplace`;
3. smooth reference solutions: `smooth` (exact elastica, the Lagrange top, Kirchhoff rods);
4. output: `plot`;
5. the application: `verify`, `cli` (the only part that imports `energies` and `solvers`).
"""

import importlib as _importlib

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from . import curves as curves  # noqa: E402
from . import errors as errors  # noqa: E402
from . import frames as frames  # noqa: E402
from . import intrinsic as intrinsic  # noqa: E402
from . import laplace as laplace  # noqa: E402
from . import limits as limits  # noqa: E402
from . import mesh as mesh  # noqa: E402
from . import plot as plot  # noqa: E402
from . import quaternion as quaternion  # noqa: E402
from . import smooth as smooth  # noqa: E402
from .flows import (  # noqa: E402
    gradient_flow as gradient_flow,
    hamiltonian_flow as hamiltonian_flow,
    integrate as integrate,
    lie_bracket as lie_bracket,
    spin_poisson as spin_poisson,
)
from .locality import concat as concat, local_map as local_map, local_sum as local_sum  # noqa: E402
from .plot import surface as plot_surface  # noqa: E402, F401  (the old name of ddgjax.plot.surface)
from .problem import Problem as Problem, euler_lagrange as euler_lagrange, lagrangian as lagrangian  # noqa: E402
from .smooth import top as top  # noqa: E402

__version__ = "0.1.0"

# Modules that moved into the layered subpackages, still importable as attributes of ddgjax
# (`from ddgjax.smooth import kirchhoff`); loaded on first use.
_MOVED = {
    "elastica_exact": ".smooth.elastica",
    "kirchhoff": ".smooth.kirchhoff",
    "plot_laplace": ".plot.laplace",
}


def __getattr__(name: str):
    if name in _MOVED:
        return _importlib.import_module(_MOVED[name], __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
