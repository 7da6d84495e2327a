"""Quadratic against linear tetrahedra on the cases of issue 43 that meet a rigid obstacle.

Each row is one run of :func:`contactqvi.runner.run_case` with default settings and ``[mesh]
order`` 1 (P1) or 2 (P2 displacements, the contact in the modified basis of
:mod:`contactqvi.contact.quadratic`):

* ``oring``: the new user's O-ring cord (``benchmarks/data/oring/oring.toml``: d = 5 mm,
  neo-Hookean, E = 5 MPa, squeezed 30 % between plates in 20 steps, a plane-strain slice) at
  Poisson's ratio ``--poisson`` on the meshes of h = 0.25 and 0.125 mm, frictionless or with Coulomb
  friction ``--friction``, its ``[material] formulation`` ``--formulation`` (``nodal_pressure``
  with ``order`` 2 is the condensed Taylor-Hood pair, docs/nearly_incompressible.md Sect. 6): the
  plate's force at 30 %, its ratio to the same mesh, order, formulation and friction at nu = 0.45,
  the contact area, the Newton steps that fell back on a direct solve.
* ``hertz``: ``cases/hertz.toml`` (a rigid sphere, R = 1 m, pressed 1 mm into a block, E = 70 GPa,
  nu = 0.3) on its coarse and medium meshes: P, a and p0 against Hertz.

Per row the dofs, Newton steps per load step, Krylov iterations per Newton step and seconds::

    .venv/bin/python benchmarks/quadratic_elements.py [--cases oring hertz] [--poisson 0.45 0.499]
    .venv/bin/python benchmarks/quadratic_elements.py --cases oring --orders 2 --formulation nodal_pressure \
        --friction 0 0.4 --poisson 0.45 0.499 0.4999 --table oring_taylor_hood

Results: ``benchmarks/results/quadratic_elements.{json,md}`` (``--table``: another name).
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import shutil
import time
import tomllib

from mpi4py import MPI

import numpy as np

from contactqvi.case import load_case, parse_case
from contactqvi.runner import run_case
from contactqvi.tables import write_table
from hertz_incompressible import closed_form
from rows import cell, failed_row, percent

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
ORING = HERE / "data" / "oring"
MESHES = {"oring": ("h0.25", "h0.125"), "hertz": ("coarse", "medium")}


def oring(order: int, mesh: str, poisson: float, formulation: str = "displacement", friction: float = 0.0):
    """The O-ring case on ``mesh`` at ``poisson`` with elements of ``order``, the cord's ``formulation``
    and, if ``friction`` > 0, Coulomb friction of that coefficient on the plate."""
    data = tomllib.loads((ORING / "oring.toml").read_text())
    data["mesh"].update(file=f"oring_{mesh}.msh", order=order)
    data["material"].update(poisson=poisson, formulation=formulation)
    if friction > 0.0:
        data["contact"].update(law="coulomb", friction=friction)
    return parse_case(data, ORING)


def hertz_case(order: int, mesh: str, poisson: float):
    """``cases/hertz.toml`` on ``meshes/hertz_{mesh}.geo`` with elements of ``order``."""
    case = load_case(ROOT / "cases" / "hertz.toml")
    return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / f"hertz_{mesh}.geo",
                                                              order=order))


def measure(name: str, order: int, mesh: str, poisson: float, work: pathlib.Path, comm: MPI.Comm,
            formulation: str = "displacement", friction: float = 0.0) -> dict:
    """One run's row (``formulation`` and ``friction``: the O-ring's)."""
    key = {"case": name, "order": order, "mesh": mesh, "poisson": poisson}
    if name == "oring":
        key.update(formulation=formulation, friction=friction)
    case = oring(order, mesh, poisson, formulation, friction) if name == "oring" else hertz_case(order, mesh, poisson)
    out = work / "_".join(str(value) for value in key.values())
    start = time.perf_counter()
    try:
        summary, code = run_case(case, out, comm, plot=False)
    except Exception as exc:  # an input or mesh error: the table says so and the other runs go on
        return failed_row(f"failed: {type(exc).__name__}: {exc}", time.perf_counter() - start, **key)
    steps = summary["steps"]
    newton = sum(s["iterations"] for s in steps)
    krylov = sum(h.get("krylov_iterations") or 0 for s in steps for h in s["history"])
    fallbacks = sum("direct_fallback" in h for s in steps for h in s["history"])
    last = steps[-1]
    row = {**key, "status": summary["status"], "dofs": summary["n"], "newton_per_step": newton / len(steps),
           "newton": newton, "krylov_per_newton": krylov / max(newton, 1), "direct_fallbacks": fallbacks,
           "seconds": time.perf_counter() - start, "failed": code != 0}
    if name == "oring":
        row.update(force=abs(last["contact_force"][2]), area=last["contact_area"])
    else:
        exact = closed_form(case)  # the summary's force and area are the quarter model's
        row.update(P=4.0 * abs(last["contact_force"][2]) / exact["P"] - 1.0,
                   a=(4.0 * last["contact_area"] / np.pi) ** 0.5 / exact["a"] - 1.0,
                   p0=last["max_nodal_contact_pressure"] / exact["p0"] - 1.0)
    if comm.rank == 0:
        shutil.rmtree(out, ignore_errors=True)
    return row


def markdown(rows: list[dict]) -> str:
    """The O-ring table and the Hertz table."""
    lines = ["## Quadratic (P2) against linear (P1) tetrahedra with a rigid obstacle", "",
             "Default settings, one run each (`benchmarks/quadratic_elements.py`). O-ring: the plate's force at 30 % "
             "squeeze (N, the quarter slice), its ratio to the same mesh, order, formulation and friction at "
             "ν = 0.45, the contact area, Newton steps per load step and in all, Krylov iterations per Newton step "
             "and their ratio to ν = 0.45's, the Newton steps solved by the direct fall-back.", "",
             "| O-ring | ν | order | formulation | μ | dofs | force (N) | / ν = 0.45 | area (mm²) | Newton / step "
             "(in all) | Krylov / Newton | / ν = 0.45 | LU fall-backs | run s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [_oring_line(r, rows) for r in rows if r["case"] == "oring"]
    lines += ["", "Hertz, a rigid sphere (R = 1 m) 1 mm into a block (E = 70 GPa, ν = 0.3): errors against Hertz.", "",
              "| Hertz mesh | order | dofs | P | a | p0 | Newton / step | Krylov / Newton | run s |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in (r for r in rows if r["case"] == "hertz"):
        status = r.get("status", "\u2013")
        lines.append(f"| {r['mesh']} | {r['order']} | {cell(r, 'dofs')} | {percent(r, 'P', status)} "
                     f"| {percent(r, 'a', status)} | {percent(r, 'p0', status)} | {cell(r, 'newton_per_step', '.1f')} "
                     f"| {cell(r, 'krylov_per_newton', '.1f')} "
                     f"| {cell(r, 'seconds', '.0f')} |")
    return "\n".join(lines) + "\n"


def _oring_line(r: dict, rows: list[dict]) -> str:
    """The O-ring table's line of row ``r``, with its ratios to the row of ν = 0.45 among ``rows``."""
    same = ("order", "mesh", "formulation", "friction")
    reference = next((q for q in rows if q["case"] == "oring" and q["poisson"] == 0.45 and "force" in q
                      and all(q.get(k) == r.get(k) for k in same)), None)

    def ratio(field: str, form: str, less: float = 0.0) -> str:
        if reference is None or field not in r:
            return "\u2013"
        return form.format(r[field] / reference[field] - less)

    force = f"{r['force']:.5f}" if "force" in r else r.get("status", "")
    area = f"{1e6 * r['area']:.3f}" if "area" in r else "\u2013"
    newton = f"{cell(r, 'newton_per_step', '.1f')} ({cell(r, 'newton')})"
    return (f"| {r['mesh']} | {r['poisson']:g} | {r['order']} | {r.get('formulation', 'displacement')} "
            f"| {r.get('friction', 0.0):g} | {cell(r, 'dofs')} | {force} | {ratio('force', '{:+.1%}', 1.0)} | {area} "
            f"| {newton} | {cell(r, 'krylov_per_newton', '.1f')} | {ratio('krylov_per_newton', '{:.2f}×')} "
            f"| {cell(r, 'direct_fallbacks')} | {cell(r, 'seconds', '.0f')} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=tuple(MESHES), default=list(MESHES))
    parser.add_argument("--poisson", nargs="+", type=float, default=[0.45, 0.499])
    parser.add_argument("--orders", nargs="+", type=int, choices=(1, 2), default=[1, 2])
    parser.add_argument("--meshes", nargs="+", help="the meshes of each case (default: all of them)")
    parser.add_argument("--formulation", default="displacement", help="the O-ring's [material] formulation")
    parser.add_argument("--friction", nargs="+", type=float, default=[0.0],
                        help="the O-ring's Coulomb friction coefficients (0: frictionless)")
    parser.add_argument("--output", type=pathlib.Path, default=HERE / "results")
    parser.add_argument("--table", default="quadratic_elements", help="name of the table (.json and .md appended)")
    args = parser.parse_args()
    known = {mesh for name in args.cases for mesh in MESHES[name]}
    if args.meshes is not None and not set(args.meshes) <= known:
        parser.error(f"--meshes: {sorted(set(args.meshes) - known)} not among the cases' meshes {sorted(known)}")
    comm = MPI.COMM_WORLD
    work = args.output / f"{args.table}_work"
    rows = []
    for name in args.cases:
        for friction in args.friction if name == "oring" else [0.0]:
            for poisson in args.poisson if name == "oring" else [0.3]:
                for mesh in (m for m in MESHES[name] if args.meshes is None or m in args.meshes):
                    for order in args.orders:
                        rows.append(measure(name, order, mesh, poisson, work, comm, args.formulation, friction))
                        if comm.rank == 0:
                            print(rows[-1], flush=True)
                        write_table(comm, args.output / args.table, {"mpi_size": comm.size, "rows": rows},
                                    markdown(rows), echo=False)
    if comm.rank == 0:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
