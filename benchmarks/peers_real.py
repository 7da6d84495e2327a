"""Our SCD semismooth* Newton solver beside GetFEM 5.4 and Kratos 10.4 on the same meshes and cases.

Problems (``--problems``):
  * ``d1_L1``, ``d3_L2``: the body Omega(d) of seed 000, Sect. 7 (F = 0.23, loads L1/L2) at the
    levels ``--levels``, exported as gmsh meshes (:mod:`peers.export`);
  * ``hertz``: cases/hertz.toml (rigid sphere, frictionless, quarter model) on the meshes
    ``--hertz-meshes`` (meshes/hertz_*.geo), at the final depth delta = 1 mm in one step
    (frictionless contact is path-independent), against the closed form of
    :mod:`contactqvi.problems.hertz`;
  * ``mindlin``: cases/cattaneo_mindlin.toml (rigid sphere, mu = 0.3, indentation then 14
    tangential steps) on the full block ``meshes/hertz_full_{--mindlin-meshes}.geo`` (no rollers
    on the contact surface: GetFEM's nodal bricks cannot take a roller and a tangential
    condition on one node), against Mindlin's Q(s);
  * ``patch``: cases/patch_test.toml (two blocks, non-matching tetrahedra, Coulomb 0.3),
    against the homogeneous closed-form solution;
  * ``hertz_bodies``: cases/hertz_bodies.toml (steel ball on aluminium block, four steps) on
    ``meshes/hertz_bodies_{--hertz-bodies-meshes}.geo``, against Hertz with E*.

For each problem and size: (1) the reference, our solver with exact Newton steps (``pc = lu``) to
||y^|| <= 1e-12 ||y^0||; (2) each code from its loosest tolerance down (``TOLERANCES``) until its
total contact force and its displacement agree with the reference to ``--accuracy`` (1e-6)
relative; that run is the one timed. Between deformable bodies the codes discretise the contact
differently (ours mortar, GetFEM node-to-segment, Kratos mortar ALM), so each peer's reference
there is its own run at the tightest tolerance, and the difference of its solution to ours is
reported beside it. Every code runs in its own process on one core (``OMP_NUM_THREADS=1``),
ours also on 2 ranks. Writes ``peers_real.json`` / ``.md`` to ``--output``; the load average
of the machine is recorded with every run.

    python benchmarks/peers_real.py --problems d1_L1 d3_L2 --levels 3 4 5 6 7 --hertz-meshes coarse medium
    python benchmarks/peers_real.py --problems patch hertz_bodies mindlin
    python benchmarks/peers_real.py --peers getfem --problems d1_L1 --levels 3     # a quick check

Needs ``make peers`` (GetFEM from Debian, Kratos in build/kratos-venv); a peer that is not
installed is skipped. Our solver runs from a snapshot of a commit (``--ours-commit``, default
HEAD) exported to ``--work``, so that edits in the working tree do not change a running benchmark.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import platform
import resource
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "peers"))
import common  # noqa: E402
import export  # noqa: E402
from rows import cell, failed, failed_row, order, read_table, write_text  # noqa: E402

#: Tolerance ladders, loosest first: ours ``rtol`` (||y^|| <= rtol ||y^0||), GetFEM ``max_res``
#: (residual in GPa units), Kratos' relative tolerances.
TOLERANCES = {
    "ours": [1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
    "getfem": [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
    "kratos": [1e-4, 1e-6, 1e-8, 1e-10],
}
#: GetFEM settings compared at ``--settings-case``: (linear solver, Alart-Curnier r as a multiple
#: of E in GPa; GetFEM advises r close to E). Debian's GetFEM 5.4 has no SuperLU ("SuperLU is not
#: interfaced"): MUMPS (its ordering is not settable from Python) or GetFEM's GMRES + ILU.
GETFEM_TRIALS = [("mumps", 0.1), ("mumps", 1.0), ("mumps", 10.0), ("gmres/ilu", 1.0)]
#: Kratos' options in the table: the one configuration that came closest (docs/peers.md, Kratos).
KRATOS_OPTIONS = ["--move-mesh", "--substeps", "10", "--max-iter", "30", "--tol", "1e-6"]
#: Kratos' options between bodies: the contact search needs the moved mesh where the contact
#: grows (Hertz); the patch test's interface is closed from the start. Linear solver: AMGCL is
#: the fastest on Hertz (2.8x Eigen's SparseLU), but Newton does not converge with it on the
#: patch test (docs/peers.md, Kratos). AMGCL to 1e-8 instead of its default 1e-6: with 1e-6
#: no Newton tolerance comes within 1e-6 of Kratos' own reference on the fine mesh, and with
#: 1e-8 Newton needs fewer iterations (coarse mesh, tol 1e-4: 22 iterations, 10.4 s, against
#: 32 and 15.2 s at tol 1e-8 with AMGCL's default).
KRATOS_BODIES_OPTIONS = {"patch": [],
                         "hertz_bodies": ["--move-mesh", "--linear-solver", "amgcl", "--linear-tol", "1e-8"]}
#: Problems between deformable bodies: each code's discretisation of the contact is its own.
BODIES = ("patch", "hertz_bodies")
#: Each code's own reference between bodies: its tightest tolerance, with exact linear solves ...
OWN_REFERENCE = {"getfem": ["--max-res", "1e-12"], "kratos": ["--tol", "1e-12", "--linear-solver", "sparse_lu"]}
#: ... or, for Kratos above this size (Eigen's SparseLU took 637 s at 31 k dofs), AMGCL to 1e-12.
KRATOS_LU_MAX_DOFS = 50_000
KRATOS_ITERATIVE_REFERENCE = ["--tol", "1e-12", "--linear-solver", "amgcl", "--linear-tol", "1e-12"]

PYTHON = {"ours": str(ROOT / ".venv/bin/python"), "getfem": "/usr/bin/python3",
          "kratos": str(ROOT / "build/kratos-venv/bin/python")}
DRIVER = {name: str(HERE / "peers" / f"{name}_contact.py") for name in ("ours", "getfem", "kratos")}
#: Drivers of the peers for cases with [[bodies]] (ours reads every case).
BODIES_DRIVER = {name: str(HERE / "peers" / f"{name}_bodies.py") for name in ("getfem", "kratos")}
MPIENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
          "OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm"}
ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def installed(peer: str) -> bool:
    """Whether ``make peers`` installed the peer."""
    probe = {"getfem": "import getfem", "kratos": "import KratosMultiphysics.ContactStructuralMechanicsApplication",
             "ours": "import dolfinx"}[peer]
    if not pathlib.Path(PYTHON[peer]).exists():
        return False
    return subprocess.run([PYTHON[peer], "-c", probe], capture_output=True).returncode == 0


def snapshot(work: pathlib.Path, commit: str) -> tuple[pathlib.Path, str]:
    """Export ``contactqvi/`` of ``commit`` to ``work/ours-src`` (PYTHONPATH of our runs); its hash."""
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", commit], capture_output=True, text=True,
                         check=True).stdout.strip()
    target = work / "ours-src"
    stamp = target / "COMMIT"
    if not (stamp.exists() and stamp.read_text() == sha):
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir(parents=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", sha, "contactqvi"],
                                 capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, check=True)
        stamp.write_text(sha)
    return target, sha


class Runner:
    """Runs the drivers in subprocesses and keeps every run."""

    def __init__(self, work: pathlib.Path, ours_src: pathlib.Path, timeout: float):
        self.work, self.ours_src, self.timeout = work, ours_src, timeout
        self.count = 0

    def run(self, code: str, case: pathlib.Path, options: list[str], ranks: int = 1) -> dict:
        """Run ``code``'s driver on ``case``; its result.json plus ``process_seconds``, ``load_average``."""
        self.count += 1
        out = self.work / "runs" / f"{case.stem}-{code}-{self.count:03d}"
        shutil.rmtree(out, ignore_errors=True)
        driver = BODIES_DRIVER[code] if code in BODIES_DRIVER and common.is_bodies_case(case) else DRIVER[code]
        command = [PYTHON[code], driver, str(case), "--output", str(out), *options]
        env = {**os.environ, **ONE_THREAD}
        if code == "ours":
            env["PYTHONPATH"] = str(self.ours_src)
            if ranks > 1:
                env.update(MPIENV)
                command = ["mpirun", "-n", str(ranks), *command]
        load = os.getloadavg()[0]
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(command, env=env, capture_output=True, text=True, timeout=self.timeout)
            failure = None if proc.returncode == 0 else (proc.stdout[-2000:] + proc.stderr[-2000:])
        except subprocess.TimeoutExpired:
            failure = f"timeout after {self.timeout:g} s"
        seconds = time.perf_counter() - t0
        cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
        record = {"process_seconds": seconds, "process_cpu_seconds": cpu, "load_average": load,
                  "options": options, "ranks": ranks,
                  "output": str(out)}
        if (out / "result.json").exists():
            record.update(json.loads((out / "result.json").read_text()))
        else:
            record["status"] = f"failed: {failure}"
        if failure and "status" in record and record["status"] == "converged":
            record["status"] = f"failed: {failure}"
        print(f"  {code:6s} {' '.join(options):45s} ranks {ranks}: {record['status'][:60]}, "
              f"{record.get('newton_iterations', '-')} Newton, solve {record.get('solve_time', float('nan')):.2f} s, "
              f"process {seconds:.1f} s (load {load:.1f})", flush=True)
        return record


def errors(record: dict, reference: dict) -> dict:
    """Relative contact-force and displacement differences of a run to the reference (None if it failed)."""
    if not str(record.get("status")).startswith("converged"):
        return {"force_error": None, "displacement_error": None, "displacement_error_max": None}
    a = np.load(pathlib.Path(record["output"]) / "solution.npz")
    b = np.load(pathlib.Path(reference["output"]) / "solution.npz")
    if a["x"].shape != b["x"].shape or np.abs(a["x"] - b["x"]).max() > 1e-9 * np.abs(b["x"]).max():
        raise RuntimeError(f"{record['output']}: nodes differ from the reference's")
    du = a["u"] - b["u"]
    force = np.asarray(record["contact_force"]) - np.asarray(reference["contact_force"])
    return {"force_error": float(np.linalg.norm(force) / np.linalg.norm(reference["contact_force"])),
            "displacement_error": float(np.linalg.norm(du) / np.linalg.norm(b["u"])),
            "displacement_error_max": float(np.abs(du).max() / np.abs(b["u"]).max())}


def accurate(entry: dict, accuracy: float) -> bool:
    return (entry.get("force_error") is not None and entry["force_error"] <= accuracy
            and entry["displacement_error"] <= accuracy)


def ladder(runner: Runner, code: str, case: pathlib.Path, reference: dict, options: list[str], flag: str,
           accuracy: float, start: float | None = None, ranks: int = 1) -> tuple[dict | None, list[dict]]:
    """Run ``code`` from its loosest tolerance (or ``start``, the one that sufficed on the size
    before) down; the first run within ``accuracy`` and all runs."""
    runs = []
    tolerances = TOLERANCES[code]
    if start is not None:
        tolerances = [t for t in tolerances if t <= start]
    for tol in tolerances:
        record = runner.run(code, case, [*options, flag, f"{tol:g}"], ranks=ranks)
        record.update(errors(record, reference), tolerance=tol)
        runs.append(record)
        if accurate(record, accuracy):
            return record, runs
        if record["status"].startswith("failed: timeout"):
            break
    return None, runs


def closed_form(problem: str, case: pathlib.Path) -> dict | None:
    """What the closed form of ``problem`` needs (:func:`closed_form_error` uses it)."""
    from contactqvi.problems import hertz

    if problem == "hertz":
        c = common.load_case(case)
        depth = -float(c.steps[-1][1][2])
        force = hertz.contact_force(c.young, c.poisson, float(c.obstacle["radius"]), depth)
        return {"kind": "force", "force_z": force / 4.0, "depth": depth, "model": "quarter"}
    if problem == "hertz_bodies":
        c = common.load_bodies_case(case)
        first, second = c.bodies[:2]
        e_star = hertz.combined_modulus(first.young, first.poisson, second.young, second.poisson)
        ball = next(b for b in c.bodies if b.name == "ball")
        depth = -ball.displacement["load"][2] * c.steps[-1][0]
        return {"kind": "force", "force_z": hertz.contact_force(e_star, 0.0, 1.0, depth) / 4.0, "depth": depth,
                "model": "quarter"}
    if problem == "mindlin":
        c = common.load_case(case)
        radius, depth = float(c.obstacle["radius"]), -float(c.steps[0][1][2])
        force = hertz.contact_force(c.young, c.poisson, radius, depth)
        s_star = hertz.sliding_displacement(c.friction, force, hertz.shear_modulus(c.young, c.poisson), c.poisson,
                                            hertz.contact_radius(radius, depth))
        return {"kind": "mindlin", "friction": c.friction, "s_star": s_star,
                "s": [float(t[0]) for _, t in c.steps]}
    if problem == "patch":
        c = common.load_bodies_case(case)
        upper = next(b for b in c.bodies if b.traction)
        return {"kind": "patch", "pressure": -float(next(iter(upper.traction.values()))[2]),
                "young": upper.young, "poisson": upper.poisson}
    return None


def closed_form_error(closed: dict | None, run: dict) -> float | None:
    """A run's distance to the closed form: 'force' (F_z - P) / P; 'mindlin' max over the
    tangential steps of |Q/(mu P) - [1 - (1 - s/s*)^(3/2)]| with the run's own P and Q;
    'patch' max |u - u_exact| / max |u_exact| over all nodes."""
    if closed is None or not str(run.get("status")).startswith("converged"):
        return None
    kind = closed.get("kind", "force")
    if kind == "force":
        return (abs(run["contact_force"][2]) - closed["force_z"]) / closed["force_z"]
    if kind == "mindlin":
        forces = np.abs(np.asarray(run["contact_force_per_step"]))
        s = np.asarray(closed["s"])
        ratio = 1.0 - (1.0 - np.clip(s / closed["s_star"], 0.0, 1.0)) ** 1.5
        measured = forces[:, 0] / (closed["friction"] * forces[:, 2])
        return float(np.abs(measured - ratio)[s > 0].max())
    solution = np.load(pathlib.Path(run["output"]) / "solution.npz")
    x, u = solution["x"], solution["u"]
    p, young, nu = closed["pressure"], closed["young"], closed["poisson"]
    exact = np.column_stack([nu * p * x[:, 0] / young, nu * p * x[:, 1] / young, -p * x[:, 2] / young])
    return float(np.abs(u - exact).max() / np.abs(exact).max())


def machine() -> dict:
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "")
    memory_gib = round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    return {"cpu": cpu, "cores": os.cpu_count(), "memory_gib": memory_gib, "machine": platform.machine(),
            "python": platform.python_version()}


def getfem_settings(runner: Runner, case: pathlib.Path, reference: dict,
                    accuracy: float) -> tuple[list[str], list[dict]]:
    """GetFEM's fastest linear solver and augmentation r at one case (tight tolerance, 1 core)."""
    trials = []
    young = common.load_case(case).young / 1e9
    for lsolver, factor in GETFEM_TRIALS:
        options = ["--lsolver", lsolver, "--r", f"{factor * young:g}"]
        record = runner.run("getfem", case, [*options, "--max-res", "1e-10"])
        record.update(errors(record, reference), r_over_E=factor)
        trials.append(record)
    good = [t for t in trials if accurate(t, accuracy)]
    if not good:
        return ["--lsolver", "mumps"], trials
    best = min(good, key=lambda t: t["solve_time"])
    return ["--lsolver", best["settings"]["lsolver"], "--r", f"{best['settings']['r']:g}"], trials


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--problems", nargs="+", default=["d1_L1", "d3_L2", "hertz"])
    parser.add_argument("--levels", nargs="+", type=int, default=[3, 4, 5, 6, 7])
    parser.add_argument("--hertz-meshes", nargs="+", default=["coarse", "medium"])
    parser.add_argument("--mindlin-meshes", nargs="+", default=["coarse"], help="meshes/hertz_full_*.geo")
    parser.add_argument("--hertz-bodies-meshes", nargs="+", default=["coarse", "medium"],
                        help="meshes/hertz_bodies_*.geo")
    parser.add_argument("--peers", nargs="+", default=["getfem", "kratos"])
    parser.add_argument("--peer-max-dofs", type=int, default=10**9,
                        help="skip a peer above this many dofs (its time is extrapolated instead)")
    parser.add_argument("--kratos-max-dofs", type=int, default=10_000,
                        help="Kratos runs only up to this size (it does not converge here, see docs/peers.md)")
    parser.add_argument("--accuracy", type=float, default=1e-6)
    parser.add_argument("--start", nargs="*", default=[], metavar="CODE=TOL",
                        help="start CODE's ladder at TOL (its looser runs measured before were not accurate)")
    parser.add_argument("--reference-pc", default="lu",
                        help="Newton-step solver of the reference (gamg: for sizes where LU is too costly; "
                             "then the reference is ours to rtol 1e-12 with inexact steps)")
    parser.add_argument("--no-np2", action="store_true", help="skip our 2-rank runs")
    parser.add_argument("--settings-case", default="d1_L1:5", help="problem:level of the GetFEM settings sweep")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds before a run is stopped")
    parser.add_argument("--ours-commit", default="HEAD")
    parser.add_argument("--work", default=str(ROOT / "build/peers"))
    parser.add_argument("--output", default=str(HERE / "results"))
    parser.add_argument("--rewrite", action="store_true", help="only rewrite peers_real.md from peers_real.json")
    args = parser.parse_args()
    if args.rewrite:
        stem = pathlib.Path(args.output) / "peers_real"
        write_text(stem.with_suffix(".md"), markdown(read_table(stem.with_suffix(".json"))))
        return 0

    work = pathlib.Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    ours_src, sha = snapshot(work, args.ours_commit)
    runner = Runner(work, ours_src, args.timeout)
    peers = [p for p in args.peers if p != "none" and installed(p)]
    skipped = sorted(set(args.peers) - set(peers) - {"none"})
    if skipped:
        print(f"not installed (make peers): {', '.join(skipped)}")

    cases: list[tuple[str, str, pathlib.Path]] = []
    for problem in args.problems:
        if problem == "hertz":
            for size in args.hertz_meshes:
                case = export.export_case(work / "cases", ROOT / "cases/hertz.toml", f"hertz_{size}",
                                          mesh=ROOT / f"meshes/hertz_{size}.geo",
                                          steps=[{"translation": [0.0, 0.0, -1e-3]}])
                cases.append((problem, size, case))
        elif problem == "mindlin":
            for size in args.mindlin_meshes:
                case = export.export_case(work / "cases", ROOT / "cases/cattaneo_mindlin.toml", f"mindlin_{size}",
                                          mesh=ROOT / f"meshes/hertz_full_{size}.geo", boundary={"clamped": ["bottom"]})
                cases.append((problem, f"full {size}", case))
        elif problem == "patch":
            cases.append((problem, "h 0.25 / 0.16", export.export_case(work / "cases", ROOT / "cases/patch_test.toml",
                                                                       "patch")))
        elif problem == "hertz_bodies":
            for size in args.hertz_bodies_meshes:
                case = export.export_case(work / "cases", ROOT / "cases/hertz_bodies.toml", f"hertz_bodies_{size}",
                                          mesh=ROOT / f"meshes/hertz_bodies_{size}.geo")
                cases.append((problem, size, case))
        else:
            geometry, load = problem.split("_")
            for lev in args.levels:
                cases.append((problem, f"lev {lev}", export.export_box(work / "cases", lev, geometry, load)))

    rows, settings_trials = [], []
    previous = pathlib.Path(args.output) / "peers_real.json"
    old_rows = read_table(previous)
    getfem_options = old_rows.get("getfem_options", ["--lsolver", "mumps"])  # a sweep of an earlier run
    sufficed: dict[tuple[str, str], float] = {}  # (code, problem) -> tolerance that sufficed on the last size
    for row in sorted(old_rows.get("rows", []), key=order("dofs")):  # earlier runs' largest sizes
        if row.get("best") and row["code"] in TOLERANCES:
            sufficed[(row["code"], row["problem"])] = row["best"]["tolerance"]
    for start in args.start:  # e.g. getfem=1e-8: a ladder known to need no looser run
        code, tolerance = start.split("=")
        sufficed.update({(code, problem): float(tolerance) for problem in args.problems})

    def timed(code: str, case: pathlib.Path, reference: dict, options: list[str], flag: str, problem: str,
              closed: dict | None) -> dict:
        """The row of ``code``: its timed run and all runs; between bodies against its own reference
        (its run at the tightest tolerance), with the difference of that run to ours."""
        own = None
        if problem in BODIES and code != "ours":
            own_options = OWN_REFERENCE[code]
            if code == "kratos" and reference["dofs"] > KRATOS_LU_MAX_DOFS:
                own_options = KRATOS_ITERATIVE_REFERENCE
            own = runner.run(code, case, [*options, *own_options])
            own.update(errors(own, reference), tolerance=float(own_options[1]))
            if not own["status"].startswith("converged"):
                return {"code": code, "best": None, "runs": [own]}
        best, runs = ladder(runner, code, case, own or reference, options, flag, args.accuracy,
                            sufficed.get((code, problem)))
        if best is not None:
            sufficed[(code, problem)] = best["tolerance"]
        row = {"code": code, "best": best, "runs": runs}
        if own is not None:
            row["own_reference"] = own
            if best is not None:
                best.update(difference_to_ours=errors(best, reference))
        for run in runs + ([own] if own else []):
            run["closed_form_error"] = closed_form_error(closed, run)
        return row

    settings_problem, settings_level = args.settings_case.split(":")
    for problem, size, case in cases:
        print(f"{problem} {size}: {case}", flush=True)
        reference = runner.run("ours", case, ["--pc", args.reference_pc, "--rtol", "1e-12"])
        if reference["status"] != "converged":  # a row of its own, with the time it used; no peer runs
            rows.append(failed_row(reference["status"], reference["process_seconds"], problem=problem, size=size,
                                   code="reference", case=str(case), output=reference["output"]))
            continue
        base = {"problem": problem, "size": size, "case": str(case), "dofs": reference["dofs"],
                "contact_nodes": reference["contact_nodes"], "ours_commit": sha}
        closed = closed_form(problem, case)
        reference["closed_form_error"] = closed_form_error(closed, reference)
        rows.append({**base, **reference, **errors(reference, reference), "closed_form": closed, "code": "reference",
                     "reference_pc": args.reference_pc})
        rows.append({**base, **timed("ours", case, reference, [], "--rtol", problem, closed), "closed_form": closed})
        best = rows[-1]["best"]
        if best is not None and not args.no_np2:  # from the tolerance that sufficed on 1 rank
            np2, runs = ladder(runner, "ours", case, reference, [], "--rtol", args.accuracy, best["tolerance"], ranks=2)
            for run in runs:
                run["closed_form_error"] = closed_form_error(closed, run)
            rows.append({**base, "code": "ours np2", "best": np2, "runs": runs, "closed_form": closed})
        if "getfem" in peers and reference["dofs"] <= args.peer_max_dofs:
            if problem == settings_problem and size == f"lev {settings_level}" and not settings_trials:
                getfem_options, settings_trials = getfem_settings(runner, case, reference, args.accuracy)
                print(f"  GetFEM settings: {' '.join(getfem_options)}", flush=True)
            options = getfem_options if problem not in BODIES else []  # the bodies driver: r = E of the slave
            rows.append({**base, **timed("getfem", case, reference, options, "--max-res", problem, closed),
                         "closed_form": closed})
        if "kratos" in peers and problem in BODIES:
            options = KRATOS_BODIES_OPTIONS[problem]
            rows.append({**base, **timed("kratos", case, reference, options, "--tol", problem, closed),
                         "closed_form": closed})
            best = rows[-1]["best"]
            if best is not None:  # the same run on 2 threads (Kratos' OpenMP; ours: 2 MPI ranks)
                threads = runner.run("kratos", case, [*options, "--tol", f"{best['tolerance']:g}", "--threads", "2"])
                threads.update(errors(threads, rows[-1]["own_reference"]), tolerance=best["tolerance"],
                               closed_form_error=closed_form_error(closed, threads))
                rows.append({**base, "code": "kratos 2 threads", "best": threads if accurate(threads, args.accuracy)
                             else None, "runs": [threads], "closed_form": closed})
        elif "kratos" in peers and reference["dofs"] <= args.kratos_max_dofs and problem not in ("hertz", "mindlin"):
            record = runner.run("kratos", case, KRATOS_OPTIONS)
            record.update(errors(record, reference) if record["status"] == "converged" else {}, tolerance=1e-6)
            rows.append({**base, "code": "kratos", "best": record if accurate(record, args.accuracy) else None,
                         "runs": [record], "closed_form": closed})
        save(pathlib.Path(args.output), sha, args.accuracy, getfem_options, settings_trials, rows, old_rows)

    print(save(pathlib.Path(args.output), sha, args.accuracy, getfem_options, settings_trials, rows, old_rows))
    return 0


def save(out: pathlib.Path, sha: str, accuracy: float, getfem_options: list[str], settings_trials: list[dict],
         rows: list[dict], old: dict) -> str:
    """Write ``peers_real.json`` and ``.md``: this run's rows and the rows of earlier runs for other
    problems and sizes (``old``, the file as it was when this run started); the markdown."""
    out.mkdir(parents=True, exist_ok=True)
    keys = {(r["problem"], r["size"], r["code"]) for r in rows}
    data = {"machine": machine(), "ours_commit": sha, "accuracy": accuracy, "tolerances": TOLERANCES,
            "getfem_options": getfem_options if settings_trials else old.get("getfem_options", getfem_options),
            "getfem_settings_trials": settings_trials or old.get("getfem_settings_trials", []),
            "rows": [r for r in old.get("rows", []) if (r["problem"], r["size"], r["code"]) not in keys] + rows,
            "load_average_end": os.getloadavg()}
    data["limits"] = limits(data)
    write_text(out / "peers_real.json", json.dumps(data, indent=1) + "\n")
    text = markdown(data)
    write_text(out / "peers_real.md", text)
    return text


def _fmt(value, spec: str = ".3g") -> str:
    if value is None:
        return "\u2013"
    if isinstance(value, float):
        return format(value, spec)
    return str(value)


def _failed(row: dict) -> bool:
    """A failed run's row (:func:`rows.failed_row`), or a failed reference's row as runs before
    issue 46 wrote it (its status, no flag)."""
    return failed(row) or (row["code"] == "reference" and not str(row.get("status")).startswith("converged"))


def _timed_run(row: dict) -> dict | None:
    if _failed(row):
        return None
    return row if row["code"] == "reference" else row.get("best")


#: Order of the table: problems as in the module docstring, then size, then code.
PROBLEM_ORDER = ("d1_L1", "d3_L2", "hertz", "mindlin", "patch", "hertz_bodies")
CODE_ORDER = ("reference", "ours", "ours np2", "getfem", "kratos", "kratos 2 threads")
#: Runs shorter than this (process CPU seconds) are start-up, not solver: not extrapolated from.
EXTRAPOLATE_MIN_SECONDS = 5.0


def _row_order(row: dict) -> tuple:
    problem = PROBLEM_ORDER.index(row["problem"]) if row["problem"] in PROBLEM_ORDER else len(PROBLEM_ORDER)
    code = CODE_ORDER.index(row["code"]) if row["code"] in CODE_ORDER else len(CODE_ORDER)
    return problem, *order("dofs")(row), code


def limits(data: dict, seconds: float = 600.0, memory_mib: float = 20 * 1024) -> list[dict]:
    """Largest size each code solves within ``seconds`` (process CPU time on one core, wall time
    on several) and ``memory_mib``:
    the largest measured one, and a power law through the code's two largest sizes of at least
    :data:`EXTRAPOLATE_MIN_SECONDS` (None where there are not two: start-up would dominate)."""
    series: dict = {}
    for row in data["rows"]:
        run = _timed_run(row)
        if run is None or row["code"] == "reference":
            continue
        several = run.get("ranks", 1) > 1 or run.get("threads", 1) > 1  # wall time; on 1 core CPU time
        seconds_used = run.get("process_seconds") if several else run.get("process_cpu_seconds")
        series.setdefault((row["problem"], row["code"]), []).append(
            (row["dofs"], seconds_used or run["wall_time"], run["peak_memory_mib"]))
    out = []
    for (problem, code), points in sorted(series.items(), key=lambda item: _row_order(
            {"problem": item[0][0], "code": item[0][1], "dofs": 0})):
        points.sort()
        within = [n for n, t, m in points if t <= seconds and m <= memory_mib]
        lim = {"problem": problem, "code": code, "largest_measured": points[-1][0],
               "largest_measured_within": max(within) if within else None,
               "time_exponent": None, "memory_exponent": None, "dofs_at_time_limit": None,
               "dofs_at_memory_limit": None, "largest": max(within) if within else None}
        long = [p for p in points if p[1] >= EXTRAPOLATE_MIN_SECONDS]
        if len(long) >= 2:
            (n0, t0, m0), (n1, t1, m1) = long[-2], long[-1]
            alpha = math.log(t1 / t0) / math.log(n1 / n0)
            beta = math.log(m1 / m0) / math.log(n1 / n0)
            # n where value (n / n1)^exponent = limit; exponents below 0.1 cannot be told from noise
            n_time = n1 * (seconds / t1) ** (1 / alpha) if alpha >= 0.1 else None
            n_memory = n1 * (memory_mib / m1) ** (1 / beta) if beta >= 0.1 else None
            reach = min([n for n in (n_time, n_memory) if n is not None], default=None)
            lim.update(time_exponent=alpha, memory_exponent=beta, dofs_at_time_limit=n_time,
                       dofs_at_memory_limit=n_memory, largest=max(filter(None, [reach, lim["largest"]]), default=None))
        out.append(lim)
    return out


def markdown(data: dict) -> str:
    """The tables of ``peers_real.md``: per problem and size, each code's timed run; ratios; limits."""
    lines = [
        "# Our SCD Newton solver beside GetFEM and Kratos (benchmarks/peers_real.py)",
        "",
        f"Same gmsh meshes and case data for every code; the reference is ours with exact Newton steps "
        f"(pc = lu, rtol 1e-12; 'reference (gamg)': GAMG steps to rtol 1e-12 where LU costs too much). "
        f"Each code's timed run is its loosest tolerance whose total contact force and displacement agree "
        f"with the reference to {data['accuracy']:g} relative (ladders: "
        + "; ".join(f"{k} {', '.join(f'{t:g}' for t in v)}" for k, v in data["tolerances"].items())
        + "). 1 core each (OMP_NUM_THREADS=1), ours also on 2 MPI ranks. *solve*: the load path's solves "
        "(wall and CPU seconds; CPU summed over ranks); *process*: the whole process (start-up, mesh, assembly, "
        "solve, output), CPU seconds. Memory: VmHWM (summed over ranks). The 1-minute load average at the start "
        "of each run is listed (2 cores: above about 1, another job ran beside it and wall times may be "
        "stretched; CPU times much less). Between deformable bodies (patch, hertz_bodies) each peer's *force err* "
        "and *u err* are against its own run at tolerance 1e-12 with exact linear solves (Kratos above "
        f"{KRATOS_LU_MAX_DOFS} dofs: AMGCL to 1e-12; its discretisation is not ours) and *u vs ours* is "
        "||u - u_ours|| / ||u_ours|| (the difference of the discretisations). "
        "*vs closed form*: hertz, hertz_bodies (F_z - P)/P; mindlin max over the tangential steps of "
        "|Q/(mu P) - Q_M(s)/(mu P)| with the run's own P and Q (Mindlin's law, which assumes Dundurs' beta = 0; "
        "it is 0.29 for a rigid sphere on nu = 0.3); patch max |u - u_exact| / max |u_exact|. "
        f"Our code at commit {data['ours_commit'][:10]}; GetFEM options {' '.join(data['getfem_options'])}.",
        "",
        "| problem | size | dofs | code | tol | Newton | solve s | solve CPU s | process CPU s | peak MiB "
        "| contact force z (N) | force err | u err | u vs ours | vs closed form | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in sorted(data["rows"], key=_row_order):
        run = _timed_run(row)
        if _failed(row):
            seconds = row.get("seconds", row.get("process_seconds"))
            lines.append(f"| {row['problem']} | {row['size']} | {cell(row, 'dofs')} | {row['code']} | "
                         f"**failed after {_fmt(seconds, '.0f')} s: {str(row.get('status', '')).splitlines()[0][:70]}** "
                         "| | | | | | | | | | | |")
            continue
        if run is None:
            last = (row.get("runs") or [{}])[-1]
            lines.append(f"| {row['problem']} | {row['size']} | {row['dofs']} | {row['code']} | "
                         f"{_fmt(last.get('tolerance'))} | {_fmt(last.get('newton_iterations'))} | "
                         f"{_fmt(last.get('solve_time'))} | {_fmt(last.get('solve_cpu_time'))} | "
                         f"{_fmt(last.get('process_cpu_seconds'))} | – | – | "
                         f"{_fmt(last.get('force_error'))} | {_fmt(last.get('displacement_error'))} | – | – | "
                         f"{_fmt(last.get('load_average'), '.1f')} |")
            lines.append(f"| | | | | **{row['code']} not within accuracy: {str(last.get('status', ''))[:70]}** "
                         "| | | | | | | | | | | |")
            continue
        closed = row.get("closed_form")
        force_z = run["contact_force"][2]
        label = row["code"]
        if label == "reference" and row.get("reference_pc", "lu") != "lu":
            label += f" ({row['reference_pc']})"
        versus = run["closed_form_error"] if "closed_form_error" in run else closed_form_error(closed, run)
        to_ours = (run.get("difference_to_ours") or {}).get("displacement_error")
        lines.append(
            f"| {row['problem']} | {row['size']} | {row['dofs']} | {label} | {_fmt(run.get('tolerance'))} | "
            f"{run['newton_iterations']} | {_fmt(run['solve_time'])} | {_fmt(run.get('solve_cpu_time'))} | "
            f"{_fmt(run.get('process_cpu_seconds'))} | {_fmt(run['peak_memory_mib'], '.0f')} | {force_z:.7g} | "
            f"{_fmt(run.get('force_error'))} | {_fmt(run.get('displacement_error'))} | {_fmt(to_ours)} | "
            f"{_fmt(versus, '+.3g')} | "
            f"{_fmt(run.get('load_average'), '.1f')} |")
    lines += ["", "Ratios at equal accuracy, peer / ours on 1 core (solve wall, solve CPU, process CPU):", "",
              "| problem | size | dofs | peer | solve | solve CPU | process CPU |", "|---|---|---|---|---|---|---|"]
    by_key: dict = {}
    for row in sorted(data["rows"], key=_row_order):
        by_key.setdefault((row["problem"], row["size"]), {})[row["code"]] = row
    for (problem, size), codes in by_key.items():
        ours = (codes.get("ours") or {}).get("best")
        for peer in ("getfem", "kratos"):
            other = (codes.get(peer) or {}).get("best")
            if ours and other:
                def ratio(key):
                    return _fmt(other[key] / ours[key], ".1f") if other.get(key) and ours.get(key) else "–"
                lines.append(f"| {problem} | {size} | {codes['ours']['dofs']} | {peer} | {ratio('solve_time')} | "
                             f"{ratio('solve_cpu_time')} | {ratio('process_cpu_seconds')} |")
    lines += ["", "Largest size within 10 minutes (the process's CPU time on one core, its wall time on two "
              "ranks or threads) and 20 GiB: the largest measured one, and "
              "**extrapolated** by a power law through each code's two largest measured sizes of at least "
              f"{EXTRAPOLATE_MIN_SECONDS:g} s (t ~ n^a, memory ~ n^b; – where there are not two such sizes, or "
              "an exponent below 0.1 cannot be told from noise):", "",
              "| problem | code | largest measured dofs | largest measured within | a | b | dofs at 600 s "
              "| dofs at 20 GiB |", "|---|---|---|---|---|---|---|---|"]
    for lim in limits(data):
        lines.append(f"| {lim['problem']} | {lim['code']} | {lim['largest_measured']} | "
                     f"{_fmt(lim['largest_measured_within'])} | {_fmt(lim['time_exponent'], '.2f')} | "
                     f"{_fmt(lim['memory_exponent'], '.2f')} | {_fmt(lim['dofs_at_time_limit'], '.3g')} | "
                     f"{_fmt(lim['dofs_at_memory_limit'], '.3g')} |")
    if data.get("getfem_settings_trials"):
        lines += ["", "GetFEM settings sweep (max_res 1e-10; the fastest accurate one is used above):", "",
                  "| lsolver | r / E | Newton | solve s | solve CPU s | status |", "|---|---|---|---|---|---|"]
        for t in data["getfem_settings_trials"]:
            lines.append(f"| {t['options'][1]} | {_fmt(t.get('r_over_E'))} | {_fmt(t.get('newton_iterations'))} | "
                         f"{_fmt(t.get('solve_time'))} | {_fmt(t.get('solve_cpu_time'))} | "
                         f"{str(t.get('status')).splitlines()[0][:60]} |")
    lines += ["", f"Machine: {data['machine']['cpu']}, {data['machine']['cores']} cores, "
              f"{data['machine']['memory_gib']} GiB; 1-minute load average at the end "
              f"{data['load_average_end'][0]:.1f}."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
