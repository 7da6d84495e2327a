"""Static contact of an elastic body with a rigid foundation and Coulomb friction (seed 000).

This demo illustrates how to:
  * build the body Omega(d) of seed 000, Sect. 7, at discretisation level ``--lev``;
  * assemble the generalized equation 0 in A u - l + Q(u) (6.3) in displacements;
  * solve it with the SCD semismooth* Newton method (Sects. 4-6) on PETSc objects,
    in parallel (``mpirun -n 2 python demos/coulomb3d.py``);
  * optionally start from the interpolated solution of the previous level (Table 3);
  * or solve it with another contact law of :mod:`contactqvi.laws`: Tresca with a given
    slip bound (``--law tresca --slip-bound S``), frictionless, or a pressure-dependent
    friction coefficient (``--law pressure_coulomb --friction-limit F --pressure-scale P``);
  * write ParaView files, ``summary.json`` and ``solution.npz`` to ``--output``.

Units are SI (m, Pa, N). ``--pc`` picks the Newton-step solver (``gamg`` default,
``paper`` = GMRES + ILU of Sect. 7, ``hypre``, ``lu`` = exact); unknown options
starting with '-' go to PETSc and override it, e.g. ``-coulomb_ksp_monitor``.
Your own body, obstacle and load path: ``python -m contactqvi run CASE.toml``.
"""

from __future__ import annotations

import logging
import sys

from mpi4py import MPI
from petsc4py import PETSc

from contactqvi import cli, tables
from contactqvi.contact.driver import solve_nested
from contactqvi.contact.postprocess import write_contact_results
from contactqvi.contact.scd_newton import PARAMETERS
from contactqvi.elasticity import lame_parameters
from contactqvi.laws import DEFAULT_LAW, LAWS, ContactLaw, Coulomb, create_law, parameter_names
from contactqvi.parameters import ParameterError, require
from contactqvi.problems import coulomb as data

logger = logging.getLogger("coulomb3d")


def parse(argv: list[str] | None = None):
    parser = cli.make_parser(__doc__.split("\n")[0], "results/coulomb3d", "-coulomb_ksp_monitor")
    parser.add_argument("--lev", type=int, default=5, help="discretisation level (Table 2)")
    parser.add_argument("--geometry", default="d1", choices=sorted(data.GEOMETRIES), help="bottom surface d")
    parser.add_argument("--load", default="L1", choices=sorted(data.LOADS), help="load case")
    parser.add_argument("--law", default=DEFAULT_LAW, choices=list(LAWS), help="contact law (contactqvi.laws)")
    for key in parameter_names():
        users = [name for name, law in LAWS.items() if key in law.parameters]
        default = f"; default {data.FRICTION} (the paper's F)" if key == "friction" else ""
        parser.add_argument("--" + key.replace("_", "-"), type=float, default=None,
                            help=f"{LAWS[users[0]].parameters[key].range_text}, law {' or '.join(users)}{default}")
    parser.add_argument("--young", type=float, default=data.YOUNG, help="Young's modulus E (Pa)")
    parser.add_argument("--poisson", type=float, default=data.POISSON, help="Poisson's ratio nu")
    PARAMETERS.add_arguments(parser.add_argument_group("SCD Newton solver"))
    parser.add_argument("--initial", default="zero", choices=["zero", "nested"], help="u0 = 0 or nested (Table 3)")
    parser.add_argument("--nested-from", type=int, default=3, help="coarsest level of a nested start (solved from 0)")
    parser.add_argument("--no-plot", action="store_true", help="skip the PNG of the contact states")
    args = cli.parse_args(parser, argv)
    lame_parameters(args.young, args.poisson)
    args.contact_law = _contact_law(args)
    require(0 <= args.nested_from < args.lev or args.initial == "zero", "nested-from", "must lie in [0, lev)")
    args.solver_parameters = PARAMETERS.from_namespace(args)
    return args


def _contact_law(args) -> ContactLaw:
    """The law of ``--law`` and its parameters (``--friction`` defaults to the paper's F); errors
    named by the option."""
    values = {key: getattr(args, key) for key in parameter_names()}
    if "friction" in LAWS[args.law].parameters and values["friction"] is None:
        values["friction"] = data.FRICTION
    try:
        return create_law({"law": args.law, **values})
    except ParameterError as exc:
        raise ParameterError(exc.name.replace("_", "-"), str(exc).removeprefix(f"{exc.name}: ")) from None


def main(argv: list[str] | None = None) -> int:
    comm = MPI.COMM_WORLD
    try:  # every input check (here and in the library) runs before assembly
        args = parse(argv)
        levels = range(args.nested_from, args.lev + 1) if args.initial == "nested" else [args.lev]
        solutions = solve_nested(
            comm, levels, gap=data.gap_function(args.geometry), tractions=data.tractions(args.load),
            young=args.young, poisson=args.poisson, law=args.contact_law, parameters=args.solver_parameters,
        )
    except ParameterError as exc:
        cli.print_error(exc, comm)
        return 2
    out = tables.prepare_output_dir(comm, args.output)
    problem, u, result = solutions[-1].problem, solutions[-1].u, solutions[-1].result
    case = f"{args.geometry}/{args.load}"
    paper_data = (args.contact_law, args.young, args.poisson) == (Coulomb(data.FRICTION), data.YOUNG, data.POISSON)
    paper = (data.PAPER_TABLE3 if args.initial == "nested" else data.PAPER_TABLE2).get(args.lev, {}).get(case)
    summary = {
        "problem": "coulomb3d",
        **result.summary(),
        "parameters": {k: v for k, v in vars(args).items() if k not in ("solver_parameters", "contact_law")},
        "law": args.contact_law.to_dict(),
        "solver_parameters": args.solver_parameters,
        "petsc_options": PETSc.Options().getAll(),
        "mpi_size": comm.size,
        "p": problem.n_contact,
        "n": problem.n_free,
        "gamma": result.gamma,
        "levels": [{"lev": s.lev, **s.result.summary()} for s in solutions],
        "paper": {"iterations": paper[0], "gmres": paper[1]} if paper and paper_data else None,
    }
    if result.converged:
        summary.update(write_contact_results(out, problem, u, result, plot=not args.no_plot))
        norm = summary["displacement_norm"]
        if comm.rank == 0:
            print(f"||u~||_2 = {norm:.10e}  ({result.iterations} Newton steps, {result.inner_iterations} Krylov)")
    tables.write_summary(comm, out / "summary.json", summary)
    if not result.converged:
        logger.error("not converged: status %s (see %s)", result.status, out / "summary.json")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(cli.abort_on_error(main))
