"""The frictional rubber seal of issue 45: how far the quasi-static path goes, over nu and mu.

A neo-Hookean strip (E = 5 MPa; a quarter cross-section 10 x 5 mm, a plane-strain slice 2 mm
deep) is squeezed 30 % by a rigid plate with Coulomb friction in 20 steps
(``benchmarks/data/seal/seal_half.toml``, the new user's case). For each Poisson's ratio
(``--poisson``), friction coefficient (``--friction``) and mesh (``--meshes``) the case runs in
this process with default solver settings, ``max_cuts`` raised to ``--max-cuts`` where asked
(a step that fails is halved up to that many times in a row, so the last converged part of a
failed step brackets the end of the path to 0.075 mm / 2^max_cuts); the table gives the squeeze
reached (of the strip's height, the converged parts of a failed step included), the run's status
and failure, the Newton steps per converged load step, the steps that relaxed past a limit point
(``[solver] limit_points``, docs/finite_strain.md Sect. 15) with their relaxation steps, the plate's
force at the last converged step and the time. A failed run is a row. docs/finite_strain.md,
Sects. 11 and 15, read the tables (the tables of Sect. 11, before relaxation existed, are those of
``--limit-points stop``).

    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.45 0.49 0.499 --friction 0.3 0.4 0.5 \
        --meshes h1.0 h0.5 --table seal_relaxed
    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.3 0.4 0.45 0.49 --friction 0.2 0.3 0.4 0.5 \
        --limit-points stop
    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.45 0.49 0.499 --friction 0.3 0.4 0.5 --meshes h0.25 \
        --table seal_relaxed_h025
    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.45 0.499 --friction 0.4 --squeeze 0.45 --table seal_45
    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.45 --friction 0.4 --max-cuts 14 --limit-points stop \
        --table seal_path_end
    .venv/bin/python benchmarks/seal_squeeze.py --meshes h0.5 --poisson 0.45 0.49 --friction 0.3 0.4 \
        --limit-points stop --table seal_squeeze_h05
    .venv/bin/python benchmarks/seal_squeeze.py --poisson 0.45 0.49 --formulation nodal_pressure \
        --limit-points stop --table seal_squeeze_nodal_pressure
"""

from __future__ import annotations

import argparse
import pathlib
import time
import tomllib

from mpi4py import MPI

from contactqvi.case import parse_case
from contactqvi.runner import run_case
from contactqvi.tables import write_table

HERE = pathlib.Path(__file__).resolve().parent
CASE = HERE / "data" / "seal" / "seal_half.toml"
#: Mesh name -> file in benchmarks/data/seal (element size at the contact group; the 0.25 mm one written by
#: ../shared/repro/turn5/rubber/mesh_block.py --A 0.010 --B 0.002 --H 0.005 --h 0.25e-3 --merge_side 1).
MESHES = {"h1.0": "seal_half_h1.0.msh", "h0.5": "seal_half_h0.5.msh", "h0.25": "seal_half_h0.25.msh"}
#: Half the strip's height (m): the quarter model's plate travel over it is the squeeze.
HALF_HEIGHT = 5e-3


def run(poisson: float, friction: float, mesh: str, max_cuts: int | None, work: pathlib.Path,
        formulation: str = "displacement", limit_points: str | None = None, squeeze: float = 0.3) -> dict:
    """One run of the seal case (the strip's ``formulation``, docs/nearly_incompressible.md; ``[solver]``
    ``max_cuts`` and ``limit_points`` if given) to ``squeeze`` of the strip's height: the case's steps,
    cut short or continued by its first (1.5 %); its row of the table."""
    data = tomllib.loads(CASE.read_text())
    stride = data["steps"][0]["translation"][2]
    count = round(squeeze * HALF_HEIGHT / -stride)
    data["steps"] = data["steps"][:count] + [{"translation": [0.0, 0.0, k * stride]}
                                             for k in range(len(data["steps"]) + 1, count + 1)]
    data["material"]["formulation"] = formulation
    data["mesh"]["file"] = MESHES[mesh]
    data["material"]["poisson"] = poisson
    data["contact"]["friction"] = friction
    solver = {"max_cuts": max_cuts, "limit_points": limit_points}
    data.setdefault("solver", {}).update({key: value for key, value in solver.items() if value is not None})
    case = parse_case(data, CASE.parent)
    name = (f"{mesh}_nu{poisson:g}_mu{friction:g}_{formulation}" + ("" if max_cuts is None else f"_cuts{max_cuts}")
            + ("" if limit_points is None else f"_{limit_points}") + ("" if squeeze == 0.3 else f"_to{squeeze:g}"))
    start = time.perf_counter()
    summary, code = run_case(case, work / name, MPI.COMM_WORLD, plot=False)
    seconds = time.perf_counter() - start
    converged = [step for step in summary["steps"] if step["converged"]]
    parts = [entry["substep_translation"][2] for step in summary["steps"] if not step["converged"]
             for entry in step["history"] if entry.get("substep_status", "").startswith("converged")]
    travel = [-step["translation"][2] for step in converged] + [-z for z in parts]
    reached = max(travel, default=0.0) / HALF_HEIGHT
    newton = [step["iterations"] for step in converged]
    relaxed = [step for step in summary["steps"] if any("relaxation" in entry for entry in step["history"])]
    return {"mesh": mesh, "poisson": poisson, "friction": friction, "max_cuts": max_cuts,
            "limit_points": limit_points, "exit": code, "status": summary["status"],
            "failure": summary.get("failure"), "squeeze": reached, "newton_per_step": newton,
            "newton_total": sum(step["iterations"] for step in summary["steps"]),
            "relaxed_steps": [step["step"] for step in relaxed],
            "relaxation_steps": [max(entry["relaxation"] for entry in step["history"] if "relaxation" in entry)
                                 for step in relaxed],
            "force": converged[-1]["contact_force"] if converged else None, "seconds": seconds}


def markdown(rows: list[dict]) -> str:
    """The table: one row per run."""
    lines = ["| mesh | nu | mu | max_cuts | limit_points | squeeze reached | status | Newton per converged step "
             "(mean, max) | Newton in all | relaxed steps (relaxation steps) | plate force F_z (N) | s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        steps = r["newton_per_step"]
        mean = f"{sum(steps) / len(steps):.1f}, {max(steps)}" if steps else "-"
        cuts = "default" if r["max_cuts"] is None else r["max_cuts"]
        relaxed = ", ".join(f"{k} ({n})" for k, n in zip(r["relaxed_steps"], r["relaxation_steps"])) or "-"
        force = "-" if r["force"] is None else f"{r['force'][2]:.4f}"
        lines.append(f"| {r['mesh']} | {r['poisson']:g} | {r['friction']:g} | {cuts} | "
                     f"{r['limit_points'] or 'default'} | {100 * r['squeeze']:.5f} % | {r['status']} | {mean} | "
                     f"{r['newton_total']} | {relaxed} | {force} | {r['seconds']:.0f} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--poisson", type=float, nargs="+", default=[0.3, 0.4, 0.45, 0.49])
    parser.add_argument("--friction", type=float, nargs="+", default=[0.2, 0.3, 0.4, 0.5])
    parser.add_argument("--meshes", nargs="+", choices=tuple(MESHES), default=["h1.0"])
    parser.add_argument("--max-cuts", type=int, default=None, help="[solver] max_cuts (default: the solver's)")
    parser.add_argument("--formulation", default="displacement", help="[material] formulation of the strip")
    parser.add_argument("--limit-points", choices=("relax", "stop"), default=None,
                        help="[solver] limit_points (default: the solver's, relax)")
    parser.add_argument("--squeeze", type=float, default=0.3,
                        help="of the strip's height, in the case's steps of 1.5 %% (the case file's 30 %% in 20)")
    parser.add_argument("--work", default="/tmp/seal_squeeze", help="where the runs write their results")
    parser.add_argument("--table", default="seal_squeeze",
                        help="name of the table in benchmarks/results (no dot: .json and .md are appended)")
    args = parser.parse_args()
    work = pathlib.Path(args.work)
    rows = [run(nu, mu, mesh, args.max_cuts, work, args.formulation, args.limit_points, args.squeeze)
            for mesh in args.meshes for nu in args.poisson for mu in args.friction]
    write_table(MPI.COMM_WORLD, HERE / "results" / args.table, {"case": str(CASE.relative_to(HERE.parent)),
                                                                "formulation": args.formulation, "runs": rows},
                markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
