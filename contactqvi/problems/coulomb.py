"""Data of the Coulomb-friction experiments of seed 000, Sect. 7 (SI units: m, Pa).

The body is Omega(d) = {(x1, x2) in (0,2)x(0,1), d(x1,x2) < x3 < 1} on the rigid
foundation {x3 <= 0}; u = 0 on x1 = 0, tractions P_T on x3 = 1 and P_R on x1 = 2.
"""

from __future__ import annotations

import numpy as np

from contactqvi.meshes import GapFunction
from contactqvi.parameters import require

__all__ = [
    "GEOMETRIES",
    "LOADS",
    "YOUNG",
    "POISSON",
    "FRICTION",
    "gap_function",
    "tractions",
    "PAPER_TABLE2",
    "PAPER_TABLE3",
    "PAPER_TABLE4",
]

YOUNG = 70e9  #: Young's modulus E (Pa), aluminium
POISSON = 0.334  #: Poisson's ratio nu
FRICTION = 0.23  #: Coulomb friction coefficient F

#: Bottom surfaces d1, d2, d3 (m): the initial gap to the foundation.
GEOMETRIES: dict[str, GapFunction] = {
    "d1": lambda x1, x2: np.full_like(np.asarray(x1, dtype=float), 0.01),
    "d2": lambda x1, x2: np.maximum(0.01 - 0.015 * np.sqrt(0.5 * (x1 - 1.0) ** 2 + 2.0 * (x2 - 0.5) ** 2), 0.0025),
    "d3": lambda x1, x2: 0.01 + 0.005 * (np.sin(2.0 * np.pi * x1) + np.cos(2.0 * np.pi * x2)),
}

#: Load cases: surface tractions (Pa) on the top (P_T) and right (P_R) faces.
LOADS: dict[str, dict[str, tuple[float, float, float]]] = {
    "L1": {"top": (0.0, 0.0, -1e9), "right": (-0.2e9, 0.0, 0.0)},
    "L2": {"top": (0.0, 0.0, -1e9), "right": (-0.17e9, -0.1e9, 0.0)},
}


def gap_function(geometry: str) -> GapFunction:
    """The gap d(x1, x2) of geometry ``d1``, ``d2`` or ``d3``."""
    require(geometry in GEOMETRIES, "geometry", f"unknown geometry {geometry!r}; known: {', '.join(GEOMETRIES)}")
    return GEOMETRIES[geometry]


def tractions(load: str) -> dict[str, tuple[float, float, float]]:
    """Surface tractions per boundary name of load case ``L1`` or ``L2``."""
    require(load in LOADS, "load", f"unknown load case {load!r}; known: {', '.join(LOADS)}")
    return LOADS[load]


_CASES = ("d1/L1", "d1/L2", "d2/L1", "d2/L2", "d3/L1", "d3/L2")


def _table(rows: dict[int, tuple[int, ...]]) -> dict[int, dict[str, tuple[int, int]]]:
    return {lev: {case: (its[2 * i], its[2 * i + 1]) for i, case in enumerate(_CASES)} for lev, its in rows.items()}


#: Seed 000, Table 2: (Newton iterations, GMRES iterations), tol = 0.1, u0 = 0.
PAPER_TABLE2 = _table(
    {
        3: (13, 774, 13, 833, 13, 830, 13, 833, 14, 781, 13, 780),
        4: (13, 866, 15, 982, 15, 868, 14, 937, 14, 874, 14, 882),
        5: (15, 952, 15, 1012, 16, 986, 13, 995, 14, 979, 15, 919),
        6: (16, 1148, 16, 1216, 14, 1065, 15, 1101, 17, 1085, 16, 1145),
        7: (15, 1157, 17, 1210, 14, 1078, 15, 1189, 15, 1154, 16, 1186),
        8: (16, 1402, 16, 1332, 16, 1301, 16, 1443, 17, 1437, 19, 1538),
        9: (19, 1926, 18, 1589, 16, 1401, 17, 1692, 19, 1722, 18, 1714),
        10: (19, 1864, 17, 1768, 18, 1896, 19, 1880, 19, 1920, 19, 2122),
    }
)

#: Seed 000, Table 3: nested start (interpolated solution of level lev - 1).
PAPER_TABLE3 = _table(
    {
        4: (11, 678, 11, 678, 12, 624, 11, 629, 11, 620, 10, 622),
        5: (11, 703, 11, 652, 11, 643, 12, 717, 11, 650, 11, 781),
        6: (13, 778, 11, 744, 11, 719, 12, 822, 11, 802, 11, 767),
        7: (11, 781, 9, 717, 11, 786, 11, 849, 11, 862, 10, 905),
        8: (11, 763, 12, 786, 12, 858, 11, 937, 11, 842, 11, 981),
        9: (10, 867, 11, 997, 11, 1043, 13, 1179, 11, 1052, 10, 1058),
        10: (11, 1087, 10, 958, 11, 1147, 12, 1050, 11, 1092, 12, 1123),
    }
)

#: Seed 000, Table 4: d3/L2, lev 10, u0 = 0: tol -> (Newton, GMRES) iterations.
PAPER_TABLE4 = {1e-1: (19, 2122), 1e-2: (14, 4438), 1e-3: (12, 5349), 1e-4: (12, 7337)}
