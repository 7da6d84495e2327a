"""The same dynamic history on any number of ranks (issue 44): the shipped dynamic cases on 1-4 ranks.

Each case of ``--cases`` (``cases/<name>.toml``, with exact Newton-step solves, ``pc = "lu"``) runs
as a user runs it, ``python -m contactqvi run CASE --output DIR --no-plot`` under ``mpirun -n N``
for each N of ``--ranks`` (the first is the reference). Per case and N: whether every time step's
Newton counts (the step's and its projection's) equal the reference's, and the largest difference
over the steps of the energy terms and of each body's mean velocity from ``summary.json``, relative
to their scale as ``tests/test_dynamics.py::test_history_on_any_number_of_ranks`` takes it (the
largest kinetic plus elastic energy, the largest speed). The issue's bound is 1e-9.

    .venv/bin/python benchmarks/dynamics_ranks.py --ranks 1 2 3 4

Writes ``dynamics_ranks.json`` and ``dynamics_ranks.md`` in ``--output``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import sys
import tempfile

from mpi4py import MPI

from contactqvi.tables import write_table

from benchlib import machine
from ranks import ROOT, case_variant, checkout_commit, mpirun

#: The energy terms compared (docs/dynamics.md Sect. 4).
TERMS = ("kinetic", "elastic", "contact_work", "friction_dissipation", "external_work")


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--cases", nargs="+", default=["sliding_block", "bars_impact", "drop_test"])
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 3, 4])
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    return parser.parse_args()


def differences(reference: dict, run: dict) -> dict:
    """Whether the counts agree and the largest relative differences of ``run``'s steps from
    ``reference``'s (two summaries)."""
    ones, others = reference["steps"], run["steps"]
    scale = max(s["energy"]["kinetic"] + s["energy"]["elastic"] for s in ones)
    speed = max(abs(v) for s in ones for velocity in s["body_velocity"].values() for v in velocity)
    row = {"steps": len(others), "same_steps": len(ones) == len(others),
           "same_newton": all(a["iterations"] == b["iterations"] for a, b in zip(ones, others)),
           "same_projection": all(a["predictor"]["iterations"] == b["predictor"]["iterations"]
                                  for a, b in zip(ones, others))}
    for term in TERMS:
        row[term] = max(abs(a["energy"][term] - b["energy"][term]) / max(abs(a["energy"][term]), scale)
                        for a, b in zip(ones, others))
    row["velocity"] = max(abs(x - y) / speed for a, b in zip(ones, others) for body, velocity in
                          a["body_velocity"].items() for x, y in zip(velocity, b["body_velocity"][body]))
    return row


def run_case(name: str, ranks: list[int], work: pathlib.Path) -> list[dict]:
    """The rows of one case: each N of ``ranks`` against the first."""
    case = case_variant(work, name, None, lu=True)
    summaries, rows = {}, []
    for n in ranks:
        out = work / f"{name}_np{n}"
        code, seconds = mpirun(n, [sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(out),
                                   "--no-plot"], out.with_suffix(".log"))
        summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else None
        row = {"case": name, "ranks": n, "exit_code": code, "seconds": round(seconds, 1)}
        if code == 0 and summary is not None:
            summaries[n] = summary
            row["newton"] = sum(s["iterations"] for s in summary["steps"])
            row["projection"] = sum(s["predictor"]["iterations"] for s in summary["steps"])
            if n != ranks[0] and ranks[0] in summaries:
                row |= differences(summaries[ranks[0]], summary)
        rows.append(row)
    return rows


def markdown(data: dict) -> str:
    lines = ["# The same dynamic history on any number of ranks (issue 44)", "",
             f"`benchmarks/dynamics_ranks.py`, commit {data['commit']}: each shipped dynamic case with "
             "`pc = \"lu\"`, run as a user runs it under `mpirun -n N`, against 1 rank. Largest difference over "
             "the time steps relative to the term's scale (the largest kinetic + elastic energy; the largest "
             "speed for the bodies' mean velocities). The issue's bound: 1e-9.", "",
             "| case | ranks | Newton (step + projection) | counts equal | kinetic | elastic | contact work | "
             "friction dissipation | external work | velocity | s |", "|" + "---|" * 11]
    for r in data["rows"]:
        if "newton" not in r:
            lines.append(f"| {r['case']} | {r['ranks']} | failed (exit {r['exit_code']}) | | | | | | | | "
                         f"{r['seconds']} |")
            continue
        same = "reference" if "kinetic" not in r else ("yes" if r["same_newton"] and r["same_steps"] else "no") + (
            "" if r.get("same_projection", True) else " (projections: no)")
        values = " | ".join(f"{r[t]:.1e}" if t in r else "" for t in (*TERMS, "velocity"))
        lines.append(f"| {r['case']} | {r['ranks']} | {r['newton']} + {r['projection']} | {same} | {values} | "
                     f"{r['seconds']} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    args = parse()
    work = pathlib.Path(tempfile.mkdtemp(prefix="contactqvi-dynamics-ranks-"))
    try:
        rows = [row for name in args.cases for row in run_case(name, args.ranks, work)]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    data = {"commit": checkout_commit(), "machine": machine(MPI.COMM_SELF), "rows": rows}
    write_table(MPI.COMM_SELF, pathlib.Path(args.output) / "dynamics_ranks", data, markdown(data))


if __name__ == "__main__":
    main()
