"""The SCD semismooth* Newton method beside what a user would otherwise run (seed 000 problems).

On the same mesh and to the same final accuracy (||y^|| <= 1e-12 ||y^0|| of (6.17)):
  1. Coulomb: SCD Newton against the classical fixed point of Tresca problems
     (slip bound F lambda of the previous iterate, each Tresca problem by SCD Newton);
  2. F = 0 (Signorini): SCD Newton against PETSc's SNES VI (``vinewtonrsls``);
  3. the floor: one linear elastic solve A u = l (CG + GAMG with the rigid-body
     near-nullspace, relative residual 1e-12), and our solve time divided by it.
Writes ``coulomb_peers.json`` / ``.md`` to ``--output`` (rows of earlier runs for
other levels or cases are kept). Wall times exclude mesh generation and assembly.

    python benchmarks/coulomb_peers.py --levels 7
    mpirun -n 2 python benchmarks/coulomb_peers.py --levels 8 --cases d3/L2
"""

from __future__ import annotations

import dataclasses
import time

from mpi4py import MPI
from petsc4py import PETSc

import benchlib
from contactqvi.contact import FrictionLaw, SCDNewtonSolver, build_contact_problem
from contactqvi.contact.fixed_point import solve_tresca_fixed_point
from contactqvi.contact.signorini_vi import solve_signorini_vi
from contactqvi.elasticity import rigid_motions_nullspace
from contactqvi.linalg import create_ksp, preset
from contactqvi.meshes import create_contact_body
from contactqvi.problems import coulomb as data


def _timed_newton(problem, parameters, prefix):
    u = problem.A.createVecRight()
    t0 = time.perf_counter()
    solver = SCDNewtonSolver(problem, parameters, prefix=prefix)
    result = solver.solve(u)
    seconds = time.perf_counter() - t0
    solver.destroy()
    return u, result, seconds


def _relative_difference(u: PETSc.Vec, reference: PETSc.Vec) -> float:
    d = u.copy()
    d.axpy(-1.0, reference)
    return d.norm() / reference.norm()


def run_case(comm: MPI.Comm, lev: int, case: str, pc: str, forcing: float) -> dict:
    geometry, load = case.split("/")
    msh, tags = create_contact_body(comm, lev, data.gap_function(geometry))
    problem = build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), data.FRICTION)
    row = {"lev": lev, "case": case, "p": problem.n_contact, "n": problem.n_free, "pc": pc}

    u, scd, seconds = _timed_newton(problem, {"pc": pc}, "peer_scd_")
    row["scd"] = {"status": str(scd.status), "it": scd.iterations, "krylov": scd.inner_iterations, "seconds": seconds}

    u_fp = problem.A.createVecRight()
    fp = solve_tresca_fixed_point(problem, u_fp, {"pc": pc}, forcing=forcing, prefix="peer_tresca_")
    row["fixed_point"] = {"status": str(fp.status), "tresca_solves": fp.iterations, "it": fp.newton_iterations,
                          "krylov": fp.inner_iterations, "seconds": fp.timings["solve"], "forcing": forcing,
                          "difference_to_scd": _relative_difference(u_fp, u)}

    frictionless = dataclasses.replace(problem, law=FrictionLaw())
    u0, scd0, seconds0 = _timed_newton(frictionless, {"pc": pc}, "peer_scd0_")
    row["frictionless_scd"] = {"status": str(scd0.status), "it": scd0.iterations, "krylov": scd0.inner_iterations,
                               "seconds": seconds0}
    u_vi = problem.A.createVecRight()
    vi = solve_signorini_vi(frictionless, u_vi, prefix="peer_vi_")
    measure = SCDNewtonSolver(frictionless, {"gamma": scd0.gamma})
    accuracy = measure.residual(u_vi).norm
    row["snes_vi"] = {"converged": vi.converged, "reason": vi.reason, "it": vi.iterations, "krylov": vi.inner_iterations,
                      "seconds": vi.timings["solve"], "relative_residual": accuracy / scd0.history[0]["residual"],
                      "difference_to_scd": _relative_difference(u_vi, u0)}

    problem.A.setNearNullSpace(rigid_motions_nullspace(problem.V))
    ksp = create_ksp(comm, "peer_elastic_", preset("cg_gamg"), A=problem.A, rtol=1e-12)
    x = problem.A.createVecRight()
    t0 = time.perf_counter()
    ksp.solve(problem.load, x)
    row["elastic"] = {"krylov": ksp.getIterationNumber(), "seconds": time.perf_counter() - t0}
    row["peak_rss_mib"] = benchlib.peak_rss_mib(comm)
    benchlib.release(comm, measure, ksp, x, u, u_fp, u0, u_vi, problem)
    return row


def markdown(rows: list[dict], comm: MPI.Comm) -> str:
    lines = [
        "## SCD Newton beside its peers (seed 000 problems, u0 = 0, ||y^|| <= 1e-12 ||y^0||)", "",
        f"Wall times in s; {comm.size} MPI rank(s). Tresca fixed point: Tresca solves / Newton steps / s. "
        "SNES VI: Newton its / Krylov / s (CG + GAMG on the inactive set). Elastic: one solve A u = l, CG + GAMG, "
        "relative residual 1e-12.", "",
        "| lev | case | SCD it / Krylov / s | Tresca fixed point | FP ÷ SCD | F = 0: SCD it / s | F = 0: SNES VI "
        "| VI ÷ SCD | elastic Krylov / s | SCD ÷ elastic |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(rows, key=lambda r: (r["lev"], r["case"])):
        s, f, s0, vi, e = r["scd"], r["fixed_point"], r["frictionless_scd"], r["snes_vi"], r["elastic"]
        fp_cell = (f"{f['tresca_solves']} / {f['it']} / {f['seconds']:.1f}" if f["status"].startswith("converged")
                   else f["status"])
        vi_cell = f"{vi['it']} / {vi['krylov']} / {vi['seconds']:.1f}" if vi["converged"] else vi["reason"]
        lines.append(
            f"| {r['lev']} | {r['case']} | {s['it']} / {s['krylov']} / {s['seconds']:.1f} | {fp_cell} "
            f"| {f['seconds'] / s['seconds']:.2f} | {s0['it']} / {s0['seconds']:.1f} | {vi_cell} "
            f"| {vi['seconds'] / s0['seconds']:.2f} | {e['krylov']} / {e['seconds']:.2f} "
            f"| {s['seconds'] / e['seconds']:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--levels", type=int, nargs="+", default=[7])
    parser.add_argument("--cases", nargs="+", default=benchlib.CASES, choices=benchlib.CASES)
    parser.add_argument("--forcing", type=float, default=1e-2, help="inner tolerance factor of the fixed point")
    args, comm, out = benchlib.parse(parser)
    name = f"coulomb_peers_np{comm.size}"
    rows = []
    for lev in args.levels:
        for case in args.cases:
            rows.append(run_case(comm, lev, case, args.pc, args.forcing))
            if comm.rank == 0:
                r = rows[-1]
                print(f"lev {lev} {case}: SCD {r['scd']['seconds']:.1f} s, fixed point "
                      f"{r['fixed_point']['seconds']:.1f} s, F=0 SCD {r['frictionless_scd']['seconds']:.1f} s, "
                      f"SNES VI {r['snes_vi']['seconds']:.1f} s, elastic {r['elastic']['seconds']:.2f} s", flush=True)
            merged = benchlib.merge_rows(out / f"{name}.json", rows, ("lev", "case"))
            benchlib.emit(comm, out, name, merged, markdown(merged, comm))


if __name__ == "__main__":
    main()
