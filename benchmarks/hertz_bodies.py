"""Hertz and Cattaneo-Mindlin between two elastic bodies on non-matching meshes.

``--tables hertz``: ``cases/hertz_bodies.toml`` (a steel ball pressed into an
aluminium block, both meshed, mortar contact) on three meshes; the force P, the
contact radius a and the peak pressure p0 of the last step beside Hertz's formulas
with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (:mod:`contactqvi.problems.hertz`). P is
the total contact force (four times the quarter model's), a = sqrt(4 A / pi) from the
contact area A (the sum of the D_ii of the nodes in contact), p0 the largest nodal
pressure lambda_i / D_ii. Writes ``hertz_bodies.{json,md}``. ``--order 2``: quadratic elements on
second-order meshes of the same sizes (the sphere curved; the quadratic dual mortar of
docs/quadratic.md; 27-node hexahedra for the ``hex_*`` meshes), into ``hertz_bodies_p2.{json,md}`` by default.

``--tables mindlin``: ``cases/cattaneo_mindlin_bodies.toml`` (one material, Dundurs'
beta = 0) on ``--mindlin-mesh``; per step Q/(mu P) beside Mindlin's law at the
ball's displacement s (two identical bodies: twice a rigid ball's compliance) and
the stick radius beside Cattaneo's c = a (1 - Q/(mu P))^(1/3). Writes
``mindlin_bodies.{json,md}``::

    python benchmarks/hertz_bodies.py [--tables hertz mindlin] [--meshes coarse medium fine xfine] [--order 2]
    mpirun -n 2 python benchmarks/hertz_bodies.py --tables hertz --meshes xxfine --name hertz_bodies_xxfine
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import shutil
import time

from mpi4py import MPI

import numpy as np

import benchlib
from contactqvi import tables
from contactqvi.case import MeshSource, load_case
from contactqvi.contact.load_path import solve_load_path
from contactqvi.contact.nodal import State
from contactqvi.problems import hertz
from contactqvi.parameters import require
from contactqvi.runner import build_problem

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "hertz_bodies.toml"
MINDLIN_CASE = ROOT / "cases" / "cattaneo_mindlin_bodies.toml"
MESHES = {"xcoarse": 4, "coarse": 6, "medium": 10, "fine": 16, "xfine": 21, "xxfine": 35,  # h at the contact = a / value (block; the ball 0.7 of it)
          "hex_coarse": 6, "hex_medium": 10}  # hexahedra: tetrahedra of twice that h split into four each


def mesh_source(mesh: str, order: int, work: pathlib.Path, comm: MPI.Comm) -> MeshSource:
    """``meshes/hertz_bodies_{mesh}.geo``, or with ``order`` 2 the same sizes in 10-node tetrahedra or
    27-node hexahedra (a wrapper written into ``work``) with quadratic displacements."""
    if order == 1:
        return MeshSource(file=ROOT / "meshes" / f"hertz_bodies_{mesh}.geo")
    geo = work / f"hertz_bodies_{mesh}_order2.geo"
    included = ROOT / "meshes" / ("hertz_bodies.geo" if not mesh.startswith("hex") else f"hertz_bodies_{mesh}.geo")
    refinement = "" if mesh.startswith("hex") else f"refinement = {MESHES[mesh]};\n"
    if comm.rank == 0:
        work.mkdir(parents=True, exist_ok=True)
        geo.write_text(f'{refinement}order = 2;\nInclude "{included}";\n')
    comm.Barrier()
    return MeshSource(file=geo, order=2)


def run(mesh: str, comm: MPI.Comm, order: int = 1, work: pathlib.Path | None = None) -> dict:
    """One load path on ``meshes/hertz_bodies_{mesh}.geo`` (elements of ``order``; wrappers in ``work``):
    counts, times and the last step's P, a, p0."""
    case = dataclasses.replace(load_case(CASE), mesh=mesh_source(mesh, order, work, comm))
    start = time.perf_counter()
    with build_problem(case, comm) as problem:
        built = time.perf_counter()
        problem_seconds = {f"{name}_s": seconds for name, seconds in problem.setup_seconds.items()}
        searches = []  # the search before each later step: contact search + change of variables (s)

        def record(index, step, u, result, state) -> None:
            if index > 0:
                searches.append(sum(problem.setup_seconds.values()))

        u = problem.A.createVecRight()
        results = solve_load_path(problem, case.steps, u, dict(case.solver), "hertz_bodies_", record, from_rest=True)
        solved = time.perf_counter()
        u.destroy()
        elastic = min((benchlib.elastic_solve(problem, "hertz_bodies_elastic_") for _ in range(2)),
                      key=lambda e: e["seconds"])
        force, a, p0 = benchlib.hertz_measures(problem, results[-1])
        dofs = problem.A.getSize()[0]
    return {
        "mesh": mesh, "h": f"a/{MESHES[mesh]}", "dofs": dofs, "ranks": comm.size,
        "status": [str(r.status) for r in results], "newton": [r.iterations for r in results],
        "krylov": [r.inner_iterations for r in results], "assembly_s": built - start, "solve_s": solved - built,
        "elastic_s": elastic["seconds"], "elastic_krylov": elastic["krylov"], **problem_seconds,
        "step_search_s": float(np.mean(searches)) if searches else 0.0,
        "P": force, "a": a, "p0": p0, "peak_rss_mib": benchlib.peak_rss_mib(comm, MPI.SUM),
    }


def closed_form() -> dict:
    """Hertz's P, a, p0 for the case's bodies at the last step."""
    case = load_case(CASE)
    (E1, nu1), (E2, nu2) = ((b.material.young, b.material.poisson) for b in case.bodies)
    e_star = hertz.combined_modulus(E1, nu1, E2, nu2)
    depth = -case.bodies[1].boundary.displacement["load"].z * case.steps[-1].load
    return {"E_star": e_star, "delta": depth, "P": hertz.contact_force(e_star, 0.0, 1.0, depth),
            "a": hertz.contact_radius(1.0, depth), "p0": hertz.peak_pressure(e_star, 0.0, 1.0, depth)}


def mindlin(mesh: str, comm: MPI.Comm) -> list[dict]:
    """The Cattaneo-Mindlin path on ``meshes/mindlin_bodies_{mesh}.geo``: per step P, Q, a, c
    and the closed forms (half model: forces and areas doubled)."""
    case = load_case(MINDLIN_CASE)
    case = dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / f"mindlin_bodies_{mesh}.geo"))
    (young, poisson), friction = (case.bodies[0].material.young, case.bodies[0].material.poisson), case.contacts[0].law.friction
    shear = hertz.shear_modulus(young, poisson)
    rows = []
    with build_problem(case, comm) as problem:

        def record(index, step, u, result, state) -> None:
            force = np.einsum("ij,ijk->k", np.column_stack([result.friction_force, result.normal_force]), problem.frames)
            force = 2.0 * comm.allreduce(force, op=MPI.SUM)
            sticking = np.isin(result.states, (State.STICKING, State.WEAK_STICKING))
            area = 2.0 * comm.allreduce(float(problem.contact_area[result.normal_force > 0.0].sum()), op=MPI.SUM)
            stick = 2.0 * comm.allreduce(float(problem.contact_area[sticking].sum()), op=MPI.SUM)
            P, Q, s = force[2], -force[0], step.translation[0]
            a = float(np.sqrt(area / np.pi))
            rows.append({"step": index + 1, "status": str(result.status), "newton": result.iterations,
                         "krylov": result.inner_iterations, "s": s, "P": P, "Q": Q, "a": a,
                         "Q_muP": Q / (friction * P),  # identical bodies: s* twice a rigid ball's
                         "Q_muP_mindlin": hertz.mindlin_force(s / 2.0, friction, P, shear, poisson, a) / (friction * P),
                         "c": float(np.sqrt(stick / np.pi)), "c_cattaneo": float(hertz.stick_radius(a, Q, friction, P))})

        u = problem.A.createVecRight()
        solve_load_path(problem, case.steps, u, dict(case.solver), "mindlin_bodies_", record, from_rest=True)
        u.destroy()
    return rows


def _mindlin_table(rows: list[dict], mesh: str, comm: MPI.Comm, output: pathlib.Path) -> None:
    header = ["step", "s (mm)", "Newton / Krylov", "P (MN)", "Q/(mu P)", "Mindlin", "difference",
              "c (mm)", "Cattaneo (mm)", "|c - c_C| / (0.05 a + h)"]
    h = 0.0316 / {"coarse": 6, "medium": 10}[mesh]
    table = [[r["step"], f"{r['s'] * 1e3:.2f}", f"{r['newton']} / {r['krylov']}", f"{r['P'] / 1e6:.4f}",
              f"{r['Q_muP']:.3f}", f"{r['Q_muP_mindlin']:.3f}", f"{r['Q_muP'] - r['Q_muP_mindlin']:+.3f}",
              f"{r['c'] * 1e3:.2f}", f"{r['c_cattaneo'] * 1e3:.2f}",
              f"{abs(r['c'] - r['c_cattaneo']) / (0.05 * r['a'] + h):.2f}"] for r in rows]
    title = ("## Cattaneo-Mindlin between two elastic bodies of one material (E = 70 GPa, nu = 0.3, mu = 0.3; "
             f"Dundurs' beta = 0), mesh {mesh} (h = {h * 1e3:.1f} mm at the contact), {comm.size} rank(s)\n\n"
             "A ball (R = 1 m) pressed 1 mm into a block, then its flat face moved along x by s. Q/(mu P) from the "
             "contact forces beside Mindlin's Q(s) for two identical bodies (twice a rigid ball's compliance); the "
             "stick radius from the sticking area (pi c^2 / 2, half model) beside Cattaneo's c = a (1 - Q/(mu P))^(1/3) "
             "at the measured Q.")
    tables.write_table(comm, output / "mindlin_bodies", {"mesh": mesh, "rows": rows},
                       title + "\n\n" + tables.markdown_table(header, table))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--tables", nargs="+", choices=("hertz", "mindlin"), default=["hertz", "mindlin"])
    parser.add_argument("--meshes", nargs="+", choices=tuple(MESHES), default=["coarse", "medium", "fine", "xfine"])
    parser.add_argument("--mindlin-mesh", choices=("coarse", "medium"), default="coarse")
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    parser.add_argument("--name", default=None,
                        help="file name of the Hertz table (without suffix); default hertz_bodies (_p2 for --order 2)")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1, help="1: linear, 2: quadratic elements")
    args, _ = parser.parse_known_args(argv)
    comm = MPI.COMM_WORLD
    args.output.mkdir(parents=True, exist_ok=True)
    if "mindlin" in args.tables:
        _mindlin_table(mindlin(args.mindlin_mesh, comm), args.mindlin_mesh, comm, args.output)
    if "hertz" in args.tables:
        name = args.name or ("hertz_bodies" if args.order == 1 else "hertz_bodies_p2")
        _hertz_table(args.meshes, comm, args.output / name, args.order)


def _hertz_table(meshes: list[str], comm: MPI.Comm, output: pathlib.Path, order: int = 1) -> None:
    """The Hertz table of ``meshes`` with elements of ``order``, written to ``output``.{json,md}."""
    reference = closed_form()
    work = output.parent / f"{output.name}_work"
    rows = [run(mesh, comm, order, work) for mesh in meshes]
    if comm.rank == 0:
        shutil.rmtree(work, ignore_errors=True)
    header = ["mesh (h at contact)", "dofs", "Newton per step", "Krylov per step", "P (MN) / Hertz", "error P",
              "a (mm) / Hertz", "|a - a_H| / h", "p0 (GPa) / Hertz", "error p0", "solve (s)",
              "elastic solve (s)", "solve per step / elastic", "search + mortar (s)", "/ solve per step",
              "search per later step (s)", "/ solve per step",
              "peak memory (GiB)", "KB per dof"]
    table = []
    for row in rows:
        h = reference["a"] / MESHES[row["mesh"]]
        table.append([f"{row['mesh']} ({row['h']})", row["dofs"], " ".join(map(str, row["newton"])),
                      " ".join(map(str, row["krylov"])), f"{row['P'] / 1e6:.4f} / {reference['P'] / 1e6:.4f}",
                      f"{row['P'] / reference['P'] - 1:+.2%}", f"{row['a'] * 1e3:.2f} / {reference['a'] * 1e3:.2f}",
                      f"{abs(row['a'] - reference['a']) / h:.2f}",
                      f"{row['p0'] / 1e9:.3f} / {reference['p0'] / 1e9:.3f}", f"{row['p0'] / reference['p0'] - 1:+.2%}",
                      f"{row['solve_s']:.1f}", f"{row['elastic_s']:.2f}",
                      f"{row['solve_s'] / len(row['newton']) / row['elastic_s']:.2f}",
                      f"{row['contact_search_s']:.2f}", f"{row['contact_search_s'] * len(row['newton']) / row['solve_s']:.1%}",
                      f"{row['step_search_s']:.2f}", f"{row['step_search_s'] * len(row['newton']) / row['solve_s']:.1%}",
                      f"{row['peak_rss_mib'] / 1024:.1f}", f"{row['peak_rss_mib'] * 1024 / row['dofs']:.1f}"])
    hexahedra = all(mesh.startswith("hex") for mesh in meshes)
    elements = {(1, False): "linear tetrahedra", (1, True): "trilinear hexahedra (Q1)",
                (2, False): "quadratic elements (10-node tetrahedra, P2; docs/quadratic.md)",
                (2, True): "quadratic elements (27-node hexahedra, Q2; docs/quadratic.md)"}[order, hexahedra]
    title = ("## Hertz between two elastic bodies: steel ball (R = 1 m, E = 210 GPa) pressed 1 mm into an "
             f"aluminium block (E = 70 GPa), nu = 0.3, non-matching meshes, mortar contact, {elements}\n\n"
             f"E* = {reference['E_star'] / 1e9:.2f} GPa; quarter model, four steps of 0.25 mm on "
             f"{comm.size} rank(s); P the total contact force, a from the contact area (pi a^2 = sum of D_ii in "
             "contact), p0 the largest nodal pressure lambda_i / D_ii on the block (the slave: the softer body). "
             "The ball's own compliance between its loaded face (R = 32 a from the contact) and the contact is not "
             "in the half-space formula. Elastic solve: A w = l of the same system by CG + GAMG to 1e-12 with the "
             "same near-nullspace and multigrid options, set-up included (fastest of 2); the last column is the "
             "load path's solve time per load step over it. Search + mortar: the contact search, nodal frames "
             "and segment-to-segment integration (largest rank) in the reference configuration, beside the solve "
             "time of one load step. Search per later step: the search again before steps 2-4 in the configuration "
             "of the step before with the change of variables it needs (T, A = T^T A_K T, loads), mean over the "
             "steps; it is part of the solve time.")
    tables.write_table(comm, output, {"closed_form": reference, "runs": rows},
                       title + "\n\n" + tables.markdown_table(header, table))


if __name__ == "__main__":
    main()
