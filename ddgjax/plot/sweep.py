"""The figure of a stored sweep (`ddgjax.sweep`), drawn from the HDF5 file alone.

    from ddgjax.plot import sweep as plot_sweep
    plot_sweep.family("chords.h5", out="chords.png")      # or family(ddgjax.sweep.read(path))

Panels: energy, KKT residual (log scale) and Newton steps against the swept parameter (a grid
along one line: the first of its varying coordinates; otherwise against the member index), and,
when `x` holds unit tangents (B, n, 3) (the elastica), the shapes overlaid.  Failed members
(`done` and not `converged`) are red crosses in the three curves (always visible in the steps
panel: a member whose solve raised has NaN energy and residual) and red dashed shapes.

**Edge length.**  The file does not store the parameters outside the grid, so not the edge
length h.  With `chord` (B, 3) in the grid, h is recovered from the chord constraint
`h Σ_k T_k = chord` of the converged members (least squares, checked to 1e-6); with `h` in the
grid it is read; otherwise the shapes are drawn normalised to length 1 (h = 1/n) and the title
says so.

The plot layer does not import `ddgjax.sweep` (the application layer): the file is read here
with h5py, the format tag `FORMAT` being `ddgjax.sweep.FORMAT` (a test checks they agree).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InvalidInputError
from ._figure import pyplot, save_figure

__all__ = ["family", "load"]

FORMAT = "ddgjax.sweep/1"
FIELDS = ("energy", "residual", "steps", "converged", "done", "error")
MAX_SHAPES = 40  # shapes drawn at most (evenly spaced members), besides the failed ones


def load(path) -> dict:
    """The arrays of a sweep file the figure needs: `x` (absent if it is a pytree), `FIELDS`,
    `params` (dict by name), `attrs`.  **Raises:** `InvalidInputError` if `path` cannot be read
    or is not a ddgjax sweep file."""
    import h5py

    path = Path(path)
    if not path.is_file():
        raise InvalidInputError(f"cannot read the sweep file {path}: no such file")
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise InvalidInputError(f"{path} is not a ddgjax sweep file")
            data = {name: f[name][()] for name in FIELDS if name != "error"}
            data["error"] = np.asarray(f["error"].asstr()[()], dtype=object).astype(str)
            data["params"] = {name: f["params"][name][()] for name in f.get("params", {})}
            if isinstance(f.get("x"), h5py.Dataset):
                data["x"] = f["x"][()]
            data["attrs"] = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
    except (OSError, KeyError) as error:
        raise InvalidInputError(f"cannot read the sweep file {path}: {' '.join(str(error).split())}") from None
    return data


def _abscissa(params: dict, size: int) -> tuple[np.ndarray, str]:
    """The swept coordinate and its label: the first varying coordinate of the grid if all
    varying coordinates lie on one line and it is strictly monotone; else the member index."""
    columns, labels = [], []
    for name, values in params.items():
        flat = np.asarray(values, dtype=float).reshape(size, -1)
        for j in range(flat.shape[1]):
            if np.ptp(flat[:, j]) > 0:
                columns.append(flat[:, j])
                labels.append(name if flat.shape[1] == 1 else f"{name}[{j}]")
    if columns and size > 1:
        varying = np.stack(columns, axis=1)
        first, steps = varying[:, 0], np.diff(varying[:, 0])
        on_a_line = np.linalg.matrix_rank(varying - varying.mean(axis=0), tol=1e-9 * np.abs(varying).max()) == 1
        if on_a_line and (np.all(steps > 0) or np.all(steps < 0)):
            return first, labels[0]
    return np.arange(size, dtype=float), "member"


def _edge_length(data: dict, ok: np.ndarray) -> tuple[np.ndarray | None, str]:
    """h per member (None: normalise to length 1) and a note for the title (module docstring)."""
    x, params, size = data["x"], data["params"], len(data["done"])
    if "h" in params and np.shape(params["h"]) == (size,):
        return np.asarray(params["h"], dtype=float), ""
    chord = params.get("chord")
    if chord is not None and np.shape(chord) == (size, 3) and ok.any():
        sums, c = x[ok].sum(axis=1), np.asarray(chord, dtype=float)[ok]
        h = np.sum(sums * c) / np.sum(sums * sums)
        if np.isfinite(h) and h > 0 and np.max(np.abs(h * sums - c)) <= 1e-6 * max(1.0, np.abs(c).max()):
            return np.full(size, h), f", h = {h:.4g} from the chord"
    return None, ", normalised to length 1 (edge length not stored)"


def _is_tangents(data: dict, ok: np.ndarray) -> bool:
    x = data.get("x")
    return (x is not None and x.ndim == 3 and x.shape[2] == 3 and ok.any()
            and np.allclose(np.linalg.norm(x[ok], axis=2), 1.0, atol=1e-6))


def _draw_shapes(ax, data: dict, ok: np.ndarray, failed: np.ndarray) -> str:
    x = data["x"]
    h, note = _edge_length(data, ok)
    n = x.shape[1]
    shown = np.flatnonzero(ok)
    if len(shown) > MAX_SHAPES:
        shown = shown[np.unique(np.linspace(0, len(shown) - 1, MAX_SHAPES).round().astype(int))]
        note += f", {len(shown)} of {int(ok.sum())} converged shown"
    planar = ax.name != "3d"
    colours = pyplot().get_cmap("viridis")(np.linspace(0.0, 1.0, max(len(shown), 2)))
    for k, style in [(k, dict(color=colours[i], lw=1.0)) for i, k in enumerate(shown)] + \
                    [(k, dict(color="red", ls="--", lw=1.0)) for k in np.flatnonzero(failed)]:
        if not np.all(np.isfinite(x[k])):
            continue
        step = 1.0 / n if h is None else h[k]
        points = np.vstack([np.zeros((1, 3)), np.cumsum(step * x[k], axis=0)])
        ax.plot(*(points[:, :2] if planar else points).T, **style)
    ax.set_title(f"shapes{note}", fontsize="small")
    if planar:
        ax.set_aspect("equal", adjustable="datalim")
    return note


def family(path_or_data, out=None):
    """The figure of a sweep: energy, residual and steps against the swept parameter, and the
    shapes of an elastica family (module docstring); failed members marked red.

    **Arguments:** `path_or_data`: a sweep file, or the dict `ddgjax.sweep.read` returns; `out`:
    where to save the figure (PNG by its suffix), or None.
    **Returns:** the matplotlib Figure, or `out` after saving there.
    **Raises:** `InvalidInputError` for a file that cannot be read or is not a sweep file, or a
    sweep with no member done.
    """
    data = load(path_or_data) if isinstance(path_or_data, (str, Path)) else path_or_data
    done = np.asarray(data["done"], dtype=bool)
    if not done.any():
        raise InvalidInputError("the sweep has no member done yet: nothing to plot")
    ok = done & np.asarray(data["converged"], dtype=bool)
    failed = done & ~ok
    t, label = _abscissa(data.get("params", {}), len(done))
    shapes = _is_tangents(data, ok)
    plt = pyplot()
    fig = plt.figure(figsize=(4.0 * (3 + shapes), 3.6))
    for i, (name, log) in enumerate([("energy", False), ("residual", True), ("steps", False)]):
        ax = fig.add_subplot(1, 3 + shapes, i + 1)
        values = np.asarray(data[name], dtype=float)
        good = ok & np.isfinite(values) & ((values > 0) if log else True)
        bad = failed & np.isfinite(values) & ((values > 0) if log else True)
        ax.plot(t[good], values[good], ".-", color="C0", ms=3, label="converged")
        if bad.any():
            ax.plot(t[bad], values[bad], "x", color="red", ms=7, label=f"failed ({int(failed.sum())})")
            ax.legend(fontsize="small")
        if log:
            ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.set_ylabel(name if name != "residual" else "KKT residual")
    if shapes:
        # planar when the family's shapes are: a failed member's last iterate is no shape of it
        shown = ok if ok.any() else done
        projection = None if np.allclose(np.nan_to_num(data["x"][shown][..., 2]), 0.0) else "3d"
        _draw_shapes(fig.add_subplot(1, 4, 4, projection=projection), data, ok, failed)
    problem = data.get("attrs", {}).get("problem", "sweep")
    fig.suptitle(f"{problem}: {int(done.sum())} of {len(done)} members done, {int(failed.sum())} failed", fontsize="medium")
    return fig if out is None else save_figure(fig, out)
