"""Finite strain against small strain: the cost of a load step, its parts, ranks and a million dofs (issue 36).

Parts (``--parts``), each writing its section of ``finite_strain_performance.{json,md}``
(a part not run keeps its old numbers):

* ``ratio``: ``cases/hertz_bodies.toml`` (steel ball on aluminium block, mortar contact,
  four steps of 0.25 mm) on ``--mesh`` (default the fine mesh of
  ``benchmarks/hertz_bodies.py``), first with linear elasticity (small strain), then
  with both bodies neo-Hookean (finite strain, same E and nu, same steps), back to back
  in one process. The pair is searched in the configuration of the step before
  (``search = "every_step"``, the case's default for a body pair) in both; with
  ``--settled`` also neo-Hookean with ``search = "until_settled"`` (each step searched
  again in its own configuration and solved again until it settles). Per load step:
  wall time, Newton steps, Krylov iterations; the ratio of the neo-Hookean step to the
  linear one (issue 36: at most 3). Per run: the geometry update (``problem.search``:
  contact search, mortar segments, D, M, normals and nodal frames in the deformed
  configuration, T and A = T^T A_K T), the tangent assembly (``problem.tangent``:
  K_T, T^T K_T T) and the residual assembly (``problem.residual``), each timed around
  the problem's own method by a :class:`~contactqvi.result.Timings` phase (a PETSc log
  stage), beside the solver's phases; and the preconditioner set-ups (PCSetUp).
* ``ranks``: ``python -m contactqvi run`` of the neo-Hookean two-body Hertz case on its
  coarse mesh (``search = "every_step"``) on 1, 2 and 3 ranks, with exact Newton-step
  solves (``pc = "lu"``) and with the default GAMG (``tol`` 1e-3), Newton stopped at
  ||y^|| <= 1e-12 ||y^0|| (``rtol``, the default); max |u_N - u_1| / max |u_1| of
  ``solution.npz`` (issue 36: 1e-9; ``benchmarks/ranks.py``'s comparison).
* ``large``: the neo-Hookean two-body Hertz path on ``--large-mesh`` (default xxfine,
  1.05 M dofs) on the ranks it runs on: converged or not, Newton steps, time, peak
  memory (the ranks' peaks added).

::

    mpirun -n 2 python benchmarks/finite_strain_performance.py --parts ratio
    python benchmarks/finite_strain_performance.py --parts ranks
    timeout 30m mpirun -n 2 python benchmarks/finite_strain_performance.py --parts large

Wall times on a machine shared with other jobs are noisy: the counts and the ratios
measured in one run are what compare.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import shutil
import sys
import tempfile
import time

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import benchlib
import ranks
from rows import read_table
from contactqvi import tables
from contactqvi.case import load_case
from contactqvi.contact.load_path import solve_load_path
from contactqvi.result import Timings
from contactqvi.runner import build_problem

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "hertz_bodies.toml"
NAME = "finite_strain_performance"
#: Methods of the problem timed per call: name -> phase.
TIMED = {"search": "geometry_update", "tangent": "tangent_assembly", "residual": "residual_assembly"}
#: Issue 36's bounds.
MAX_RATIO, MAX_RANK_DIFFERENCE, MIN_LARGE_DOFS = 3.0, 1e-9, 1_000_000


def hertz_case(mesh: str, model: str | None, search: str | None = None):
    """``cases/hertz_bodies.toml`` on ``meshes/hertz_bodies_{mesh}.geo``, both bodies of ``model``
    (None: linear), the pair searched by ``search`` (None: as the case)."""
    case = load_case(CASE)
    bodies = tuple(dataclasses.replace(b, material=dataclasses.replace(b.material, model=model)) for b in case.bodies)
    contacts = tuple(dataclasses.replace(c, search=search or c.search) for c in case.contacts)
    return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / f"hertz_bodies_{mesh}.geo"),
                               bodies=bodies, contacts=contacts)



def _timed_methods(problem, timings: Timings) -> dict[str, int]:
    """Time every call of the problem's :data:`TIMED` methods in ``timings`` (instance attributes
    shadowing the methods; the solver is not touched); returns the calls counted per phase."""
    calls = dict.fromkeys(TIMED.values(), 0)
    for name, phase in TIMED.items():
        def timed(*args, _method=getattr(problem, name), _phase=phase, **kwargs):
            calls[_phase] += 1
            with timings.phase(_phase):
                return _method(*args, **kwargs)
        setattr(problem, name, timed)
    return calls


def run_path(label: str, case, comm: MPI.Comm) -> dict:
    """The case's load path from rest: per step wall seconds (largest rank) and counts; per run the
    solver's phases and the timed problem methods (:data:`TIMED`) with their PETSc events."""
    timings, steps, before = Timings(), [], benchlib.event_totals()
    comm.Barrier()
    start = time.perf_counter()
    with build_problem(case, comm) as problem:
        calls = _timed_methods(problem, timings)
        comm.Barrier()
        built = last = time.perf_counter()

        def record(index, step, u, result, state) -> None:
            nonlocal last
            now = time.perf_counter()
            steps.append({"load": step.load, "status": str(result.status), "newton": result.iterations,
                          "krylov": result.inner_iterations, "seconds": comm.allreduce(now - last, op=MPI.MAX)})
            for phase, seconds in result.timings.items():
                timings[phase] = timings.get(phase, 0.0) + seconds
            peak = benchlib.peak_rss_mib(comm, MPI.SUM)
            if comm.rank == 0:  # progress, also of a run stopped by a time limit
                print(json.dumps({"label": label, "step": index + 1, **steps[-1], "peak_rss_mib": peak}), flush=True)
            last = time.perf_counter()

        u = problem.A.createVecRight()
        solve_load_path(problem, case.steps, u, dict(case.solver), "fsperf_", record, from_rest=True)
        solved = time.perf_counter()
        dofs, contact = problem.A.getSize()[0], problem.n_contact
        u.destroy()
    PETSc.garbage_cleanup(comm)
    return {"label": label, "mesh": pathlib.Path(case.mesh.file).stem.removeprefix("hertz_bodies_"),
            "model": case.bodies[0].material.model or "linear", "search": case.contacts[0].search or "every_step",
            "ranks": comm.size, "dofs": dofs, "contact_nodes": contact,
            "assembly_s": comm.allreduce(built - start, op=MPI.MAX),
            "solve_s": comm.allreduce(solved - built, op=MPI.MAX), "steps": steps, "calls": calls,
            "phases": benchlib.phases(comm, timings, before), "peak_rss_mib": benchlib.peak_rss_mib(comm, MPI.SUM)}


def ratio_part(comm: MPI.Comm, mesh: str, settled: bool) -> list[dict]:
    """Linear, then neo-Hookean (and with ``settled`` neo-Hookean until settled) on ``mesh``."""
    runs = [("small strain (linear)", None, None), ("finite strain (neo-Hookean)", "neo_hookean", None)]
    if settled:
        runs.append(("finite strain, until_settled", "neo_hookean", "until_settled"))
    rows = []
    for label, model, search in runs:
        rows.append(run_path(label, hertz_case(mesh, model, search), comm))
        if comm.rank == 0:
            r = rows[-1]
            print(f"{label}: {[s['newton'] for s in r['steps']]} Newton, {[s['krylov'] for s in r['steps']]} "
                  f"Krylov, {r['solve_s']:.1f} s", flush=True)
    return rows


def large_part(comm: MPI.Comm, mesh: str) -> dict:
    """The neo-Hookean path on ``mesh`` (the Hertz bodies of about a million dofs)."""
    return run_path("finite strain (neo-Hookean)", hertz_case(mesh, "neo_hookean"), comm)


def ranks_part(rank_counts: list[int], commit: str | None) -> list[dict]:
    """The neo-Hookean case on the coarse mesh by ``python -m contactqvi run`` on each number of
    ranks, with exact solves and with GAMG; each compared with its run on 1 rank."""
    work = pathlib.Path(tempfile.mkdtemp(prefix="contactqvi-fsperf-"))
    rows = []
    try:
        for lu in (True, False):
            case = ranks.case_variant(work, "hertz_bodies", "hertz_bodies_coarse.geo", lu)
            text = case.read_text().replace("poisson = 0.3}", 'poisson = 0.3, model = "neo_hookean"}')
            # searched before every step, as measured (a hyperelastic pair's default is "newton" since session 47)
            case.write_text(text.replace('law = "frictionless"', 'law = "frictionless"\nsearch = "every_step"'))
            label = f"hertz_bodies coarse, neo-Hookean, {'pc lu' if lu else 'gamg'}"
            reference = None
            for n in rank_counts:
                out = work / f"{case.stem}_np{n}"
                code, seconds = ranks.mpirun(n, ["nice", sys.executable, "-m", "contactqvi", "run", str(case),
                                                 "--output", str(out)], out.with_suffix(".log"))
                row = {"case": label, "ranks": n, "exit_code": code, "seconds": round(seconds, 1),
                       **ranks.record(out, ["solution.npz", "summary.json"]), "commit": commit}
                solution = np.load(out / "solution.npz") if (out / "solution.npz").is_file() else None
                if solution is not None and reference is None:
                    reference = {"x": solution["x"], "u": solution["u"], "newton_steps": row["newton_steps"],
                                 "u_max": float(np.abs(solution["u"]).max())}
                elif solution is not None:
                    row["relative_difference"] = ranks.relative_difference(reference["x"], reference["u"],
                                                                           solution["x"], solution["u"])
                    row["max_newton_difference"] = int(np.abs(np.subtract(row["newton_steps"],
                                                                           reference["newton_steps"])).max())
                row["u_max"] = reference["u_max"] if reference else None
                print(json.dumps(row), flush=True)
                rows.append(row)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return rows


def _per_newton(row: dict) -> float:
    return row["solve_s"] / max(sum(s["newton"] for s in row["steps"]), 1)


def ratio_markdown(rows: list[dict]) -> str:
    """The cost table (per load step, finite over small strain) and the phase table."""
    linear = next(r for r in rows if r["model"] == "linear")
    header = ["run", "dofs", "contact nodes", "status", "Newton per step", "Krylov per step", "wall per step (s)",
              "solve (s)", "s per Newton step", "step / small strain (≤ 3)", "mean step / small strain (≤ 3)",
              "per Newton step / small strain"]
    table = []
    for r in rows:
        step_ratios = [s["seconds"] / l["seconds"] for s, l in zip(r["steps"], linear["steps"])]
        table.append([r["label"], r["dofs"], r["contact_nodes"], " ".join(sorted({s["status"] for s in r["steps"]})),
                      " ".join(str(s["newton"]) for s in r["steps"]), " ".join(str(s["krylov"]) for s in r["steps"]),
                      " ".join(f"{s['seconds']:.1f}" for s in r["steps"]), f"{r['solve_s']:.1f}",
                      f"{_per_newton(r):.2f}", " ".join(f"{x:.2f}" for x in step_ratios),
                      f"{r['solve_s'] / linear['solve_s']:.2f}", f"{_per_newton(r) / _per_newton(linear):.2f}"])
    phases = []
    for r in rows:
        newton = sum(s["newton"] for s in r["steps"])
        for name, p in r["phases"].items():
            events = ", ".join(f"{e} ({v['count']}, {v['seconds']:.2f})" for e, v in
                               sorted(p["events"].items(), key=lambda kv: -kv[1]["seconds"])[:3])
            inside = " (in newton_matrix)" if name == "tangent_assembly" else (
                " (in residual, line_search)" if name == "residual_assembly" else "")
            phases.append([r["label"], name + inside, r["calls"].get(name, ""), f"{p['seconds']:.2f}",
                           f"{p['seconds'] / r['solve_s']:.1%}", f"{p['seconds'] / newton:.3f}", events])
    worst = max(s["seconds"] / l["seconds"] for r in rows for s, l in zip(r["steps"], linear["steps"]))
    verdict = (f"\nLargest ratio of a load step to the small-strain step: {worst:.2f} (requirement ≤ {MAX_RATIO:g}: "
               f"{'met' if worst <= MAX_RATIO else 'not met'}).\n\n")
    return tables.markdown_table(header, table) + verdict + tables.markdown_table([
        "run", "phase", "calls", "seconds", "share of the solve", "per Newton step (s)",
        "dominant PETSc events (count, s)"], phases)


def ranks_markdown(rows: list[dict]) -> str:
    table = [[r["case"], r["ranks"], r["status"], " ".join(map(str, r["newton_steps"])), r["krylov"],
              r.get("max_newton_difference"), r.get("relative_difference"),
              None if "relative_difference" not in r else ("yes" if r["relative_difference"] <= MAX_RANK_DIFFERENCE
                                                           else "no"), r["commit"], r["seconds"]] for r in rows]
    worst = max((r.get("relative_difference", 0.0) for r in rows), default=0.0)
    return tables.markdown_table(["case", "ranks", "status", "Newton per step", "Krylov", "dNewton",
                                  f"rel. diff (≤ {MAX_RANK_DIFFERENCE:g})", "within", "commit", "wall s"], table) + (
        f"\nLargest rel. diff: {worst:.2g} (requirement ≤ {MAX_RANK_DIFFERENCE:g}: "
        f"{'met' if worst <= MAX_RANK_DIFFERENCE else 'not met'}).\n")


def large_markdown(r: dict) -> str:
    converged = all(s["status"].startswith("converged") for s in r["steps"]) and len(r["steps"]) == 4
    table = [[r["mesh"], f"{r['dofs']} (≥ {MIN_LARGE_DOFS})", r["ranks"], "yes" if converged else "no",
              " ".join(str(s["newton"]) for s in r["steps"]), " ".join(str(s["krylov"]) for s in r["steps"]),
              f"{r['assembly_s']:.0f}", f"{r['solve_s']:.0f}", f"{r['peak_rss_mib'] / 1024:.1f}",
              r.get("commit")]]
    return tables.markdown_table(["mesh", "dofs", "ranks", "converged (all 4 steps)", "Newton per step",
                                  "Krylov per step", "assembly (s)", "solve (s)", "peak memory, ranks added (GiB)",
                                  "commit"], table)


def history_markdown(history: list[dict]) -> str:
    """Earlier measurements of the ratio part (``history`` of the JSON file: one dict per code
    version with its counts and phases, kept when the part is measured again)."""
    table = [[h["version"], h["run"], h["newton"], h["krylov"], h["solve_s"], h["ratio"], h["pc_set_ups"],
              h["pc_set_up_s"], h["tangent_s"]] for h in history]
    return tables.markdown_table(["version", "run", "Newton per step", "Krylov per step", "solve (s)",
                                  "mean step / small strain", "PC set-ups", "PC set-up (s)", "tangent assembly (s)"],
                                 table)


def markdown(data: dict) -> str:
    """All parts present in ``data``, each with its text (:data:`TEXTS`) and its notes (``notes``)."""
    notes = data.get("notes", {})
    text = [TEXTS["head"].format(**data["machine"])]
    if "ratio" in data:
        text += [TEXTS["ratio"].format(commit=data["ratio"]["commit"]), ratio_markdown(data["ratio"]["rows"])]
        if data.get("history"):
            text += [TEXTS["history"], history_markdown(data["history"])]
        text.append(notes.get("ratio", ""))
    if "ranks" in data:
        text += [TEXTS["ranks"], ranks_markdown(data["ranks"]), notes.get("ranks", "")]
    if "large" in data:
        text += [TEXTS["large"], large_markdown(data["large"]), notes.get("large", "")]
    return "\n".join(text)


TEXTS = {
    "head": "# Finite strain against small strain: cost, ranks, a million dofs (issue 36)\n\n"
            "benchmarks/finite_strain_performance.py. Measured on {cpu}, {cores} cores, {memory_gib} GiB, PETSc "
            "{petsc}, **shared with two other engineers' jobs**: wall times are noisy; the counts, and the ratios "
            "of runs made back to back in one process, are what compare.\n",
    "ratio": "## A load step at finite strain against the small-strain step (two-body Hertz, fine mesh, 2 ranks)\n\n"
             "cases/hertz_bodies.toml on meshes/hertz_bodies_fine.geo (the fine mesh of benchmarks/hertz_bodies.py): "
             "steel ball (E = 210 GPa) 1 mm into an aluminium block (E = 70 GPa), nu = 0.3, four steps of "
             "0.25 mm from rest, frictionless mortar contact searched before every step after the first in the "
             "configuration the step before ended in (`every_step`); linear elasticity, then both bodies "
             "neo-Hookean with the same E and nu, back to back in one process (commit {commit}); default solver "
             "(GAMG; Krylov tol 0.1 for the linear body, 1e-3 for the hyperelastic one, `HYPERELASTIC_TOL`; "
             "Newton rtol 1e-12). Wall per step: from the end of the step before (the search before the step "
             "included) to the end of the step, largest rank. Requirement (issue 36): a finite-strain step at "
             "most 3x the small-strain step.\n\n"
             "Phases (second table): the solver's own phases (`Timings`, each a PETSc log stage) summed over the "
             "steps, and, timed around the problem's methods by the benchmark (the solver untouched): the "
             "geometry update `problem.search` (contact search, mortar segments, D, M and the slave normals of "
             "the deformed surfaces, nodal frames, T and A = T^T A_K T and the loads; before steps 2-4), the "
             "tangent assembly `problem.tangent` (K_T by DOLFINx and T^T K_T T; part of `newton_matrix`) and the "
             "residual assembly `problem.residual` (r_K and T^T r_K; part of `residual` and `line_search`). "
             "Share: of the load path's solve time; per Newton step: the phase's seconds over all Newton steps.\n",
    "history": "Before and after the solver change of this benchmark (same script, same machine, shared: "
               "the before run's machine load differed; compare counts and the shares):\n",
    "ranks": "## The same solution on 1, 2 and 3 ranks (finite strain)\n\n"
             "`python -m contactqvi run` of cases/hertz_bodies.toml on meshes/hertz_bodies_coarse.geo with both "
             "bodies neo-Hookean (four steps of 0.25 mm, `every_step`), on 1, 2 and 3 ranks (3 oversubscribed on "
             "2 cores); with exact Newton-step solves (`pc = \"lu\"`, MUMPS) and with the default GAMG (Krylov "
             "tol 1e-3). Newton stops at ||y^|| <= 1e-12 ||y^0|| of the first step (`rtol`, default; later steps "
             "at that step's target). rel. diff: max |u_N - u_1| / max |u_1| of solution.npz (the comparison of "
             "benchmarks/ranks.py); requirement 1e-9.\n",
    "large": "## A finite-strain case of a million dofs on 2 ranks\n\n"
             "cases/hertz_bodies.toml on meshes/hertz_bodies_xxfine.geo (h = a/35 at the contact), both bodies "
             "neo-Hookean, four steps of 0.25 mm, `every_step`, default solver (GAMG, Krylov tol 1e-3), "
             "2 ranks, under `timeout 30m`. Peak memory: the ranks' peak resident sizes added.\n",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--parts", nargs="*", choices=("ratio", "ranks", "large"), default=["ratio"],
                        help="parts to measure (none: write the tables of the JSON file again)")
    parser.add_argument("--mesh", default="fine", help="Hertz bodies mesh of the ratio part")
    parser.add_argument("--settled", action="store_true", help="ratio part: also neo-Hookean until_settled")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 3], help="ranks part: numbers of ranks, 1 first")
    parser.add_argument("--large-mesh", default="xxfine")
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    args, _ = parser.parse_known_args()
    comm = MPI.COMM_WORLD
    PETSc.Log.begin()
    args.output.mkdir(parents=True, exist_ok=True)
    path = args.output / f"{NAME}.json"
    data = read_table(path)
    commit = ranks.checkout_commit()
    if "ratio" in args.parts:
        data["ratio"] = {"commit": commit, "rows": ratio_part(comm, args.mesh, args.settled)}
    if "ranks" in args.parts:
        data["ranks"] = ranks_part(args.ranks, commit) if comm.rank == 0 else []
    if "large" in args.parts:
        data["large"] = large_part(comm, args.large_mesh) | {"commit": commit}
    data["machine"] = benchlib.machine(comm)
    tables.write_table(comm, args.output / NAME, data, markdown(data))


if __name__ == "__main__":
    main()
