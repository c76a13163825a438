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

Subpackages and the names below are loaded on first use (PEP 562), so that `import ddgjax`
costs little more than `import jax`: `ddgjax.mesh`, `from ddgjax import Problem` and
`import ddgjax.flows` all work as usual.
"""

import importlib as _importlib

import jax as _jax

_jax.config.update("jax_enable_x64", True)

__version__ = "0.1.0"

# Names defined in a submodule, loaded from it on first access: name -> (module, attribute).
_NAMES = {
    "Problem": (".problem", "Problem"),
    "euler_lagrange": (".problem", "euler_lagrange"),
    "lagrangian": (".problem", "lagrangian"),
    "concat": (".locality", "concat"),
    "local_map": (".locality", "local_map"),
    "local_sum": (".locality", "local_sum"),
    "gradient_flow": (".flows", "gradient_flow"),
    "hamiltonian_flow": (".flows", "hamiltonian_flow"),
    "integrate": (".flows", "integrate"),
    "lie_bracket": (".flows", "lie_bracket"),
    "spin_poisson": (".flows", "spin_poisson"),
}

# Modules available as attributes of ddgjax; the last four under the names they had before
# moving into the layered subpackages (`from ddgjax import kirchhoff` still works).
_MODULES = {
    **{name: f".{name}" for name in (
        "curves", "errors", "flows", "frames", "intrinsic", "laplace", "limits", "locality", "mesh",
        "plot", "problem", "quaternion", "smooth")},
    "top": ".smooth.top",
    "elastica_exact": ".smooth.elastica",
    "kirchhoff": ".smooth.kirchhoff",
    "plot_laplace": ".plot.laplace",
    "plot_surface": ".plot.surface",
}

__all__ = sorted([*_NAMES, *_MODULES, "__version__"])


def __getattr__(name: str):
    if name in _NAMES:
        module, attribute = _NAMES[name]
        value = getattr(_importlib.import_module(module, __name__), attribute)
    elif name in _MODULES:
        value = _importlib.import_module(_MODULES[name], __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later accesses are plain attribute lookups
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
