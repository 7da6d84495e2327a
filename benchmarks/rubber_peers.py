"""The rubber pad (cases/rubber_pad.toml) against GetFEM 5.4's large-sliding contact (issue 36).

For each mesh (``--meshes``: ``coarse`` = meshes/rubber_pad_coarse.geo, ``shipped`` = the case's
meshes/rubber_pad.geo, ``fine`` = the same script at h = 0.625 mm, meshed in ``--work``) the case
is exported once to a ``.msh`` that both codes read (:func:`peers.export.export_case`), with its
law (Coulomb, friction 0.5) and as a frictionless copy, each also in the roller's frame (roller at
rest, bottom moved up: the frame GetFEM's driver solves in). Our solver (``python -m contactqvi
run``, one rank) on both frames and ``peers/getfem_rubber.py`` (serial) run one process at a
time; the table compares per load step the roller's force on the pad (half model; ours the pair
force ``top/obstacle``, GetFEM's the nodal internal forces at the contact surface), the wall
times of the processes and of their load steps alone (ours the steps' ``solve_seconds``, GetFEM's its
step loop; the processes' wall times include Python's imports and the set-up, 0.8 s of ours), and
how far the last step's nodal contact forces are from the roller's normal (:func:`force_directions`).
Our runs take the case's ``search`` (``"newton"``: the geometry inside the Newton iteration,
docs/finite_strain.md Sect. 18), or ``--search``. Writes
``--table``.json/.md (:func:`contactqvi.tables.write_table`).

    .venv/bin/python benchmarks/rubber_peers.py --meshes coarse shipped
    .venv/bin/python benchmarks/rubber_peers.py --meshes fine --laws frictionless --update
"""

from __future__ import annotations

import argparse
import os
import pathlib
import platform
import subprocess
import sys
import time
import tomllib

from mpi4py import MPI

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "peers"))
sys.path.insert(0, str(ROOT))
import common  # noqa: E402
import export  # noqa: E402
from rows import failed_row, read_table  # noqa: E402

from contactqvi.tables import write_table  # noqa: E402

CASE = ROOT / "cases" / "rubber_pad.toml"
#: Mesh name -> (gmsh script or None for the case's own, element size under the roller in mm).
MESHES = {"coarse": ("meshes/rubber_pad_coarse.geo", 2.5), "shipped": (None, 1.25), "fine": ("fine", 0.625)}
#: GetFEM's settings (benchmarks/peers/getfem_rubber.py): r = E / 1 mm, release distance 2.5 mm.
GETFEM_OPTIONS = ["--release", "2.5", "--max-iter", "40", "--max-res", "1e-8"]
LAWS = {"coulomb": "Coulomb, friction 0.5", "frictionless": "frictionless"}


def export_mesh(work: pathlib.Path, mesh: str, search: str | None = None) -> dict[str, dict[str, pathlib.Path]]:
    """The case on ``mesh`` exported to ``work`` (its contact searched by ``search``; None: the
    case's own), per law (its own and frictionless) and frame:
    ``"moved"`` as shipped (the roller moved by the steps' translations), ``"roller"`` in the
    roller's frame (the roller at rest, the clamped groups moved by minus the translations, as
    GetFEM's driver solves it; the same problem up to a rigid translation)."""
    geo, _ = MESHES[mesh]
    if geo == "fine":  # the shipped script at half its element size, meshed here
        source = work / "rubber_pad_fine.geo"
        source.write_text(f'DefineConstant[ h = 0.625e-3 ];\nInclude "{ROOT / "meshes" / "rubber_pad.geo"}";\n')
    else:
        source = None if geo is None else ROOT / geo
    data = tomllib.loads(CASE.read_text())
    contact = data["contact"] | ({} if search is None else {"search": search})
    laws = {"coulomb": contact,
            "frictionless": {k: v for k, v in contact.items() if k != "friction"} | {"law": "frictionless"}}
    # The roller's frame: the translations t_k = s_k t_n of the steps along one direction.
    last = np.asarray(data["steps"][-1]["translation"], float)
    translations = np.array([s["translation"] for s in data["steps"]], float)
    loads = translations @ last / (last @ last)
    if not np.allclose(np.outer(loads, last), translations, rtol=0, atol=1e-15):
        raise ValueError("the roller's frame takes translations along one direction")
    boundary = dict(data["boundary"], clamped=[])
    boundary["displacement"] = {name: dict(zip("xyz", (-last).tolist())) for name in data["boundary"]["clamped"]} \
        | data["boundary"].get("displacement", {})
    frame = {"boundary": boundary, "steps": [{"load": float(s)} for s in loads]}
    return {law: {"moved": export.export_case(work, CASE, f"rubber_{mesh}_{law}", mesh=source, contact=table),
                  "roller": export.export_case(work, CASE, f"rubber_{mesh}_{law}_roller_frame", mesh=source,
                                               contact=table, **frame)}
            for law, table in laws.items()}


def run(command: list[str], log: pathlib.Path) -> tuple[int, float]:
    """Run ``command`` from the repository root (output to ``log``); its exit code and wall time (s)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    start = time.perf_counter()
    with log.open("w") as out:
        code = subprocess.run(command, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, env=env).returncode
    return code, time.perf_counter() - start


def ours(case: pathlib.Path, out: pathlib.Path) -> dict:
    """Our solver on ``case``: per-step roller force (N), Newton steps, process wall time and the steps'
    solve time (their ``solve_seconds``: searches and Newton steps, not the writing of results, as
    GetFEM's ``solve_time`` takes its step loop)."""
    code, wall = run([str(ROOT / ".venv" / "bin" / "python"), "-m", "contactqvi", "run", str(case),
                      "--output", str(out), "--no-plot"], out.with_suffix(".log"))
    summary = read_table(out / "summary.json")
    if not summary:  # it stopped before its first step's summary: a failed run
        return _failed(code, wall)
    steps = summary["steps"]
    return {"status": summary["status"] if code == 0 else f"exit {code}", "wall_time": wall,
            "solve_time": sum(s["solve_seconds"] for s in steps),
            "force": [s["pair_forces"]["top/obstacle"] for s in steps],
            "newton": [s["iterations"] for s in steps]}


def getfem(case: pathlib.Path, out: pathlib.Path, options: list[str]) -> dict:
    """``peers/getfem_rubber.py`` on ``case``: the same fields as :func:`ours` (steps it finished)."""
    code, wall = run(["/usr/bin/python3", str(HERE / "peers" / "getfem_rubber.py"), str(case),
                      "--output", str(out), *options], out.with_suffix(".log"))
    result = read_table(out / "result.json")
    if not result:
        return _failed(code, wall) | {"nodes": None, "law_check": None}
    return {"status": result["status"], "wall_time": wall, "solve_time": result["solve_time"],
            "force": result["contact_force_per_step"], "newton": result["newton_per_step"],
            "nodes": result["dofs"] // 3, "law_check": result["law_check"], "settings": result["settings"]}


def _failed(code: int, wall: float) -> dict:
    """The record of a run that wrote no result: its exit code and wall time (s), no steps."""
    return failed_row(f"failed: exit {code}, no result file", wall) | {"wall_time": wall, "force": [], "newton": []}


def force_directions(case: pathlib.Path, out: pathlib.Path, translation: np.ndarray) -> dict:
    """How far the contact surface's nodal forces of the last step in ``out/solution.npz`` are
    from the normal of the roller moved by ``translation`` (frictionless: they should not be).

    The nodal forces are the internal forces of the neo-Hookean body at the solution (P1
    tetrahedra, F constant per cell: f_a = V P grad N_a), less the prescribed components,
    at the contact surface's nodes; the normal is the roller's at each deformed node.
    Returns the sum of the forces' tangential parts (N), their share sum |f_t| / sum |f_n|,
    and the largest angle between a node's force and its normal (degrees; nodes carrying more
    than 1 % of the largest normal force).
    """
    data = common.load_case(case)
    mesh = common.read_msh(data.mesh)
    solution = np.load(out / "solution.npz")
    u = np.empty_like(solution["u"])
    u[common.sort_nodes(mesh.points)] = solution["u"]  # the file's node order
    mu = data.young / (2 * (1 + data.poisson))
    lmbda = data.young * data.poisson / ((1 + data.poisson) * (1 - 2 * data.poisson))
    x = mesh.points[mesh.cells]  # (cells, 4, 3)
    edges = x[:, 1:] - x[:, :1]  # rows: x_i - x_0
    grad_ref = np.linalg.inv(edges)  # columns: gradients of N_1..N_3
    grads = np.concatenate([-grad_ref.sum(axis=2, keepdims=True), grad_ref], axis=2)  # (cells, 3, 4)
    F = np.eye(3) + np.einsum("cak,cja->ckj", u[mesh.cells], grads)  # I + sum_a u_a grad N_a^T
    J = np.linalg.det(F)
    F_inv_T = np.linalg.inv(F).transpose(0, 2, 1)
    P = mu * (F - F_inv_T) + (lmbda * np.log(J))[:, None, None] * F_inv_T
    volume = np.abs(np.linalg.det(edges)) / 6
    cell_forces = volume[:, None, None] * np.einsum("cij,cja->cai", P, grads)  # (cells, 4, 3)
    nodal = np.zeros_like(u)
    np.add.at(nodal, mesh.cells, cell_forces)
    top = mesh.group_nodes(data.contact)
    force = nodal[top]
    for name, components in data.displacement.items():
        on_top = np.isin(top, mesh.roller_nodes(data, name))
        force[np.ix_(on_top, list(components))] = 0.0
    axis_point = np.asarray(data.obstacle["point"], float) + translation
    radial = mesh.points[top] + u[top] - axis_point
    radial[:, 1] = 0.0  # the axis is along y
    normal = radial / np.linalg.norm(radial, axis=1)[:, None]
    normal_part = np.einsum("ij,ij->i", force, normal)
    tangential = force - normal_part[:, None] * normal
    loaded = np.abs(normal_part) > 0.01 * np.abs(normal_part).max()
    angle = np.degrees(np.arctan2(np.linalg.norm(tangential, axis=1), np.abs(normal_part)))
    return {"tangential_sum": tangential.sum(axis=0).tolist(),
            "tangential_share": float(np.linalg.norm(tangential, axis=1).sum() / np.abs(normal_part).sum()),
            "max_angle_deg": float(angle[loaded].max())}


def _steps_line(name: str, run: dict) -> str:
    newton = run["newton"]
    solve = (f" (solve {run['solve_time']:.2f} s, {run['solve_time'] / max(len(newton), 1):.3f} s a step)"
             if "solve_time" in run else "")
    return (f"* {name}: {run['status']}, wall {run['wall_time']:.1f} s{solve}, Newton {sum(newton)} "
            f"({' '.join(map(str, newton))})")


def _directions(run: dict) -> str:
    if "force_directions" not in run:
        return "—"
    d = run["force_directions"]
    return f"{100 * d['tangential_share']:.3g} %, {d['max_angle_deg']:.2g}°"


def _force(force: list[float] | None, component: int) -> str:
    """A force component for the table (F_z as the roller's downward push, positive)."""
    return "—" if force is None else f"{(-1 if component == 2 else 1) * force[component]:.2f}"


def _percent(ratio: float | None) -> str:
    return "—" if ratio is None else f"{100 * ratio:+.2f} %"


def markdown(data: dict) -> str:
    lines = ["# The rubber pad against GetFEM 5.4 (issue 36)", "",
             "cases/rubber_pad.toml (neo-Hookean pad, E = 6 MPa, nu = 0.45, rigid roller R = 15 mm pressed "
             "4 mm in 8 steps; half model), the same P1 tetrahedra in both codes. F: the roller's force on the "
             f"pad (N). Ours: the pair force top/obstacle (nodal contact, search = \"{data['search']}\"), "
             "for the case as shipped (roller moved) and in the roller's frame (roller at rest, "
             "bottom moved up: the same problem up to a rigid translation, and the frame GetFEM is solved in). "
             "GetFEM: large-sliding integral contact brick (raytracing), Compressible_Neo_Hookean_Bonet, "
             f"options {' '.join(data['getfem_options'])}. diff = GetFEM / ours - 1. Wall: each process from "
             "start to exit, one core, one process at a time. Written by benchmarks/rubber_peers.py; "
             "docs/rubber_getfem.md.", ""]
    for mesh, entry in data["meshes"].items():
        for law, runs in entry["laws"].items():
            moved, roller, other = runs["ours_moved"], runs["ours_roller"], runs["getfem"]
            lines += [f"## {mesh} mesh ({entry['nodes']} nodes, h = {MESHES[mesh][1]} mm under the roller), "
                      f"{LAWS[law]}", "",
                      _steps_line("ours, roller moved", moved), _steps_line("ours, roller's frame", roller),
                      _steps_line("GetFEM", other), ""]
            if law == "frictionless":
                lines += ["Nodal contact forces of the last step against the moved roller's normal at each "
                          "deformed node (sum |f_t| / sum |f_n|; largest angle, nodes with > 1 % of the largest "
                          "normal force): " + "; ".join(f"{name} {_directions(run)}" for name, run in (
                              ("ours moved", moved), ("ours roller frame", roller), ("GetFEM", other))), ""]
            lines += ["| step | depth (mm) | F_z ours moved | F_z ours roller frame | F_z GetFEM "
                      "| diff (roller frame) | diff (moved) | F_x ours moved | F_x ours roller frame | F_x GetFEM |",
                      "|---|---|---|---|---|---|---|---|---|---|"]
            for k, row in enumerate(runs["per_step"]):
                lines.append(f"| {k + 1} | {row['depth_mm']:.1f} | {_force(row['ours_moved'], 2)} | "
                             f"{_force(row['ours_roller'], 2)} | {_force(row['getfem'], 2)} | "
                             f"{_percent(row['diff_roller'])} | {_percent(row['diff_moved'])} | "
                             f"{_force(row['ours_moved'], 0)} | {_force(row['ours_roller'], 0)} | "
                             f"{_force(row['getfem'], 0)} |")
            lines.append("")
    return "\n".join(lines)


def _finished(run: dict, k: int) -> list[float] | None:
    """The force of step ``k`` if the run converged there."""
    forces = run["force"]
    return forces[k] if k < len(forces) - 1 or (k == len(forces) - 1 and run["status"].startswith("converged")) \
        else None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--meshes", nargs="+", default=["coarse", "shipped"], choices=list(MESHES))
    parser.add_argument("--laws", nargs="+", default=list(LAWS), choices=list(LAWS))
    parser.add_argument("--work", default=str(ROOT / "build" / "rubber_getfem"))
    parser.add_argument("--table", default=str(HERE / "results" / "rubber_getfem"))
    parser.add_argument("--update", action="store_true", help="add to the table's JSON instead of replacing it")
    parser.add_argument("--rewrite", action="store_true", help="only write the markdown again from the table's JSON")
    parser.add_argument("--search", choices=["newton", "until_settled", "every_step"],
                        help="how our runs search the roller (default: the case's)")
    parser.add_argument("--getfem-options", nargs=argparse.REMAINDER, default=GETFEM_OPTIONS,
                        help="options of peers/getfem_rubber.py (last on the command line)")
    args = parser.parse_args()
    work = pathlib.Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    table = pathlib.Path(args.table)
    if args.rewrite:
        data = read_table(table.with_suffix(".json"))
        write_table(MPI.COMM_WORLD, table, data, markdown(data), echo=False)
        return 0
    data = read_table(table.with_suffix(".json")) if args.update else {}
    data.setdefault("meshes", {})
    search = args.search or tomllib.loads(CASE.read_text())["contact"]["search"]
    data |= {"case": str(CASE.relative_to(ROOT)), "getfem_options": args.getfem_options, "search": search}
    data.setdefault("machine", {})
    for mesh in args.meshes:
        cases = export_mesh(work, mesh, search)
        entry = data["meshes"].setdefault(mesh, {"laws": {}})
        for law in args.laws:
            cases_of = {"ours_moved": cases[law]["moved"], "ours_roller": cases[law]["roller"],
                        "getfem": cases[law]["moved"]}
            outs = {"ours_moved": work / f"ours_{mesh}_{law}", "ours_roller": work / f"ours_{mesh}_{law}_roller_frame",
                    "getfem": work / f"getfem_{mesh}_{law}"}
            runs = {"ours_moved": ours(cases_of["ours_moved"], outs["ours_moved"]),
                    "ours_roller": ours(cases_of["ours_roller"], outs["ours_roller"]),
                    "getfem": getfem(cases_of["getfem"], outs["getfem"], args.getfem_options)}
            entry["nodes"], entry["law_check"] = runs["getfem"]["nodes"], runs["getfem"]["law_check"]
            final = np.asarray(tomllib.loads(cases[law]["moved"].read_text())["steps"][-1]["translation"], float)
            for name, run in runs.items():  # the roller at its last position: at rest in the roller's frame
                if run["status"].startswith("converged"):
                    translation = np.zeros(3) if name == "ours_roller" else final
                    run["force_directions"] = force_directions(cases_of[name], outs[name], translation)
            depths = [-s["translation"][2] * 1e3 for s in tomllib.loads(cases[law]["moved"].read_text())["steps"]]
            per_step = []
            for k, depth in enumerate(depths):
                row = {"depth_mm": depth} | {name: _finished(run, k) for name, run in runs.items()}
                for frame in ("moved", "roller"):
                    a, b = row[f"ours_{frame}"], row["getfem"]
                    row[f"diff_{frame}"] = None if a is None or b is None else b[2] / a[2] - 1
                per_step.append(row)
            entry["laws"][law] = runs | {"per_step": per_step}
            data["machine"][f"{mesh}/{law}"] = {"cpus": os.cpu_count(), "load": os.getloadavg(),
                                                "python": platform.python_version()}
            print(f"{mesh} {law}: " + " ".join("—" if r["diff_roller"] is None else f"{100 * r['diff_roller']:+.2f}%"
                                               for r in per_step), flush=True)
    write_table(MPI.COMM_WORLD, table, data, markdown(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
