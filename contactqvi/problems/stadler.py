"""Data of Examples 1-3 of seed 002 (Stadler 2004, Sect. 6) on the unit square.

Only data lives here: friction and Dirichlet boundaries, g, mu and the load f.
:func:`create_stadler_problem` turns an example into a
:class:`~contactqvi.friction.FrictionProblem` on a mesh with N grid points per
direction (N - 1 cells), the finite-element counterpart of the paper's N x N grid.

Example 2's load is printed as f(x) = 10(sin 4 pi x + cos 4 pi x) with x the
point (x1, x2); we read it as 10(sin 4 pi x1 + cos 4 pi x2) (``load_reading="x1x2"``),
the reading that reproduces the iteration counts of Table 6.3; the literal
one-coordinate reading 10(sin 4 pi x1 + cos 4 pi x1) is available as ``"x1x1"``.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI

import numpy as np
import ufl

from contactqvi.friction.problem import FrictionProblem, LoadFunction
from contactqvi.meshes import create_unit_square
from contactqvi.parameters import require

__all__ = ["StadlerExample", "stadler_example", "create_stadler_problem", "EXAMPLE_NUMBERS", "EXAMPLE2_READINGS"]


EXAMPLE_NUMBERS = (1, 2, 3)
EXAMPLE2_READINGS = ("x1x2", "x1x1")


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


def stadler_example(number: int, load_reading: str = "x1x2") -> StadlerExample:
    """The data of Example ``number`` of seed 002, Sect. 6.

    Args:
        number: 1, 2 or 3.
        load_reading: for Example 2 only, how the second argument of f is read
            (see the module docstring).
    """
    require(number in EXAMPLE_NUMBERS, "example", f"must be one of {EXAMPLE_NUMBERS}, got {number!r}")
    require(
        load_reading in EXAMPLE2_READINGS, "load_reading", f"must be one of {EXAMPLE2_READINGS}, got {load_reading!r}"
    )
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


def create_stadler_problem(
    comm: MPI.Comm,
    example: StadlerExample,
    N: int,
    cell_type: str = "quadrilateral",
    g: float | None = None,
    mu: float | None = None,
) -> FrictionProblem:
    """The discrete problem of ``example`` with N grid points per direction (N - 1 cells).

    Args:
        comm: communicator.
        example: the example's data (:func:`stadler_example`).
        N: grid points per direction, >= 3 (the paper's N).
        cell_type: ``quadrilateral`` (Q1, default) or ``triangle`` (P1).
        g, mu: override the example's g and mu (for parameter studies).
    """
    valid = isinstance(N, (int, np.integer)) and N >= 3
    require(valid, "N", f"must be an integer >= 3 (grid points per direction), got {N!r}")
    msh, facet_tags = create_unit_square(comm, N - 1, cell_type)
    return FrictionProblem(
        msh,
        facet_tags,
        example.friction_boundaries,
        example.dirichlet_boundaries,
        example.load,
        mu=example.mu if mu is None else mu,
        g=example.g if g is None else g,
        quadrature_degree=example.quadrature_degree,
    )
