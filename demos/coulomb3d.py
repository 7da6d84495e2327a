"""Static contact of an elastic body with a rigid foundation and Coulomb friction (seed 000).

This demo illustrates how to:
  * build the body Omega(d) of seed 000, Sect. 7, at discretisation level ``--lev``;
  * assemble the generalized equation 0 in A u - l + Q(u) (6.3) in displacements;
  * solve it with the SCD semismooth* Newton method (Sects. 4-6) on PETSc objects,
    in parallel (``mpirun -n 2 python demos/coulomb3d.py``);
  * optionally start from the interpolated solution of the previous level (Table 3);
  * or solve the Tresca variant with a given slip bound (``--law tresca --slip-bound S``);
  * write ParaView files, ``summary.json`` and ``solution.npz`` to ``--output``.

Units are SI (m, Pa). ``--pc`` picks the Newton-step solver (``gamg`` default,
``paper`` = GMRES + ILU of Sect. 7, ``hypre``, ``lu`` = exact); unknown options
starting with '-' go to PETSc and override it, e.g. ``-coulomb_ksp_monitor``.
"""

from __future__ import annotations

import logging
import sys

from mpi4py import MPI
from petsc4py import PETSc

from contactqvi import cli, io
from contactqvi.contact.driver import solve_nested
from contactqvi.contact.postprocess import contact_fields, plot_contact_states
from contactqvi.contact.scd_newton import APPROXIMATION_STEPS, GAMMA_RULES, KSP_PRESETS, PARAMETERS, check_parameters
from contactqvi.elasticity import lame_parameters
from contactqvi.parameters import ParameterError, require
from contactqvi.problems import coulomb as data

logger = logging.getLogger("coulomb3d")


def parse(argv: list[str] | None = None):
    parser = cli.make_parser(__doc__.split("\n")[0], "results/coulomb3d")
    parser.add_argument("--lev", type=int, default=5, help="discretisation level (Table 2)")
    parser.add_argument("--geometry", default="d1", choices=sorted(data.GEOMETRIES), help="bottom surface d")
    parser.add_argument("--load", default="L1", choices=sorted(data.LOADS), help="load case")
    parser.add_argument("--law", default="coulomb", choices=["coulomb", "tresca"],
                        help="friction law: Coulomb (bound F x normal force) or Tresca (given bound)")
    parser.add_argument("--friction", type=float, default=data.FRICTION, help="Coulomb friction coefficient F")
    parser.add_argument("--slip-bound", type=float, default=None,
                        help="Tresca slip bound: friction traction limit (Pa), required with --law tresca")
    parser.add_argument("--young", type=float, default=data.YOUNG, help="Young's modulus E (Pa)")
    parser.add_argument("--poisson", type=float, default=data.POISSON, help="Poisson's ratio nu")
    parser.add_argument("--pc", default=PARAMETERS["pc"][0], choices=sorted(KSP_PRESETS), help=PARAMETERS["pc"][1])
    parser.add_argument("--tol", type=float, default=PARAMETERS["tol"][0], help=PARAMETERS["tol"][1])
    parser.add_argument("--rtol", type=float, default=PARAMETERS["rtol"][0], help=PARAMETERS["rtol"][1])
    parser.add_argument(
        "--max-iterations", type=int, default=PARAMETERS["max_iterations"][0], help=PARAMETERS["max_iterations"][1]
    )
    parser.add_argument(
        "--gamma-rule", default=PARAMETERS["gamma_rule"][0], choices=GAMMA_RULES,
        help=PARAMETERS["gamma_rule"][1],
    )
    parser.add_argument(
        "--approximation", default=PARAMETERS["approximation"][0], choices=APPROXIMATION_STEPS,
        help=PARAMETERS["approximation"][1],
    )
    parser.add_argument("--state-tol", type=float, default=PARAMETERS["state_tol"][0], help=PARAMETERS["state_tol"][1])
    parser.add_argument(
        "--no-elimination", action="store_true", help="keep the identity rows in the Krylov solve (paper's variant)"
    )
    parser.add_argument("--initial", default="zero", choices=["zero", "nested"], help="u0 = 0 or nested (Table 3)")
    parser.add_argument("--nested-from", type=int, default=3, help="coarsest level of a nested start (solved from 0)")
    parser.add_argument("--no-plot", action="store_true", help="skip the PNG of the contact states")
    args = cli.parse_args(parser, argv)
    lame_parameters(args.young, args.poisson)
    if args.law == "tresca":
        require(args.slip_bound is not None and args.slip_bound > 0, "slip-bound", "--law tresca needs a slip bound > 0 (Pa)")
        args.friction = 0.0
    else:
        require(args.slip_bound is None, "slip-bound", "only used with --law tresca")
    require(0 <= args.nested_from < args.lev or args.initial == "zero", "nested-from", "must lie in [0, lev)")
    args.solver_parameters = check_parameters({
        "pc": args.pc,
        "tol": args.tol,
        "rtol": args.rtol,
        "max_iterations": args.max_iterations,
        "state_tol": args.state_tol,
        "gamma_rule": args.gamma_rule,
        "approximation": args.approximation,
        "eliminate_fixed_rows": not args.no_elimination,
    })
    return args


def main(argv: list[str] | None = None) -> int:
    comm = MPI.COMM_WORLD
    try:  # every input check (here and in the library) runs before assembly
        args = parse(argv)
        levels = range(args.nested_from, args.lev + 1) if args.initial == "nested" else [args.lev]
        solutions = solve_nested(
            comm, levels, gap=data.gap_function(args.geometry), tractions=data.tractions(args.load),
            young=args.young, poisson=args.poisson, friction=args.friction, slip_bound=args.slip_bound or 0.0,
            parameters=args.solver_parameters,
        )
    except ParameterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = io.prepare_output_dir(comm, args.output)
    problem, u, result = solutions[-1].problem, solutions[-1].u, solutions[-1].result
    runs = [{"lev": s.lev, "status": s.result.status, "iterations": s.result.iterations,
             "krylov_iterations": s.result.krylov_iterations} for s in solutions]

    case = f"{args.geometry}/{args.load}"
    paper_data = args.law == "coulomb" and (args.friction, args.young, args.poisson) == (data.FRICTION, data.YOUNG, data.POISSON)
    paper = (data.PAPER_TABLE3 if args.initial == "nested" else data.PAPER_TABLE2).get(args.lev, {}).get(case) if paper_data else None
    summary = {
        "problem": "coulomb3d",
        "status": result.status,
        "parameters": vars(args),
        "petsc_options": PETSc.Options().getAll(),
        "mpi_size": comm.size,
        "p": problem.n_contact,
        "n": problem.n_free,
        "iterations": result.iterations,
        "krylov_iterations": result.krylov_iterations,
        "gamma": result.gamma,
        "residual_history": [h["residual"] for h in result.history],
        "history": result.history,
        "timings": result.timings,
        "levels": runs,
        "paper": None if paper is None else {"iterations": paper[0], "gmres": paper[1]},
    }
    if result.converged:
        displacement = solutions[-1].physical_displacement()
        io.write_vtx(out / "displacement.bp", [displacement])
        io.write_xdmf(out / "contact.xdmf", problem.V.mesh, [displacement])
        surface = contact_fields(problem, u, result)
        io.write_xdmf(out / "contact_surface.xdmf", surface.mesh, surface.functions)
        io.write_solution_npz(out / "solution.npz", displacement)
        if not args.no_plot:
            summary["plot"] = plot_contact_states(str(out / "contact_states.png"), surface)
        norm = displacement.x.petsc_vec.norm()
        if comm.rank == 0:
            print(f"||u~||_2 = {norm:.10e}  ({result.iterations} Newton steps, {result.krylov_iterations} Krylov)")
    io.write_summary(comm, out / "summary.json", summary)
    if not result.converged:
        logger.error("not converged: status %s (see %s)", result.status, out / "summary.json")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
