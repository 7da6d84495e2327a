"""A press fit meshed the ordinary way, on flat and on curved (second-order) tetrahedra, against Lamé (issue 43).

The fit of the user's case (``../shared/repro/turn5/press_fit/``): a steel pin of radius b + δ in a
ring with hole radius b = 20 mm and outer radius c = 40 mm, a quarter slice t = 2 mm thick with
rollers on the symmetry planes and both flat faces (plane strain), frictionless, meshed in
unstructured tetrahedra by ``meshes/press_fit.geo``: h_pin on the pin's face, h_ring on the bore.
gmsh's ``order = 1`` gives the flat facets whose chords cut inside the cylinders by up to h²/(8R), about
δ itself; ``order = 2`` 10-node tetrahedra whose midside nodes lie on them (docs/press_fit.md,
"Curved contact surfaces"), with linear displacements (P1) or quadratic ones (P2, ``[mesh] order = 2``,
the quadratic dual mortar of docs/quadratic.md); ``exact``: the surfaces declared coaxial cylinders
(``[[contacts]] cylinder``, the gap between the exact cylinders: docs/press_fit.md, "Exact cylindrical
surfaces"). Each row is one run of :func:`contactqvi.runner.run_case`, as a user runs the case, with
default settings:

* ``p(F)``: the pressure from the pair force, (|F_x| + |F_y|) / (2 b t), against Lamé's p;
* ``u ring b``, ``u ring c``, ``u pin``: the mean radial displacement of the nodes of ``body.bp``
  on the bore, the ring's outer face and the pin's face more than 10° from the symmetry planes,
  against Lamé's;
* ``open``: slave nodes not in contact; ``nodal p``: the smallest and largest nodal contact
  pressure λ_i / D_ii over the slave nodes in contact (``summary.json``'s ``min_nodal_contact_pressure``
  and ``max_nodal_contact_pressure``; the edge nodes of P2 too), against Lamé's p.

    .venv/bin/python benchmarks/press_fit_curved.py                  # the table of the issue
    .venv/bin/python benchmarks/press_fit_curved.py --fits coarse    # the coarse meshes only

Results: ``benchmarks/results/press_fit_curved.{json,md}``.
"""

from __future__ import annotations

import argparse
import itertools
import pathlib
import shutil
import time

from mpi4py import MPI

import numpy as np

from contactqvi.case import parse_case
from contactqvi.paraview import read_vtx
from contactqvi.problems import press_fit
from contactqvi.runner import run_case
from contactqvi.tables import write_table
from rows import cell, failed_row, percent

HERE = pathlib.Path(__file__).resolve().parent
GEO = HERE.parent / "meshes" / "press_fit.geo"
B, C, T = 0.020, 0.040, 0.002
STEEL, ALUMINIUM = (210e9, 0.3), (70e9, 0.33)
#: Element sizes (m) on the pin's face and on the bore: the user's two meshes.
SIZES = {"1.0 / 1.5": (1.0e-3, 1.5e-3), "0.5 / 0.75": (0.5e-3, 0.75e-3)}
#: Nodes compared lie between these angles (degrees) from the x axis.
AWAY = (10.0, 80.0)


def fits(which: str) -> list[dict]:
    """The runs: both meshes, slaves and (gmsh order, displacement degree, exact cylinders) (1, P1),
    (1, P1, exact), (2, P1), (2, P2) and (2, P2, exact) at the user's 15 µm; on the coarse meshes also
    0.01 % and 0.5 % of b, and a steel pin in an aluminium ring, with all but the first."""
    sizes = list(SIZES) if which == "all" else ["1.0 / 1.5"]
    kinds = ((1, 1, False), (1, 1, True), (2, 1, False), (2, 2, False), (2, 2, True))
    runs = [{"mesh": mesh, "slave": slave, "order": order, "degree": degree, "exact": exact, "delta": 15e-6,
             "ring": "steel"} for mesh, (order, degree, exact), slave in itertools.product(sizes, kinds, ("ring", "pin"))]
    variants = [(delta, "steel") for delta in (1e-4 * B, 5e-3 * B)] + [(15e-6, "aluminium")]
    runs += [{"mesh": "1.0 / 1.5", "slave": slave, "order": order, "degree": degree, "exact": exact, "delta": delta,
              "ring": ring} for (delta, ring), (order, degree, exact), slave in itertools.product(variants, kinds[1:],
                                                                                                ("ring", "pin"))]
    return runs


def case(fit: dict, work: pathlib.Path, comm: MPI.Comm) -> dict:
    """The case file of ``fit`` (as ``tomllib`` reads it), its mesh a variant of :data:`GEO`."""
    h_pin, h_ring = SIZES[fit["mesh"]]
    values = {"delta": fit["delta"], "h_pin": h_pin, "h_ring": h_ring, "order": fit["order"]}
    geo = work / ("fit_" + "_".join(f"{key}{value:g}" for key, value in values.items()) + ".geo")
    if comm.rank == 0:
        geo.write_text("".join(f"{key} = {value!r}; " for key, value in values.items()) + f'\nInclude "{GEO}";\n')
    comm.Barrier()
    rollers = {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}, "flat": {"z": 0.0}}
    ring = STEEL if fit["ring"] == "steel" else ALUMINIUM
    bodies = [{"name": name, "material": {"young": E, "poisson": nu}, "boundary": {"displacement": rollers}}
              for name, (E, nu) in (("pin", STEEL), ("ring", ring))]
    surfaces = {"ring": "ring.ring_inner", "pin": "pin.pin_outer"}
    master = "pin" if fit["slave"] == "ring" else "ring"
    contact = {"slave": surfaces[fit["slave"]], "master": surfaces[master], "law": "frictionless",
               "interference": fit["delta"]}
    if fit["exact"]:
        contact["cylinder"] = {"axis": [0.0, 0.0, 1.0], "point": [0.0, 0.0, 0.0]}
    return {"mesh": {"file": str(geo), "order": fit["degree"]}, "bodies": bodies, "contacts": [contact]}


def radial_means(out: pathlib.Path, delta: float) -> dict[str, float]:
    """Mean radial displacement (m) of ``body.bp``'s points on the bore, the ring's outer face and the
    pin's face, more than 10° from the symmetry planes."""
    body = read_vtx(out / "body.bp", -1)
    x, u = body.points, body.point_data["displacement [m]"]
    r, angle = np.hypot(x[:, 0], x[:, 1]), np.degrees(np.arctan2(x[:, 1], x[:, 0]))
    away = (angle > AWAY[0]) & (angle < AWAY[1])
    radial = np.einsum("ij,ij->i", u[:, :2], x[:, :2]) / np.maximum(r, 1e-300)
    return {name: float(radial[away & np.isclose(r, radius, rtol=0.0, atol=1e-9)].mean())
            for name, radius in (("u_ring_b", B), ("u_ring_c", C), ("u_pin", B + delta))}


def measure(fit: dict, work: pathlib.Path, comm: MPI.Comm) -> dict:
    """One run's row (rank 0's; the others get it broadcast)."""
    out = work / f"run_{len(list(work.glob('run_*')))}"
    comm.Barrier()
    start = time.perf_counter()
    try:
        summary, _ = run_case(parse_case(case(fit, work, comm)), out, comm, plot=False)
    except Exception as exc:  # a mesh or input error: the table says so and the other runs go on
        return failed_row(f"failed: {type(exc).__name__}: {exc}", time.perf_counter() - start, **fit)
    seconds = time.perf_counter() - start
    row = None
    if comm.rank == 0:
        (step,) = summary["steps"]
        ring = STEEL if fit["ring"] == "steel" else ALUMINIUM
        p = press_fit.contact_pressure(fit["delta"], B, C, STEEL, ring)
        lame = {"u_ring_b": press_fit.ring_displacement(B, p, B, C, ring),
                "u_ring_c": press_fit.ring_displacement(C, p, B, C, ring),
                "u_pin": press_fit.pin_displacement(p, B, STEEL)}
        (force,) = step["pair_forces"].values()
        low, high = step["min_nodal_contact_pressure"], step["max_nodal_contact_pressure"]
        row = {**fit, "status": step["status"], "newton": step["iterations"], "seconds": seconds,
               "slave_nodes": summary["p"], "open": step["state_counts"]["no contact"], "p_lame": p,
               "p_force": (abs(force[0]) + abs(force[1])) / (2.0 * B * T) / p - 1.0,
               "nodal_low": low / p - 1.0, "nodal_high": high / p - 1.0,
               **{name: value / lame[name] - 1.0 for name, value in radial_means(out, fit["delta"]).items()}}
        shutil.rmtree(out)
    return comm.bcast(row, root=0)


def markdown(rows: list[dict]) -> str:
    """One line per run: errors against Lamé in %."""
    lines = ["## A press fit meshed the ordinary way, in flat (gmsh order 1) and curved (gmsh order 2) tetrahedra, "
             "against Lamé", "",
             "Steel pin of radius b + δ (b = 20 mm) in a ring (c = 40 mm), quarter slice 2 mm thick in plane strain, "
             "frictionless, unstructured tetrahedra of `meshes/press_fit.geo` (h on the pin's face / on the bore), u: "
             "linear (P1) or quadratic (P2, `[mesh] order = 2`, docs/quadratic.md Sect. 5) displacements; exact: the "
             "surfaces declared coaxial cylinders (`cylinder`, docs/press_fit.md \"Exact cylindrical surfaces\"); "
             "default settings, one load step. Errors against Lamé: p(F) the pressure from the pair force, u the mean "
             "radial displacements of the bore (b), the ring's outer face (c) and the pin's face, 10°–80° from the "
             "symmetry planes; open: slave nodes not in contact; nodal p: the smallest and largest λ_i / D_ii of the "
             "slave nodes in contact, edge nodes of P2 included (docs/press_fit.md, \"Curved contact surfaces\").", "",
             "| mesh pin / ring (mm) | gmsh order | u | exact | slave | δ (µm) | ring | Lamé p (MPa) | p(F) "
             "| u ring b | u ring c | u pin | open / slave nodes | nodal p | Newton | run s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        nodal = f"{percent(r, 'nodal_low')} … {percent(r, 'nodal_high')}" if "nodal_low" in r else r.get("status", "")
        p = f"{r['p_lame'] / 1e6:.2f}" if "p_lame" in r else "\u2013"
        exact = "yes" if r["exact"] else "no"
        lines.append(f"| {r['mesh']} | {r['order']} | P{r['degree']} | {exact} | {r['slave']} | {1e6 * r['delta']:g} "
                     f"| {r['ring']} | {p} "
                     f"| {percent(r, 'p_force')} | {percent(r, 'u_ring_b')} | {percent(r, 'u_ring_c')} "
                     f"| {percent(r, 'u_pin')} "
                     f"| {cell(r, 'open')} / {cell(r, 'slave_nodes')} | {nodal} | {cell(r, 'newton')} "
                     f"| {cell(r, 'seconds', '.1f')} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fits", choices=("all", "coarse"), default="all")
    parser.add_argument("--output", type=pathlib.Path, default=HERE / "results")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    work = args.output / "press_fit_curved_work"
    if comm.rank == 0:
        work.mkdir(parents=True, exist_ok=True)
    comm.Barrier()
    rows = []
    for fit in fits(args.fits):
        rows.append(measure(fit, work, comm))
        if comm.rank == 0:
            print(markdown(rows[-1:]).splitlines()[-1], flush=True)
    if comm.rank == 0:
        shutil.rmtree(work)
    write_table(comm, args.output / "press_fit_curved", {"mpi_size": comm.size, "rows": rows}, markdown(rows),
                echo=False)


if __name__ == "__main__":
    main()
