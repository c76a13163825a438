"""`ddgjax verify`: every statement of the reference the library implements, checked numerically.

Each check is a small function registered with `@check(...)` in a module of
`ddgjax.verify.checks` (one module per object: curves, elastica, rods, meshes, …), stating the
statement, its number in the reference, the quantity computed, the tolerance and the sizes of
the quick and the full run.  `verify(out, quick=...)` imports every module of that package, runs
the checks and writes `out/report.md` (a table statement | reference | quantity | value |
tolerance | result, the convergence tables with their fitted orders, and the PNG figures).

To add checks for a new object, add one module to `ddgjax/verify/checks/`; it is found
automatically:

```python
\"\"\"Discrete minimal surfaces (Sec 6).\"\"\"
import numpy as np

import ddgjax as dg
from ddgjax.verify import check

@check("Def 6.2", "the cotan Laplacian annihilates constants", quantity="max |L·1|",
       at_most=1e-12, quick=dict(level=2), full=dict(level=5))
def cotan_laplacian_kills_constants(ctx, level):
    V, F = dg.mesh.icosphere(level)
    return float(abs(dg.laplace.cotan_laplacian(V, F) @ np.ones(len(V))).max())
```
"""

from ._registry import Check as Check
from ._registry import Context as Context
from ._registry import Outcome as Outcome
from ._registry import check as check
from ._registry import registry as registry
from ._report import figure_paths as figure_paths
from ._report import write_report as write_report
from ._run import load_checks as load_checks
from ._run import run as run
from ._run import select as select
from ._run import verify as verify

__all__ = ["Check", "Context", "Outcome", "check", "registry", "figure_paths", "write_report", "load_checks", "run", "select",
           "verify"]
