"""Obstacle-type QVIs and the thermoforming problem by semismooth Newton (seed 003).

This demo illustrates how to:
  * set up the QVI (58) (Tests 1-3) or the semilinear VI (48) (Test 4) of seed 003, Sect. 4,
    on P1 (1D) or Q1 (2D) elements;
  * evaluate H = S o Phi: the temperature map Phi by semismooth Newton (PETSc SNES), the
    obstacle solver S by path-following Moreau-Yosida + primal-dual active set (or SNES VI);
  * solve u = H(u) with Algorithm 1, Algorithm 2 or the comparison methods C1-C3, with the
    Newton system (62)-(64) as one block system, optionally localised to a ball B_R(0) (Test 2);
  * print one line per outer iteration, and write summary.json, solution.npz, ParaView (VTX)
    files of the membrane u, the temperature T and the mould Phi0 + varphi T, and PNGs
    like Fig. 3 (surfaces, slice at x2 = 1/2, convergence of Alg. 2 vs C1 vs C2).

Run in parallel as ``mpirun -n 2 python demos/thermoforming.py``.
"""

from __future__ import annotations

import sys

from mpi4py import MPI

import ufl

from dolfinx import fem

from contactqvi import cli, tables
from contactqvi.parameters import Parameter, ParameterError, Parameters
from contactqvi.problems import thermoforming as data
from contactqvi.qvi import BUILD_PARAMETERS, FIXED_POINT_PARAMETERS, build, create_mesh, postprocess
from contactqvi.vi.solver import OBSTACLE_PARAMETERS, check_obstacle_parameters

#: mesh sizes of the paper's figures: Fig. 1/Table 1 (h = 5e-4), Fig. 3 (h = 0.02), Table 3 (h = 0.01 row)
DEFAULT_H = {1: 5e-4, 2: 5e-4, 3: 0.02, 4: 0.01}
#: C2 regularisation parameters in the convergence comparison (Fig. 3(d))
C2_RHOS = (1e-2, 1e-3, 1e-4)

DEMO_PARAMETERS = Parameters(
    h=Parameter(None, f"mesh size (none: per test, {DEFAULT_H})", minimum=0.0, exclusive=True, optional=True),
    compare=Parameter(True, "Test 3: also run Alg. 2, C1 and C2 for Fig. 3(d)", type=bool),
    plots=Parameter(True, "write the PNGs", type=bool),
)
#: the parameter tables on the command line: group -> (table, names; None: all)
TABLES = {
    "problem": (data.TEST_PARAMETERS, None),
    "build": (BUILD_PARAMETERS, None),
    "outer": (FIXED_POINT_PARAMETERS, [n for n in FIXED_POINT_PARAMETERS if n not in ("method", "label")]),
    "obstacle": (OBSTACLE_PARAMETERS, None),
    "demo": (DEMO_PARAMETERS, None),
}


def parse(argv: list[str] | None = None) -> tuple[dict[str, dict], str]:
    """Checked parameters by group, and the output directory."""
    parser = cli.make_parser(__doc__.split("\n")[0], "results/thermoforming", petsc_example="-obstacle_pfmy_snes_monitor")
    for table, names in TABLES.values():
        table.add_arguments(parser, names)
    parser.description += " Test 2: --radius none is 0.01."
    args = cli.parse_args(parser, argv)
    given = {group: {n: getattr(args, n) for n in (names or table)} for group, (table, names) in TABLES.items()}
    test = data.TEST_PARAMETERS.check(given["problem"])["test"]
    if given["outer"]["radius"] is None and test == 2:
        given["outer"]["radius"] = 0.01
    if given["demo"]["h"] is None:
        given["demo"]["h"] = DEFAULT_H[test]
    prm = {group: {n: v for n, v in table.check(given[group]).items() if n in given[group]}
           for group, (table, _) in TABLES.items()}
    check_obstacle_parameters(prm["obstacle"])
    return prm, args.output


def run(prm: dict[str, dict], method: str, rho: float | None = None):
    """Build and solve one configuration; returns (setup, result)."""
    problem = data.make_test(**prm["problem"])
    msh, _ = create_mesh(MPI.COMM_WORLD, problem.dim, prm["demo"]["h"])
    build_prm = {**prm["build"], "method": method, "rho": rho or prm["build"]["rho"]}
    setup = build(problem, msh, outer_parameters=prm["outer"], obstacle_parameters=prm["obstacle"], **build_prm)
    return setup, setup.solver.solve(setup.initial)


def compare(prm: dict[str, dict], histories: dict[str, list[float]]) -> dict[str, dict]:
    """Fig. 3(d): Algorithm 2, C1 and C2 for several rho beside the main run (added to ``histories``)."""
    comparisons = {}
    for method, rho in [("alg2", None), ("c1", None)] + [("c2", r) for r in C2_RHOS]:
        label = method if rho is None else f"c2 (rho={rho:g})"
        if label not in histories:
            setup, other = run(prm, method, rho)
            setup.destroy()
            histories[label] = other.residuals
            comparisons[label] = {key: other.summary()[key] for key in ("status", "iterations", "timings")}
    return comparisons


def main(argv: list[str] | None = None) -> int:
    try:
        prm, output = parse(argv)
        setup, result = run(prm, prm["build"]["method"])
    except ParameterError as exc:
        cli.print_error(exc)
        return 2
    comm = MPI.COMM_WORLD
    test, h = prm["problem"]["test"], prm["demo"]["h"]
    prm["outer"]["atol"] = setup.solver.params["atol"]  # none: the test's (the paper's)
    histories = {prm["build"]["method"]: result.residuals}
    comparisons = compare(prm, histories) if test == 3 and prm["demo"]["compare"] else {}
    out = tables.prepare_output_dir(comm, output)
    postprocess.write_results(out, result, setup.Phi0, histories, f"Test {test}, h = {h:g}", prm["demo"]["plots"])
    u = result.solution
    l2 = comm.allreduce(fem.assemble_scalar(fem.form(u * u * ufl.dx)), op=MPI.SUM) ** 0.5
    summary = {
        "test": test,
        "method": prm["build"]["method"],
        "h": h,
        "mpi_size": comm.size,
        **result.summary(),
        "inner_totals": result.totals,
        "errors_h10": result.errors,
        "eoc": result.eocs,
        "residual_eoc": result.residual_eocs,
        "u_l2_norm": l2,
        "comparison": comparisons,
        "parameters": prm,
    }
    tables.write_summary(comm, out / "summary.json", summary)
    if comm.rank == 0:
        print(f"||u||_L2 = {l2:.12e}  ({result.status}, {result.iterations} outer iterations, totals {result.totals})")
    setup.destroy()
    return 0 if result.converged else 1


if __name__ == "__main__":
    sys.exit(cli.abort_on_error(main))
