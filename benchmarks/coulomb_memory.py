"""Memory of a Coulomb solve (seed 000) by phase, in bytes per free dof summed over ranks.

One case is solved as in ``coulomb_scaling.py`` (``benchlib.run_coulomb_case``);
each phase of :data:`PHASES` ends when its library function returns (a profile
hook, so the library is measured unchanged). At each phase end every rank reads
the peak of its resident memory since the previous phase end (VmHWM), gives the
heap's free memory back to the OS (``malloc_trim``), reads its resident memory
(VmRSS: what is alive) and restarts VmHWM there (``/proc/self/clear_refs``); the
table sums both over the ranks. PETSc's ``MatGetInfo`` no longer reports memory,
so the matrices' storage is counted from their nonzeros (8-byte values, 4-byte
column indices per nonzero of AIJ or per block of BAIJ, 4-byte row offsets).

    mpirun -n 2 python benchmarks/coulomb_memory.py --lev 9
    PETSC_OPTIONS="-matptap_via nonscalable -mat_product_clear 0" \
        mpirun -n 2 python benchmarks/coulomb_memory.py --lev 9 --label "PETSc's default products"

Rows are added to ``coulomb_memory.{json,md}`` in ``--output`` (same lev, case,
ranks and ``--label`` replaced).
"""

from __future__ import annotations

import ctypes
import sys
import types
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import benchlib
from contactqvi.contact.scd_newton import SCDNewtonSolver
from contactqvi.lifetime import PETScOwner

#: Phases in order: (qualified name of the function whose return ends the phase, label).
#: A phase whose function does not return before a later phase's (e.g. no second
#: multigrid set-up, or no multigrid at all) has no row; its memory goes to the next phase.
PHASES = (
    ("create_contact_body", "mesh"),
    ("functionspace", "function space"),
    ("elasticity_forms", "forms"),
    ("assemble_system", "assembly of A and load"),
    ("build_contact_problem", "contact nodes, frames, load vectors"),
    ("SCDNewtonSolver.__init__", "solver object"),
    ("SCDNewtonSolver.newton_system", "first Newton matrix"),
    ("GalerkinUpdate.__init__", "multigrid set-up"),
    ("SCDNewtonSolver.linear_solve", "first Krylov solve"),
    ("GalerkinUpdate.update", "to the first coarse-operator update"),
    ("GalerkinUpdate.__init__", "to the end of the second multigrid set-up"),
    ("solve_load_path", "rest of the solve"),
)

KIB = 1024
LIBC = ctypes.CDLL("libc.so.6")


def memory_kib() -> tuple[int, int]:
    """(VmRSS, VmHWM) of this process in KiB."""
    fields = dict(line.split(":", 1) for line in open("/proc/self/status"))
    return int(fields["VmRSS"].split()[0]), int(fields["VmHWM"].split()[0])


def trim_and_reset_peak() -> None:
    """Give the heap's free memory back to the OS (``malloc_trim``) and restart VmHWM there."""
    LIBC.malloc_trim(0)
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def matrix_bytes(M: PETSc.Mat) -> int:
    """Storage of an assembled AIJ/BAIJ matrix from its nonzeros (this rank)."""
    info = M.getInfo(PETSc.Mat.InfoType.LOCAL)
    bs = M.getBlockSize() if "baij" in M.getType() else 1
    nz = int(info["nz_allocated"])
    return 8 * nz + 4 * nz // bs**2 + 4 * (M.getLocalSize()[0] // bs + 1)


def owned_objects(owner: PETScOwner) -> typing.Iterator[PETSc.Object]:
    """The PETSc objects of ``owner`` and of the owners it holds (``petsc_objects()``)."""
    for obj in owner.petsc_objects():
        if isinstance(obj, PETSc.Object):
            yield obj
        else:
            yield from owned_objects(obj)


def solver_storage(solver: SCDNewtonSolver) -> dict[str, int]:
    """Bytes (this rank) of A, J, the multigrid levels and the solver's other matrices and vectors."""
    pc = solver.ksp.getPC()
    levels = pc.getMGLevels() if pc.getType() in ("gamg", "mg") else 0
    kinds = [("A", solver.problem.A), ("J", solver.ksp.getOperators()[0])]
    kinds += [("multigrid coarse operators", pc.getMGSmoother(level).getOperators()[0]) for level in range(levels - 1)]
    kinds += [("multigrid interpolations", pc.getMGInterpolation(level)) for level in range(1, levels)]
    kinds += [("other matrices" if isinstance(obj, PETSc.Mat) else "vectors", obj) for obj in owned_objects(solver)
              if isinstance(obj, (PETSc.Mat, PETSc.Vec, PETSc.NullSpace))]
    sizes, seen = {"multigrid levels": levels}, set()
    for kind, obj in kinds:
        if obj.handle not in seen:
            seen.add(obj.handle)
            vectors = obj.getVecs() if isinstance(obj, PETSc.NullSpace) else [obj]
            size = matrix_bytes(obj) if isinstance(obj, PETSc.Mat) else sum(8 * v.getLocalSize() for v in vectors)
            sizes[kind] = sizes.get(kind, 0) + size
    return sizes


class PhaseMemory:
    """Resident memory at the end of each of :data:`PHASES`, from a profile hook."""

    def __init__(self) -> None:
        self.start = 0
        self.records: list[tuple[str, int, int]] = []
        self.storage: dict[str, int] = {}
        self._next = 0

    def __enter__(self) -> PhaseMemory:
        trim_and_reset_peak()
        self.start = memory_kib()[0]
        sys.setprofile(self._hook)
        return self

    def __exit__(self, *exc: object) -> None:
        sys.setprofile(None)
        self._record("release of the problem and solution")

    def _record(self, label: str) -> None:
        peak = memory_kib()[1]
        trim_and_reset_peak()
        self.records.append((label, memory_kib()[0], peak))

    def _hook(self, frame: types.FrameType, event: str, arg: object) -> None:
        if event != "return":
            return
        names = [name for name, _ in PHASES[self._next:]]
        if frame.f_code.co_qualname not in names:
            return
        self._next += names.index(frame.f_code.co_qualname)
        name, label = PHASES[self._next]
        if name == "SCDNewtonSolver.linear_solve":
            self.storage = solver_storage(frame.f_locals["self"])
        self._next += 1
        self._record(label)


def measure(comm: MPI.Comm, lev: int, case: str, pc: str, label: str) -> dict:
    with PhaseMemory() as memory:
        row = benchlib.run_coulomb_case(comm, lev, case, {"pc": pc}, prefix="memory_")
    n = row["n"]
    start = comm.allreduce(memory.start, op=MPI.SUM)
    rss = np.array(comm.allreduce(np.array([r[1] for r in memory.records]), op=MPI.SUM))
    peak = np.array(comm.allreduce(np.array([r[2] for r in memory.records]), op=MPI.SUM))
    phases = []
    for (name, _, _), now, before, top in zip(memory.records, rss, [start, *rss[:-1]], peak):
        phases.append({"phase": name, "rss_mib": now / KIB, "delta_mib": (now - before) / KIB,
                       "peak_mib": top / KIB, "peak_over_start_mib": (top - before) / KIB,
                       "delta_bytes_per_dof": (now - before) * KIB / n})
    storage = {k: v if k == "multigrid levels" else comm.allreduce(v, op=MPI.SUM) for k, v in memory.storage.items()}
    total_peak = float(peak.max())
    return {**{k: row[k] for k in ("lev", "case", "mpi_size", "status", "it", "krylov", "n")}, "label": label,
            "pc": pc, "start_mib": start / KIB, "peak_mib": total_peak / KIB,
            "peak_bytes_per_dof": total_peak * KIB / n, "phases": phases, "storage": storage}


def markdown(rows: list[dict]) -> str:
    rows = sorted(rows, key=lambda r: (r["lev"], r["case"], r["mpi_size"], r["label"]))
    lines = ["## Memory of the Coulomb solve by phase (u0 = 0, tol = 0.1), summed over ranks", "",
             "Resident memory at the end of each phase and its peak during the phase (VmRSS, VmHWM of all "
             "ranks added); B/dof = bytes per free dof; start = Python, DOLFINx and PETSc loaded, before the "
             "mesh. Storage: matrices from their nonzeros, vectors from their length. Peaks of phases that free "
             "and rebuild large objects (a second multigrid set-up) vary by a few per cent between runs of the "
             "same code.", "",
             "| lev | n | case | ranks | configuration | it / Krylov | peak MiB | B/dof | B/dof above the start |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['lev']} | {r['n']} | {r['case']} | {r['mpi_size']} | {r['label']} "
                     f"| {r['it']} / {r['krylov']} "
                     f"| {r['peak_mib']:.0f} | {r['peak_bytes_per_dof']:.0f} "
                     f"| {(r['peak_mib'] - r['start_mib']) * KIB * KIB / r['n']:.0f} |")
    lines.append("")
    for r in rows:
        lines += [f"### lev {r['lev']} {r['case']}, {r['mpi_size']} ranks, n = {r['n']}, {r['label']}: "
                  f"{r['it']} / {r['krylov']} iterations, peak {r['peak_mib']:.0f} MiB = "
                  f"{r['peak_bytes_per_dof']:.0f} B/dof", "",
                  "| phase | RSS MiB | + MiB | + B/dof | peak in phase MiB | peak over start of phase B/dof |",
                  "|---|---|---|---|---|---|",
                  f"| start (Python, DOLFINx, PETSc) | {r['start_mib']:.0f} | | | | |"]
        n = r["n"]
        for p in r["phases"]:
            lines.append(f"| {p['phase']} | {p['rss_mib']:.0f} | {p['delta_mib']:+.0f} "
                         f"| {p['delta_bytes_per_dof']:+.0f} "
                         f"| {p['peak_mib']:.0f} | {p['peak_over_start_mib'] * KIB * KIB / n:.0f} |")
        storage = ", ".join(f"{k} {v / n:.0f}" for k, v in r["storage"].items() if k != "multigrid levels")
        lines += ["", f"Storage after the first linear solve (B/dof): {storage}; "
                  f"{r['storage']['multigrid levels']} multigrid levels.", ""]
    return "\n".join(lines)


def main() -> None:
    parser = benchlib.make_parser(__doc__)
    parser.add_argument("--lev", type=int, default=8)
    parser.add_argument("--case", default="d3/L2", choices=benchlib.CASES)
    parser.add_argument("--label", default="default", help="name of the configuration (e.g. PETSc options)")
    args, comm, out = benchlib.parse(parser)
    row = measure(comm, args.lev, args.case, args.pc, args.label)
    rows = benchlib.merge_rows(out / "coulomb_memory.json", [row], ("lev", "case", "mpi_size", "label"))
    benchlib.emit(comm, out, "coulomb_memory", rows, markdown(rows))


if __name__ == "__main__":
    main()
