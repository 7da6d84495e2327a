"""Stadler's simplified (scalar Tresca) friction problem, seed 002, Examples 1-3.

This demo illustrates how to:
  * build the paper's examples on the unit square with N grid points per
    direction (Q1 quadrilaterals, or P1 triangles) and a lumped boundary mass;
  * solve the regularised problem (P*_gamma) with the primal-dual active set
    method (PDAS, parameter sigma) or the semismooth Newton method (SS, sigma = 1/gamma);
  * solve the original problem (P*) with the augmented Lagrangian method (ALM,
    exact or inexact inner solves, fixed gamma or gamma_l = 10^l) or with Uzawa's method;
  * report d_lambda = ||lambda_bar - lambda||_{L2(Gamma_f)} against lambda_bar = lambda_{1e16};
  * write summary.json, solution.npz, ParaView files and (with a display) a PNG of y.

Run, e.g.::

    python demos/simplified_friction.py --example 2 --method pdas --gamma 1e3 --N 160
    mpirun -n 2 python demos/simplified_friction.py --example 3 --method alm --alm-inner inexact \
        --alm-schedule power10
"""

from __future__ import annotations

import argparse
import logging
import pathlib
import sys
import time

from mpi4py import MPI

import numpy as np

from dolfinx import fem

from contactqvi import io
from contactqvi.cli import make_parser, parse_args
from contactqvi.friction import (
    INNER_SOLVES,
    PrimalDualActiveSet,
    augmented_lagrangian,
    semismooth_newton_sigma,
    uzawa,
)
from contactqvi.parameters import ParameterError, require, require_positive
from contactqvi.problems.stadler import EXAMPLE2_READINGS, create_stadler_problem, stadler_example

logger = logging.getLogger("simplified_friction")

METHODS = ("pdas", "ss", "alm", "uzawa")
SCHEDULES = ("constant", "power10")
#: gamma of the reference solution lambda_bar = lambda_{1e16} (Sect. 6).
REFERENCE_GAMMA = 1e16


def boundary_function(V: fem.FunctionSpace, dofs: np.ndarray, values: np.ndarray, name: str) -> fem.Function:
    """A function of V equal to ``values`` at the friction nodes and 0 elsewhere (for ParaView)."""
    u = fem.Function(V, name=name)
    u.x.array[dofs] = values
    u.x.scatter_forward()
    return u


def write_png(path: pathlib.Path, comm: MPI.Comm, y: fem.Function, title: str) -> bool:
    """Surface plot of y over the unit square like Fig. 6.1/6.2 (rank 0, if a display is available)."""
    n_owned = y.function_space.dofmap.index_map.size_local
    xs = comm.gather(y.function_space.tabulate_dof_coordinates()[:n_owned, :2], root=0)
    vs = comm.gather(y.x.array[:n_owned].copy(), root=0)
    if not io.start_virtual_display():
        return False
    if comm.rank == 0:
        import pyvista

        # Sort the vertices by (x2, x1) rounded (dof coordinates carry round-off) into an n x n grid.
        x, values = np.round(np.vstack(xs), 12) + 0.0, np.concatenate(vs)
        order = np.lexsort((x[:, 0], x[:, 1]))
        n = int(round(np.sqrt(len(values))))
        x, surface = x[order], values[order].reshape(n, n)  # row = x2, column = x1
        grid = pyvista.StructuredGrid(x[:, 0].reshape(n, n), x[:, 1].reshape(n, n), surface)
        grid["y"] = surface.ravel(order="F")  # pyvista stores structured points in Fortran order
        plotter = pyvista.Plotter(off_screen=True, window_size=(900, 700))
        plotter.add_mesh(grid, scalars="y", cmap="viridis", show_edges=False)
        plotter.add_text(title, font_size=10)
        plotter.set_scale(zscale=1.0 / max(float(np.abs(values).max()), 1e-12))
        plotter.show_grid()
        plotter.screenshot(str(path))
        plotter.close()
    return True


def main(argv: list[str] | None = None) -> int:
    parser = make_parser(__doc__.split("\n")[0], "results/simplified_friction")
    parser.add_argument("--example", type=int, default=1, help="example of Sect. 6: 1, 2 or 3")
    parser.add_argument("--method", default="pdas", help="pdas | ss | alm | uzawa")
    parser.add_argument("--gamma", type=float, default=1e4, help="regularisation/penalty parameter gamma")
    parser.add_argument("--sigma", type=float, default=1.0, help="sigma of (PDAS) and of ALM's inner PDAS (ss: 1/gamma)")
    parser.add_argument("--N", type=int, default=80, help="grid points per direction (N - 1 cells)")
    parser.add_argument("--g", type=float, default=None, help="override the example's friction bound g")
    parser.add_argument("--mu", type=float, default=None, help="override the example's mu in a(y, z)")
    parser.add_argument("--cell-type", default="quadrilateral", help="quadrilateral (Q1) or triangle (P1)")
    parser.add_argument("--max-iterations", type=int, default=50, help="PDAS/SS iterations (Uzawa: x20)")
    parser.add_argument("--alm-inner", default="exact", help="ALM inner solve: exact | inexact")
    parser.add_argument("--alm-schedule", default="constant", help="ALM gamma: constant | power10 (gamma_l = 10^l)")
    parser.add_argument("--alm-steps", type=int, default=7, help="maximal number of ALM steps")
    parser.add_argument(
        "--tol", type=float, default=None,
        help="ALM/Uzawa tolerance on d_lambda, or on ||lambda^l - lambda^(l-1)|| with --no-reference (Uzawa: 1e-4)",
    )  # fmt: skip
    parser.add_argument("--example2-reading", default="x1x2", help="reading of f in Example 2: x1x2 | x1x1")
    parser.add_argument(
        "--reference", action=argparse.BooleanOptionalAction, default=True,
        help="compute lambda_bar = lambda_{1e16} for d_lambda and the paper's stopping test of ALM/Uzawa",
    )  # fmt: skip
    parser.add_argument(
        "--png", action=argparse.BooleanOptionalAction, default=True, help="plot y to y.png if a display is available"
    )
    args = parse_args(parser, argv)
    comm = MPI.COMM_WORLD
    try:
        require(args.method in METHODS, "method", f"must be one of {METHODS}, got {args.method!r}")
        require(args.alm_inner in INNER_SOLVES, "alm-inner", f"must be one of {INNER_SOLVES}, got {args.alm_inner!r}")
        require(
            args.alm_schedule in SCHEDULES, "alm-schedule", f"must be one of {SCHEDULES}, got {args.alm_schedule!r}"
        )
        require(
            args.example2_reading in EXAMPLE2_READINGS,
            "example2-reading",
            f"must be one of {EXAMPLE2_READINGS}, got {args.example2_reading!r}",
        )
        require_positive("gamma", args.gamma)
        require_positive("sigma", args.sigma)
        require(args.max_iterations >= 1, "max-iterations", f"must be >= 1, got {args.max_iterations!r}")
        require(args.alm_steps >= 1, "alm-steps", f"must be >= 1, got {args.alm_steps!r}")
        if args.tol is not None:
            require_positive("tol", args.tol)
        example = stadler_example(args.example, args.example2_reading)
        problem = create_stadler_problem(comm, example, args.N, args.cell_type, g=args.g, mu=args.mu)
    except ParameterError as exc:
        if comm.rank == 0:
            print(f"error: {exc}", file=sys.stderr)
        return 2
    out = io.prepare_output_dir(comm, args.output)
    power10 = args.method == "alm" and args.alm_schedule == "power10"
    gamma_label = "10^l" if power10 else f"{args.gamma:g}"
    logger.info(
        "Example %d (%s), g=%g, mu=%g, N=%d (%d cells/direction, %s), %d friction nodes; method %s, gamma=%s",
        example.number, example.description, problem.g, problem.mu, args.N, args.N - 1, args.cell_type,
        problem.n_boundary, args.method, gamma_label,
    )  # fmt: skip

    pdas = PrimalDualActiveSet(problem)
    start = time.perf_counter()
    reference = None
    if args.reference:
        logger.info("reference lambda_bar = lambda_gamma, gamma = %.0e (PDAS, sigma = 1):", REFERENCE_GAMMA)
        ref_result = pdas.solve(REFERENCE_GAMMA, 1.0, max_iterations=100)
        if not ref_result.converged:
            raise RuntimeError(f"PDAS for lambda_bar ended with status {ref_result.status!r}")
        reference = ref_result.lam
    summary: dict = {
        "example": example.number,
        "load": example.description,
        "method": args.method,
        "N": args.N,
        "cells_per_direction": args.N - 1,
        "cell_type": args.cell_type,
        "g": problem.g,
        "mu": problem.mu,
        "gamma": gamma_label if power10 else args.gamma,
        "friction_nodes": problem.n_boundary,
        "mpi_ranks": comm.size,
    }
    solve_start = time.perf_counter()
    if args.method in ("pdas", "ss"):
        sigma = semismooth_newton_sigma(args.gamma) if args.method == "ss" else args.sigma
        result = pdas.solve(args.gamma, sigma, reference=reference, max_iterations=args.max_iterations)
        summary.update(sigma=sigma, iterations=result.iterations, history=result.history)
        y, lam, states = result.y, result.lam, result.states
    elif args.method == "alm":
        gamma = (lambda step: 10.0**step) if power10 else args.gamma
        result = augmented_lagrangian(
            pdas, gamma, inner=args.alm_inner, sigma=args.sigma, reference=reference, tol=args.tol,
            max_outer=args.alm_steps, max_inner=args.max_iterations,
        )  # fmt: skip
        summary.update(
            sigma=args.sigma, alm_inner=args.alm_inner, alm_schedule=args.alm_schedule,
            outer_iterations=result.outer_iterations, inner_iterations=[h["inner_iterations"] for h in result.history], linear_solves=result.linear_solves,
            history=result.history,
        )  # fmt: skip
        y, lam = result.y, result.lam
        states = np.where(np.abs(lam.array_r) >= problem.g, np.sign(lam.array_r), 0).astype(np.int8)
    else:
        result = uzawa(
            problem, args.gamma, reference=reference, tol=1e-4 if args.tol is None else args.tol,
            max_iterations=20 * args.max_iterations,
        )  # fmt: skip
        summary.update(iterations=result.iterations, history=result.history)
        y, lam = result.y, result.lam
        states = np.where(np.abs(lam.array_r) >= problem.g, np.sign(lam.array_r), 0).astype(np.int8)
    solve_seconds = time.perf_counter() - solve_start

    y_norm = problem.energy_norm(y.x.petsc_vec)
    lam_norm = problem.boundary_norm(lam.array_r)
    d_lambda = problem.boundary_norm(reference.array_r - lam.array_r) if reference is not None else None
    summary.update(
        status=result.status,
        converged=result.converged,
        energy_norm_y=y_norm,
        l2_norm_lambda=lam_norm,
        max_abs_lambda=comm.allreduce(float(np.abs(lam.array_r).max(initial=0.0)), op=MPI.MAX),
        d_lambda=d_lambda,
        active_minus=problem.count(states == -1),
        active_plus=problem.count(states == 1),
        inactive=problem.count(states == 0),
        solve_seconds=solve_seconds,
        total_seconds=time.perf_counter() - start,
    )

    V = problem.V
    lam_fn = boundary_function(V, problem.boundary_dofs, lam.array_r, "lambda")
    set_fn = boundary_function(V, problem.boundary_dofs, states.astype(float), "active_set")
    io.write_vtx(out / "solution.bp", [y, lam_fn, set_fn])
    x_b = V.tabulate_dof_coordinates()[problem.boundary_dofs]
    gathered = [comm.gather(a, root=0) for a in (x_b, lam.array_r.copy(), states)]
    extra = {}
    if comm.rank == 0:
        xb, lb, sb = (np.concatenate(a) for a in gathered)
        order = np.lexsort((xb[:, 0], xb[:, 1]))
        extra = {"boundary_x": xb[order], "lam": lb[order], "active_set": sb[order]}
    io.write_solution_npz(out / "solution.npz", y, **extra)
    title = f"Example {example.number}, {args.method}, gamma = {gamma_label}, N = {args.N}"
    summary["png"] = "y.png" if args.png and write_png(out / "y.png", comm, y, title) else None
    io.write_summary(comm, out / "summary.json", summary)
    pdas.destroy()

    if comm.rank == 0:
        print(f"status {result.status}; |||y||| = {y_norm:.12e}; ||lambda||_L2(Gamma_f) = {lam_norm:.12e}")
    return 0 if result.converged else 1


if __name__ == "__main__":
    sys.exit(main())
