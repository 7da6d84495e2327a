"""Hertz at nu = 0.4999: plain P1 tetrahedra against the nodally averaged volume change (issue 43).

A rigid sphere (``cases/hertz.toml``, R = 1 m, E = 70 GPa) and a steel ball on an aluminium block
(``cases/hertz_bodies.toml``, both bodies meshed, mortar contact) pressed 1 mm (a/R = 0.03), every
body at Poisson's ratio ``--poisson`` (default 0.4999), frictionless, on the meshes of :data:`MESHES`
(``xcoarse`` for the quadratic rows, whose finest mesh is ``medium``: P2 there has the dofs of P1 on
``fine``), with
``formulation = "displacement"`` (plain P1), ``"nodal_pressure"`` (docs/nearly_incompressible.md) and,
as ``--formulations quadratic``, quadratic elements (P2, ``[mesh] order = 2``; the two bodies on
second-order meshes of the same sizes, docs/quadratic.md); ``taylor_hood`` is P2 with the nodal
pressure, the condensed Taylor-Hood pair (docs/nearly_incompressible.md Sect. 5; with
``--pc pressure_schur``, its block preconditioner).
The last step's total force P (four times the quarter model's), contact radius a = sqrt(A / pi) (A
the summed D_ii of the nodes in contact) and peak nodal pressure p0 beside Hertz's with
1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (:mod:`contactqvi.problems.hertz`); the two-body case keeps
the ball's own compliance between its flat face and the contact (R = 32 a), which the half-space
formula does not have (P about 1-2 % low at nu = 0.3: ``results/hertz_bodies.md``). Newton steps
and Krylov iterations per load step with the default solver (``--pc`` to change it)::

    python benchmarks/hertz_incompressible.py [--cases rigid bodies] [--meshes coarse medium fine]

Results: ``benchmarks/results/hertz_incompressible.{json,md}`` (rows of other runs kept).
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import shutil
import time

from mpi4py import MPI

from contactqvi import tables
from contactqvi.case import ContactCase, load_case
from contactqvi.cli import setup_logging
from contactqvi.contact.load_path import solve_load_path
from contactqvi.problems import hertz
from contactqvi.runner import build_problem
from benchlib import hertz_measures
from hertz_bodies import mesh_source
from rows import cell, failed, failed_row, merge_rows, order, percent

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASES = {"rigid": (ROOT / "cases" / "hertz.toml", "hertz_{}.geo"),
         "bodies": (ROOT / "cases" / "hertz_bodies.toml", "hertz_bodies_{}.geo")}
FORMULATIONS = ("displacement", "nodal_pressure", "quadratic", "taylor_hood")
#: The material formulation of the rows on quadratic elements.
QUADRATIC = {"quadratic": "displacement", "taylor_hood": "nodal_pressure"}
#: Meshes by h at the contact: a/4, a/8, a/16, a/32 (rigid sphere); a/4, a/6, a/10, a/16 (two bodies);
#: the two bodies' hexahedral meshes at a/6 and a/10 (``hertz_bodies.py``; 27-node with quadratic rows).
MESHES = ("xcoarse", "coarse", "medium", "fine", "hex_coarse", "hex_medium")
KEY = ("case", "poisson", "formulation", "mesh", "pc")
#: Where the second-order meshes of quadratic rows are written (removed at the end).
WORK = ROOT / "benchmarks" / "results" / "hertz_incompressible_work"


def configured(name: str, mesh: str, poisson: float, formulation: str, pc: str | None,
               work: pathlib.Path, comm: MPI.Comm) -> ContactCase:
    """The case ``name`` on ``mesh`` with every body at ``poisson`` in ``formulation`` (``"quadratic"``:
    and ``"taylor_hood"``: P2 displacements, the bodies' second-order meshes written into ``work``)."""
    path, geo = CASES[name]
    case = load_case(path)

    def material(m):
        return dataclasses.replace(m, poisson=poisson, formulation=QUADRATIC.get(formulation, formulation))

    changes = {"mesh": dataclasses.replace(case.mesh, file=ROOT / "meshes" / geo.format(mesh))}
    if formulation in QUADRATIC:
        changes["mesh"] = (mesh_source(mesh, 2, work, comm) if name == "bodies"
                           else dataclasses.replace(changes["mesh"], order=2))
    if case.bodies:
        changes["bodies"] = [dataclasses.replace(b, material=material(b.material)) for b in case.bodies]
    else:
        changes["material"] = material(case.material)
    if pc is not None:
        changes["solver"] = {**case.solver, "pc": pc}
    return dataclasses.replace(case, **changes)


def closed_form(case: ContactCase) -> dict[str, float]:
    """Hertz's P, a, p0 at the case's last step (R = 1 m)."""
    if case.bodies:
        (E1, nu1), (E2, nu2) = ((b.material.young, b.material.poisson) for b in case.bodies)
        e_star = hertz.combined_modulus(E1, nu1, E2, nu2)
        depth = -case.bodies[1].boundary.displacement["load"].z * case.steps[-1].load
    else:
        e_star = hertz.effective_modulus(case.material.young, case.material.poisson)
        depth = -case.steps[-1].translation[2]
    return {"P": hertz.contact_force(e_star, 0.0, 1.0, depth), "a": hertz.contact_radius(1.0, depth),
            "p0": hertz.peak_pressure(e_star, 0.0, 1.0, depth)}


def run(name: str, mesh: str, poisson: float, formulation: str, pc: str | None, comm: MPI.Comm) -> dict:
    """One load path: its last step's P, a, p0 against Hertz's, its counts and seconds."""
    key = {"case": name, "poisson": poisson, "formulation": formulation, "mesh": mesh, "pc": pc or "default"}
    case = configured(name, mesh, poisson, formulation, pc, WORK, comm)
    start = time.perf_counter()
    try:
        with build_problem(case, comm) as problem:
            u = problem.A.createVecRight()
            try:
                results = solve_load_path(problem, case.steps, u, dict(case.solver), "hertz_nu_", from_rest=True)
            finally:
                u.destroy()
            force, a, p0 = hertz_measures(problem, results[-1])
            dofs = problem.A.getSize()[0]
    except Exception as exc:  # a step that failed: the table says so and the other runs go on
        return failed_row(f"failed: {type(exc).__name__}: {exc}", time.perf_counter() - start, **key)
    exact = closed_form(case)
    converged = all(r.converged for r in results)
    errors = ({"P": force / exact["P"] - 1.0, "a": a / exact["a"] - 1.0, "p0": p0 / exact["p0"] - 1.0} if converged
              else {})  # a path that stopped has no last step to measure
    return {**key, "dofs": dofs, "status": [str(r.status) for r in results], "newton": [r.iterations for r in results],
            "krylov": [r.inner_iterations for r in results], "seconds": time.perf_counter() - start,
            **errors, "failed": not converged}


def markdown(rows: list[dict]) -> str:
    """One line per run: errors against Hertz in %."""
    lines = ["## Hertz at a Poisson's ratio near 0.5: plain P1, the nodally averaged volume change, quadratic "
             "elements and the condensed Taylor-Hood pair (taylor_hood: P2 with the nodal pressure)", "",
             "Every body at the row's ν, pressed 1 mm by a sphere of R = 1 m (rigid, or a steel ball on an aluminium "
             "block), frictionless, default solver unless `pc` says; errors of the last step's P, a and p0 against "
             "Hertz's (E* = E/(1 − ν²) per body); the two-body rows include the ball's own compliance, which the "
             "half-space formula lacks (P 1–2 % low at ν = 0.3). Newton steps and Krylov iterations per load step. "
             "Taylor–Hood rows with `pc` = `pressure_schur` are session 34's, Krylov iterations on the condensed "
             "Newton matrix; with `default` (the same block preconditioner) since session 35 on the uncondensed "
             "system (docs/nearly_incompressible.md Sect. 5).",
             "", "| case | ν | formulation | mesh | pc | dofs | P | a | p0 | Newton | Krylov | run s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        counts = (" ".join(map(str, r[k])) if k in r else r.get("status", "") for k in ("newton", "krylov"))
        status = r.get("status", "")
        errors = ([percent(r, name) for name in ("P", "a", "p0")] if not failed(r) else
                  [f"stopped at step {len(status)}: {status[-1]}" if isinstance(status, list) else status, "", ""])
        lines.append(f"| {r['case']} | {r['poisson']:g} | {r['formulation']} | {r['mesh']} | {r['pc']} "
                     f"| {cell(r, 'dofs')} | " + " | ".join(errors) + " | "
                     + " | ".join(counts) + f" | {cell(r, 'seconds', '.0f')} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=tuple(CASES), default=list(CASES))
    parser.add_argument("--meshes", nargs="+", choices=MESHES, default=list(MESHES[1:4]))
    parser.add_argument("--formulations", nargs="+", choices=FORMULATIONS, default=list(FORMULATIONS))
    parser.add_argument("--poisson", type=float, default=0.4999)
    parser.add_argument("--pc", default=None, help="the Newton-step solver ([solver] pc); default: the case's")
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    parser.add_argument("--log-level", choices=("DEBUG", "INFO", "WARNING", "ERROR"), default="INFO",
                        help="progress of the runs (INFO: each load step and Newton step, as the case runner)")
    args = parser.parse_args()
    if "rigid" in args.cases and any(m.startswith("hex") for m in args.meshes):
        parser.error("--meshes: the hexahedral meshes are the two bodies' (--cases bodies)")
    setup_logging(args.log_level)
    comm = MPI.COMM_WORLD
    path = args.output / "hertz_incompressible.json"
    rows = []
    for name in args.cases:
        for formulation in args.formulations:
            for mesh in args.meshes:
                rows.append(run(name, mesh, args.poisson, formulation, args.pc, comm))
                if comm.rank == 0:
                    print(markdown(rows[-1:]).splitlines()[-1], flush=True)
                all_rows = sorted(merge_rows(path, rows, KEY), key=lambda r: (order(*KEY[:3])(r), MESHES.index(r["mesh"])))
                tables.write_table(comm, args.output / "hertz_incompressible", {"rows": all_rows}, markdown(all_rows),
                                   echo=False)
    if comm.rank == 0:
        shutil.rmtree(WORK, ignore_errors=True)


if __name__ == "__main__":
    main()
