"""A plain obstacle problem with a known exact solution, to verify the S-solver alone.

The radially symmetric problem on (-2, 2)^2 with the hemispherical lower obstacle
psi(r) = sqrt(1 - r^2) (r <= 1), -1 (r > 1), zero load and exact solution
U(r) = psi(r) for r <= r*, -r*^2 log(r/2) / sqrt(1 - r*^2) for r > r*, with
r* = 0.697965148223374 solving r*^2 (1 - log(r*/2)) = 1 (free boundary r = r*).
It is mapped to the unit square by X = 4x - 2 and turned into the upper-obstacle
form of (21) by u = -U, theta = -psi (the Laplacian only picks up a factor 16,
and the load stays zero).
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import ufl

__all__ = ["RadialObstacle", "radial_obstacle", "FREE_BOUNDARY_RADIUS"]

#: r* of the radial problem: r^2 (1 - log(r / 2)) = 1.
FREE_BOUNDARY_RADIUS = 0.697965148223374


@dataclasses.dataclass(frozen=True)
class RadialObstacle:
    """Data of the radial problem on the unit square (upper-obstacle form)."""

    obstacle: typing.Callable[[np.ndarray], np.ndarray]
    exact: typing.Callable[[np.ndarray], np.ndarray]
    exact_ufl: typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr]
    source: float = 0.0


def _radius(x: np.ndarray) -> np.ndarray:
    return np.hypot(4 * x[0] - 2, 4 * x[1] - 2)


def radial_obstacle() -> RadialObstacle:
    """The radial obstacle problem with free boundary at r = r*."""
    rs = FREE_BOUNDARY_RADIUS
    scale = rs**2 / np.sqrt(1 - rs**2)

    def obstacle(x: np.ndarray) -> np.ndarray:
        r = _radius(x)
        return -np.where(r <= 1, np.sqrt(np.maximum(1 - r**2, 0)), -1.0)

    def exact(x: np.ndarray) -> np.ndarray:
        r = np.maximum(_radius(x), 1e-300)
        return -np.where(r <= rs, np.sqrt(np.maximum(1 - r**2, 0)), -scale * np.log(r / 2))

    def exact_ufl(x: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        r = ufl.sqrt((4 * x[0] - 2) ** 2 + (4 * x[1] - 2) ** 2)
        return -ufl.conditional(ufl.le(r, rs), ufl.sqrt(1 - ufl.min_value(r, rs) ** 2), -scale * ufl.ln(ufl.max_value(r, rs) / 2))

    return RadialObstacle(obstacle, exact, exact_ufl)
