"""The discrete problem (P) on the unit square from its data: Q1 or P1 elements, or finite differences.

The grid has N points per direction (N - 1 cells, h = 1/(N - 1)); its vertices are
the grid points of all three discretisations, so their vectors share index maps and
parallel layout.
"""

from __future__ import annotations

import typing

from mpi4py import MPI

from contactqvi.friction.finite_differences import PaperFiniteDifferences
from contactqvi.friction.problem import FrictionData, FrictionProblem
from contactqvi.meshes import create_unit_square
from contactqvi.parameters import Parameter, Parameters

__all__ = ["DISCRETISATIONS", "GRID_PARAMETERS", "create_problem"]

#: Q1 or P1 finite elements with a lumped boundary mass, or the paper's finite differences.
DISCRETISATIONS = ("q1", "p1", "fd")

#: The grid and discretisation of :func:`create_problem`.
GRID_PARAMETERS = Parameters(
    N=Parameter(80, "grid points per direction (N - 1 cells)", int, minimum=3),
    discretisation=Parameter("q1", "q1/p1 finite elements or the paper's finite differences", str,
                             choices=DISCRETISATIONS),
)  # fmt: skip


def create_problem(comm: MPI.Comm, data: FrictionData, **parameters: typing.Any) -> FrictionProblem:
    """The discrete problem of ``data`` on the unit square.

    Args:
        comm: communicator.
        data: boundaries, load, g, mu and quadrature degree (:class:`~contactqvi.friction.problem.FrictionData`).
        parameters: values of :data:`GRID_PARAMETERS` (N, discretisation), checked first.
    """
    params = GRID_PARAMETERS.check(parameters)
    N = params["N"]
    if params["discretisation"] == "fd":
        return PaperFiniteDifferences(comm, data, N)
    cell_type = "quadrilateral" if params["discretisation"] == "q1" else "triangle"
    msh, facet_tags = create_unit_square(comm, N - 1, cell_type)
    return FrictionProblem(
        msh, facet_tags, data.friction_boundaries, data.dirichlet_boundaries, data.load, mu=data.mu, g=data.g,
        quadrature_degree=data.quadrature_degree,
    )  # fmt: skip
