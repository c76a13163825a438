"""Reference values of smooth solutions that the checks and examples compare discrete results with."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

__all__ = ["catenoid_neck", "enneper", "enneper_distance", "neck_radius"]


def catenoid_neck(R: float = 1.0, H: float = 0.5) -> float:
    """The neck radius c of the stable catenoid r(z) = c cosh(z/c) through the circles of radius R
    at z = ±H: the larger root of c cosh(H/c) = R (the smaller one is the unstable catenoid)."""
    fold = brentq(lambda c: np.tanh(H / c) - c / H, 1e-3 * H, H)  # c cosh(H/c) is least here
    return brentq(lambda c: c * np.cosh(H / c) - R, fold, R)


def neck_radius(V) -> float:
    """min over the vertices of the distance to the z-axis."""
    return float(np.min(np.linalg.norm(np.asarray(V)[:, :2], axis=1)))


def enneper(w) -> np.ndarray:
    """Enneper's minimal surface at w = u + iv, (..., 3): the Weierstrass data g = w, f = 1,

        X(u, v) = (u + u v² − u³/3,  −v − u² v + v³/3,  u² − v²),

    stable over |w| < 1 (its Gauss map covers less than a hemisphere there)."""
    u, v = np.real(w), np.imag(w)
    return np.stack([u + u * v**2 - u**3 / 3, -v - u**2 * v + v**3 / 3, u**2 - v**2], -1)


def enneper_distance(P, w0, steps: int = 30) -> np.ndarray:
    """The distance of each point of P (n, 3) to Enneper's surface: Gauss–Newton on
    min_w |X(w) − p|² from the parameters w0 (n,), with X_u = (1 + v² − u², −2uv, 2u) and
    X_v = (2uv, −1 − u² + v², −2v)."""
    P, w = np.asarray(P, dtype=np.float64), np.asarray(w0, dtype=np.complex128).copy()
    for _ in range(steps):
        u, v = w.real, w.imag
        J = np.stack([np.stack([1 + v**2 - u**2, -2 * u * v, 2 * u], -1),
                      np.stack([2 * u * v, -1 - u**2 + v**2, -2 * v], -1)], -1)  # (n, 3, 2)
        r = enneper(w) - P
        step = np.linalg.solve(np.einsum("nki,nkj->nij", J, J), np.einsum("nki,nk->ni", J, r)[..., None])[..., 0]
        w = w - (step[:, 0] + 1j * step[:, 1])
    return np.linalg.norm(enneper(w) - P, axis=1)
