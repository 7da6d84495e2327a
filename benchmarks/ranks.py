"""The same answer on any number of ranks: the rank table and the per-rank peak memory (issue 24).

Runs the programs a user runs, under ``mpirun -n N`` (oversubscribed where N is
above the number of cores), each with its output directory, and compares them
with the run on 1 rank:

* ``demos/coulomb3d.py --lev L --geometry d1 --load L1`` (default solver: GAMG,
  tol 0.1) for each ``--levels``;
* ``python -m contactqvi run cases/hertz.toml`` on ``meshes/hertz_coarse.geo``
  (a sphere, four load steps), with its default solver and with exact
  Newton-step solves (``pc = "lu"``);
* several bodies (``--bodies``): ``cases/vice.toml`` as shipped (three bodies, two
  Coulomb joints, two load steps) and ``cases/hertz_bodies.toml`` on
  ``meshes/hertz_bodies_coarse.geo`` (ball on block, four load steps), each with its
  default solver and with ``pc = "lu"``.

Per run: Newton and Krylov iterations (summed over load steps), the largest
difference of Newton steps in a load step from 1 rank, the relative difference of
the solution (``solution.npz``, max |u_N - u_1| / max |u_1|; nodes of two bodies at the same
point, whose order in the file depends on the partition, matched among themselves), whether every output
file was written, how many ranks wrote a block of ``contact_surface.bp`` (the
others own no contact facet) and, for several bodies, how many ranks own cells of
each body (the blocks of ``body.bp``; the others own none of its cells).

``--memory-lev 10``: each rank's peak resident memory (VmHWM of
/proc/self/status) after the demo at that level, d1/L1, on 2 ranks, output
included. Run by ``mpirun -n 2 python benchmarks/ranks.py --worker memory ...``.

Writes ``ranks.json`` and ``ranks.md``; a part not run keeps its old numbers (rows are
replaced by case and number of ranks, each row records the commit it was measured
at). Only the several-body rows, for example::

    nice python benchmarks/ranks.py --levels --no-hertz --bodies vice hertz_bodies

Run with ``nice`` on a shared machine: it starts up to 8 ranks.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from rows import read_table

ROOT = pathlib.Path(__file__).resolve().parent.parent
PYTHON = sys.executable
MPIENV = {"OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm"}
if os.getuid() == 0:
    MPIENV |= {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--ranks", type=int, nargs="*", default=[1, 2, 3, 4, 8], help="numbers of ranks (1 first)")
    parser.add_argument("--levels", type=int, nargs="*", default=[5, 6], help="levels of the demo")
    parser.add_argument("--no-hertz", action="store_true", help="skip cases/hertz.toml")
    parser.add_argument("--bodies", nargs="*", choices=sorted(BODY_CASES), default=sorted(BODY_CASES),
                        help="several-body case files to run (none: skip them)")
    parser.add_argument("--memory-lev", type=int, default=None, help="level of the 2-rank memory run (e.g. 10)")
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    parser.add_argument("--commit", default=checkout_commit(), help="the code's commit, recorded with the numbers")
    parser.add_argument("--worker", choices=["memory"], help=argparse.SUPPRESS)
    parser.add_argument("--worker-output", help=argparse.SUPPRESS)
    return parser.parse_args()


def checkout_commit() -> str | None:
    """The checkout's commit (None outside a git checkout, e.g. a `git archive` copy)."""
    done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    return done.stdout.strip() or None


def mpirun(n: int, argv: list[str], log: pathlib.Path) -> tuple[int, float]:
    """Run ``argv`` on ``n`` ranks; exit code and wall seconds."""
    t0 = time.perf_counter()
    with log.open("w") as fh:
        code = subprocess.call(["mpirun", "-n", str(n), *argv], cwd=ROOT, env=os.environ | MPIENV,
                               stdout=fh, stderr=subprocess.STDOUT)
    return code, time.perf_counter() - t0


#: Several-body case files (``cases/<name>.toml``) -> the mesh they run on here: the
#: coarsest mesh file the case lists, as tests/test_shipped_cases.py's COARSE (None: as shipped).
BODY_CASES: dict[str, str | None] = {"vice": None, "hertz_bodies": "hertz_bodies_coarse.geo"}


def case_variant(directory: pathlib.Path, name: str, mesh: str | None, lu: bool) -> pathlib.Path:
    """``cases/<name>.toml`` written to ``directory`` with its mesh file as an absolute path
    (``meshes/<mesh>`` if given, else the case's own), and with ``pc = "lu"`` if ``lu``."""
    source = ROOT / "cases" / f"{name}.toml"
    text = source.read_text()
    pattern = re.compile(r'^file = "([^"]+)"$', re.MULTILINE)
    (found,) = pattern.findall(text)  # the [mesh] table's file, relative to the case file
    path = ROOT / "meshes" / mesh if mesh else (source.parent / found).resolve()
    assert path.is_file(), f"{source}: mesh file {path} not found"
    text = pattern.sub(f'file = "{path}"', text)
    if lu and "\n[solver]\n" in text:
        text = text.replace("\n[solver]\n", '\n[solver]\npc = "lu"\n')
    elif lu:
        text += '\n[solver]\npc = "lu"\n'
    case = directory / f"{name}{'_' + pathlib.Path(mesh).stem if mesh else ''}{'_lu' if lu else ''}.toml"
    case.write_text(text)
    return case


def programs(args: argparse.Namespace, work: pathlib.Path) -> dict[str, tuple[list[str], list[str]]]:
    """Case name -> (command after ``python``, the files it must write)."""
    demo_files = ["body.bp", "contact_surface.bp", "solution.npz", "contact_states.png", "summary.json"]
    case_files = ["body.bp", "contact_surface.bp", "solution.npz", "contact_states.png", "summary.json"]
    runs = {f"demo lev {lev} d1/L1": (["demos/coulomb3d.py", "--lev", str(lev), "--geometry", "d1", "--load", "L1"],
                                      demo_files) for lev in args.levels}
    if not args.no_hertz:
        for lu, label in ((False, "hertz coarse"), (True, "hertz coarse, pc lu")):
            runs[label] = (["-m", "contactqvi", "run", str(case_variant(work, "hertz", "hertz_coarse.geo", lu))],
                           case_files)
    for name in args.bodies:
        mesh = BODY_CASES[name]
        for lu in (False, True):
            label = f"{name}{' coarse' if mesh else ''}{', pc lu' if lu else ''}"
            runs[label] = (["-m", "contactqvi", "run", str(case_variant(work, name, mesh, lu))],
                           [*case_files, "bodies.png"])
    return runs


def surface_blocks(path: pathlib.Path) -> int:
    """Ranks that wrote a block of the last step of ``contact_surface.bp``."""
    import adios2

    with adios2.FileReader(str(path)) as reader:
        return len(reader.all_blocks_info("geometry")[reader.num_steps() - 1])


def body_ranks(path: pathlib.Path) -> list[int]:
    """Per body (``body`` cell field of the last step of ``body.bp``), how many ranks own
    cells of it: each rank writes its owned cells as one block."""
    import adios2

    with adios2.FileReader(str(path)) as reader:
        step = reader.num_steps() - 1
        blocks = [np.unique(reader.read("body [1]", block_id=int(info["BlockID"]), step_selection=[step, 1]))
                  for info in reader.all_blocks_info("body [1]")[step]]
    bodies = np.unique(np.concatenate(blocks)) if blocks else []
    return [sum(int(b in block) for block in blocks) for b in bodies]


def record(out: pathlib.Path, files: list[str]) -> dict:
    """Counts, files written and the ranks owning contact facets (and bodies) of the run in ``out``."""
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else {}
    steps = summary.get("steps") or [summary]  # a case file has steps, the demo one solve
    several = "bodies.png" in files and (out / "body.bp").is_dir()
    return {
        "status": summary.get("status"),
        "newton_steps": [s.get("iterations") for s in steps],
        "newton": sum(s.get("iterations") or 0 for s in steps),
        "krylov": sum(s.get("inner_iterations") or 0 for s in steps),
        "written": all((out / f).exists() for f in files),
        "missing": [f for f in files if not (out / f).exists()],
        "surface_blocks": surface_blocks(out / "contact_surface.bp") if (out / "contact_surface.bp").is_dir() else 0,
        **({"body_ranks": body_ranks(out / "body.bp")} if several else {}),
    }


def relative_difference(x_ref: np.ndarray, u_ref: np.ndarray, x: np.ndarray, u: np.ndarray) -> float:
    """max |u - u_ref| / max |u_ref| of two ``solution.npz`` (rows sorted by coordinate).

    Nodes at the same point (two bodies that touch there, a node of each) tie in that
    sort, so their order in the file depends on the partition: within each such group
    the nodes are matched by the permutation that fits best (the coordinates cannot
    tell them apart).
    """
    scale = np.abs(x_ref).max()
    assert x.shape == x_ref.shape and np.abs(x - x_ref).max() <= 1e-9 * scale, "different nodes"
    difference = np.abs(u - u_ref).reshape(len(u), -1).max(axis=1)
    keys = np.round(x_ref / scale, 10)  # as contactqvi.tables.gather_vertex_values sorts them
    _, group, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    for g in np.flatnonzero(counts > 1):
        nodes = np.flatnonzero(group.ravel() == g)
        assert len(nodes) <= 6, f"{len(nodes)} nodes at one point"
        difference[nodes] = min((np.abs(u[list(perm)] - u_ref[nodes]).reshape(len(nodes), -1).max(axis=1)
                                 for perm in itertools.permutations(nodes)), key=np.max)
    return float(difference.max() / np.abs(u_ref).max())


def rank_table(args: argparse.Namespace, work: pathlib.Path) -> list[dict]:
    """One row per program and number of ranks, compared with its run on 1 rank."""
    rows = []
    for case, (command, files) in programs(args, work).items():
        reference = None
        for n in args.ranks:
            out = work / f"{case.replace(' ', '_').replace('/', '').replace(',', '')}_np{n}"
            code, seconds = mpirun(n, ["nice", PYTHON, *command, "--output", str(out)], out.with_suffix(".log"))
            row = {"case": case, "ranks": n, "exit_code": code, "seconds": round(seconds, 1), **record(out, files),
                   "commit": args.commit}
            if (out / "solution.npz").is_file():
                solution = np.load(out / "solution.npz")
                x, u = solution["x"], solution["u"]
                if reference is None:
                    reference = row | {"x": x, "u": u}
                else:
                    row["relative_difference"] = relative_difference(reference["x"], reference["u"], x, u)
                    row["max_newton_difference"] = int(np.abs(np.subtract(row["newton_steps"],
                                                                           reference["newton_steps"])).max())
            print(json.dumps(row), flush=True)
            if code != 0:
                print(out.with_suffix(".log").read_text()[-3000:], file=sys.stderr, flush=True)
            rows.append(row)
    return rows


def in_case_order(rows: list[dict], cases: list[str]) -> list[dict]:
    """``rows`` sorted by case (in the order of ``cases``, others last) and number of ranks."""
    order = list(dict.fromkeys([*cases, *(r["case"] for r in rows)]))
    return sorted(rows, key=lambda r: (order.index(r["case"]), r["ranks"]))


def memory_worker(lev: int, output: str) -> None:
    """In ``mpirun -n 2``: the demo at ``lev`` d1/L1 with its output, then each rank's VmHWM (MiB)."""
    import importlib.util

    from mpi4py import MPI

    spec = importlib.util.spec_from_file_location("coulomb3d_demo", ROOT / "demos" / "coulomb3d.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    code = demo.main(["--lev", str(lev), "--geometry", "d1", "--load", "L1", "--output", output])
    status = pathlib.Path("/proc/self/status").read_text().split("\n")
    hwm_mib = next(int(line.split()[1]) for line in status if line.startswith("VmHWM:")) / 1024
    comm = MPI.COMM_WORLD
    peaks = comm.allgather(hwm_mib)
    if comm.rank == 0:
        summary = json.loads((pathlib.Path(output) / "summary.json").read_text())
        result = {"lev": lev, "case": "d1/L1", "ranks": comm.size, "exit_code": code, "vmhwm_mib": peaks,
                  "newton": summary["iterations"], "krylov": summary["inner_iterations"], "n": summary["n"],
                  "files": summary.get("files", [])}
        (pathlib.Path(output) / "memory.json").write_text(json.dumps(result))


def memory(lev: int, work: pathlib.Path) -> dict:
    out = work / f"memory_lev{lev}"
    code, seconds = mpirun(2, ["nice", PYTHON, __file__, "--worker", "memory", "--memory-lev", str(lev),
                               "--worker-output", str(out)], work / f"memory_lev{lev}.log")
    result = json.loads((out / "memory.json").read_text()) if (out / "memory.json").is_file() else {"exit_code": code}
    peaks = result.get("vmhwm_mib", [])
    if len(peaks) == 2:
        result["rank0_over_rank1"] = peaks[0] / peaks[1]
    result["seconds"] = round(seconds, 1)
    return result


def _within(row: dict) -> bool:
    """Issue 24's bounds: Newton steps per load step within 1 of 1 rank, solution to 1e-9, files written."""
    return ((row.get("max_newton_difference") or 0) <= 1 and (row.get("relative_difference") or 0) <= 1e-9
            and row["written"] and row["exit_code"] == 0)


def _outside_the_bounds(rows: list[dict]) -> str:
    """The runs outside issue 24's bounds, and whether the exact-solve controls are within them."""
    outside = [f"{r['case']} on {r['ranks']} ranks (dNewton {r.get('max_newton_difference')}, rel. diff "
               f"{r.get('relative_difference', 0):.2g}{'' if r['written'] else ', files missing'})"
               for r in rows if r["ranks"] > 1 and not _within(r)]
    if not outside:
        return "\nEvery run is within the bounds (Newton steps within 1 of 1 rank, solution to 1e-9, files written).\n"
    controls = list(dict.fromkeys(r["case"] for r in rows if r["case"].endswith(", pc lu")))
    exact = [case for case in controls if all(_within(r) for r in rows if r["case"] == case)]
    return ("\nOutside the bounds (Newton steps within 1 of 1 rank, solution to 1e-9, files written): "
            + "; ".join(outside) + ". The inexact Newton-step solves (GAMG, tol 0.1) depend on the partition "
            "through the multigrid aggregates, so each rank count takes its own path of "
            "Newton iterates; a solution meeting the Newton stopping test is only as close to the exact one as "
            "those solves allow. The controls with exact solves"
            + (f" within the bounds on every number of ranks: {'; '.join(exact)}" if exact else ": none within the bounds")
            + (f"; outside: {'; '.join(c for c in controls if c not in exact)}" if len(exact) < len(controls) else "")
            + ".\n")


def markdown(data: dict) -> str:
    from contactqvi.tables import markdown_table

    text = ["## The same answer on any number of ranks (issue 24)\n\n",
            "Each program as a user runs it, under `mpirun -n N` on this machine's "
            f"{data['machine']['cores']} cores (oversubscribed above), against its run on 1 rank "
            "(benchmarks/ranks.py): the demo at lev 5 and 6 (d1/L1); cases/hertz.toml on its coarse "
            "mesh (a rigid sphere, four load steps); several bodies: cases/vice.toml as shipped (three "
            "bodies, two Coulomb joints, two load steps) and cases/hertz_bodies.toml on its coarse mesh "
            "(ball on block, four load steps), full load paths. Each case also with exact Newton-step "
            "solves (`pc = \"lu\"`, MUMPS) as the control. Newton / Krylov: summed over the load steps; "
            "dNewton: largest difference in a step's Newton count from 1 rank; rel. diff: "
            "max |u_N - u_1| / max |u_1| of `solution.npz` (two bodies touching at a node have a node each at that "
            "point, and the file's order of the two depends on the partition: they are matched among themselves); "
            "written: every output file (body.bp, "
            "contact_surface.bp, solution.npz, contact_states.png, summary.json; bodies.png for several "
            "bodies); surface ranks: ranks that own contact facets (the others write no block of "
            "contact_surface.bp); body ranks: per body (in the case file's order), the ranks that own "
            "cells of it (the others own none); commit: the code measured; wall s: on a machine shared "
            "with other jobs.\n\n"]
    rows = [[r["case"], r["ranks"], r["status"], r["newton"], r["krylov"], r.get("max_newton_difference"),
             r.get("relative_difference"), "yes" if r["written"] and r["exit_code"] == 0 else "no",
             r["surface_blocks"], "/".join(map(str, r["body_ranks"])) if r.get("body_ranks") else None,
             r.get("commit", data.get("rows_commit")), r["seconds"]] for r in data.get("rows", [])]
    text.append(markdown_table(["case", "ranks", "status", "Newton", "Krylov", "dNewton", "rel. diff", "written",
                                "surface ranks", "body ranks", "commit", "wall s"], rows))
    text.append(_outside_the_bounds(data.get("rows", [])))
    mem = data.get("memory")
    if mem and mem.get("vmhwm_mib"):
        peaks = mem["vmhwm_mib"]
        text.append(f"\n## Peak memory per rank, lev {mem['lev']} d1/L1 on {mem['ranks']} ranks, at {mem['commit']}\n\n"
                    f"VmHWM of /proc/self/status after the demo with its output ({', '.join(mem['files'])}; "
                    f"solution.npz is not gathered above {data.get('gather_max_nodes')} nodes), n = {mem['n']} "
                    f"free dofs, {mem['newton']} Newton / {mem['krylov']} Krylov, {mem['seconds']} s wall.\n\n")
        text.append(markdown_table(["rank", "peak MiB"], [[i, round(p)] for i, p in enumerate(peaks)]))
        text.append(f"\nRank 0 / rank 1: {mem['rank0_over_rank1']:.3f}.\n")
    return "".join(text)


def main() -> None:
    args = parse()
    if args.worker == "memory":
        memory_worker(args.memory_lev, args.worker_output)
        return
    assert args.ranks and args.ranks[0] == 1, "--ranks must start with 1 (the reference)"
    out = pathlib.Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "ranks.json"
    data = read_table(path)
    work = pathlib.Path(tempfile.mkdtemp(prefix="contactqvi-ranks-"))
    try:
        if args.levels or not args.no_hertz or args.bodies:
            from benchlib import merge_rows

            old_cases = [r["case"] for r in data.get("rows", [])]
            rows = merge_rows(path, rank_table(args, work), ("case", "ranks"))  # a part not run keeps its rows
            for row in rows:  # rows measured before each row recorded its commit
                row.setdefault("commit", data.get("rows_commit"))
            data["rows"] = in_case_order(rows, old_cases)
            data.pop("rows_commit", None)
        if args.memory_lev is not None:
            data["memory"] = memory(args.memory_lev, work) | {"commit": args.commit}
    finally:
        shutil.rmtree(work, ignore_errors=True)

    from mpi4py import MPI

    from benchlib import machine
    from contactqvi.tables import GATHER_MAX_NODES, write_table

    data["machine"] = machine(MPI.COMM_SELF)
    data["gather_max_nodes"] = GATHER_MAX_NODES
    write_table(MPI.COMM_SELF, out / "ranks", data, markdown(data))


if __name__ == "__main__":
    main()
