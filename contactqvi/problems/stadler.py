"""Data of Examples 1-3 of seed 002 (Stadler 2004, Sect. 6) on the unit square, and the paper's results.

Only data lives here: friction and Dirichlet boundaries, g, mu and the load f
of each example (:func:`stadler_example`), the numbers of the paper's tables
(:data:`PAPER`) and the gamma of its reference solution (:data:`REFERENCE_GAMMA`).
:func:`contactqvi.friction.build.create_problem` turns an example into a discrete
problem with N grid points per direction: Q1 or P1 finite elements, or the paper's
own finite differences.

Example 2's load is printed as f(x) = 10(sin 4 pi x + cos 4 pi x) with x the
point (x1, x2); we read it as 10(sin 4 pi x1 + cos 4 pi x2) (``load_reading="x1x2"``),
the reading that reproduces the iteration counts of Table 6.3; the literal
one-coordinate reading 10(sin 4 pi x1 + cos 4 pi x1) is available as ``"x1x1"``.
"""

from __future__ import annotations

import dataclasses
import typing

import ufl

from contactqvi.parameters import Parameter, Parameters

__all__ = [
    "EXAMPLE2_READINGS",
    "PAPER",
    "PARAMETERS",
    "REFERENCE_GAMMA",
    "StadlerExample",
    "stadler_example",
]

EXAMPLE2_READINGS = ("x1x2", "x1x1")
#: lambda_bar := lambda_gamma with gamma = 1e16, the reference of d_lambda (6.1).
REFERENCE_GAMMA = 1e16

#: The arguments of :func:`stadler_example`.
PARAMETERS = Parameters(
    example=Parameter(1, "example of Sect. 6", int, minimum=1, maximum=3),
    g=Parameter(None, "friction bound g; none: the example's", minimum=0.0, exclusive=True, optional=True),
    mu=Parameter(None, "coefficient mu of (y, z) in a(y, z); none: the example's", minimum=0.0, optional=True),
    example2_reading=Parameter("x1x2", "reading of f in Example 2 (module docstring)", str,
                               choices=EXAMPLE2_READINGS),
)  # fmt: skip

#: The paper's numbers (seed 002, Sect. 6); "div" = (SS) did not find the solution,
#: ``pdas_used`` marks the entries of Table 6.6 computed by (PDAS) because (SS) chattered.
PAPER = {
    "6.1": {"gamma": [1e2, 1e4, 1e6, 1e8], "ss": [2, 3, 3, 3]},
    "fig6.1": {"gamma": [1, 10, 1e2, 1e3, 1e4, 1e5, 1e6],
               "error": [4.46e-1, 1.79e-1, 2.30e-2, 2.49e-3, 2.54e-4, 2.54e-5, 2.54e-6]},
    "6.2": {"gamma": 50, "q": [0.58, 0.45, 0.25, 0.18, 0.00]},
    "6.3": {"gamma": [3, 5, 10, 50, 100, 150, 160, 1e3, 1e10],
            "ss": [3, 4, 4, 5, 6, 7, "div", "div", "div"], "pdas": [3, 4, 4, 5, 6, 5, 5, 6, 6]},
    "6.4": {
        "1e2": {"iter": [6, 3, 2, 1, 1, 1, 1],
                "d": [2.55e-2, 8.54e-3, 3.62e-3, 1.62e-3, 7.45e-4, 3.58e-4, 1.77e-4]},
        "1e4": {"iter": [6, 1, 1, 1, 1], "d": [4.00e-4, 3.06e-6, 2.67e-8, 2.62e-10, 2.84e-12]},
    },
    "6.5": {
        "1e2": {"iter": [1, 2, 2, 2, 1, 1, 1],
                "d": [2.96e-1, 5.03e-2, 7.60e-3, 1.89e-3, 9.99e-4, 5.36e-4, 2.91e-4]},
        "1e4": {"iter": [1, 2, 1, 2, 1, 1, 1],
                "d": [3.81e-1, 1.46e-1, 3.79e-2, 1.87e-4, 2.20e-6, 2.67e-8, 3.28e-10]},
        "10^l": {"iter": [1, 3, 2, 1, 1, 1], "d": [1.41e-1, 2.30e-2, 2.16e-3, 1.11e-5, 1.04e-8, 1.14e-12]},
    },
    "6.6": {
        "gamma": [5, 10, 30, 50, 1e2, 1e3, 1e5, 1e10],
        "N": [20, 40, 80, 160, 320],
        "iter": [[3, 3, 3, 3, 3, 3, 3, 3], [3, 3, 4, 5, 4, 4, 4, 4], [3, 4, 4, 5, 5, 6, 6, 6],
                 [3, 3, 5, 5, 6, 8, 7, 7], [3, 4, 5, 6, 7, 7, 8, 8]],
        "pdas_used": [[0, 0, 0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0, 0, 1],
                      [0, 0, 0, 0, 0, 0, 1, 1], [0, 0, 0, 0, 0, 0, 1, 1]],
    },
    "6.7": {
        "1e2": {"iter": [1, 2, 1, 1, 1, 1, 2],
                "d": [1.62e-1, 1.99e-2, 6.94e-3, 1.40e-3, 4.67e-4, 1.91e-4, 9.20e-5]},
        "1e4": {"iter": [1, 3, 2, 1, 1, 1], "d": [2.14e-1, 1.46e-2, 4.11e-4, 9.06e-7, 8.20e-9, 8.43e-11]},
        "10^l": {"iter": [1, 2, 2, 1, 1, 1], "d": [8.54e-2, 2.62e-2, 2.40e-3, 4.21e-4, 9.08e-8, 8.23e-12]},
        "exact_alm_system_solves": "16 for gamma = 50, 10-20 for the other gamma (d_lambda < 1e-4, N = 160)",
    },
    "uzawa": {"example1_N80": {"10": 32, "20": 17, "30": "no convergence"},
              "example2_gamma0.2": "stopped after 400 iterations at d_lambda = 1.03e-2; "
                                   "no convergence for gamma > 0.2"},
}  # fmt: skip


#: f as a function of the spatial coordinate (a UFL expression).
LoadFunction = typing.Callable[[ufl.SpatialCoordinate], ufl.core.expr.Expr]


@dataclasses.dataclass(frozen=True)
class StadlerExample:
    """One example of Sect. 6 of seed 002.

    Attributes:
        number: 1, 2 or 3.
        friction_boundaries: the unit-square boundaries forming Gamma_f.
        dirichlet_boundaries: the boundaries forming Gamma_0 (y = 0).
        g: friction bound.
        mu: coefficient of (y, z) in a(y, z).
        load: f as a UFL expression of the spatial coordinate.
        description: the paper's formula for f.
        quadrature_degree: degree of the quadrature rule for (f, v).
    """

    number: int
    friction_boundaries: tuple[str, ...]
    dirichlet_boundaries: tuple[str, ...]
    g: float
    mu: float
    load: LoadFunction
    description: str
    quadrature_degree: int = 4


def _load_example1(x: ufl.SpatialCoordinate) -> ufl.core.expr.Expr:
    """f = 10 on (0, 1/2) x (0, 1), -10 on [1/2, 1) x (0, 1) (Sect. 6.1)."""
    return ufl.conditional(ufl.lt(x[0], 0.5), 10.0, -10.0)


def _load_example2(reading: str) -> LoadFunction:
    """f = 10(sin 4 pi x1 + cos 4 pi x2) (reading ``x1x2``) or 10(sin 4 pi x1 + cos 4 pi x1) (Sect. 6.2)."""
    second = 1 if reading == "x1x2" else 0

    def load(x: ufl.SpatialCoordinate) -> ufl.core.expr.Expr:
        return 10.0 * (ufl.sin(4.0 * ufl.pi * x[0]) + ufl.cos(4.0 * ufl.pi * x[second]))

    return load


def _load_example3(x: ufl.SpatialCoordinate) -> ufl.core.expr.Expr:
    """f = |3x - 1| + 2 sgn(2y - 1) + 2 sgn(x - 0.75) + 5 sin(6 pi x) with (x, y) = (x1, x2) (Sect. 6.3)."""
    return (
        abs(3.0 * x[0] - 1.0)
        + 2.0 * ufl.sign(2.0 * x[1] - 1.0)
        + 2.0 * ufl.sign(x[0] - 0.75)
        + 5.0 * ufl.sin(6.0 * ufl.pi * x[0])
    )


def stadler_example(example: int, example2_reading: str = "x1x2", g: float | None = None,
                    mu: float | None = None) -> StadlerExample:  # fmt: skip
    """The data of Example ``example`` of seed 002, Sect. 6 (arguments: :data:`PARAMETERS`, checked).

    Args:
        example: 1, 2 or 3.
        example2_reading: for Example 2 only, how the second argument of f is read
            (see the module docstring).
        g, mu: replace the example's friction bound and coefficient of (y, z) (None: the paper's).
    """
    params = PARAMETERS.check({"example": example, "example2_reading": example2_reading, "g": g, "mu": mu})
    data = _paper_example(params["example"], params["example2_reading"])
    overrides = {name: params[name] for name in ("g", "mu") if params[name] is not None}
    return dataclasses.replace(data, **overrides)


def _paper_example(number: int, load_reading: str) -> StadlerExample:
    """Example ``number`` as printed in Sect. 6."""
    whole_boundary = ("left", "right", "bottom", "top")
    if number == 1:
        # f jumps on x1 = 1/2, the centre line of the middle cell column when N is even
        # (N - 1 cells). The degree-4 Gauss rule (3 x 3 points) samples that line, where
        # the value (-10 by the paper's formula, or 10 after round-off in the point's
        # coordinate) makes (f, v) lose the antisymmetry about x1 = 1/2 that the data and
        # the paper's grids (no grid point on x1 = 1/2 for even N) have; lambda_bar then
        # loses it too (N = 80: ||lambda_bar + lambda_bar(1 - x1, .)||_{L2(Gamma_f)} = 0.09,
        # 50 inactive nodes instead of 48). It is also inaccurate there: across the jump,
        # the 3-point rule with -10 on the line misses the cut cell's share of (f, phi_i)
        # by 75-100 %, the 2-point rule by 15 %. The degree-3 rule (2 x 2 points) has no
        # point on cell centre lines.
        return StadlerExample(
            1, ("bottom", "top"), ("left", "right"), g=1.5, mu=0.0, load=_load_example1,
            description="f = 10 for x1 < 1/2, -10 for x1 >= 1/2", quadrature_degree=3,
        )  # fmt: skip
    if number == 2:
        formula = "x2" if load_reading == "x1x2" else "x1"
        return StadlerExample(
            2, whole_boundary, (), g=0.4, mu=0.5, load=_load_example2(load_reading),
            description=f"f = 10 (sin 4 pi x1 + cos 4 pi {formula})",
        )  # fmt: skip
    return StadlerExample(
        3, whole_boundary, (), g=0.3, mu=0.5, load=_load_example3,
        description="f = |3 x1 - 1| + 2 sgn(2 x2 - 1) + 2 sgn(x1 - 0.75) + 5 sin(6 pi x1)",
    )  # fmt: skip

