"""Problem data containers for obstacle-type QVIs (58) and semilinear VIs (48) of seed 003.

Every field is a function of the spatial coordinate ``x`` (a UFL
SpatialCoordinate) returning a UFL expression, so the same data serve the
forms and the nodal interpolation of obstacles and initial guesses.
"""

from __future__ import annotations

import dataclasses
import typing

import ufl

from contactqvi.qvi.temperature import ScalarNonlinearity

__all__ = ["Field", "ObstacleQVIData", "SemilinearVIData"]

Field = typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr]


@dataclasses.dataclass(frozen=True)
class ObstacleQVIData:
    """(58): u <= Phi0 + varphi T, -Lap u <= f; k T - Lap T = g(Psi0 + psi T - u), dT/dn = 0.

    ``initial`` None means u0 = (-Lap)^{-1} f; ``exact`` is the known solution, if any.
    """

    dim: int
    k: float
    g: ScalarNonlinearity
    Phi0: Field
    f: Field
    varphi: Field
    Psi0: Field
    psi: Field
    initial: Field | None
    exact: Field | None = None


@dataclasses.dataclass(frozen=True)
class SemilinearVIData:
    """(48): u <= Phi0, -Lap u - b1(u) b2(u) - f >= 0 tested against v - u."""

    dim: int
    b1: ScalarNonlinearity
    b2: ScalarNonlinearity
    f: Field
    Phi0: Field
    initial: Field
