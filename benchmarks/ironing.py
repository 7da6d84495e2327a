"""Shallow ironing, 3D (issue 36): our force histories beside the reference and Kratos 10.4.

    .venv/bin/python benchmarks/ironing.py --run                  # runs both cases (1 rank), then the table
    .venv/bin/python benchmarks/ironing.py                        # the table from earlier runs
    .venv/bin/python benchmarks/ironing.py --kratos DIR [DIR]     # with Kratos' runs (peers/kratos_ironing.py;
                                                                  # without: those of the table before)
    .venv/bin/python benchmarks/ironing.py --run --mesh meshes/shallow_ironing_hex.msh \
        --results results/ironing-hex --table benchmarks/results/ironing_hex
                                                                  # the cases on another mesh

Cases ``cases/shallow_ironing.toml`` (frictionless) and ``cases/shallow_ironing_frictional.toml``
(Coulomb, mu = 0.3): Kratos' validation case ``shallow_ironing_3D`` (KratosMultiphysics/Examples,
commit 9eacc7b, fetched into ``build/kratos-ironing/`` by scripts/fetch-kratos-ironing.sh) after
Poulios & Renard (2015). Our runs go to
``results/ironing/<case>`` (``--results``); each step's time t of Kratos' path is read from the
die's translation: t = 0.2 + |u_y| while it is pressed, t = 1 + u_x / 10 while it slides.

Forces, in the sign convention of Kratos' figures (both positive in the plateau of the frictional
case): F_y = the force of the block on the die along y (the pair force's y component; = -R_y of
the die's top, the support that moves it), F_x = the support's force on the die along x (R_x of
``die.top``, = -the pair force's x component in equilibrium: the force that drags the die).

REFERENCE holds the values of Poulios & Renard's curve ("F ref." in Kratos' figures
``build/kratos-ironing/solution_frictionless.png`` and ``solution_frictional.png``), read from the figures:
the axes calibrated on their grid lines (122.25 px per 1e8 N frictionless, 130.0 px frictional,
266.75 px per second), the plateau t in [1.3, 1.7] as the median height of the curve's pixels
(reading accuracy +-0.03e8 N), single times from the marker or the line there (+-0.05e8 N; at
t = 1 the curves are steep, F_y +-0.1e8 N).
"""

from __future__ import annotations

import argparse
import csv
import json
import pathlib
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from mpi4py import MPI  # noqa: E402

from contactqvi import tables  # noqa: E402

CASES = {"frictionless": ("cases/shallow_ironing.toml", 0.0),
         "frictional": ("cases/shallow_ironing_frictional.toml", 0.3)}
PAIR = "die.contact/block.contact"
SUPPORT = "die.top"
PLATEAU = (1.3, 1.7)
#: Poulios & Renard's reference read from Kratos' figures, 1e8 N: {case: {what: (F_y, F_x, accuracy)}}.
REFERENCE = {
    "frictionless": {"plateau": (3.38, 0.00, 0.03), "t = 1": (2.70, 0.31, 0.10), "t = 2": (2.91, -0.20, 0.05)},
    "frictional": {"plateau": (3.37, 1.03, 0.03), "t = 1": (2.70, 0.56, 0.10), "t = 2": (2.89, 0.64, 0.05)},
}


def path_time(translation: np.ndarray) -> np.ndarray:
    """Kratos' time of each step from the die's translation (the literature path)."""
    tx, ty = translation[:, 0], translation[:, 1]
    return np.where(tx > 0, 1.0 + tx / 10.0, 0.2 - ty)


def ours(directory: pathlib.Path) -> dict:
    """Steps, times, F_y, F_x, Newton counts and cuts of one of our runs."""
    summary = json.loads((directory / "summary.json").read_text())
    steps = [step for step in summary["steps"] if step["converged"]]  # a path that failed: up to its last step
    translation = np.array([s["translation"] for s in steps], dtype=float).reshape(-1, 3)  # no step: (0, 3)
    pair = np.array([s["pair_forces"][PAIR] for s in steps], dtype=float).reshape(-1, 3)
    support = np.array([s["reaction_forces"][SUPPORT] for s in steps], dtype=float).reshape(-1, 3)
    cuts = [len({h.get("substep") for h in s["history"] if h.get("substep") is not None}) for s in steps]
    searches = [max((h.get("search", 0) for h in s["history"]), default=0) for s in steps]
    record = {"status": summary["status"], "n": summary["n"], "p": summary["p"], "mpi_size": summary["mpi_size"],
              "t": path_time(translation).tolist(), "F_y": pair[:, 1].tolist(), "F_x": support[:, 0].tolist(),
              "F_x_pair": (-pair[:, 0]).tolist(), "F_y_support": (-support[:, 1]).tolist(),
              "newton": [s["iterations"] for s in steps], "krylov": [s["inner_iterations"] for s in steps],
              "searches": searches, "substeps": cuts,
              "solver_seconds": [sum(s["timings"].values()) + sum(s.get("search_seconds", {}).values()) for s in steps],
              "equilibrium_error": [s.get("equilibrium_error") for s in steps]}
    record["nodal_friction_ratio"] = nodal_friction_ratio(directory)
    wall = directory / "wall_time.json"
    if wall.exists():
        record["wall_time"] = json.loads(wall.read_text())["wall_time"]
    return record


def nodal_friction_ratio(directory: pathlib.Path) -> list[float] | None:
    """Per step, the largest |friction traction| / contact pressure of the slave nodes that press
    (pressure above 1e-6 of the step's largest), from ``contact_surface.bp`` (every rank's block)."""
    surface = directory / "contact_surface.bp"
    if not surface.exists():
        return None
    import adios2

    reader = adios2.FileReader(str(surface))
    blocks = reader.all_blocks_info("contact_pressure [Pa]")  # per step, one per rank that wrote
    ratios = []
    for k, step_blocks in enumerate(blocks):
        pressure, traction = [], []
        for block in range(len(step_blocks)):
            pressure.append(reader.read("contact_pressure [Pa]", block_id=block, step_selection=[k, 1]))
            traction.append(reader.read("friction_traction [Pa]", block_id=block, step_selection=[k, 1]))
        pressure, traction = np.concatenate(pressure), np.concatenate(traction).reshape(-1, 3)
        pressing = pressure > 1e-6 * pressure.max()
        ratios.append(float((np.linalg.norm(traction[pressing], axis=1) / pressure[pressing]).max()))
    reader.close()
    return ratios


def kratos(directory: pathlib.Path) -> dict:
    """The same quantities from ``kratos_ironing.json``: F_y = -REACTION_y, F_x = REACTION_x of the die's top
    (Kratos' REACTION is the support's force on the die, as our R: t = 0.3 on the coarse mesh, Kratos
    (3.23e5, -2.331e7) N, ours (4.66e5, -2.334e7) N)."""
    record = json.loads((directory / "kratos_ironing.json").read_text())
    steps = record["steps"]
    reaction = np.array([s["reaction_die_top"] for s in steps]) if steps else np.zeros((0, 3))
    return {"status": record.get("status", "running"), "error": record.get("error"), "t": [s["time"] for s in steps],
            "converged": [s["converged"] for s in steps], "F_y": (-reaction[:, 1]).tolist(),
            "F_x": reaction[:, 0].tolist(), "newton": [s["newton"] for s in steps],
            "wall_time": record.get("wall_time"), "friction": record.get("friction"), "mdpa": record.get("mdpa")}


def at(run: dict, what: str) -> tuple[float, float] | None:
    """(F_y, F_x) in 1e8 N: the mean over the plateau's steps, or at t = 1, 2 (None if not reached)."""
    t, fy, fx = (np.asarray(run[k], dtype=float) for k in ("t", "F_y", "F_x"))
    if what == "plateau":
        inside = (t >= PLATEAU[0] - 1e-9) & (t <= PLATEAU[1] + 1e-9)
        return (fy[inside].mean() / 1e8, fx[inside].mean() / 1e8) if inside.any() else None
    target = float(what.split("=")[1])
    near = np.flatnonzero(np.isclose(t, target, atol=1e-6))
    return (fy[near[-1]] / 1e8, fx[near[-1]] / 1e8) if len(near) else None


def run_case(name: str, out: pathlib.Path, ranks: int, mesh: pathlib.Path | None = None) -> None:
    """Run one case with our solver, timing the whole process (``wall_time.json``).

    ``mesh`` replaces the case's mesh file: the case is copied to ``out/case.toml`` with it.
    """
    case = ROOT / CASES[name][0]
    if mesh is not None:
        text = case.read_text()
        line = next(s for s in text.splitlines() if s.startswith("file = "))
        out.mkdir(parents=True, exist_ok=True)
        case = out / "case.toml"
        case.write_text(text.replace(line, f"file = {str(mesh.resolve())!r}"))
    command = [str(ROOT / ".venv" / "bin" / "python"), "-m", "contactqvi", "run", str(case),
               "--output", str(out), "--no-plot"]
    if ranks > 1:
        command = ["mpirun", "-n", str(ranks)] + command
    start = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=False)
    (out / "wall_time.json").write_text(json.dumps({"wall_time": time.perf_counter() - start, "ranks": ranks}))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--run", action="store_true", help="run our cases first")
    parser.add_argument("--ranks", type=int, default=1)
    parser.add_argument("--case", choices=sorted(CASES), nargs="+", default=sorted(CASES), help="cases to run")
    parser.add_argument("--mesh", type=pathlib.Path, default=None,
                        help="run on this mesh instead of the cases' (e.g. meshes/shallow_ironing_hex.msh)")
    parser.add_argument("--results", type=pathlib.Path, default=ROOT / "results" / "ironing")
    parser.add_argument("--kratos", type=pathlib.Path, nargs="*", default=[],
                        help="output directories of peers/kratos_ironing.py (frictionless, frictional)")
    parser.add_argument("--table", type=pathlib.Path, default=ROOT / "benchmarks" / "results" / "ironing")
    args = parser.parse_args()
    runs = {}
    for name in CASES:
        out = args.results / name
        if args.run and name in args.case:
            run_case(name, out, args.ranks, args.mesh)
        if (out / "summary.json").exists():
            runs[name] = ours(out)
    peers = {}
    for directory in args.kratos:
        if (directory / "kratos_ironing.json").exists():
            record = kratos(directory)
            peers["frictional" if record["friction"] else "frictionless"] = record
    earlier = args.table.with_suffix(".json")
    if not args.kratos and earlier.exists():  # Kratos' runs of the table before (peers/kratos_ironing.py)
        peers = json.loads(earlier.read_text()).get("kratos", {})

    rows = []
    for name, (case, mu) in CASES.items():
        for what, (ref_y, ref_x, accuracy) in REFERENCE[name].items():
            row = [name, what, f"{ref_y:.2f}", f"{ref_x:.2f}"]
            for run in (runs.get(name), peers.get(name)):
                value = at(run, what) if run else None
                if value is None:
                    row += ["–", "–", "–"]
                    continue
                fy, fx = value
                row += [f"{fy:.3f}", f"{fx:.3f}", f"{100 * (fy / ref_y - 1):+.1f} %"]
            rows.append(row)
    checks = {}
    for name, run in runs.items():
        mu = CASES[name][1]
        fy, fx, fxp = (np.asarray(run[k]) for k in ("F_y", "F_x", "F_x_pair"))
        ratio = np.abs(fxp) / np.where(fy > 0, fy, np.nan)
        slide = np.asarray(run["t"]) > 1.0
        checks[name] = {"max_ratio_all_steps": float(np.nanmax(ratio, initial=0.0)),
                        "max_ratio_sliding": float(np.nanmax(ratio[slide])) if slide.any() else None,
                        "mean_ratio_plateau": float(np.nanmean(ratio[(np.asarray(run["t"]) >= PLATEAU[0])
                                                                    & (np.asarray(run["t"]) <= PLATEAU[1])]))
                        if slide.any() else None, "mu": mu,
                        "max_nodal_ratio": max(run["nodal_friction_ratio"]) if run["nodal_friction_ratio"] else None}
    headers = ["case", "where", "ref F_y", "ref F_x", "ours F_y", "ours F_x", "ours F_y vs ref",
               "Kratos F_y", "Kratos F_x", "Kratos F_y vs ref"]
    notes = ["Forces in 1e8 N. F_y: the block's force on the die along y (pair force); F_x: the support's force on "
             "the die along x (R_x of die.top, the force that drags it); Kratos: REACTION_x, -REACTION_y of "
             "Displacement_Auto2 (the die's top; Kratos' REACTION is the support's force on the die, as our R).",
             f"plateau: mean over the steps with t in [{PLATEAU[0]}, {PLATEAU[1]}]; ref: Poulios & Renard (2015) "
             "read from Kratos' figures (build/kratos-ironing/solution_*.png, scripts/fetch-kratos-ironing.sh), "
             "accuracy +-0.03 (plateau), +-0.05 (t = 2), "
             "+-0.1 (t = 1, steep).",
             "F_x at the frictionless plateau is ~0: compare it absolutely (ref 0.00 +- 0.03)."]
    for name, c in checks.items():
        if c["mu"]:
            notes.append(f"{name}: |F_x| / F_y (pair force) at most {c['max_ratio_all_steps']:.4f} over all steps, "
                         f"{c['max_ratio_sliding']:.4f} while sliding, mean {c['mean_ratio_plateau']:.4f} on the "
                         f"plateau (mu = {c['mu']}); |friction traction| / pressure at the pressing slave nodes at "
                         f"most {c['max_nodal_ratio']} over all steps (contact_surface.bp).")
    for name, run in runs.items():
        notes.append(f"ours {name}: {run['status']}, {len(run['t'])} steps, n = {run['n']} free dofs, p = {run['p']} "
                     f"slave nodes, {run['mpi_size']} rank(s), Newton {sum(run['newton'])} "
                     f"(per step {min(run['newton'], default=0)}-{max(run['newton'], default=0)}), steps cut: "
                     f"{sum(1 for s in run['substeps'] if s > 1)}, solver {sum(run['solver_seconds']):.0f} s"
                     + (f", wall {run['wall_time']:.0f} s" if "wall_time" in run else ""))
    for name, run in peers.items():
        notes.append(f"Kratos {name}: {run['status']}, {len(run['t'])} steps to t = "
                     f"{run['t'][-1] if run['t'] else 0:.3f}, Newton {sum(run['newton'])}"
                     + (f", wall {run['wall_time']:.0f} s" if run.get("wall_time") else "")
                     + (f", {run['error']}" if run.get("error") else ""))
    history = []
    for name, run in runs.items():
        peer = peers.get(name)
        for k, t in enumerate(run["t"]):
            match = [i for i, tk in enumerate(peer["t"]) if abs(tk - t) < 1e-6] if peer else []
            kr = (f"{peer['F_y'][match[0]] / 1e8:.3f}", f"{peer['F_x'][match[0]] / 1e8:.3f}",
                  str(peer["newton"][match[0]])) if match else ("–", "–", "–")
            history.append([name, k + 1, f"{t:.2f}", f"{run['F_y'][k] / 1e8:.3f}", f"{run['F_x'][k] / 1e8:.3f}",
                            run["newton"][k], run["searches"][k], run["substeps"][k] or 1,
                            f"{run['solver_seconds'][k]:.0f}", *kr])
    history_headers = ["case", "step", "t", "F_y", "F_x", "Newton", "searches after the first solve", "parts",
                       "solver s", "Kratos F_y", "Kratos F_x", "Kratos Newton"]
    args.table.parent.mkdir(parents=True, exist_ok=True)
    markdown = ("# Shallow ironing 3D: forces beside the reference and Kratos\n\n"
                + tables.markdown_table(headers, rows) + "\n" + "".join(f"\n- {note}" for note in notes) + "\n"
                + "\n## Per step (forces in 1e8 N)\n\n" + tables.markdown_table(history_headers, history) + "\n")
    tables.write_table(MPI.COMM_SELF, args.table, {"ours": runs, "kratos": peers, "checks": checks,
                                                   "reference": REFERENCE}, markdown)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
