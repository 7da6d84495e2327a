"""Stacked neo-Hookean blocks in compression (issue 45): each contact search mode against a closed form.

Two tables, each run per search mode of the body pair (``--searches``: by default the modes of
today, ``once``, ``every_step`` and ``until_settled``, and for the bulging block ``reference``:
``until_settled`` with ``geometry_tol`` = 1e-9 and up to 100 searches per step; any other name is
put into the case as ``search`` as it is, so that a new mode is measured the same way) with default solver
settings otherwise, through :func:`contactqvi.runner.run_case` (``summary.json``, ``body.bp``):

* ``homogeneous_compression``: two blocks of different moduli on non-matching tetrahedra
  (``benchmarks/data/homogeneous_compression/stacked_{30,50}.toml``), frictionless, pressed by
  30 % in 6 steps and 50 % in 10, the upper block's Poisson's ratio chosen so that both expand
  alike at the end (docs/finite_strain.md, Sect. 12); and the 50 % with the lower block's face as
  the slave surface (``stacked_50_lower_slave.toml``: before the end the upper block is the wider
  one, so its face overhangs the lower block's edge). Per load step: the Newton steps (the
  attempts of a cut step included), the attempts (a step solved whole: 1), the searches, the
  displacement error against the closed form of :mod:`contactqvi.problems.uniaxial` (largest
  over the nodes of ``body.bp``, relative to the top's travel), the pair force's tangential
  part over its normal part, the error of its normal part against P33 times the reference
  area, and the closed form's lateral mismatch
  (a_upper - a_lower) times the half-width over the travel: where it is not zero (every step
  before the last) the blocks expand differently, and the homogeneous state is the solution of
  the reference coupling (``once``) only, not of the contact in the current configuration.
* ``bulging_block``: a soft block (nu = 0.45) pressed 30 % by a stiff one (nu = 0.3) that it
  bulges past (``bulging_block.toml``), frictionless and with Coulomb friction 0.3
  (``--friction``): per load step the Newton steps, attempts, searches, the pair force and its
  relative difference from the ``reference`` run of the same friction.

The searches of a step are read from its summary: ``searches`` where the step records them
(a mode that searches inside the Newton iteration should), else ``once`` searches before the
first step only, and the other modes before every solve: one before the step (and before each
attempt of a cut step) and one before each solve in the step's own configuration (the
``search`` marks of its history).

    .venv/bin/python benchmarks/homogeneous_compression.py
    .venv/bin/python benchmarks/homogeneous_compression.py --searches current   # a new mode, rows merged

A new run replaces the rows of its (case, friction, mode) and keeps the others.
"""

from __future__ import annotations

import argparse
import pathlib
import shutil
import time
import tomllib
import typing

from mpi4py import MPI

import numpy as np

from contactqvi.case import ContactCase, parse_case
from contactqvi.paraview import read_vtx
from contactqvi.problems.uniaxial import stacked_compression
from contactqvi.runner import run_case
from contactqvi.tables import write_table
from rows import cell, failed_row, merge_rows, order

HERE = pathlib.Path(__file__).resolve().parent
DATA = HERE / "data" / "homogeneous_compression"
#: Case name -> file of the homogeneous compressions.
HOMOGENEOUS = {"30 %": "stacked_30.toml", "50 %": "stacked_50.toml",
               "50 %, lower slave": "stacked_50_lower_slave.toml"}
BULGING = "bulging_block.toml"
#: The blocks of meshes/patch_blocks.geo (quarter model): heights (m, bottom first), the
#: interface's reference area (m^2) and half-width (m).
HEIGHTS, AREA, HALF_WIDTH = (1.0, 1.0), 1.0, 1.0
#: Search modes run by default (the bulging block also ``reference``: until_settled to :data:`REFERENCE`).
MODES = ("once", "every_step", "until_settled")
REFERENCE = {"geometry_tol": 1e-9, "max_searches": 100}
#: One step of ``body.bp``: reference points (N, 3), each point's body index (N,), displacement (N, 3).
Fields = tuple[np.ndarray, np.ndarray, np.ndarray]


def configured(path: pathlib.Path, search: str, friction: float = 0.0) -> ContactCase:
    """The case of ``path`` with its pair searched by ``search`` (``reference``: :data:`REFERENCE`)
    and Coulomb friction ``friction`` (0: as the file says, frictionless)."""
    data = tomllib.loads(path.read_text())
    for pair in data["contacts"]:
        pair["search"] = "until_settled" if search == "reference" else search
        if friction > 0.0:
            pair.update(law="coulomb", friction=friction)
    if search == "reference":
        data.setdefault("solver", {}).update(REFERENCE)
    return parse_case(data, path.parent)


def searches(step: dict[str, typing.Any], mode: str) -> int:
    """The contact searches of one load step of ``summary.json`` (module docstring): every solve of a mode
    searched each step follows a search (before the step or one of its attempts, or in its own configuration)."""
    if "searches" in step:
        return int(step["searches"])
    if mode == "once":
        return int(step["step"] == 1)
    return len({(entry.get("substep", 0), entry.get("search", 0)) for entry in step["history"]})


def attempts(step: dict[str, typing.Any]) -> int:
    """The solves of a load step's parts: 1 for a step solved whole, more for a cut one (failed attempts included)."""
    return len({entry.get("substep", 0) for entry in step["history"]})


def run(path: pathlib.Path, mode: str, friction: float, work: pathlib.Path,
        comm: MPI.Comm) -> tuple[dict, float, list[Fields] | None]:
    """``summary.json`` of the case ``path`` run with ``mode`` and ``friction`` in ``work`` (then removed), its
    wall seconds and the :func:`fields` of each converged step (on rank 0; None elsewhere)."""
    out = work / f"{path.stem}_mu{friction:g}_{mode}"
    start = time.perf_counter()
    summary, _ = run_case(configured(path, mode, friction), out, comm, plot=False)
    seconds = time.perf_counter() - start
    steps = None
    if comm.rank == 0:
        steps = [fields(out / "body.bp", k) for k in range(sum(s["converged"] for s in summary["steps"]))]
        shutil.rmtree(out)
    comm.Barrier()
    return summary, seconds, steps


def fields(path: pathlib.Path, step: int) -> Fields:
    """Reference points, each point's body index and the displacement of step ``step`` of ``body.bp``."""
    dataset = read_vtx(path, step)
    body = dataset.cell_data_at_points("body [1]").astype(np.int64)
    return dataset.points, body, dataset.point_data["displacement [m]"]


def force_ratio(force: typing.Sequence[float]) -> float:
    """|F_t| / |F_n| of a pair force whose normal is z (the reference interface)."""
    return float(np.hypot(force[0], force[1]) / abs(force[2]))


def homogeneous_rows(name: str, mode: str, summary: dict, seconds: float, steps: list[Fields]) -> list[dict]:
    """The rows of one run of the homogeneous compression ``name``: one per load step."""
    data = tomllib.loads((DATA / HOMOGENEOUS[name]).read_text())
    blocks = [(b["material"]["young"], b["material"]["poisson"]) for b in data["bodies"]]
    travel = -data["bodies"][1]["boundary"]["displacement"]["top"]["z"]
    on_upper = 1.0 if data["contacts"][0]["slave"].startswith("upper") else -1.0  # the pair force acts on the slave
    converged = iter(steps)
    rows = []
    for step in summary["steps"]:
        exact = stacked_compression(blocks, HEIGHTS, step["load"] * travel)
        row = {"case": name, "search": mode, "step": step["step"], "load": step["load"], "status": step["status"],
               "newton": step["iterations"], "attempts": attempts(step), "searches": searches(step, mode),
               "seconds": seconds, "mismatch": float(np.diff(exact.lateral_stretches)[0] * HALF_WIDTH / exact.travel)}
        if step["converged"]:
            points, body, u = next(converged)
            (force,) = step["pair_forces"].values()
            row.update(u_error=float(np.abs(u - exact.displacement(points, body)).max() / exact.travel),
                       tangential=force_ratio(force),
                       force_error=abs(on_upper * force[2] + exact.nominal_stress * AREA)
                       / abs(exact.nominal_stress * AREA))
        rows.append(row)
    return rows


def bulging_rows(mode: str, friction: float, summary: dict, seconds: float) -> list[dict]:
    """The rows of one run of the bulging block: one per load step (the reference's difference added later)."""
    rows = []
    for step in summary["steps"]:
        row = {"case": "bulging", "friction": friction, "search": mode, "step": step["step"], "load": step["load"],
               "status": step["status"], "newton": step["iterations"], "attempts": attempts(step),
               "searches": searches(step, mode), "seconds": seconds}
        if step["converged"]:
            (force,) = step["pair_forces"].values()
            row.update(force=list(force), tangential=force_ratio(force))
        rows.append(row)
    return rows


def against_reference(rows: list[dict]) -> None:
    """Each bulging row's ``force_difference``: |F - F_ref| / |F_ref| against the reference run of its friction
    and step (where both converged)."""
    reference = {(r["friction"], r["step"]): np.asarray(r["force"]) for r in rows
                 if r["search"] == "reference" and "force" in r}
    for r in rows:
        ref = reference.get((r["friction"], r.get("step")))
        if ref is not None and "force" in r:
            r["force_difference"] = float(np.linalg.norm(np.asarray(r["force"]) - ref) / np.linalg.norm(ref))


def homogeneous_markdown(rows: list[dict]) -> str:
    """One line per case, mode and load step."""
    lines = ["| case | search | step | status | Newton | attempts | searches | u error / travel | F_t / F_n "
             "| force error | closed form's lateral mismatch / travel | run s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['search']} | {cell(r, 'step')} | {r['status']} | {cell(r, 'newton')} "
                     f"| {cell(r, 'attempts')} "
                     f"| {cell(r, 'searches')} | {cell(r, 'u_error', '.2e')} | {cell(r, 'tangential', '.2e')} "
                     f"| {cell(r, 'force_error', '.2e')} | {cell(r, 'mismatch', '.2e')} "
                     f"| {cell(r, 'seconds', '.0f')} |")
    return "\n".join(lines) + "\n"


def bulging_markdown(rows: list[dict]) -> str:
    """One line per friction, mode and load step."""
    lines = ["| mu | search | step | status | Newton | attempts | searches | F_z (N) | F_t / F_n "
             "| \\|F - F_ref\\| / \\|F_ref\\| | run s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        fz = f"{r['force'][2]:.6e}" if "force" in r else "\u2013"
        lines.append(f"| {r['friction']:g} | {r['search']} | {cell(r, 'step')} | {r['status']} | {cell(r, 'newton')} "
                     f"| {cell(r, 'attempts')} "
                     f"| {cell(r, 'searches')} | {fz} | {cell(r, 'tangential', '.2e')} "
                     f"| {cell(r, 'force_difference', '.2e')} | {cell(r, 'seconds', '.0f')} |")
    return "\n".join(lines) + "\n"


def measured(make_rows: typing.Callable[[dict, float, list[Fields]], list[dict]], path: pathlib.Path, mode: str,
             friction: float, work: pathlib.Path, comm: MPI.Comm, **key: typing.Any) -> list[dict]:
    """The rows of one run; a run that raises is one failed row (:func:`rows.failed_row`)."""
    start = time.perf_counter()
    try:
        summary, seconds, steps = run(path, mode, friction, work, comm)
    except Exception as exc:  # an unknown mode, a mesh error: the table says so and the other runs go on
        return [failed_row(f"failed: {type(exc).__name__}: {exc}", time.perf_counter() - start, search=mode,
                           friction=friction, **key)]
    return comm.bcast(make_rows(summary, seconds, steps) if comm.rank == 0 else None, root=0)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--searches", nargs="+", default=None,
                        help=f"search modes of the pair; 'reference': until_settled to {REFERENCE}; default: {MODES}, "
                             "and 'reference' for the bulging block")
    parser.add_argument("--tables", nargs="+", choices=("homogeneous_compression", "bulging_block"),
                        default=["homogeneous_compression", "bulging_block"])
    parser.add_argument("--cases", nargs="+", choices=tuple(HOMOGENEOUS), default=list(HOMOGENEOUS))
    parser.add_argument("--friction", type=float, nargs="+", default=[0.0, 0.3], help="of the bulging block")
    parser.add_argument("--work", default="/tmp/homogeneous_compression", help="where the runs write their results")
    parser.add_argument("--output", default=str(HERE / "results"))
    args = parser.parse_args()
    comm, work, out = MPI.COMM_WORLD, pathlib.Path(args.work), pathlib.Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    if "homogeneous_compression" in args.tables:
        rows = [row for name in args.cases for mode in args.searches or MODES
                for row in measured(lambda s, t, f: homogeneous_rows(name, mode, s, t, f), DATA / HOMOGENEOUS[name],
                                    mode, 0.0, work, comm, case=name)]
        rows = sorted(merge_rows(out / "homogeneous_compression.json", rows, ("case", "search", "step")),
                      key=order("case", "search", "step"))
        write_table(comm, out / "homogeneous_compression", {"cases": HOMOGENEOUS, "rows": rows},
                    homogeneous_markdown(rows))
    if "bulging_block" in args.tables:
        rows = [row for mu in args.friction for mode in args.searches or (*MODES, "reference")
                for row in measured(lambda s, t, _: bulging_rows(mode, mu, s, t), DATA / BULGING, mode, mu, work, comm,
                                    case="bulging")]
        rows = sorted(merge_rows(out / "bulging_block.json", rows, ("friction", "search", "step")),
                      key=order("friction", "search", "step"))
        against_reference(rows)
        write_table(comm, out / "bulging_block", {"case": BULGING, "rows": rows}, bulging_markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
