"""Reference values of smooth solutions that the checks and examples compare discrete results with."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

__all__ = ["catenoid_neck", "neck_radius"]


def catenoid_neck(R: float = 1.0, H: float = 0.5) -> float:
    """The neck radius c of the stable catenoid r(z) = c cosh(z/c) through the circles of radius R
    at z = ±H: the larger root of c cosh(H/c) = R (the smaller one is the unstable catenoid)."""
    fold = brentq(lambda c: np.tanh(H / c) - c / H, 1e-3 * H, H)  # c cosh(H/c) is least here
    return brentq(lambda c: c * np.cosh(H / c) - R, fold, R)


def neck_radius(V) -> float:
    """min over the vertices of the distance to the z-axis."""
    return float(np.min(np.linalg.norm(np.asarray(V)[:, :2], axis=1)))
