"""Semismooth Newton for fixed-point equations u = S(Phi(u)) (seed 003, Sects. 2-4).

Phi (temperature map E1), S (obstacle solver E2, :mod:`contactqvi.vi`), the
composite maps with their Newton systems (61)-(64), the projection of Sect. 2.3,
and the outer methods Algorithm 1, Algorithm 2, C1, C2, C3.
"""

from contactqvi.qvi.build import BUILD_PARAMETERS, OUTER_METHODS, QVISetup, build, create_mesh
from contactqvi.qvi.maps import CompositeMap, Evaluation, ObstacleQVIMap, RegularisedQVIMap, SemilinearVIMap
from contactqvi.qvi.newton_system import BlockNewtonSystem, diagonal_matrix
from contactqvi.qvi.outer import FIXED_POINT_PARAMETERS, FixedPointSolver, QVIResult
from contactqvi.qvi.projection import BallProjection
from contactqvi.qvi.temperature import Nonlinearity, TemperatureMap

__all__ = [
    "BUILD_PARAMETERS",
    "FIXED_POINT_PARAMETERS",
    "OUTER_METHODS",
    "BallProjection",
    "BlockNewtonSystem",
    "CompositeMap",
    "Evaluation",
    "FixedPointSolver",
    "Nonlinearity",
    "ObstacleQVIMap",
    "QVIResult",
    "QVISetup",
    "RegularisedQVIMap",
    "SemilinearVIMap",
    "TemperatureMap",
    "build",
    "create_mesh",
    "diagonal_matrix",
]
