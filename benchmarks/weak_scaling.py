"""Weak scaling of the flagship Coulomb solve (seed 000): messages, reductions and memory per Newton step.

The demo's solve (``demos/coulomb3d.py``: :func:`benchlib.run_coulomb_case`, i.e.
``solve_level`` with the default solver, GAMG and tol 0.1, from u0 = 0) on 1, 2,
4 and 8 ranks at about the same number of free dofs per rank: the 1-rank run is
at ``--lev``, and each other number of ranks N runs the level whose n / N is
closest (in ratio) to the 1-rank level's n; the levels grow by about 2.7x, so the
dofs per rank can only match to that step (the table gives the ratio).

Each run is ``mpirun -n N python benchmarks/weak_scaling.py --worker ...`` with
``-log_view :log_view.txt`` (the option a user passes to the demo). The worker puts
every ``SCDNewtonSolver.solve`` into a PETSc log stage "Newton solve" (the Newton
steps: gamma, approximation steps, Newton matrices, multigrid set-ups and updates,
Krylov solves, line search; not the mesh, assembly or output; the solver's own phases
are stages inside it, so -log_view splits the solve by phase), and reads PETSc's
per-rank message counters at the stage's ends (the counters -log_view sums:
messages = (sent + received) / 2, bytes likewise, reductions = allreduces + gathers
+ scatters), so that the busiest rank is seen as well as the average. Only MPI calls
made by PETSc are counted: DOLFINx's scatters and the solver's few mpi4py
reductions (``contactqvi/contact/scd_newton.py``) are not. From ``log_view.txt`` it
parses the summary lines "Time (sec)", "Flops", "MPI Msg Count", "MPI Msg Len
(bytes)", "MPI Reductions" (whole run) and the stages' lines (and checks the
totals of the stages inside the solve against the counters). Memory: each rank's
peak resident set (getrusage; -log_view of PETSc 3.22 prints no memory line). Also recorded: the multigrid
hierarchy (levels and rows per level, at the last set-up) and each rank's number
of neighbours (ranks owning a ghost of its displacement dofs) and of owned and ghost dofs.

The markdown ends with a projection to 64, 512 and 4096 ranks at the same dofs
per rank (:func:`projection`): the measured rates per neighbour and per ghost dof
and the reductions in proportion to the multigrid levels, scaled by a model of a
3D partition, with the network constants
of :data:`ASSUMED` (assumptions, not measurements; docs/cluster.md discusses them).

With more ranks than cores (here 2) the ranks share cores: wall times of 4 and 8
ranks say nothing about scaling; message counts and volumes, reductions, flops
and memory do.

    nice python benchmarks/weak_scaling.py --lev 7

Writes ``weak_scaling.json`` and ``weak_scaling.md`` to ``--output`` (rows replaced
by case and number of ranks; a part not run keeps its old numbers; each row
records the commit measured).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import pathlib
import re
import resource
import sys
import tempfile
import time
import typing

import numpy as np

from ranks import PYTHON, ROOT, checkout_commit, mpirun
from rows import failed, failed_row, read_table

#: PETSc's global per-process counters behind -log_view's "MPI Msg Count", "MPI Msg Len" and "MPI Reductions".
COUNTERS = ("petsc_send_ct", "petsc_isend_ct", "petsc_recv_ct", "petsc_irecv_ct", "petsc_send_len",
            "petsc_isend_len", "petsc_recv_len", "petsc_irecv_len", "petsc_allreduce_ct", "petsc_gather_ct",
            "petsc_scatter_ct")

STAGE = "Newton solve"

#: The projection's assumptions (not measured here): ranks to project to; the most
#: neighbours of a rank (a compact subdomain of a 3D partition touches its 26 face,
#: edge and vertex neighbours); point-to-point latency (s) and per-rank bandwidth
#: (bytes/s: a node's injection bandwidth shared by its ranks, InfiniBand class);
#: latency (s) per tree level of an allreduce (log2 P levels); ghost dofs of an interior
#: subdomain over those of the largest measured run's busiest rank at the same dofs per
#: rank (an interior subdomain shares all six faces with others, a subdomain of a 2 x 2 x 2
#: split of the box three).
ASSUMED = {"ranks": (64, 512, 4096), "max_neighbours": 26, "latency_s": 2e-6, "bandwidth_bytes_per_s": 1e9,
           "allreduce_level_s": 2e-6, "interior_ghost_factor": 2.0}


def parse() -> tuple[argparse.Namespace, list[str]]:
    """The options, and the ``-options`` left for PETSc (the worker's ``-log_view``)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--lev", type=int, default=7, help="level of the 1-rank run (sets the dofs per rank)")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 4, 8], help="numbers of ranks (1 first)")
    parser.add_argument("--case", default="d3/L2", help="geometry/load of seed 000")
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    parser.add_argument("--commit", default=checkout_commit(), help="the code's commit, recorded with the numbers")
    parser.add_argument("--tables-only", action="store_true",
                        help="rewrite the markdown and the projection from the JSON file, without running")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--run-dir", help=argparse.SUPPRESS)
    args, petsc = parser.parse_known_args()
    if petsc and (not args.worker or not petsc[0].startswith("-")):
        parser.error(f"unrecognized arguments: {' '.join(petsc)}")
    return args, petsc


# -- level choice ------------------------------------------------------------------------------------
def free_dofs(lev: int) -> int:
    """Free dofs n of the paper's body at ``lev`` (without meshing it)."""
    from contactqvi.meshes import contact_body_sizes

    return contact_body_sizes(lev)["n"]


def weak_levels(base_lev: int, ranks: list[int]) -> dict[int, int]:
    """Number of ranks -> the level whose dofs per rank are closest in ratio to ``base_lev``'s on 1 rank."""
    target = free_dofs(base_lev)
    return {n: min(range(base_lev, base_lev + 2 * math.ceil(math.log2(n)) + 2),
                   key=lambda lev: abs(math.log(free_dofs(lev) / n / target))) for n in ranks}


# -- PETSc's counters and -log_view --------------------------------------------------------------------
class PetscCounters:
    """PETSc's global message and reduction counters of this process, read through ctypes
    from the loaded PETSc library (the numbers -log_view reports)."""

    def __init__(self) -> None:
        from petsc4py import PETSc  # noqa: F401  (loads the library)

        maps = pathlib.Path("/proc/self/maps").read_text().split("\n")
        path = next(line.split()[-1] for line in maps if re.search(r"/libpetsc[^/]*\.so", line))
        self._lib = ctypes.CDLL(path)

    def read(self) -> dict[str, float]:
        """Messages and bytes ((sent + received) / 2, as -log_view), reductions and flops so far."""
        from petsc4py import PETSc

        c = {name: ctypes.c_double.in_dll(self._lib, name).value for name in COUNTERS}
        return {"messages": 0.5 * (c["petsc_send_ct"] + c["petsc_isend_ct"] + c["petsc_recv_ct"] + c["petsc_irecv_ct"]),
                "bytes": 0.5 * (c["petsc_send_len"] + c["petsc_isend_len"] + c["petsc_recv_len"]
                                + c["petsc_irecv_len"]),
                "reductions": c["petsc_allreduce_ct"] + c["petsc_gather_ct"] + c["petsc_scatter_ct"],
                "flops": PETSc.Log.getFlops()}


_NUMBER = r"([-+0-9.eE]+)"


def parse_log_view(text: str) -> dict[str, typing.Any]:
    """The summary lines of a -log_view text (Max, Max/Min, Avg, Total where printed; per rank,
    except that the Avg of "MPI Msg Len" is per message), the "Summary of Stages" lines
    (average time, flop summed over ranks, messages summed over ranks, average message length,
    reductions per rank) and each stage's events (count, largest time and flop, messages summed
    over ranks, average length, reductions)."""
    summary = {}
    for key, label in (("time_s", r"Time \(sec\):"), ("flops", r"Flops:"), ("messages", r"MPI Msg Count:"),
                       ("bytes", r"MPI Msg Len \(bytes\):"), ("reductions", r"MPI Reductions:")):
        match = re.search(rf"^{label}((?:\s+{_NUMBER})+)\s*$", text, re.MULTILINE)
        if match:
            values = [float(v) for v in match.group(1).split()]
            names = ("max", "max_over_min", "avg_per_message" if key == "bytes" else "avg", "total")
            summary[key] = dict(zip(names, values))
    stages = {}
    for match in re.finditer(rf"^\s*\d+:\s+(.+?):\s+{_NUMBER}\s+{_NUMBER}%\s+{_NUMBER}\s+{_NUMBER}%\s+{_NUMBER}\s+"
                             rf"{_NUMBER}%\s+{_NUMBER}\s+{_NUMBER}%\s+{_NUMBER}\s+{_NUMBER}%", text, re.MULTILINE):
        v = [float(x) for x in match.groups()[1:]]
        stages[match.group(1).strip()] = {"time_avg_s": v[0], "flop_total": v[2], "messages_total": v[4],
                                          "message_length_avg": v[6], "reductions": v[8]}
    events: dict[str, dict[str, dict[str, float]]] = {}
    stage_name = None
    for line in text.split("\n"):
        header = re.match(r"^--- Event Stage \d+: (.+)$", line)
        if header:
            stage_name = header.group(1).strip()
            continue
        match = re.match(rf"^([A-Za-z][\w ]*?)\s+(\d+)\s+{_NUMBER}\s+{_NUMBER}\s+{_NUMBER}\s+{_NUMBER}\s+{_NUMBER}\s+"
                         rf"{_NUMBER}\s+{_NUMBER}\s+{_NUMBER}\s", line)
        if match and stage_name:
            v = [float(x) for x in match.groups()[1:]]
            events.setdefault(stage_name, {}).setdefault(match.group(1), {
                "count": v[0], "time_max_s": v[2], "flop_max": v[4], "messages_total": v[6],
                "message_length_avg": v[7], "reductions": v[8]})
    return {"summary": summary, "stages": stages, "events": events}


# -- the worker (under mpirun) -------------------------------------------------------------------------
def worker(args: argparse.Namespace, petsc_options: list[str]) -> None:
    """Solve ``args.case`` at ``args.lev`` with the Newton solves in a log stage; write ``worker.json``.
    ``petsc_options`` (``-log_view :FILE``) go to PETSc as the demo's unknown options do."""
    from mpi4py import MPI
    from petsc4py import PETSc

    import benchlib
    from contactqvi.cli import pass_to_petsc, setup_logging
    from contactqvi.contact.scd_newton import SCDNewtonSolver
    from contactqvi.multigrid import GalerkinUpdate

    pass_to_petsc(petsc_options)
    setup_logging("WARNING")
    comm = MPI.COMM_WORLD
    stage = PETSc.Log.Stage(STAGE)
    counters = PetscCounters()
    spent = {"messages": 0.0, "bytes": 0.0, "reductions": 0.0, "flops": 0.0, "seconds": 0.0}
    seen: dict[str, typing.Any] = {}
    solve, setup = SCDNewtonSolver.solve, GalerkinUpdate.__init__

    def staged_solve(self, *a, **k):
        """SCDNewtonSolver.solve inside the stage, with this rank's counters before and after."""
        index_map, bs = self.problem.V.dofmap.index_map, self.problem.V.dofmap.index_map_bs
        seen["neighbours"] = int(np.unique(index_map.owners).size)
        seen["owned_dofs"], seen["ghost_dofs"] = index_map.size_local * bs, index_map.num_ghosts * bs
        comm.Barrier()
        start, t0 = counters.read(), time.perf_counter()
        stage.push()
        try:
            return solve(self, *a, **k)
        finally:
            stage.pop()
            end = counters.read()
            for key in ("messages", "bytes", "reductions", "flops"):
                spent[key] += end[key] - start[key]
            spent["seconds"] += time.perf_counter() - t0

    def recorded_setup(self, pc):
        """GalerkinUpdate.__init__, recording the multigrid hierarchy just set up (rows per level, coarse first)."""
        setup(self, pc)
        seen["mg_rows"] = [pc.getMGSmoother(level).getOperators()[0].getSize()[0] for level in range(pc.getMGLevels())]

    SCDNewtonSolver.solve, GalerkinUpdate.__init__ = staged_solve, recorded_setup
    row = benchlib.run_coulomb_case(comm, args.lev, args.case, {"pc": "gamg"}, "weak_")
    per_rank = comm.gather({**spent, **{key: seen.get(key, 0) for key in ("neighbours", "owned_dofs", "ghost_dofs")},
                            "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}, root=0)
    if comm.rank == 0:
        row["per_rank"] = {key: [r[key] for r in per_rank] for key in per_rank[0]}
        row["mg_rows"] = seen.get("mg_rows")
        (pathlib.Path(args.run_dir) / "worker.json").write_text(json.dumps(row))


# -- the driver ----------------------------------------------------------------------------------------
def spread(values: list[float]) -> dict[str, float]:
    """Largest, smallest and mean of per-rank values."""
    return {"max": float(np.max(values)), "min": float(np.min(values)), "mean": float(np.mean(values))}


def measure(n: int, lev: int, args: argparse.Namespace, work: pathlib.Path, target: int) -> dict:
    """One run on ``n`` ranks at ``lev``: the row of the table (per Newton step where it says so)."""
    run = work / f"np{n}_lev{lev}"
    run.mkdir()
    log_view = run / "log_view.txt"
    code, seconds = mpirun(n, ["nice", PYTHON, __file__, "--worker", "--lev", str(lev), "--case", args.case,
                               "--run-dir", str(run), "-log_view", f":{log_view}"], run / "run.log")
    row: dict[str, typing.Any] = {"case": args.case, "ranks": n, "lev": lev, "exit_code": code,
                                  "wall_s": round(seconds, 1), "commit": args.commit}
    if code != 0 or not (run / "worker.json").is_file():
        print((run / "run.log").read_text()[-3000:], file=sys.stderr, flush=True)
        return failed_row(f"failed: exit {code}" + ("" if code else ", no worker.json"), seconds, **row)
    result = json.loads((run / "worker.json").read_text())
    log = parse_log_view(log_view.read_text())
    steps = result["it"]
    per_rank = result["per_rank"]
    # The solver's phases (contactqvi.result.Timings.phase) are log stages of their own, pushed
    # inside the Newton solve's stage: the solve is every stage but the main one.
    inside = [v for name, v in log["stages"].items() if name != "Main Stage"]
    row |= {
        "n": result["n"], "p": result["p"], "dofs_per_rank": result["n"] / n, "dofs_per_rank_ratio": result["n"] / n / target,
        "status": result["status"], "newton": steps, "krylov": result["krylov"],
        "solve_s": result["solve_seconds"], "assembly_s": result["timings"]["assembly"],
        "mg_rows": result["mg_rows"], "neighbours": spread(per_rank["neighbours"]),
        "owned_dofs": spread(per_rank["owned_dofs"]), "ghost_dofs": spread(per_rank["ghost_dofs"]),
        "peak_rss_mib": spread(per_rank["peak_rss_mib"]),
        "per_newton_step": {key: spread(np.asarray(per_rank[key]) / steps)
                            for key in ("messages", "bytes", "reductions", "flops", "seconds")},
        "log_view": log,
        # the stage's totals in -log_view against the counters read here (the same numbers, summed)
        "stage_matches_counters": bool(inside)
                                  and math.isclose(sum(v["messages_total"] for v in inside), sum(per_rank["messages"]),
                                                   rel_tol=1e-3, abs_tol=1.0)
                                  and math.isclose(sum(v["reductions"] for v in inside), np.mean(per_rank["reductions"]),
                                                   rel_tol=1e-3, abs_tol=1.0),
    }
    return row


def projection(rows: list[dict]) -> dict[str, typing.Any]:
    """Per Newton step at 64, 512, 4096 ranks and the 1-rank run's dofs per rank, from the measured
    rows (the rates below) and :data:`ASSUMED`.

    * messages per rank = (largest measured messages per neighbour) x min(P - 1, max_neighbours);
    * ghost dofs = interior_ghost_factor x the largest run's most ghosts, scaled by (dofs per rank)^(2/3);
    * bytes per rank = (largest measured bytes per ghost dof) x ghost dofs;
    * multigrid levels: the largest run's, plus log(n_P / n) / log(its mean coarsening ratio);
    * reductions = the largest run's Krylov reductions (VecMDot, VecNorm: Krylov iterations per Newton
      step as measured, GAMG's counts do not grow with n here) + its other reductions (the GAMG
      set-up, the Galerkin updates, assembly, residuals, line search) x levels / its levels;
    * memory per rank = a + b x (owned + ghost dofs), fitted to the multi-rank runs (means over ranks);
    * compute seconds = flop per dof of the largest run x dofs per rank / the 1-rank run's flop rate;
      communication seconds = messages x latency + bytes / bandwidth + reductions x log2(P) x allreduce level.
    """
    measured = [r for r in rows if "per_newton_step" in r]
    serial = next((r for r in measured if r["ranks"] == 1), None)
    parallel = [r for r in measured if r["ranks"] > 1 and r.get("ghost_dofs")]
    if not parallel or serial is None:  # a failed run is a row, not a measurement
        return {}
    ref = max(parallel, key=lambda r: r["ranks"])
    steps = ref["newton"]
    dofs = serial["n"]
    per_neighbour = max(r["per_newton_step"]["messages"]["max"] / r["neighbours"]["max"] for r in parallel)
    per_ghost = max(r["per_newton_step"]["bytes"]["max"] / r["ghost_dofs"]["max"] for r in parallel)
    mg = ref["mg_rows"]
    coarsening = (mg[-1] / mg[1]) ** (1 / (len(mg) - 2))
    events = ref["log_view"]["events"].get("linear_solve", {})
    krylov = sum(events.get(name, {}).get("reductions", 0.0) for name in ("VecMDot", "VecNorm")) / steps
    others = ref["per_newton_step"]["reductions"]["max"] - krylov
    fit = np.polyfit([r["owned_dofs"]["mean"] + r["ghost_dofs"]["mean"] for r in parallel],
                     [r["peak_rss_mib"]["mean"] for r in parallel], 1)
    flop_per_dof = ref["per_newton_step"]["flops"]["max"] / ref["owned_dofs"]["max"]
    rate = serial["per_newton_step"]["flops"]["max"] / serial["per_newton_step"]["seconds"]["max"]
    projected = []
    for ranks in ASSUMED["ranks"]:
        n = ranks * dofs
        neighbours = min(ranks - 1, ASSUMED["max_neighbours"])
        ghosts = ASSUMED["interior_ghost_factor"] * ref["ghost_dofs"]["max"] * (dofs / ref["owned_dofs"]["max"]) ** (2 / 3)
        messages, volume = per_neighbour * neighbours, per_ghost * ghosts
        levels = math.ceil(len(mg) + math.log(n / ref["n"]) / math.log(coarsening) - 1e-9)
        reductions = krylov + others * levels / len(mg)
        compute = flop_per_dof * dofs / rate
        communication = (messages * ASSUMED["latency_s"] + volume / ASSUMED["bandwidth_bytes_per_s"]
                         + reductions * math.log2(ranks) * ASSUMED["allreduce_level_s"])
        projected.append({"ranks": ranks, "n": n, "neighbours": neighbours, "ghost_dofs": ghosts,
                          "messages": messages, "bytes": volume, "mg_levels": levels, "reductions": reductions,
                          "peak_rss_mib": float(np.polyval(fit, dofs + ghosts)), "compute_s": compute,
                          "communication_s": communication})
    return {"from_ranks": ref["ranks"], "dofs_per_rank": dofs, "messages_per_neighbour": per_neighbour,
            "bytes_per_ghost_dof": per_ghost, "coarsening_ratio": coarsening,
            "krylov_reductions": krylov, "other_reductions": others, "mg_levels": len(mg), "memory_fit_mib": {"base": fit[1], "per_dof": fit[0]},
            "flop_per_dof": flop_per_dof, "flop_rate_1_rank": rate, "assumed": ASSUMED, "rows": projected}


def markdown(data: dict) -> str:
    from contactqvi.tables import markdown_table

    rows, cores = data["rows"], data.get("machine", {}).get("cores", "?")
    text = ["## Weak scaling of the Coulomb solve: messages, reductions, memory per Newton step (issue 24)\n\n",
            f"The demo's solve (`demos/coulomb3d.py`, {rows[0]['case'] if rows else ''}, default solver: GAMG, tol 0.1, "
            "from u0 = 0) at about the same free dofs per rank (benchmarks/weak_scaling.py), on this machine's "
            f"{cores} cores: 4 and 8 ranks are oversubscribed, so their wall times say nothing "
            "about scaling; counts, volumes, flops and memory do. dofs/rank: n / ranks and its ratio to the 1-rank "
            "run (the levels grow by about 2.7x). Per Newton step, in the log stage around the Newton solve (set-ups, "
            "Galerkin updates, Krylov solves, line search; not mesh, assembly or output), from PETSc's per-rank "
            "counters (those -log_view sums; only PETSc's own MPI calls): msgs = (sent + received) / 2 per rank, "
            "largest / mean over ranks; kB likewise; reductions (the same on every rank); Mflop largest rank; "
            "s: wall time of the stage per Newton step (largest rank). neighbours: ranks owning ghosts of a rank's "
            "dofs, largest. MG rows: rows of the multigrid levels, coarse to fine. peak MiB: each rank's peak "
            "resident memory (whole run), largest / smallest. -log_view (whole run): its MPI Msg Count Max and MPI "
            "Reductions Max.\n\n"]
    table = []
    for r in rows:
        if "per_newton_step" not in r:  # a failed run: its status and the time it used
            status = r.get("status", "failed") if failed(r) else f"failed: exit {r.get('exit_code')}"
            table.append([r["ranks"], r["lev"], f"{status} after {r.get('seconds', r.get('wall_s', 0.0)):.0f} s",
                          *[None] * 11, r.get("commit")])
            continue
        s = r["per_newton_step"]
        whole = r["log_view"]["summary"]
        table.append([r["ranks"], r["lev"], r["n"], f"{r['dofs_per_rank']:.0f} ({r['dofs_per_rank_ratio']:.2f})",
                      f"{r['newton']} / {r['krylov']}", f"{s['messages']['max']:.0f} / {s['messages']['mean']:.0f}",
                      f"{s['bytes']['max'] / 1e3:.0f} / {s['bytes']['mean'] / 1e3:.0f}",
                      f"{s['reductions']['max']:.0f}", f"{s['flops']['max'] / 1e6:.0f}", f"{s['seconds']['max']:.2f}",
                      int(r["neighbours"]["max"]), " / ".join(map(str, r["mg_rows"] or [])),
                      f"{r['peak_rss_mib']['max']:.0f} / {r['peak_rss_mib']['min']:.0f}",
                      f"{whole['messages']['max']:.3g} / {whole['reductions']['max']:.3g}", r["commit"]])
    text.append(markdown_table(["ranks", "lev", "n", "dofs/rank (ratio)", "Newton / Krylov", "msgs / rank",
                                "kB / rank", "reductions", "Mflop / rank", "s", "neighbours", "MG rows",
                                "peak MiB / rank", "-log_view msgs / reductions", "commit"], table))
    mismatched = [r["ranks"] for r in rows if "per_newton_step" in r and not r["stage_matches_counters"]]
    text.append("\nThe totals of the stages inside the solve in -log_view (messages summed over ranks, "
                "reductions) equal the counters' sums on every run.\n" if not mismatched else
                f"\nThe totals of the stages inside the solve in -log_view differ from the counters' sums on "
                f"{mismatched} ranks.\n")
    text.append("\nShare of the stage linear_solve (the Krylov solves with their V-cycles, the GAMG set-up and the "
                "Galerkin updates) in the solve's messages, bytes and reductions, and the share of PCSetUp alone "
                "(the one GAMG set-up of the run holds all of PCSetUp's reductions; the smoothers set up again after "
                "each Galerkin update keep GAMG's eigenvalue bounds and reduce nothing), from -log_view:\n\n")
    shares = []
    for r in rows:
        stages = {k: v for k, v in r.get("log_view", {}).get("stages", {}).items() if k != "Main Stage"}
        if r["ranks"] > 1 and "linear_solve" in stages:
            total = {key: sum(v[key] for v in stages.values()) for key in ("messages_total", "reductions")}
            volume = sum(v["messages_total"] * v["message_length_avg"] for v in stages.values())
            ksp = stages["linear_solve"]
            setup = r["log_view"].get("events", {}).get("linear_solve", {}).get("PCSetUp", {})
            shares.append([r["ranks"], f"{ksp['messages_total'] / total['messages_total']:.2f}",
                           f"{ksp['messages_total'] * ksp['message_length_avg'] / volume:.2f}",
                           f"{ksp['reductions'] / total['reductions']:.2f}",
                           f"{setup.get('messages_total', 0) / total['messages_total']:.2f}",
                           f"{setup.get('reductions', 0) / total['reductions']:.2f}"])
    text.append(markdown_table(["ranks", "messages", "bytes", "reductions", "PCSetUp messages", "PCSetUp reductions"],
                               shares))
    model = data.get("projection")
    if model:
        a = model["assumed"]
        text.append(
            f"\n### Projection (not measured) to {', '.join(map(str, a['ranks']))} ranks at "
            f"{model['dofs_per_rank']} dofs per rank\n\n"
            "From the measured rates (largest over the multi-rank runs; the "
            f"{model['from_ranks']}-rank run for the hierarchy): {model['messages_per_neighbour']:.0f} messages per "
            f"neighbour and {model['bytes_per_ghost_dof']:.0f} bytes per ghost dof per Newton step; multigrid "
            f"coarsening ratio {model['coarsening_ratio']:.1f} per level; {model['krylov_reductions']:.0f} Krylov "
            f"reductions and {model['other_reductions']:.0f} others per Newton step ({model['mg_levels']} levels; "
            "the others taken proportional to the levels); peak memory per rank "
            f"{model['memory_fit_mib']['base']:.0f} MiB + {model['memory_fit_mib']['per_dof'] * 2**20:.0f} B x "
            f"(owned + ghost dofs); {model['flop_per_dof']:.0f} flop per dof per Newton step at "
            f"{model['flop_rate_1_rank'] / 1e6:.0f} Mflop/s (1 rank, this machine). Assumed: at most "
            f"{a['max_neighbours']} neighbours, {a['interior_ghost_factor']:g} x the {model['from_ranks']}-rank run's most ghost "
            "dofs per rank (an interior subdomain shares all its faces), latency "
            f"{a['latency_s'] * 1e6:.0f} us, {a['bandwidth_bytes_per_s'] / 1e9:.0f} GB/s per rank, allreduce "
            f"{a['allreduce_level_s'] * 1e6:.0f} us per tree level (log2 P levels), Krylov iterations per Newton "
            "step as measured (benchmarks/weak_scaling.py, projection()).\n\n")
        text.append(markdown_table(
            ["ranks", "n", "neighbours", "ghost dofs", "msgs / rank", "MB / rank", "MG levels", "reductions", "peak MiB / rank",
             "compute s", "communication s"],
            [[p["ranks"], f"{p['n']:.3g}", p["neighbours"], f"{p['ghost_dofs']:.0f}", f"{p['messages']:.0f}", f"{p['bytes'] / 1e6:.1f}",
              p["mg_levels"], f"{p['reductions']:.0f}", f"{p['peak_rss_mib']:.0f}", f"{p['compute_s']:.2f}",
              f"{p['communication_s']:.3f}"] for p in model["rows"]]))
    return "".join(text)


def main() -> None:
    args, petsc_options = parse()
    if args.worker:
        worker(args, petsc_options)
        return
    assert args.ranks[0] == 1, "--ranks must start with 1 (the reference)"
    out = pathlib.Path(args.output)
    if args.tables_only:
        from mpi4py import MPI

        from contactqvi.tables import write_table

        data = read_table(out / "weak_scaling.json")  # {} if there is none, or it cannot be read
        if not data.get("rows"):
            raise SystemExit(f"error: --tables-only: no rows in {out / 'weak_scaling.json'} to rewrite the tables "
                             "from (give --output the directory of an earlier run's weak_scaling.json)")
        data["projection"] = projection(data["rows"])
        write_table(MPI.COMM_SELF, out / "weak_scaling", data, markdown(data))
        return
    out.mkdir(parents=True, exist_ok=True)
    levels = weak_levels(args.lev, args.ranks)
    target = free_dofs(args.lev)
    work = pathlib.Path(tempfile.mkdtemp(prefix="contactqvi-weak-"))
    rows = []
    for n, lev in levels.items():
        rows.append(measure(n, lev, args, work, target))
        print(json.dumps({k: v for k, v in rows[-1].items() if k != "log_view"}), flush=True)

    from mpi4py import MPI

    import benchlib
    from contactqvi.tables import write_table

    rows = sorted(benchlib.merge_rows(out / "weak_scaling.json", rows, ("case", "ranks")),
                  key=lambda r: (r["case"], r["ranks"]))
    data = {"machine": benchlib.machine(MPI.COMM_SELF), "base_lev": args.lev, "rows": rows,
            "projection": projection(rows)}
    write_table(MPI.COMM_SELF, out / "weak_scaling", data, markdown(data))
    print(f"logs and -log_view of each run: {work}")


if __name__ == "__main__":
    main()
