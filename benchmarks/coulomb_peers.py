"""The SCD semismooth* Newton method beside what a user would otherwise run (seed 000 problems).

On the same mesh and to the same final accuracy (||y^|| <= 1e-12 ||y^0|| of (6.17)):
  1. Coulomb: SCD Newton against the classical fixed point of Tresca problems
     (slip bound F lambda of the previous iterate, each Tresca problem by SCD Newton),
     for every inner tolerance factor in ``--forcings``;
  2. F = 0 (Signorini): SCD Newton against PETSc's SNES VI (``vinewtonrsls``), for
     every inactive-set solver in ``--vi-solvers`` and Krylov rtol in ``--vi-rtols``;
  3. the floor: one linear elastic solve A u = l (CG + GAMG with the rigid-body
     near-nullspace, relative residual 1e-12), and our solve time divided by it.
Each peer is reported in its fastest configuration that reached the accuracy (all
configurations in a second table). Writes ``coulomb_peers.json`` / ``.md`` to
``--output`` (rows of earlier runs for other levels or cases are kept). Wall times
exclude mesh generation and assembly.

    python benchmarks/coulomb_peers.py --levels 7
    mpirun -n 2 python benchmarks/coulomb_peers.py --levels 8 --forcings 1e-1 3e-2 --vi-rtols 1e-2 1e-3
"""

from __future__ import annotations

import dataclasses
import time

from mpi4py import MPI
from petsc4py import PETSc

import benchlib
from contactqvi.contact import ContactProblem, SCDNewtonSolver, build_contact_problem
from contactqvi.contact.fixed_point import FORCING, solve_tresca_fixed_point
from contactqvi.contact.signorini_vi import SIGNORINI_VI_OPTIONS, solve_signorini_vi
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.meshes import create_contact_body
from contactqvi.problems import coulomb as data

#: Inactive-set solvers of SNES VI: name -> (KSP preset, rigid-body modes through
#: :class:`~contactqvi.vi.snes_vi.EmbeddedInactivePC`).
VI_SOLVERS = {
    "cg_gamg_rbm": ("cg_gamg", True),  # CG + GAMG on A with the active rows eliminated, rigid-body modes
    "cg_gamg": ("cg_gamg", False),  # CG + GAMG on PETSc's submatrices (block size 1, no near-nullspace)
    "gmres_hypre": ("gmres_hypre", False),  # GMRES + BoomerAMG on the submatrices
    "lu": ("lu", False),  # MUMPS on the submatrices
}

#: The accuracy every solve must reach: ||y^|| <= RTOL ||y^0||.
RTOL = 1e-12


def _timed_newton(problem: ContactProblem, parameters: dict, prefix: str) -> tuple[PETSc.Vec, dict, SCDNewtonSolver]:
    """SCD Newton from u = 0; the solver is returned for its residual (the caller destroys it)."""
    u = problem.A.createVecRight()
    t0 = time.perf_counter()
    solver = SCDNewtonSolver(problem, parameters, prefix=prefix)
    result = solver.solve(u)
    entry = {"status": str(result.status), "it": result.iterations, "krylov": result.inner_iterations,
             "seconds": time.perf_counter() - t0, "initial_residual": result.history[0]["residual"]}
    return u, entry, solver


def _relative_difference(u: PETSc.Vec, reference: PETSc.Vec) -> float:
    d = u.copy()
    d.axpy(-1.0, reference)
    difference = d.norm() / reference.norm()
    d.destroy()
    return difference


def _fastest(entries: list[dict]) -> dict:
    """The fastest entry that reached ||y^|| <= RTOL ||y^0|| (else the fastest of all)."""
    accurate = [e for e in entries if e["converged"] and e["relative_residual"] <= RTOL]
    return min(accurate or entries, key=lambda e: e["seconds"])


def fixed_point_sweep(problem: ContactProblem, u_scd: PETSc.Vec, pc: str, forcings: list[float]) -> list[dict]:
    """The Tresca fixed point from u = 0 for each inner tolerance factor."""
    entries = []
    for forcing in forcings:
        u = problem.A.createVecRight()
        t0 = time.perf_counter()
        fp = solve_tresca_fixed_point(problem, u, {"pc": pc}, forcing=forcing, prefix="peer_tresca_")
        entries.append({"config": f"forcing {forcing:g}", "forcing": forcing, "status": str(fp.status),
                        "converged": fp.converged, "tresca_solves": fp.iterations, "it": fp.newton_iterations,
                        "krylov": fp.inner_iterations, "seconds": time.perf_counter() - t0,
                        "relative_residual": fp.history[-1]["relative_residual"],
                        "difference_to_scd": _relative_difference(u, u_scd)})
        u.destroy()
    return entries


def snes_vi_sweep(problem: ContactProblem, scd0: dict, measure: SCDNewtonSolver, u0: PETSc.Vec,
                  solvers: list[str], rtols: list[float]) -> list[dict]:
    """SNES VI from u = 0 for each inactive-set solver and Krylov rtol (one run for ``lu``)."""
    entries = []
    for name in solvers:
        ksp, near_nullspace = VI_SOLVERS[name]
        for rtol in rtols if ksp != "lu" else [SIGNORINI_VI_OPTIONS["ksp_rtol"]]:
            u = problem.A.createVecRight()
            t0 = time.perf_counter()
            vi = solve_signorini_vi(problem, u, {"ksp_rtol": rtol}, prefix="peer_vi_", ksp=ksp,
                                    near_nullspace=near_nullspace)
            seconds = time.perf_counter() - t0
            config = name if ksp == "lu" else f"{name}, rtol {rtol:g}"
            entries.append({"config": config, "solver": name, "ksp_rtol": rtol, "converged": vi.converged,
                            "reason": vi.reason, "it": vi.iterations, "krylov": vi.inner_iterations,
                            "seconds": seconds, "relative_residual": measure.residual(u).norm / scd0["initial_residual"],
                            "difference_to_scd": _relative_difference(u, u0)})
            u.destroy()
    return entries


def run_case(comm: MPI.Comm, lev: int, case: str, args) -> dict:
    geometry, load = case.split("/")
    msh, tags = create_contact_body(comm, lev, data.gap_function(geometry))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), Coulomb(data.FRICTION))
    row = {"lev": lev, "case": case, "p": problem.n_contact, "n": problem.n_free, "pc": args.pc}

    u, row["scd"], solver = _timed_newton(problem, {"pc": args.pc}, "peer_scd_")
    solver.destroy()
    row["fixed_point_configs"] = fixed_point_sweep(problem, u, args.pc, args.forcings)
    row["fixed_point"] = _fastest(row["fixed_point_configs"])

    frictionless = dataclasses.replace(problem, law=Frictionless().lumped(problem.contact_area))
    u0, row["frictionless_scd"], solver0 = _timed_newton(frictionless, {"pc": args.pc}, "peer_scd0_")
    row["snes_vi_configs"] = snes_vi_sweep(frictionless, row["frictionless_scd"], solver0, u0, args.vi_solvers,
                                           args.vi_rtols)
    row["snes_vi"] = _fastest(row["snes_vi_configs"])

    row["elastic"] = benchlib.elastic_solve(problem, "peer_elastic_")
    row["peak_rss_mib"] = benchlib.peak_rss_mib(comm)
    benchlib.release(comm, solver0, u, u0, problem)
    return row


#: The configuration of rows measured before the peers were swept.
_UNSWEPT_VI = "cg_gamg, rtol 1e-10"


def _cell(entry: dict) -> str:
    """``it / Krylov / s``, or why the entry does not count."""
    if not entry["converged"]:
        return entry.get("reason", entry["status"])
    cell = f"{entry['it']} / {entry['krylov']} / {entry['seconds']:.1f}"
    if entry["relative_residual"] > RTOL:
        cell += f" (‖ŷ‖/‖ŷ⁰‖ {entry['relative_residual']:.1e})"
    return cell


def markdown(rows: list[dict], comm: MPI.Comm) -> str:
    lines = [
        f"## SCD Newton beside its peers (seed 000 problems, u0 = 0, ||y^|| <= {RTOL:g} ||y^0||)", "",
        f"Wall times in s; {comm.size} MPI rank(s). Each peer in its fastest configuration (all of them below). "
        "Tresca fixed point: Tresca solves / Newton steps / s; forcing: each Tresca solve stops at that factor "
        "times the Coulomb residual. SNES VI: Newton its / Krylov / s; cg_gamg_rbm: CG + GAMG on A with the "
        "active rows eliminated and the rigid-body near-nullspace, cg_gamg: CG + GAMG on the inactive-set "
        "submatrices. Elastic: one solve A u = l, CG + GAMG, relative residual 1e-12.", "",
        "| lev | case | SCD it / Krylov / s | Tresca fixed point | FP config | FP ÷ SCD | F = 0: SCD it / s "
        "| F = 0: SNES VI | VI config | VI ÷ SCD | elastic Krylov / s | SCD ÷ elastic |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(rows, key=lambda r: (r["lev"], r["case"])):
        s, f, s0, vi, e = r["scd"], r["fixed_point"], r["frictionless_scd"], r["snes_vi"], r["elastic"]
        fp_cell = (f"{f['tresca_solves']} / {f['it']} / {f['seconds']:.1f}" if f["status"].startswith("converged")
                   else f["status"])
        vi_cell = _cell(vi)
        lines.append(
            f"| {r['lev']} | {r['case']} | {s['it']} / {s['krylov']} / {s['seconds']:.1f} | {fp_cell} "
            f"| forcing {f['forcing']:g} | {f['seconds'] / s['seconds']:.2f} | {s0['it']} / {s0['seconds']:.1f} "
            f"| {vi_cell} | {vi.get('config', _UNSWEPT_VI)} | {vi['seconds'] / s0['seconds']:.2f} "
            f"| {e['krylov']} / {e['seconds']:.2f} | {s['seconds'] / e['seconds']:.1f} |")
    lines += [
        "", "### Every configuration tried", "",
        "Newton steps (the fixed point's over all its Tresca solves) / Krylov / s; ÷ SCD: the time divided "
        "by SCD Newton's on the same problem (Coulomb, or F = 0 for SNES VI).", "",
        "| lev | case | peer | config | it / Krylov / s | ‖ŷ‖/‖ŷ⁰‖ | ÷ SCD |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in sorted(rows, key=lambda r: (r["lev"], r["case"])):
        for peer, key, scd in (("Tresca FP", "fixed_point_configs", "scd"), ("SNES VI", "snes_vi_configs",
                                                                           "frictionless_scd")):
            for entry in r.get(key, []):
                lines.append(f"| {r['lev']} | {r['case']} | {peer} | {entry['config']} | {_cell(entry)} "
                             f"| {entry['relative_residual']:.1e} | {entry['seconds'] / r[scd]['seconds']:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--levels", type=int, nargs="+", default=[7])
    parser.add_argument("--cases", nargs="+", default=benchlib.CASES, choices=benchlib.CASES)
    parser.add_argument("--forcings", type=float, nargs="+", default=[FORCING],
                        help="inner tolerance factors of the fixed point")
    parser.add_argument("--vi-solvers", nargs="+", default=["cg_gamg_rbm"], choices=list(VI_SOLVERS),
                        help="inactive-set solvers of SNES VI")
    parser.add_argument("--vi-rtols", type=float, nargs="+", default=[SIGNORINI_VI_OPTIONS["ksp_rtol"]],
                        help="Krylov rtol of the inactive-set solves")
    args, comm, out = benchlib.parse(parser)
    name = f"coulomb_peers_np{comm.size}"
    rows = []
    for lev in args.levels:
        for case in args.cases:
            rows.append(run_case(comm, lev, case, args))
            if comm.rank == 0:
                r = rows[-1]
                print(f"lev {lev} {case}: SCD {r['scd']['seconds']:.1f} s, fixed point "
                      f"{r['fixed_point']['seconds']:.1f} s ({r['fixed_point']['config']}), F=0 SCD "
                      f"{r['frictionless_scd']['seconds']:.1f} s, SNES VI {r['snes_vi']['seconds']:.1f} s "
                      f"({r['snes_vi']['config']}), elastic {r['elastic']['seconds']:.2f} s", flush=True)
            merged = benchlib.merge_rows(out / f"{name}.json", rows, ("lev", "case"))
            benchlib.emit(comm, out, name, merged, markdown(merged, comm))


if __name__ == "__main__":
    main()
