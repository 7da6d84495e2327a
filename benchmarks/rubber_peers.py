"""The rubber pad (cases/rubber_pad.toml) against GetFEM 5.4's large-sliding contact (issue 36).

For each mesh (``--meshes``: ``coarse`` = meshes/rubber_pad_coarse.geo, ``shipped`` = the case's
meshes/rubber_pad.geo, ``fine`` = the same script at h = 0.625 mm, meshed in ``--work``) the case
is exported once to a ``.msh`` that both codes read (:func:`peers.export.export_case`), with its
law (Coulomb, friction 0.5) and as a frictionless copy. Our solver (``python -m contactqvi run``,
one rank) and ``peers/getfem_rubber.py`` (serial) run on each, one process at a time; the
table compares per load step the roller's force on the pad (half model; ours the pair force
``top/obstacle``, GetFEM's the nodal internal forces at the contact surface) and the wall
times of the two processes. Writes ``--table``.json/.md (:func:`contactqvi.tables.write_table`).

    .venv/bin/python benchmarks/rubber_peers.py --meshes coarse shipped
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import subprocess
import sys
import time
import tomllib

from mpi4py import MPI

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "peers"))
sys.path.insert(0, str(ROOT))
import export  # noqa: E402

from contactqvi.tables import write_table  # noqa: E402

CASE = ROOT / "cases" / "rubber_pad.toml"
#: Mesh name -> (gmsh script or None for the case's own, element size under the roller in mm).
MESHES = {"coarse": ("meshes/rubber_pad_coarse.geo", 2.5), "shipped": (None, 1.25), "fine": ("fine", 0.625)}
#: GetFEM's settings (benchmarks/peers/getfem_rubber.py): r = E / 1 mm, release distance 2.5 mm.
GETFEM_OPTIONS = ["--release", "2.5", "--max-iter", "40", "--max-res", "1e-8"]
LAWS = {"coulomb": "Coulomb, friction 0.5", "frictionless": "frictionless"}


def export_mesh(work: pathlib.Path, mesh: str) -> dict[str, pathlib.Path]:
    """The case and its frictionless copy on ``mesh``, exported to ``work``."""
    geo, _ = MESHES[mesh]
    if geo == "fine":  # the shipped script at half its element size, meshed here
        source = work / "rubber_pad_fine.geo"
        source.write_text(f'DefineConstant[ h = 0.625e-3 ];\nInclude "{ROOT / "meshes" / "rubber_pad.geo"}";\n')
    else:
        source = None if geo is None else ROOT / geo
    contact = tomllib.loads(CASE.read_text())["contact"]
    frictionless = {k: v for k, v in contact.items() if k != "friction"} | {"law": "frictionless"}
    return {"coulomb": export.export_case(work, CASE, f"rubber_{mesh}", mesh=source),
            "frictionless": export.export_case(work, CASE, f"rubber_{mesh}_frictionless", mesh=source,
                                               contact=frictionless)}


def run(command: list[str], log: pathlib.Path) -> tuple[int, float]:
    """Run ``command`` from the repository root (output to ``log``); its exit code and wall time (s)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    start = time.perf_counter()
    with log.open("w") as out:
        code = subprocess.run(command, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, env=env).returncode
    return code, time.perf_counter() - start


def ours(case: pathlib.Path, out: pathlib.Path) -> dict:
    """Our solver on ``case``: per-step roller force (N), Newton steps, process wall time."""
    code, wall = run([str(ROOT / ".venv" / "bin" / "python"), "-m", "contactqvi", "run", str(case),
                      "--output", str(out), "--no-plot"], out.with_suffix(".log"))
    summary = json.loads((out / "summary.json").read_text())
    steps = summary["steps"]
    return {"status": summary["status"] if code == 0 else f"exit {code}", "wall_time": wall,
            "force": [s["pair_forces"]["top/obstacle"] for s in steps],
            "newton": [s["iterations"] for s in steps], "nodes": None}


def getfem(case: pathlib.Path, out: pathlib.Path, options: list[str]) -> dict:
    """``peers/getfem_rubber.py`` on ``case``: the same fields as :func:`ours` (steps it finished)."""
    code, wall = run(["/usr/bin/python3", str(HERE / "peers" / "getfem_rubber.py"), str(case),
                      "--output", str(out), *options], out.with_suffix(".log"))
    result = json.loads((out / "result.json").read_text())
    return {"status": result["status"], "wall_time": wall, "solve_time": result["solve_time"],
            "force": result["contact_force_per_step"], "newton": result["newton_per_step"],
            "nodes": result["dofs"] // 3, "law_check": result["law_check"], "settings": result["settings"]}


def markdown(data: dict) -> str:
    lines = ["# The rubber pad against GetFEM 5.4 (issue 36)", "",
             "cases/rubber_pad.toml (neo-Hookean pad, E = 6 MPa, nu = 0.45, rigid roller R = 15 mm pressed "
             "4 mm in 8 steps; half model), the same P1 tetrahedra in both codes. Roller force on the pad F_z "
             "(N; ours: pair force top/obstacle, nodal contact searched in the current configuration until "
             "settled; GetFEM: large-sliding integral contact brick, raytracing, Compressible_Neo_Hookean_Bonet). "
             "diff = GetFEM / ours - 1. Wall: each process from start to exit, one core. "
             "Written by benchmarks/rubber_peers.py; docs/rubber_getfem.md.", ""]
    for mesh, entry in data["meshes"].items():
        for law, runs in entry["laws"].items():
            a, b = runs["ours"], runs["getfem"]
            lines += [f"## {mesh} mesh ({entry['nodes']} nodes, h = {MESHES[mesh][1]} mm under the roller), "
                      f"{LAWS[law]}", "",
                      f"ours: {a['status']}, wall {a['wall_time']:.1f} s, Newton {sum(a['newton'])} "
                      f"({' '.join(map(str, a['newton']))}); GetFEM: {b['status']}, wall {b['wall_time']:.1f} s "
                      f"(solve {b['solve_time']:.1f} s), Newton {sum(b['newton'])} ({' '.join(map(str, b['newton']))})",
                      "", "| step | depth (mm) | F_z ours (N) | F_z GetFEM (N) | diff | F_x ours (N) | F_x GetFEM (N) |",
                      "|---|---|---|---|---|---|---|"]
            for k, row in enumerate(runs["per_step"]):
                g = "—" if row["getfem"] is None else f"{-row['getfem'][2]:.2f}"
                gx = "—" if row["getfem"] is None else f"{row['getfem'][0]:.2f}"
                d = "—" if row["diff"] is None else f"{100 * row['diff']:+.2f} %"
                lines.append(f"| {k + 1} | {row['depth_mm']:.1f} | {-row['ours'][2]:.2f} | {g} | {d} | "
                             f"{row['ours'][0]:.2f} | {gx} |")
            lines.append("")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--meshes", nargs="+", default=["coarse", "shipped"], choices=list(MESHES))
    parser.add_argument("--laws", nargs="+", default=list(LAWS), choices=list(LAWS))
    parser.add_argument("--work", default=str(ROOT / "build" / "rubber_getfem"))
    parser.add_argument("--table", default=str(HERE / "results" / "rubber_getfem"))
    parser.add_argument("--getfem-options", nargs=argparse.REMAINDER, default=GETFEM_OPTIONS,
                        help="options of peers/getfem_rubber.py (last on the command line)")
    args = parser.parse_args()
    work = pathlib.Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    data = {"case": str(CASE.relative_to(ROOT)), "getfem_options": args.getfem_options,
            "machine": {"cpus": os.cpu_count(), "load": os.getloadavg(), "python": platform.python_version()},
            "meshes": {}}
    for mesh in args.meshes:
        cases = export_mesh(work, mesh)
        entry = data["meshes"][mesh] = {"laws": {}}
        for law in args.laws:
            a = ours(cases[law], work / f"ours_{mesh}_{law}")
            b = getfem(cases[law], work / f"getfem_{mesh}_{law}", args.getfem_options)
            entry["nodes"], entry["law_check"] = b["nodes"], b["law_check"]
            depths = [-s["translation"][2] * 1e3 for s in tomllib.loads(cases[law].read_text())["steps"]]
            per_step = []
            for k, force in enumerate(a["force"]):
                other = b["force"][k] if k < len(b["force"]) and (k < len(b["force"]) - 1 or
                                                                  b["status"] == "converged") else None
                per_step.append({"depth_mm": depths[k], "ours": force, "getfem": other,
                                 "diff": None if other is None else other[2] / force[2] - 1})
            entry["laws"][law] = {"ours": a, "getfem": b, "per_step": per_step}
            print(f"{mesh} {law}: " + " ".join("—" if r["diff"] is None else f"{100 * r['diff']:+.2f}%"
                                               for r in per_step), flush=True)
    write_table(MPI.COMM_WORLD, args.table, data, markdown(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
