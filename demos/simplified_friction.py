"""Stadler's simplified (scalar Tresca) friction problem, seed 002, Examples 1-3.

This demo illustrates how to:
  * build the paper's examples on the unit square with N grid points per
    direction: Q1 (default) or P1 finite elements with a lumped boundary mass,
    or the paper's own finite differences (``--discretisation fd``);
  * solve the regularised problem (P*_gamma) with the primal-dual active set
    method (PDAS, parameter sigma) or the semismooth Newton method (SS, sigma = 1/gamma);
  * solve the original problem (P*) with the augmented Lagrangian method (ALM,
    exact or inexact inner solves, fixed gamma or gamma_l = 10^l) or with Uzawa's method;
  * report d_lambda = ||lambda_bar - lambda||_{L2(Gamma_f)} against lambda_bar = lambda_{1e16};
  * write summary.json (with the checked parameters), solution.npz, ParaView files and y.png.

The options after ``--method`` are those of the method's parameter table
(``--method alm --help`` lists ALM's). Run, e.g.::

    python demos/simplified_friction.py --example 2 --method pdas --gamma 1e3 --N 160
    python demos/simplified_friction.py --example 1 --method ss --gamma 1e8 --discretisation fd
    mpirun -n 2 python demos/simplified_friction.py --example 3 --method alm --inner inexact --schedule power10
    python demos/simplified_friction.py --example 1 --method uzawa --gamma 10 -uzawa_ksp_view
"""

from __future__ import annotations

import argparse
import logging
import sys

from mpi4py import MPI

from contactqvi import tables
from contactqvi.cli import abort_on_error, make_parser, parse_args, print_error
from contactqvi.friction import GRID_PARAMETERS, create_problem, methods
from contactqvi.friction.output import plot_surface, write_solution
from contactqvi.parameters import Parameter, ParameterError, Parameters
from contactqvi.problems import stadler

logger = logging.getLogger("simplified_friction")

#: Options of this demo besides the problem's and the methods'.
DEMO = Parameters(
    method=Parameter("pdas", "pdas | ss (sigma = 1/gamma) | alm | uzawa", str, choices=methods.METHODS),
    reference=Parameter(True, "compute lambda_bar = lambda_1e16 for d_lambda and the paper's stopping test", bool),
    png=Parameter(True, "plot y to y.png", bool),
)


def parse(argv: list[str] | None) -> tuple[str, dict, dict, dict, dict]:
    """Output directory and the checked example, grid, demo and solver parameters; raises ParameterError.

    The method is read first: its parameter table gives the solver's options.
    """
    argv = sys.argv[1:] if argv is None else argv
    chosen = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    DEMO.add_arguments(chosen, ["method"])
    method = chosen.parse_known_args(argv)[0].method
    petsc_example = "-friction_ksp_view (PDAS/SS/ALM) or -uzawa_ksp_view"
    parser = make_parser(__doc__.split("\n")[0], "results/simplified_friction", petsc_example)
    stadler.PARAMETERS.add_arguments(parser.add_argument_group("example"))
    GRID_PARAMETERS.add_arguments(parser.add_argument_group("grid"))
    DEMO.add_arguments(parser)
    table = methods.parameters_of(method)
    table.add_arguments(parser.add_argument_group(f"{method} (the method chosen)"))
    args = parse_args(parser, argv)
    example, grid = stadler.PARAMETERS.from_namespace(args), GRID_PARAMETERS.from_namespace(args)
    solver = methods.checked_parameters(method, {name: getattr(args, name) for name in table})
    return args.output, example, grid, DEMO.from_namespace(args), solver


def main(argv: list[str] | None = None) -> int:
    comm = MPI.COMM_WORLD
    try:
        output, example_parameters, grid, demo, parameters = parse(argv)
        example = stadler.stadler_example(**example_parameters)
        problem = create_problem(comm, example, **grid)
    except ParameterError as exc:
        print_error(exc, comm)
        return 2
    out = tables.prepare_output_dir(comm, output)
    problem_parameters = {**example_parameters, **grid}
    logger.info(
        "Example %d (%s), g=%g, mu=%g, N=%d, %s, %d friction nodes; method %s",
        example.number, example.description, problem.g, problem.mu, problem_parameters["N"],
        problem_parameters["discretisation"], problem.n_boundary, demo["method"],
    )  # fmt: skip
    with problem, methods.FrictionSolvers(problem) as solvers:
        reference = None
        if demo["reference"]:
            logger.info("reference lambda_bar = lambda_gamma, gamma = %.0e (PDAS, sigma = 1):", stadler.REFERENCE_GAMMA)
            lambda_bar = solvers.reference(stadler.REFERENCE_GAMMA)
            if not lambda_bar.converged:
                raise RuntimeError(f"PDAS for lambda_bar ended with status {lambda_bar.status}")
            reference = lambda_bar.lam
        result = solvers.solve(demo["method"], parameters, reference)
        lam = result.lam
        states = getattr(result, "states", None)
        states = methods.nodal_states(problem, lam) if states is None else states
        y_norm, lam_norm = problem.energy_norm(result.y.x.petsc_vec), problem.boundary_norm(lam)
        summary = {
            "example": example.number,
            "load": example.description,
            "parameters": {"problem": problem_parameters, **demo, "solver": parameters},
            "friction_nodes": problem.n_boundary,
            "mpi_ranks": comm.size,
            **result.summary(),
            "energy_norm_y": y_norm,
            "l2_norm_lambda": lam_norm,
            "max_abs_lambda": problem.max_abs(lam),
            "d_lambda": problem.boundary_norm(reference - lam) if reference is not None else None,
            "active_minus": problem.count(states == -1),
            "active_plus": problem.count(states == 1),
            "inactive": problem.count(states == 0),
            "units": "none: the problem of seed 002 is dimensionless",
        }
        write_solution(out, problem, result.y, lam, states)
        if demo["png"]:
            title = f"Example {example.number}, {demo['method']}, N = {problem_parameters['N']}"
            plot_surface(out / "y.png", result.y, title)
        summary["png"] = "y.png" if demo["png"] else None
        tables.write_summary(comm, out / "summary.json", summary)
    if comm.rank == 0:
        print(f"status {result.status}; |||y||| = {y_norm:.12e}; ||lambda||_L2(Gamma_f) = {lam_norm:.12e}")
    return 0 if result.converged else 1


if __name__ == "__main__":
    sys.exit(abort_on_error(main))
