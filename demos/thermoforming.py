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

Run in parallel as ``mpirun -n 2 python demos/thermoforming.py``. Unknown options starting
with '-' go to PETSc, e.g. ``-qvi_newton_pc_factor_mat_solver_type superlu_dist`` or
``-obstacle_pfmy_snes_monitor``.
"""

from __future__ import annotations

import sys
import time

from mpi4py import MPI

import numpy as np
import ufl

from dolfinx import fem

from contactqvi import cli, io
from contactqvi.parameters import ParameterError, require
from contactqvi.problems import thermoforming as data
from contactqvi.qvi import OUTER_METHODS, build, create_mesh
from contactqvi.qvi import postprocess


#: mesh sizes of the paper's figures: Fig. 1/Table 1 (h = 5e-4), Fig. 3 (h = 0.02), Table 3 (h = 0.01 row)
DEFAULT_H = {1: 5e-4, 2: 5e-4, 3: 0.02, 4: 0.01}
#: C2 regularisation parameters in the convergence comparison (Fig. 3(d))
C2_RHOS = (1e-2, 1e-3, 1e-4)


def parse(argv: list[str] | None = None):
    parser = cli.make_parser(__doc__.split("\n")[0], "results/thermoforming")
    parser.add_argument("--test", type=int, default=3, help="paper test 1-4 (Sects. 4.2-4.5)")
    parser.add_argument("--method", default="alg2", help=f"outer method: {', '.join(OUTER_METHODS)}")
    parser.add_argument("--h", type=float, default=None, help=f"mesh size (default per test: {DEFAULT_H})")
    parser.add_argument("--parameter-set", default="I", help="Test 1: parameter set I or II")
    parser.add_argument("--initial", default="zero", help="Test 1: u0 = 0 ('zero') or (-Lap)^{-1} f ('poisson')")
    parser.add_argument("--radius", type=float, default=None, help="projection radius R (Test 2: default 0.01)")
    parser.add_argument(
        "--projection-derivative", default="exact",
        help="G_PB outside the ball: exact (Lemma 2.9) or scaled (R/||u|| Id, as behind the paper's Table 1)",
    )
    parser.add_argument("--rho", type=float, default=1e-4, help="C2: Moreau-Yosida parameter")
    parser.add_argument("--tol", type=float, default=None, help="outer tolerance (default: the paper's)")
    parser.add_argument("--max-iterations", type=int, default=50, help="outer iterations")
    parser.add_argument("--s-solver", default="pfmy-pdas", help="S-solver: pfmy-pdas or vinewtonrsls")
    parser.add_argument("--rho0", type=float, default=1.0, help="PFMY: first rho on a cold start")
    parser.add_argument("--rho-min", type=float, default=1e-6, help="PFMY: last rho")
    parser.add_argument("--no-compare", action="store_true", help="skip the Alg. 2 / C1 / C2 comparison (Fig. 3(d))")
    parser.add_argument("--no-plots", action="store_true", help="skip the PNGs")
    args = cli.parse_args(parser, argv)
    require(args.test in data.TESTS, "test", f"unknown test {args.test!r}; known: {', '.join(map(str, data.TESTS))}")
    require(args.method in OUTER_METHODS, "method", f"unknown method {args.method!r}; known: {', '.join(OUTER_METHODS)}")
    if args.h is None:
        args.h = DEFAULT_H[args.test]
    require(args.h > 0, "h", f"must be > 0, got {args.h!r}")
    if args.radius is None and args.test == 2:
        args.radius = 0.01
    if args.tol is None:
        args.tol = data.paper_tolerance(args.test)
    return args


def run(args, method: str, rho: float | None = None):
    """Build and solve one configuration; returns (setup, result, seconds)."""
    problem = data.make_test(args.test, args.parameter_set, args.initial)
    msh, _ = create_mesh(MPI.COMM_WORLD, problem.dim, args.h)
    outer = {
        "tol": args.tol, "max_iterations": args.max_iterations, "radius": args.radius,
        "projection_derivative": args.projection_derivative,
    }
    s_params = {"method": args.s_solver, "rho0": args.rho0, "rho_min": args.rho_min}
    setup = build(problem, msh, method, outer, s_params, rho=rho if rho is not None else args.rho)
    start = time.perf_counter()
    result = setup.solver.solve(setup.initial)
    return setup, result, time.perf_counter() - start


def write_output(args, setup, result, histories) -> None:
    comm = MPI.COMM_WORLD
    out = io.prepare_output_dir(comm, args.output)
    V = setup.V
    ev = result.evaluation
    u = result.solution
    mould = fem.Function(V, name="mould")
    mould.x.array[:] = ev.obstacle.x.array
    fields = [u, mould]
    if ev.temperature is not None:
        T = fem.Function(V, name="temperature")
        T.x.array[:] = ev.temperature.x.array
        fields.append(T)
    io.write_vtx(out / "thermoforming.bp", fields)
    gathered = {f.name: io.gather_vertex_values(f) for f in fields + [setup.Phi0]}
    x = gathered["membrane"][0]
    values = {name: (vals[:, 0] if vals is not None else None) for name, (_, vals) in gathered.items()}
    with io.atomic_path(comm, out / "solution.npz") as tmp:
        if comm.rank == 0:
            with open(tmp, "wb") as fh:
                np.savez(fh, x=x, **values)
    if args.no_plots or comm.rank != 0:
        comm.Barrier()
        return
    deformation = values["mould"] - values["Phi0"]
    if V.mesh.topology.dim == 2:
        postprocess.plot_surface(out / "membrane.png", x, values["membrane"], "membrane $u$")
        postprocess.plot_surface(out / "mould.png", x, values["mould"], r"mould $\Phi_0 + \varphi T$")
        curves = {"membrane $u$": values["membrane"], r"mould $\Phi_0 + \varphi T$": values["mould"]}
        if "temperature" in values:
            curves["temperature $T$"] = values["temperature"]
            curves[r"deformation $\varphi T$"] = deformation
        postprocess.plot_slice(out / "slice.png", x, curves, 0.5)
    else:
        curves = {"u": values["membrane"], "obstacle": values["mould"]}
        if "temperature" in values:
            curves["T"] = values["temperature"]
        postprocess.plot_profile(out / "solution.png", x[:, 0], curves, f"Test {args.test}", "x")
    postprocess.plot_convergence(out / "convergence.png", histories, f"Test {args.test}, h = {args.h:g}")
    comm.Barrier()


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse(argv)
        setup, result, seconds = run(args, args.method)
    except ParameterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    histories = {args.method: result.residuals}
    comparisons = {}
    if args.test == 3 and not args.no_compare:
        for method, rho in [("alg2", None), ("c1", None)] + [("c2", r) for r in C2_RHOS]:
            label = method if rho is None else f"c2 (rho={rho:g})"
            if label in histories:
                continue
            other_setup, other, secs = run(args, method, rho)
            other_setup.destroy()
            histories[label] = other.residuals
            comparisons[label] = {"status": other.status, "iterations": other.iterations, "seconds": secs}
    write_output(args, setup, result, histories)
    comm = MPI.COMM_WORLD
    u = result.solution
    l2 = comm.allreduce(fem.assemble_scalar(fem.form(u * u * ufl.dx)), op=MPI.SUM) ** 0.5
    summary = {
        "test": args.test,
        "method": args.method,
        "h": args.h,
        "mpi_size": comm.size,
        "status": result.status,
        "outer_iterations": result.iterations,
        "residuals": result.residuals,
        "taken": result.taken,
        "inner_counts": result.counts,
        "inner_totals": result.totals,
        "errors_h10": result.errors,
        "eoc": result.eocs,
        "residual_eoc": result.residual_eocs,
        "seconds": seconds,
        "u_l2_norm": l2,
        "comparison": comparisons,
        "parameters": {k: v for k, v in vars(args).items() if k != "log_level"},
    }
    io.write_summary(comm, io.prepare_output_dir(comm, args.output) / "summary.json", summary)
    if comm.rank == 0:
        print(f"||u||_L2 = {l2:.12e}  ({result.status}, {result.iterations} outer iterations, totals {result.totals})")
    setup.destroy()
    return 0 if result.converged else 1


if __name__ == "__main__":
    sys.exit(main())
