"""Kill and restart at size (issue 24): runs killed with SIGKILL in a load step and continued
with ``--restart`` against the uninterrupted run.

Two case files, each run as a user runs it (``python -m contactqvi run``, under
``mpirun -n RANKS``):

* the paper's body d3 with load L2 (``cases/paper_d3_L2.toml``) at ``--lev``, along a
  load path of ``--loads`` (load factors; the shipped case is one static step);
* Cattaneo-Mindlin between two bodies (``cases/cattaneo_mindlin_bodies.toml``, 15 steps,
  its medium meshes).

For each: the uninterrupted run on ``--ranks``; a run killed (SIGKILL to every rank)
about half-way through the step after the middle one and restarted on the same ranks;
and one killed there and restarted on ``--other-ranks``. Compared with the uninterrupted
run: Newton and Krylov counts per step, and the displacement of the last step (read
from the checkpoints, on the checkpoint's own mesh, so no field is gathered by the runs)
as max |u - u_ref| / max |u_ref|. Bounds (issue 24): the same counts and 1e-12 on the same
ranks, 1e-9 on the others.

Writes ``restart.json`` and ``restart.md`` (rows of cases not run are kept). Run with ``nice`` on a shared machine.
A run that fails (exits non-zero, ends before the step it is to be killed in, or writes no
``summary.json``) is a failed row (:func:`rows.failed_row`) with its status and the time used,
and the other cases go on.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from mpi4py import MPI

import numpy as np

import adios4dolfinx
from dolfinx import fem

from contactqvi import tables

from benchlib import merge_rows
from rows import failed_row

ROOT = pathlib.Path(__file__).resolve().parent.parent
MPIENV = {"OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm"} | ({"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
                                      if os.getuid() == 0 else {})


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--lev", type=int, default=8, help="level of the paper's body d3")
    parser.add_argument("--loads", type=float, nargs="+", default=[0.25, 0.5, 0.75, 1.0],
                        help="load factors of the d3/L2 load path")
    parser.add_argument("--ranks", type=int, default=2, help="ranks of the uninterrupted run and the first restart")
    parser.add_argument("--other-ranks", type=int, default=1, help="ranks of the second restart")
    parser.add_argument("--cases", nargs="+", choices=["d3_L2", "mindlin_bodies"], default=["d3_L2", "mindlin_bodies"])
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    return parser.parse_args()


def case_files(args: argparse.Namespace, work: pathlib.Path) -> dict[str, pathlib.Path]:
    """The case files run, by name (written into ``work``)."""
    paper = (ROOT / "cases" / "paper_d3_L2.toml").read_text().replace("lev = 5", f"lev = {args.lev}")
    paper = paper.replace("# No [[steps]]: one static step at full load.",
                          "\n".join(f"[[steps]]\nload = {load}" for load in args.loads))
    mindlin = (ROOT / "cases" / "cattaneo_mindlin_bodies.toml").read_text()
    mindlin = mindlin.replace('file = "../meshes/', f'file = "{ROOT / "meshes"}/')
    files = {f"d3_L2 lev {args.lev}": paper, "mindlin_bodies medium": mindlin}
    paths = {}
    for name, text in files.items():
        if name.split()[0] in args.cases:
            paths[name] = work / (name.replace(" ", "_") + ".toml")
            paths[name].write_text(text)
    return paths


def command(case: pathlib.Path, out: pathlib.Path, ranks: int, *options: str) -> list[str]:
    return ["mpirun", "-n", str(ranks), sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(out),
            "--no-plot", *options]


class RunFailed(RuntimeError):
    """A run that did not give what the comparison reads: ``status`` says why, ``seconds`` the wall time it used."""

    def __init__(self, status: str, seconds: float):
        super().__init__(status)
        self.status, self.seconds = status, seconds


def run(argv: list[str], out: pathlib.Path) -> float:
    """Run to the end, writing ``out/summary.json``; its wall seconds (:class:`RunFailed` if it
    exits non-zero or writes no summary, its stderr's end printed)."""
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, env=os.environ | MPIENV)
    seconds = time.perf_counter() - start
    if done.returncode != 0 or not (out / "summary.json").is_file():
        print(f"{' '.join(argv)} failed ({done.returncode}):\n{done.stderr[-3000:]}", file=sys.stderr, flush=True)
        raise RunFailed(f"failed: exit {done.returncode}" + ("" if done.returncode else ", no summary.json"), seconds)
    return seconds


def kill_in_step(case: pathlib.Path, out: pathlib.Path, ranks: int, step: int, seconds: float) -> float:
    """Start a run, SIGKILL every rank ``seconds`` after the checkpoint of step ``step - 1``;
    returns its wall seconds."""
    start = time.perf_counter()
    process = subprocess.Popen(command(case, out, ranks), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               env=os.environ | MPIENV)
    marker = out / "checkpoint" / "checkpoint.json"
    while not (marker.exists() and json.loads(marker.read_text())["step"] >= step - 1):
        if process.poll() is not None:
            raise RunFailed(f"failed: exit {process.returncode} before step {step}", time.perf_counter() - start)
        time.sleep(0.1)
    time.sleep(seconds)
    subprocess.run(["pkill", "-KILL", "-f", str(out)])  # the ranks and mpirun: their command lines name it
    process.wait()
    if json.loads(marker.read_text())["step"] != step - 1:
        raise RunFailed(f"failed: killed after step {step} was complete (lower the delay)", time.perf_counter() - start)
    return time.perf_counter() - start


def counts(out: pathlib.Path) -> list[tuple[int, int]]:
    summary = json.loads((out / "summary.json").read_text())
    return [(s["iterations"], s["inner_iterations"]) for s in summary["steps"]]


def last_displacement(out: pathlib.Path) -> np.ndarray:
    """The last checkpoint's displacement on the checkpoint's mesh (input node order)."""
    directory = out / "checkpoint"
    marker = json.loads((directory / "checkpoint.json").read_text())
    msh = adios4dolfinx.read_mesh(directory / "mesh.bp", MPI.COMM_SELF, engine="BP4")
    u = fem.Function(fem.functionspace(msh, ("Lagrange", 1, (3,))))
    adios4dolfinx.read_function(directory / marker["file"], u, engine="BP4", time=float(marker["step"]),
                                name="displacement")
    return u.x.array.copy()


def compare(case: str, path: pathlib.Path, work: pathlib.Path, args: argparse.Namespace, commit: str | None) -> list[dict]:
    """The rows of ``case``, one per restart; a failed run is a failed row (both, if the uninterrupted run failed)."""
    reference = work / f"{path.stem}_whole"
    try:
        wall = run(command(path, reference, args.ranks), reference)
    except RunFailed as exc:
        return [failed_row(f"{exc.status} (uninterrupted run)", exc.seconds, case=case, ranks=args.ranks,
                           restart_ranks=ranks, commit=commit) for ranks in (args.ranks, args.other_ranks)]
    steps = json.loads((reference / "summary.json").read_text())["steps"]
    middle = len(steps) // 2 + 1
    delay = 0.5 * sum(steps[middle - 1]["timings"].values())  # half of that step's solve
    u_ref, ref_counts = last_displacement(reference), counts(reference)
    rows = []
    for ranks in (args.ranks, args.other_ranks):
        out = work / f"{path.stem}_restart_{ranks}"
        start = time.perf_counter()
        try:
            killed = kill_in_step(path, out, args.ranks, middle, delay)
            restarted = run(command(path, out, ranks, "--restart"), out)
        except RunFailed as exc:
            rows.append(failed_row(exc.status, time.perf_counter() - start, case=case, ranks=args.ranks,
                                   restart_ranks=ranks, steps=len(steps), killed_in_step=middle, commit=commit))
            print(rows[-1], flush=True)
            continue
        ours = counts(out)
        u = last_displacement(out)
        rows.append({
            "case": case, "ranks": args.ranks, "restart_ranks": ranks, "steps": len(steps), "killed_in_step": middle,
            "counts_equal": ours == ref_counts,
            "d_newton": max(abs(a[0] - b[0]) for a, b in zip(ours, ref_counts)),
            "rel_diff": float(np.abs(u - u_ref).max() / np.abs(u_ref).max()),
            "wall_whole": round(wall, 1), "wall_killed": round(killed, 1), "wall_restart": round(restarted, 1),
            "status": json.loads((out / "summary.json").read_text())["status"], "commit": commit,
        })
        print(rows[-1], flush=True)
    return rows


def markdown(rows: list[dict], commit: str | None) -> str:
    header = ["case", "ranks", "restarted on", "steps", "killed in step", "status", "counts equal", "dNewton",
              "rel. diff", "bound", "wall whole s", "wall killed + restart s", "commit"]
    body = [[r["case"], r["ranks"], r["restart_ranks"], r.get("steps"), r.get("killed_in_step"), r["status"],
             {True: "yes", False: "no"}.get(r.get("counts_equal")), r.get("d_newton"), r.get("rel_diff"),
             "1e-12" if r["restart_ranks"] == r["ranks"] else "1e-9", r.get("wall_whole"),
             f"{r['wall_killed']} + {r['wall_restart']}" if "wall_killed" in r else f"failed after {r['seconds']:.0f}",
             r.get("commit")] for r in rows]  # a failed row (rows.failed_row) has no measured fields
    return (f"## Kill and restart (issue 24), last run at {commit}\n\n{__doc__.split(chr(10) + chr(10), 1)[1].split('Writes')[0]}"
            + tables.markdown_table(header, body) + "\n\nWall times on a 2-core machine shared with other jobs.\n")


def main() -> None:
    args = parse()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip() or None
    rows = []
    with tempfile.TemporaryDirectory(prefix="contactqvi-restart-") as tmp:
        for case, path in case_files(args, pathlib.Path(tmp)).items():
            rows += compare(case, path, pathlib.Path(tmp), args, commit)
    out = pathlib.Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    rows = merge_rows(out / "restart.json", rows, ("case", "restart_ranks"))
    tables.write_table(MPI.COMM_SELF, out / "restart", {"commit": commit, "rows": rows}, markdown(rows, commit))


if __name__ == "__main__":
    main()
