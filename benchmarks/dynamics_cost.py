"""The cost of a dynamic time step against a quasi-static load step of the same case (issue 44).

This benchmark illustrates how to drive the two solvers of one case from Python: the load path
(:func:`~contactqvi.contact.load_path.solve_load_path`) and the contact-stabilised Newmark
integrator (:class:`~contactqvi.contact.dynamics.StabilisedNewmark`), each on a problem built
from the same case file. The case (``--case``, default ``cases/hertz.toml``: a rigid sphere
pressed 1 mm into a block in four steps) runs as shipped, and again with ``[dynamics]``: the
material gets a density (``--density``), its steps become time points ``--dt`` apart (one time
step per load step, the sphere moving as along the path), ``--steps`` time steps in all (the
sphere held after the last point). Per mesh (``--meshes``, files of ``meshes/``):

* the wall seconds of a load step and of a time step, each timed around the solve alone
  (the solver's set-up, made once, is in the first step of each and left out: steps 2 on),
  the fastest of ``--repeat`` runs of each (the machine is shared);
* the Newton steps: a load step's, a time step's implicit step (3.3) plus its projection (3.2).

Issue 44's goal: a time step costs at most 1.5 times a load step. Writes
``benchmarks/results/dynamics_cost.{json,md}``. Run with ``nice`` on a shared machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import statistics
import time

from mpi4py import MPI

from contactqvi import tables
from contactqvi.case import ContactCase, Dynamics, Step, check_solver, load_case
from contactqvi.contact.dynamics import StabilisedNewmark
from contactqvi.contact.load_path import SOLVER_PARAMETERS, solve_load_path
from contactqvi.linalg import default_options
from contactqvi.runner import PREFIX, build_problem

ROOT = pathlib.Path(__file__).resolve().parent.parent


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--case", default=str(ROOT / "cases" / "hertz.toml"), help="a quasi-static case file")
    parser.add_argument("--meshes", nargs="+", default=["hertz_coarse.geo", "hertz_medium.geo"],
                        help="mesh files of meshes/ to run the case on")
    parser.add_argument("--density", type=float, default=2700.0, help="the material's density (kg/m^3)")
    parser.add_argument("--dt", type=float, default=1e-4, help="time step (s) = time between the load steps")
    parser.add_argument("--steps", type=int, default=5, help="time steps (the default: the sphere's four and one held)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each, the fastest kept")
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    return parser.parse_args()


def quasi_static(case: ContactCase, comm: MPI.Comm) -> tuple[list[float], list[int]]:
    """Wall seconds and Newton steps of each load step of ``case``."""
    parameters = check_solver(case, SOLVER_PARAMETERS)
    seconds, marks = [], [time.perf_counter()]

    def timed(index, step, u, result, state) -> None:
        comm.Barrier()
        marks.append(time.perf_counter())

    with default_options(PREFIX, case.petsc), build_problem(case, comm) as problem:
        u = problem.A.createVecRight()
        results = solve_load_path(problem, case.steps, u, parameters, PREFIX, timed, from_rest=True)
        u.destroy()
    seconds = [b - a for a, b in zip(marks, marks[1:])]
    return seconds, [result.iterations for result in results]


def dynamic(case: ContactCase, comm: MPI.Comm) -> tuple[list[float], list[int]]:
    """Wall seconds and Newton steps (implicit step plus projection) of each time step of ``case``."""
    seconds, newton = [], []
    with default_options(PREFIX, case.petsc), build_problem(case, comm) as problem, \
            StabilisedNewmark(problem, case.material.density, case.dynamics.dt, {}, PREFIX, case.steps) as integrator:
        state, u = integrator.initial_state(), problem.A.createVecRight()
        for _ in range(case.dynamics.steps):
            start = time.perf_counter()
            projection, result = integrator.step(state, u)
            comm.Barrier()
            seconds.append(time.perf_counter() - start)
            assert projection.converged and result.converged, (projection.status, result.status)
            newton.append(result.iterations + projection.iterations)
        state.destroy()
        u.destroy()
    return seconds, newton


def with_time(case: ContactCase, density: float, dt: float, steps: int) -> ContactCase:
    """``case`` with a density and its load steps as time points dt apart, ``steps`` time steps."""
    points = tuple(dataclasses.replace(step, time=(k + 1) * dt) for k, step in enumerate(case.steps))
    material = dataclasses.replace(case.material, density=density)
    return dataclasses.replace(case, material=material, steps=points, dynamics=Dynamics(dt, steps * dt))


def main() -> None:
    args = parse()
    comm = MPI.COMM_WORLD
    base = load_case(args.case)
    header = ["mesh", "free dofs", "load step (s)", "time step (s)", "time / load step", "Newton per load step",
              "Newton per time step (step + projection)"]
    rows = []
    for mesh in args.meshes:
        case = dataclasses.replace(base, mesh=dataclasses.replace(base.mesh, file=ROOT / "meshes" / mesh))
        timed = case, with_time(case, args.density, args.dt, args.steps)
        runs = [(quasi_static(timed[0], comm), dynamic(timed[1], comm)) for _ in range(args.repeat)]
        (_, static_newton), (_, dynamic_newton) = runs[0]
        load_step = min(statistics.mean(static[0][1:]) for static, _ in runs)
        time_step = min(statistics.mean(moving[0][1:]) for _, moving in runs)
        with build_problem(case, comm) as problem:
            free = problem.n_free
        rows.append([mesh, free, round(load_step, 3), round(time_step, 3), round(time_step / load_step, 2),
                     statistics.mean(static_newton), statistics.mean(dynamic_newton)])
        text = (f"# A time step against a load step (benchmarks/dynamics_cost.py, {comm.size} rank(s))\n\n"
                f"{pathlib.Path(args.case).name} with the default solver, as shipped and with [dynamics] (density "
                f"{args.density:g} kg/m^3, its steps as time points {args.dt:g} s apart, {args.steps} time steps): "
                f"the mean wall seconds of a step from the second on (the solver's set-up is in the first), the "
                f"fastest of {args.repeat} runs.\n\n"
                + tables.markdown_table(header, rows))
        tables.write_table(comm, pathlib.Path(args.output) / "dynamics_cost", {"header": header, "rows": rows}, text)


if __name__ == "__main__":
    main()
