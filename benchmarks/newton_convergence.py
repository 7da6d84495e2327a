"""The local rate of ``search = "newton"`` (issue 45): ||y^|| per Newton step with exact Newton-step solves.

Each load step of the cases of ``benchmarks/data/homogeneous_compression`` (the 30 % compression,
the bulging block frictionless and with Coulomb friction 0.3) and of the shipped shallow ironing,
frictionless and frictional (``cases/shallow_ironing*.toml``: its 8 press steps and the first 3
of the slide), is solved with the geometry in the
current configuration and LU Newton steps; the table lists, per load step, the merit ||y^|| of
each Newton step of its last solve and the ratios ||y^_{k+1}|| / ||y^_k||^2 of its last three
steps. Bounded ratios are quadratic convergence (docs/finite_strain.md, Sect. 14); the ratio of a
step that lands on the stopping floor (about 1e-8 N here) says nothing.

    .venv/bin/python benchmarks/newton_convergence.py     # -> results/newton_convergence.{json,md}
"""

from __future__ import annotations

import argparse
import pathlib
import shutil
import tomllib

from mpi4py import MPI

import numpy as np

from contactqvi.case import parse_case
from contactqvi.runner import run_case
from contactqvi.tables import write_table

HERE = pathlib.Path(__file__).resolve().parent
DATA = HERE / "data" / "homogeneous_compression"
CASES_DIR = HERE.parent / "cases"
#: (case file, Coulomb friction (0: the file's law), load steps run (None: all)) of the table.
CASES = ((DATA / "stacked_30.toml", 0.0, None), (DATA / "bulging_block.toml", 0.0, None),
         (DATA / "bulging_block.toml", 0.3, None), (CASES_DIR / "shallow_ironing.toml", 0.0, 11),
         (CASES_DIR / "shallow_ironing_frictional.toml", 0.0, 11))


def rows(path: pathlib.Path, friction: float, steps: int | None, work: pathlib.Path, comm: MPI.Comm) -> list[dict]:
    """One row per load step of the case ``path`` (its first ``steps``) searched ``"newton"`` with friction
    ``friction`` and LU solves."""
    data = tomllib.loads(path.read_text())
    for pair in data["contacts"]:
        pair["search"] = "newton"
        if friction > 0.0:
            pair.update(law="coulomb", friction=friction)
    data.setdefault("solver", {})["pc"] = "lu"
    data["steps"] = data["steps"][:steps]
    name, mu = path.name, data["contacts"][0].get("friction", 0.0)
    out = work / f"{path.stem}_mu{mu:g}"
    summary, _ = run_case(parse_case(data, path.parent), out, comm, plot=False)
    if comm.rank == 0:
        shutil.rmtree(out, ignore_errors=True)
    table = []
    for step in summary["steps"]:
        last = max(entry.get("search", 0) for entry in step["history"])
        merit = np.array([e["residual"] for e in step["history"] if e.get("search", 0) == last])
        ratios = merit[1:] / merit[:-1] ** 2
        table.append({"case": name, "friction": mu, "step": step["step"], "status": step["status"],
                      "newton": step["iterations"], "merit": merit.tolist(), "ratios": ratios[-3:].tolist()})
    return table


def markdown(table: list[dict]) -> str:
    lines = ["| case | mu | step | status | Newton | ||y^|| of the last solve's steps (N) "
             "| last three ||y^_k+1|| / ||y^_k||^2 |",
             "|---|---|---|---|---|---|---|"]
    for r in table:
        merit = ", ".join(f"{v:.2e}" for v in r["merit"])
        ratios = ", ".join(f"{v:.1e}" for v in r["ratios"])
        lines.append(f"| {r['case']} | {r['friction']:g} | {r['step']} | {r['status']} | {r['newton']} | {merit} "
                     f"| {ratios} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--work", default="/tmp/newton_convergence", help="where the runs write their results")
    parser.add_argument("--output", default=str(HERE / "results"))
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    work = pathlib.Path(args.work)
    table = [row for path, friction, steps in CASES for row in rows(path, friction, steps, work, comm)]
    write_table(comm, pathlib.Path(args.output) / "newton_convergence", {"rows": table}, markdown(table))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
