"""Run a contact case: mesh, problem, load path, results (``python -m contactqvi run CASE.toml``).

:func:`build_problem` turns a :class:`~contactqvi.case.ContactCase` into a
:class:`~contactqvi.contact.problem.ContactProblem`; :func:`run_case` solves its
load path with the SCD semismooth* Newton method and writes the results of every
converged step as one time step (time = step number) of
``OUTPUT/body.bp`` (displacement, stress, von Mises) and ``OUTPUT/contact_surface.bp``
(:class:`~contactqvi.contact.postprocess.ContactResultsWriter`), and rewrites
``OUTPUT/summary.json`` after each step (status, Newton and Krylov counts, contact
force, reactions, equilibrium error, contact/sticking/sliding areas), so everything
up to the last converged step stays readable if a later step fails.
``OUTPUT/solution.npz`` holds ``x`` and ``u`` of the last converged step (up to
:data:`~contactqvi.tables.GATHER_MAX_NODES` nodes: it is gathered on rank 0), and
``OUTPUT/checkpoint/`` what a restart (``--restart``) needs to continue after it.
"""

from __future__ import annotations

import contextlib
import logging
import math
import pathlib
import signal
import threading
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

from dolfinx import mesh as dmesh

from contactqvi import tables
from contactqvi.case import Body, ContactCase, ContactPair, check_bodies, check_groups, check_solver
from contactqvi.contact.checkpoint import Checkpoint, CheckpointWriter, read_checkpoint, remove_checkpoints
from contactqvi.contact.diagnosis import failure_cause
from contactqvi.contact.load_path import SOLVER_PARAMETERS, LoadStep, solve_load_path
from contactqvi.contact.path_state import PathState
from contactqvi.contact.figure_data import ShownStep
from contactqvi.contact.figures import plot_contact_states, plot_deformed_bodies, plot_forces
from contactqvi.contact.force_history import write_force_table
from contactqvi.contact.postprocess import ContactResultsWriter, warn_solved_fits
from contactqvi.contact.reach import check_reach
from contactqvi.contact.interface import BodyPair, ObstaclePair
from contactqvi.contact.problem import ContactProblem, assemble_contact_problem, build_contact_problem
from contactqvi.contact.scd_newton import PARAMETERS, SCDNewtonResult, checked_parameters
from contactqvi.lifetime import unwind_together
from contactqvi.linalg import default_options
from contactqvi.materials import Material, create_material
from contactqvi.elasticity import body_materials
from contactqvi.meshes import create_contact_body, read_gmsh, split_by_body
from contactqvi.parameters import ParameterError, require
from contactqvi.problems.coulomb import gap_function
from contactqvi.records import Recorder, warn
from contactqvi.result import Status

__all__ = ["EXIT_CODES", "PREFIX", "OutputError", "build_problem", "newton_step_solver_name", "read_mesh", "run_case",
           "stop_signals"]

logger = logging.getLogger(__name__)

#: PETSc options prefix of the case's Newton-step solver (``[petsc]`` options go under it).
PREFIX = "case_"

#: Exit codes of ``python -m contactqvi run``.
EXIT_CODES = {"converged": 0, "not converged": 1, "bad input": 2, "interrupted": 3, "output failed": 4}


class OutputError(Exception):
    """Writing a step's results or checkpoint failed (a full disk, a vanished directory)."""


def read_mesh(case: ContactCase, comm: MPI.Comm) -> tuple[dmesh.Mesh, dmesh.MeshTags]:
    """The case's mesh with named facet tags; its physical groups checked against the case."""
    if case.mesh.box is not None:
        msh, tags = create_contact_body(comm, case.mesh.box.lev, gap_function(case.mesh.box.geometry))
    else:
        msh, tags, _ = read_gmsh(case.mesh.file, comm)
    check_groups(case, tags.names)
    return msh, tags


def build_problem(case: ContactCase, comm: MPI.Comm) -> ContactProblem:
    """Mesh and assembled contact problem of ``case`` (load factor 1, obstacles at rest); a warning
    when its steps turn a linear body by more than small-strain theory holds
    (:func:`_warn_linear_rotation`)."""
    _warn_linear_rotation(case, comm)
    if case.bodies:
        return _build_bodies(case, comm)
    msh, tags = read_mesh(case, comm)
    b, c = case.boundary, case.contact
    return build_contact_problem(
        msh, tags, case.material.young, case.material.poisson, dict(b.traction),
        law=c.law, clamped=b.clamped, contact=c.surface, search=c.search or "once",
        obstacle=case.obstacle.create(), body_force=b.body_force,
        displacements={name: d.components() for name, d in b.displacement.items()}, moved=b.moved,
        material=_material(case.material.model), pressures=dict(b.pressure), rotations=_rotations(case),
        formulation=case.material.formulation, degree=case.mesh.order,
    )


def _build_bodies(case: ContactCase, comm: MPI.Comm) -> ContactProblem:
    """The contact problem of a case with ``[[bodies]]`` and ``[[contacts]]``; each body's
    ``boundary.body_force`` (N/m^3) acts on its own cells."""
    msh, facet_tags, cell_tags = read_gmsh(case.mesh.file, comm)
    check_bodies(case, cell_tags.names)
    tags = split_by_body(msh, facet_tags, cell_tags)
    check_groups(case, tags.names)
    young, poisson = body_materials(msh, cell_tags, {b.name: (b.material.young, b.material.poisson)
                                                     for b in case.bodies})

    def qualified(body: Body, groups: typing.Iterable[str]) -> list[str]:
        return [f"{body.name}.{group}" for group in groups]

    clamped = [name for b in case.bodies for name in qualified(b, b.boundary.clamped)]
    displacements = {f"{b.name}.{group}": d.components() for b in case.bodies
                     for group, d in b.boundary.displacement.items()}
    tractions = {f"{b.name}.{group}": t for b in case.bodies for group, t in b.boundary.traction.items()}
    pressures = {f"{b.name}.{group}": p for b in case.bodies for group, p in b.boundary.pressure.items()}
    moved = [name for b in case.bodies for name in qualified(b, b.boundary.moved)]
    body_force = {b.name: b.boundary.body_force for b in case.bodies if b.boundary.body_force is not None}
    pairs = [_pair(pair, key) for pair, (key, _) in zip(case.contacts, case.pair_keys)]
    return assemble_contact_problem(msh, tags, young, poisson, tractions, pairs, clamped, body_force or None,
                                    displacements=displacements, cell_tags=cell_tags, moved=moved,
                                    material=_material(case.bodies[0].material.model), pressures=pressures,
                                    rotations=_rotations(case), inertia=case.dynamics is not None,
                                    formulation={b.name: b.material.formulation for b in case.bodies},
                                    degree=case.mesh.order)


def _largest_prescribed(case: ContactCase) -> float:
    """The largest length (m) of a prescribed displacement of the case at load factor 1."""
    boundaries = [case.boundary] if case.boundary is not None else [body.boundary for body in case.bodies]
    lengths = [math.hypot(*d.components().values()) for b in boundaries for d in b.displacement.values()]
    return max(lengths, default=0.0)


#: The stretch 1 - cos(angle) above which a rotation of a linear body is warned about (0.81 degrees).
ROTATION_STRETCH = 1e-4


def _rotations(case: ContactCase) -> bool:
    """Whether a step of ``case`` rotates the moved groups (the problem then builds the rotations' loads)."""
    return any(step.rotation is not None for step in case.steps)


def _warn_linear_rotation(case: ContactCase, comm: MPI.Comm) -> None:
    """Warn (key ``small_strain_rotation``) when a step turns the moved groups of a linear body by an
    angle whose stretch 1 - cos(angle) exceeds :data:`ROTATION_STRETCH`: small-strain theory reads a
    rigid rotation as that stretch, with a stress of about E (1 - cos(angle)) (docs/finite_strain.md,
    Sect. 9)."""
    model = case.bodies[0].material.model if case.bodies else case.material.model
    moved = [m for b in case.bodies for m in b.boundary.moved] if case.bodies else case.boundary.moved
    angles = [abs(step.rotation.angle) if step.rotation is not None else 0.0 for step in case.steps]
    if model is not None or not moved or not angles:
        return
    index = max(range(len(angles)), key=angles.__getitem__)
    stretch = 1.0 - math.cos(math.radians(angles[index]))
    if stretch > ROTATION_STRETCH:
        young = max(b.material.young for b in case.bodies) if case.bodies else case.material.young
        warn(comm, logger, "small_strain_rotation", f"steps[{index}].rotation turns the groups boundary.moved of a "
             f"linear (small-strain) body by {angles[index]:g} degrees, which small-strain theory reads as a stretch "
             f"of 1 - cos(angle) = {stretch:.3g} (a spurious stress of about {young * stretch / 1e6:.3g} MPa); give "
             "material.model = \"neo_hookean\" or \"saint_venant_kirchhoff\" for rotations this large",
             angle=angles[index], stretch=stretch)


def _material(model: str | None) -> Material | None:
    """The hyperelastic material called ``model``, or None for linear elasticity."""
    return None if model is None else create_material(model)


def _pair(pair: ContactPair, key: str) -> ObstaclePair | BodyPair:
    """The contact pair of the ``[[contacts]]`` entry ``key`` (``contacts[0]``), which its errors name."""
    if pair.obstacle is not None:
        return ObstaclePair(pair.slave, pair.obstacle.create(), pair.law, pair.search, key)
    return BodyPair(pair.slave, pair.master, pair.law, pair.search_distance, pair.search, pair.interference or 0.0,
                    key, pair.cylinder)


def run_case(case: ContactCase, output: str | pathlib.Path, comm: MPI.Comm = MPI.COMM_WORLD,
             plot: bool = True, restart: bool = False,
             stop_after: int | None = None) -> tuple[dict[str, typing.Any], int]:
    """Solve the case's load path and write the results to ``output``.

    The first step starts from the body at rest (``solver.start = "rest"``, the
    default, u~ = 0) or, as in seed 000, Sect. 7, from u = 0 in the shifted variables
    (``"contact"``: every contact node on the obstacle). The case's ``[petsc]``
    options are in the options database only while it runs.

    After every converged step a checkpoint is written to ``output/checkpoint``
    (:mod:`contactqvi.contact.checkpoint`). With ``restart`` the run continues after the
    last complete checkpoint of ``output`` (on any number of ranks; from step 1 when
    there is none): the output files keep the steps before it and the summary its
    counts. With ``stop_after`` = k the run stops after step k as if interrupted there
    (status ``interrupted``, its checkpoint kept), to be continued with ``restart``. SIGTERM and SIGINT (a batch system's time limit, Ctrl-C) stop the run at
    the next Newton step: the summary is written with ``status = "interrupted"`` and the
    last checkpoint is kept. The output directory is checked to be writable, and the
    checkpoint to belong to this case, before the mesh is read.

    Returns:
        The summary (also in ``output/summary.json``) and the exit code (:data:`EXIT_CODES`):
        0 when every step converged, 1 when one did not, 3 when interrupted.
    """
    require(case.dynamics is None, "dynamics", "a case with [dynamics] is a time integration: "
            "contactqvi.dynamic_runner.run_dynamics")
    parameters = check_solver(case, SOLVER_PARAMETERS)
    require(stop_after is None or stop_after >= 1, "--stop-after", f"must be a step number >= 1, got {stop_after}")
    steps = case.steps[:stop_after]
    _check_output(comm, output)
    warnings = Recorder()  # every warning of the run, for the summary
    with warnings:
        checkpoint = _checkpoint(case, output, comm, restart)
    if checkpoint is not None and checkpoint.step >= len(steps):
        return _nothing_to_solve(checkpoint, output)
    with warnings, default_options(PREFIX, case.petsc), build_problem(case, comm) as problem, stop_signals() as stop:
        logger.info("case: %d contact nodes, %d free dofs, %d steps, %d ranks; Newton steps solved by pc = %s",
                    problem.n_contact, problem.n_free, len(case.steps), comm.size,
                    newton_step_solver_name(problem, parameters))
        check_reach(problem, case.steps, _largest_prescribed(case), case.pair_keys)
        state = PathState.at_rest(problem) if checkpoint is None else checkpoint.resume(problem)
        first, u = state.done, problem.A.createVecRight()
        recorder = _StepRecorder(case, problem, output, checkpoint, stop, warnings)
        try:
            results = solve_load_path(problem, steps, u, parameters, PREFIX, recorder.record,
                                      case.solver.get("start", "rest") == "rest", state, recorder.stop_requested)
            code = _exit_code(results, len(steps) - first)
            if code == EXIT_CODES["converged"] and len(steps) < len(case.steps):
                recorder.stopped(len(steps))
                code = EXIT_CODES["interrupted"]
        except Exception as exc:
            unwind_together(exc)  # an error of one rank alone ends the job here, under abort_on_error
            raise
        finally:
            for owner in (u, state):
                owner.destroy()
            recorder.writer.close()  # keeps every converged step, also when a later one raised
    if plot and recorder.writer.last is not None:
        _draw_figures(recorder.writer, recorder.summary, comm)
    return recorder.summary, code


def _nothing_to_solve(checkpoint: Checkpoint, output: str | pathlib.Path) -> tuple[dict[str, typing.Any], int]:
    """The summary and exit code of a restart whose checkpoint holds every step asked for."""
    logger.info("the checkpoint in %s holds every step asked for: nothing to solve", output)
    status = Status[checkpoint.summary["status"].upper()]
    return checkpoint.summary, EXIT_CODES["converged" if status.converged else "not converged"]


def _checkpoint(case: ContactCase, output: str | pathlib.Path, comm: MPI.Comm, restart: bool) -> Checkpoint | None:
    """The checkpoint a restart continues from; a new run removes an earlier run's checkpoints."""
    checkpoint = read_checkpoint(comm, output, case.to_dict()) if restart else None
    if checkpoint is None:
        if restart:
            warn(comm, logger, "no_checkpoint", f"no checkpoint in {output}: the run starts from step 1")
        remove_checkpoints(comm, output)
    return checkpoint


class _StepRecorder:
    """What the runner does after each load step: result files, summary, checkpoint, signals."""

    def __init__(self, case: ContactCase, problem: ContactProblem, output: str | pathlib.Path,
                 checkpoint: Checkpoint | None, stop: threading.Event, warnings: Recorder):
        self.problem, self._stop = problem, stop
        self.summary = _start_summary(case, problem, checkpoint)
        # the summary's warnings are the run's as they come: a restart's after the earlier run's, without
        # the ones it repeats (the checks of the mesh)
        earlier = self.summary.get("warnings", [])
        warnings.records[:] = earlier + [record for record in warnings.records if record not in earlier]
        self.summary["warnings"] = warnings.records
        # the first step that takes up the whole fit (a press fit's error is estimated from it)
        self._fit_step = next((i for i, step in enumerate(case.steps) if step.fit is None or step.fit == 1.0), None)
        self.writer = ContactResultsWriter(output, problem.comm, keep=0 if checkpoint is None else checkpoint.step)
        self.checkpoints = CheckpointWriter(output, problem, 0 if checkpoint is None else checkpoint.step)
        self._clock = time.perf_counter()  # the end of the last step's recording: the next step's solve starts

    def stopped(self, step: int) -> None:
        """The run stopped after ``step`` as asked (``stop_after``): the summary says ``interrupted``."""
        logger.info("stopped after step %d as asked; continue with --restart", step)
        self.summary["status"] = str(Status.INTERRUPTED)
        tables.write_summary(self.problem.comm, self.writer.out / "summary.json", self.summary)

    def stop_requested(self) -> bool:
        """Whether a signal arrived on any rank (collective)."""
        return self.problem.comm.allreduce(self._stop.is_set(), op=MPI.LOR)

    def record(self, index: int, step: LoadStep, u: PETSc.Vec, result: SCDNewtonResult, state: PathState) -> None:
        """Write step ``index``'s results (if it converged), the summary, and the path's
        ``state`` as a checkpoint (if it converged); an :class:`OutputError` if the output
        cannot be written. ``solve_seconds``: the step's wall time from the end of the last step's
        recording (the first step's: from the start of the path), the largest over the ranks: its
        Newton steps, cuts and relaxation and the searches it makes, not the writing of its results
        (nor the first search, made with the problem: ``search_seconds``)."""
        solve_seconds = self.problem.comm.allreduce(time.perf_counter() - self._clock, op=MPI.MAX)
        entry = {"step": index + 1, **step.summary(), **({} if step.fit is None else {"fit": step.fit}),
                 **result.summary(), "solve_seconds": solve_seconds}
        if index == 0 or self.problem.searched_each_step:  # the search this step's problem comes from
            entry.update(p=self.problem.n_contact, search_seconds=dict(self.problem.setup_seconds))
        if not result.converged:
            entry["failure"] = failure_cause(self.problem, result)
        writer, summary = self.writer, self.summary
        try:
            if result.converged:
                entry.update(writer.write(self.problem, u, result, t=index + 1))
                if index == self._fit_step:
                    warn_solved_fits(self.problem, u)
                tables.write_solution_npz(writer.out / "solution.npz", writer.last.displacement)
            summary["steps"].append(entry)
            summary["status"] = str(result.status)
            summary.pop("failure", None)
            summary.update({"failure": entry["failure"]} if "failure" in entry else {})
            tables.write_summary(self.problem.comm, writer.out / "summary.json", summary)
            write_force_table(self.problem.comm, writer.out / "forces.csv", summary["steps"])
            if result.converged:
                self.checkpoints.write(state, summary)
        except OSError as exc:
            raise OutputError(f"output: writing step {index + 1} to {writer.out} failed ({exc}); the last "
                              f"complete checkpoint, of step {self.checkpoints.step}, is kept") from exc
        _log_step(index, result, entry)
        self._clock = time.perf_counter()


def _start_summary(case: ContactCase, problem: ContactProblem, checkpoint: Checkpoint | None) -> dict[str, typing.Any]:
    """A new run's summary, or the checkpoint's with this restart recorded."""
    comm = problem.comm
    if checkpoint is not None:
        summary = checkpoint.summary
        summary.setdefault("restarts", []).append({"after_step": checkpoint.step, "mpi_size": comm.size})
        summary["mpi_size"] = comm.size
        return summary
    return {"problem": "contact case", "case": case.to_dict(), "mpi_size": comm.size,
            "p": problem.n_contact, "n": problem.n_free,
            "newton_step_solver": newton_step_solver_name(problem, case.solver), "steps": []}


def newton_step_solver_name(problem: ContactProblem, solver: dict[str, typing.Any]) -> str:
    """The Newton-step solver (``pc``) that a case's ``[solver]`` table gives ``problem``, its default resolved."""
    return checked_parameters(problem, {k: v for k, v in solver.items() if k in PARAMETERS})["pc"]


def _exit_code(results: list[SCDNewtonResult], remaining: int) -> int:
    """:data:`EXIT_CODES` of a load path whose ``remaining`` steps gave ``results``."""
    if results and results[-1].status == Status.INTERRUPTED:
        return EXIT_CODES["interrupted"]
    return EXIT_CODES["converged" if results[-1].converged and len(results) == remaining else "not converged"]


def _draw_figures(writer: ContactResultsWriter, summary: dict[str, typing.Any], comm: MPI.Comm) -> None:
    """``contact_states.png`` and ``bodies.png`` of the last step written (named in them, with
    the step a failed path stopped at), ``forces.png`` of the path, and whether each was drawn
    in the summary."""
    last = writer.last
    shown = ShownStep.from_summary(summary)
    summary["plot"] = plot_contact_states(writer.out / "contact_states.png", last.surface, shown)
    summary["bodies_plot"] = plot_deformed_bodies(writer.out / "bodies.png", last.displacement, last.von_mises,
                                                  last.surface, shown)
    summary["forces_plot"] = plot_forces(writer.out / "forces.png", summary["steps"], comm)
    tables.write_summary(comm, writer.out / "summary.json", summary)


def _log_step(index: int, result: SCDNewtonResult, entry: dict[str, typing.Any]) -> None:
    """One line per step: status, counts, the force of each contact pair's master side on its slave, the area."""
    forces = "; ".join(f"{name} {_vector_text(force)}" for name, force in entry.get("pair_forces", {}).items())
    logger.info("step %d: %s, %d Newton steps, %d Krylov, %.3g s; contact forces (N) %s; contact area %.4g m^2",
                index + 1, result.status, result.iterations, result.inner_iterations, entry["solve_seconds"],
                forces or "-", entry.get("contact_area", float("nan")))
    if "failure" in entry:
        logger.error("step %d failed: %s", index + 1, entry["failure"])


def _check_output(comm: MPI.Comm, output: str | pathlib.Path) -> None:
    """Raise :class:`ParameterError` (``output``) unless the output directory can be made and written."""
    error = None
    if comm.rank == 0:
        probe = pathlib.Path(output) / ".contactqvi-write-test"
        try:
            pathlib.Path(output).mkdir(parents=True, exist_ok=True)
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            error = f"cannot write to the output directory {str(output)!r}: {exc.strerror or exc}"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise ParameterError("output", error)


@contextlib.contextmanager
def stop_signals() -> typing.Iterator[threading.Event]:
    """An event that SIGTERM and SIGINT set, instead of ending the process, while the block runs.

    Only the main thread can handle signals; elsewhere the event is never set.
    """
    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum: int, frame: typing.Any) -> None:
        warn(MPI.COMM_WORLD, logger, "signal", f"signal {signum}: stopping at the next Newton step", signal=signum)
        stop.set()

    previous = {number: signal.signal(number, handler) for number in (signal.SIGTERM, signal.SIGINT)}
    try:
        yield stop
    finally:
        for number, action in previous.items():
            signal.signal(number, action)


def _vector_text(vector: typing.Sequence[float] | None) -> str:
    return "-" if vector is None else "(" + ", ".join(f"{v:.4g}" for v in vector) + ")"
