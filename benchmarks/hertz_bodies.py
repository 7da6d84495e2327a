"""Hertz between two elastic bodies on non-matching meshes, against the closed form.

Runs ``cases/hertz_bodies.toml`` (a steel ball pressed into an aluminium block,
both meshed, mortar contact) on three meshes and puts the force P, the contact
radius a and the peak pressure p0 of the last step beside Hertz's formulas with
1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (:mod:`contactqvi.problems.hertz`)::

    python benchmarks/hertz_bodies.py [--meshes coarse medium fine] [--output DIR]

P is the total contact force (four times the quarter model's), a = sqrt(4 A / pi)
from the contact area A (the sum of the D_ii of the nodes in contact), p0 the
largest nodal pressure lambda_i / D_ii. Writes ``hertz_bodies.{json,md}``.
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import time

from mpi4py import MPI

import numpy as np

from contactqvi import tables
from contactqvi.case import load_case
from contactqvi.contact.load_path import solve_load_path
from contactqvi.problems import hertz
from contactqvi.runner import build_problem

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "hertz_bodies.toml"
MESHES = {"coarse": 6, "medium": 10, "fine": 16}  # h at the contact = a / value (block; the ball 0.7 of it)


def run(mesh: str, comm: MPI.Comm) -> dict:
    """One load path on ``meshes/hertz_bodies_{mesh}.geo``: counts, times and the last step's P, a, p0."""
    case = load_case(CASE)
    case = dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / f"hertz_bodies_{mesh}.geo"))
    start = time.perf_counter()
    with build_problem(case, comm) as problem:
        built = time.perf_counter()
        u = problem.A.createVecRight()
        results = solve_load_path(problem, case.steps, u, dict(case.solver), "hertz_bodies_", from_rest=True)
        solved = time.perf_counter()
        u.destroy()
        last = results[-1]
        touching = last.normal_force > 0.0
        force = 4.0 * comm.allreduce(float(last.normal_force.sum()), op=MPI.SUM)
        area = 4.0 * comm.allreduce(float(problem.contact_area[touching].sum()), op=MPI.SUM)
        p0 = comm.allreduce(float((last.normal_force / problem.contact_area).max(initial=0.0)), op=MPI.MAX)
        dofs = problem.A.getSize()[0]
    return {
        "mesh": mesh, "h": f"a/{MESHES[mesh]}", "dofs": dofs, "ranks": comm.size,
        "status": [str(r.status) for r in results], "newton": [r.iterations for r in results],
        "krylov": [r.inner_iterations for r in results], "assembly_s": built - start, "solve_s": solved - built,
        "P": force, "a": float(np.sqrt(area / np.pi)), "p0": p0,
    }


def closed_form() -> dict:
    """Hertz's P, a, p0 for the case's bodies at the last step."""
    case = load_case(CASE)
    (E1, nu1), (E2, nu2) = ((b.material.young, b.material.poisson) for b in case.bodies)
    e_star = hertz.combined_modulus(E1, nu1, E2, nu2)
    depth = -case.bodies[1].boundary.displacement["load"].z * case.steps[-1].load
    return {"E_star": e_star, "delta": depth, "P": hertz.contact_force(e_star, 0.0, 1.0, depth),
            "a": hertz.contact_radius(1.0, depth), "p0": hertz.peak_pressure(e_star, 0.0, 1.0, depth)}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--meshes", nargs="+", choices=tuple(MESHES), default=list(MESHES))
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    args, _ = parser.parse_known_args(argv)
    comm = MPI.COMM_WORLD
    reference = closed_form()
    rows = [run(mesh, comm) for mesh in args.meshes]
    header = ["mesh (h at contact)", "dofs", "Newton per step", "Krylov per step", "P (MN) / Hertz", "error P",
              "a (mm) / Hertz", "|a - a_H| / h", "p0 (GPa) / Hertz", "error p0", "solve (s)"]
    table = []
    for row in rows:
        h = reference["a"] / MESHES[row["mesh"]]
        table.append([f"{row['mesh']} ({row['h']})", row["dofs"], " ".join(map(str, row["newton"])),
                      " ".join(map(str, row["krylov"])), f"{row['P'] / 1e6:.4f} / {reference['P'] / 1e6:.4f}",
                      f"{row['P'] / reference['P'] - 1:+.2%}", f"{row['a'] * 1e3:.2f} / {reference['a'] * 1e3:.2f}",
                      f"{abs(row['a'] - reference['a']) / h:.2f}",
                      f"{row['p0'] / 1e9:.3f} / {reference['p0'] / 1e9:.3f}", f"{row['p0'] / reference['p0'] - 1:+.2%}",
                      f"{row['solve_s']:.1f}"])
    title = ("## Hertz between two elastic bodies: steel ball (R = 1 m, E = 210 GPa) pressed 1 mm into an "
             "aluminium block (E = 70 GPa), nu = 0.3, non-matching meshes, mortar contact\n\n"
             f"E* = {reference['E_star'] / 1e9:.2f} GPa; quarter model, four steps of 0.25 mm on "
             f"{comm.size} rank(s); P the total contact force, a from the contact area (pi a^2 = sum of D_ii in "
             "contact), p0 the largest nodal pressure lambda_i / D_ii. The ball's own compliance between its "
             "loaded face (R = 32 a from the contact) and the contact is not in the half-space formula.")
    args.output.mkdir(parents=True, exist_ok=True)
    tables.write_table(comm, args.output / "hertz_bodies", {"closed_form": reference, "runs": rows},
                       title + "\n\n" + tables.markdown_table(header, table))


if __name__ == "__main__":
    main()
