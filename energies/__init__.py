"""ddgjax.energies: the catalogue of discrete functionals of the reference.

One module per object (elastica, pendulum, rod, heisenberg, dirichlet, area), each holding the
energy density, the constraints and the problem constructors, and nothing else.  The catalogue
is filled by the curve, rod, surface and spin-chain issues.
"""

import ddgjax as _ddgjax  # noqa: F401  (float64 on import)
