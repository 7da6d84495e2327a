"""Run a case with ``[dynamics]``: a contact-stabilised Newmark-family scheme over time (docs/dynamics.md).

``python -m contactqvi run CASE.toml`` comes here when the case has a ``[dynamics]`` table.
Each converged time step is

* one time (s) of ``OUTPUT/body.bp`` (:data:`BODY_FIELDS`): displacement, velocity and
  acceleration (the step's mean, Delta v / tau), global components; a restart continues the
  file after its checkpoint's step (:class:`~contactqvi.paraview.VTXDatasetWriter`);
* one entry of ``OUTPUT/summary.json``: time, Newton and Krylov counts of the projection and
  of the step, the energy terms of :data:`~contactqvi.contact.dynamics.ENERGY_TERMS`, each
  body's mass-weighted mean velocity, displacement and acceleration, the step's mean contact
  force;
* a checkpoint (``OUTPUT/checkpoint/``): the :class:`~contactqvi.contact.dynamics.DynamicState`
  whole (displacement, velocity and acceleration in the solver's variables, the physical
  displacement, time, energies), read back bitwise on the same number of ranks.

``OUTPUT/energy.png`` draws the energies over time.

A time step that does not converge is halved and retried from the last converged state, up
to ``[solver] max_cuts`` halvings in a row (:data:`SOLVER_PARAMETERS`), growing back after
each part that converges, as a quasi-static load step is cut
(:mod:`~contactqvi.contact.load_path`); the step's entry lists its parts (``parts``), each
halving is a recorded warning (``step_cut``), and a step whose halvings ran out ends the run
with its status and cause (``failure``) in the summary and exit code 1.
"""

from __future__ import annotations

import dataclasses
import logging
import pathlib
import typing

from mpi4py import MPI
from petsc4py import PETSc

import adios4dolfinx
from dolfinx import fem

from contactqvi import tables
from contactqvi.case import ContactCase, check_solver
from contactqvi.contact.checkpoint import DIRECTORY, ENGINE, read_marker, write_step_file
from contactqvi.contact.diagnosis import failure_cause
from contactqvi.contact.figures import draw_on_rank_0
from contactqvi.contact.dynamics import ENERGY_TERMS, DynamicState, StabilisedNewmark, global_components
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import PARAMETERS, SCDNewtonResult
from contactqvi.elasticity import cellwise
from contactqvi.lifetime import unwind_together
from contactqvi.linalg import default_options
from contactqvi.load_steps import at_time
from contactqvi.paraview import MeshPiece, VTXDatasetWriter
from contactqvi.parameters import Parameter, ParameterError, Parameters
from contactqvi.records import Recorder, warn
from contactqvi.result import Status
from contactqvi.runner import EXIT_CODES, PREFIX, build_problem, newton_step_solver_name, stop_signals

__all__ = ["SOLVER_PARAMETERS", "STATE_FIELDS", "read_dynamic_checkpoint", "run_dynamics"]

logger = logging.getLogger(__name__)

#: The fields of ``body.bp`` (global components), as ParaView lists them.
BODY_FIELDS = ("displacement [m]", "velocity [m/s]", "acceleration [m/s^2]")
#: ``[solver]`` of a case with ``[dynamics]``: the SCD solver's parameters and the halvings of a failed time step.
SOLVER_PARAMETERS = Parameters({**PARAMETERS, "max_cuts": Parameter(
    4, "a time step that does not converge is halved and retried from the last converged state, at most this many "
    "halvings in a row (the step grows back after each part that converges)", type=int, minimum=0)})
#: The vectors of a checkpoint (:func:`_state_vectors`), by name in its step file.
STATE_FIELDS = ("solver_variables", "physical_displacement", "solver_velocity", "solver_acceleration",
                "solver_newmark_acceleration", "inertial_force")
_MARKER = "dynamics.json"


def run_dynamics(case: ContactCase, output: str | pathlib.Path, comm: MPI.Comm = MPI.COMM_WORLD,
                 plot: bool = True, restart: bool = False,
                 stop_after: int | None = None) -> tuple[dict[str, typing.Any], int]:
    """Integrate ``case`` (with ``[dynamics]``) over its time steps and write the results to ``output``.

    ``restart`` continues after the last checkpoint in ``output`` (from time 0 when there is
    none); ``stop_after`` = k stops after time step k (status ``interrupted``). SIGTERM and
    SIGINT (a batch system's time limit, Ctrl-C) stop the run at the next Newton step as a
    quasi-static run stops (:func:`~contactqvi.runner.stop_signals`): the time step under way is
    dropped, the summary says ``interrupted`` and the checkpoint of the last time step stays for
    ``restart``. Returns the summary and the exit code (:data:`~contactqvi.runner.EXIT_CODES`).
    """
    parameters = check_solver(case, SOLVER_PARAMETERS)
    max_cuts = parameters.pop("max_cuts", SOLVER_PARAMETERS["max_cuts"].default)
    dynamics = case.dynamics
    count = dynamics.steps if stop_after is None else min(stop_after, dynamics.steps)
    out = tables.prepare_output_dir(comm, output)
    warnings = Recorder()
    with warnings, default_options(PREFIX, case.petsc), build_problem(case, comm) as problem, stop_signals() as signal:
        scheme = dynamics.time_scheme()
        with StabilisedNewmark(problem, _density(case, problem), dynamics.dt, parameters, PREFIX, case.steps,
                               scheme) as integrator:
            velocity = _initial_velocity(case, problem)
            state = integrator.initial_state(velocity)
            velocity.destroy()
            summary = {"problem": "dynamic contact case", "case": case.to_dict(), "mpi_size": comm.size,
                       "p": problem.n_contact, "n": problem.n_free,
                       "newton_step_solver": newton_step_solver_name(problem, parameters),
                       "scheme": {"name": scheme.name, **scheme.parameters(),
                                  "stabilisation": "contact-stabilised predictor (Deuflhard, Krause, Ertel 2008)"},
                       "steps": []}
            if restart:
                summary = read_dynamic_checkpoint(problem, out, case, state, summary)
                integrator.resume(state)
            def stop() -> bool:  # collective: a signal on any rank
                return comm.allreduce(signal.is_set(), op=MPI.LOR)

            try:
                code = _integrate(problem, integrator, state, summary, out, (count, dynamics.dt, max_cuts), stop)
            finally:
                state.destroy()
    if warnings.records:
        summary.setdefault("warnings", []).extend(warnings.records)
    if code == EXIT_CODES["converged"] and count < dynamics.steps:
        summary["status"] = str(Status.INTERRUPTED)
        code = EXIT_CODES["interrupted"]
    if plot and summary["steps"]:
        summary["energy_plot"] = plot_energy(out / "energy.png", summary["steps"], comm)
    tables.write_summary(comm, out / "summary.json", summary)
    return summary, code


def _integrate(problem: ContactProblem, integrator: StabilisedNewmark, state: DynamicState,
               summary: dict[str, typing.Any], out: pathlib.Path, steps: tuple[int, float, int],
               stop: typing.Callable[[], bool]) -> int:
    """The time steps after ``state.done`` up to ``count`` of ``steps`` = (count, dt, max_cuts):
    solve (halving a step that fails, :func:`_advance`), record, write; the exit code. A step
    that ``stop()`` interrupts is not recorded (status ``interrupted``)."""
    count, dt, max_cuts = steps
    u = problem.A.createVecRight()
    fields = {name: fem.Function(problem.V) for name in BODY_FIELDS}
    displacement, velocity, acceleration = fields.values()
    piece = MeshPiece(problem.V.mesh)
    writer = VTXDatasetWriter(problem.comm, out / "body.bp", keep=state.done)
    try:
        while state.done < count:
            parts, projection, result = _advance(problem, integrator, state, u, (dt, max_cuts), stop)
            summary["status"] = str(result.status if projection.converged else projection.status)
            if Status.INTERRUPTED in (projection.status, result.status):
                summary["status"] = str(Status.INTERRUPTED)
                tables.write_summary(problem.comm, out / "summary.json", summary)
                return EXIT_CODES["interrupted"]
            if not (projection.converged and result.converged):
                failed = result if projection.converged else projection
                summary["steps"].append({"step": state.done + 1, "converged": False, "status": summary["status"],
                                         "failure": failure_cause(problem, failed), "parts": parts})
                tables.write_summary(problem.comm, out / "summary.json", summary)
                return EXIT_CODES["not converged"]
            state.done += 1
            summary["steps"].append(_entry(problem, state, projection, result, integrator)
                                    | ({"parts": parts} if len(parts) > 1 else {}))
            if problem.searched_each_step:  # the next step's contact, and the checkpoint's variables
                integrator.search(state)
            state.physical.copy(displacement.x.petsc_vec)
            displacement.x.scatter_forward()
            global_components(problem, state.velocity, velocity)
            global_components(problem, state.acceleration, acceleration)
            writer.write(piece.dataset(fields), state.time)
            tables.write_summary(problem.comm, out / "summary.json", summary)
            write_dynamic_checkpoint(problem, out, state, summary)
    except Exception as exc:
        unwind_together(exc)  # an error of one rank alone ends the job here, under abort_on_error
        raise
    finally:
        writer.close()  # keeps every converged step, also when a later one raised
        u.destroy()
    return EXIT_CODES["converged"]


def _advance(problem: ContactProblem, integrator: StabilisedNewmark, state: DynamicState, u: PETSc.Vec,
             step: tuple[float, int], stop: typing.Callable[[], bool]) -> tuple[list[dict[str, typing.Any]],
                                                                            SCDNewtonResult, SCDNewtonResult]:
    """Advance ``state`` by the time step dt of ``step`` = (dt, max_cuts) to t = ``state.time`` + dt,
    in parts where it fails: after k halvings in a row the part is 2^-k of what remains of the
    step, one halving fewer after each part that converges (module docstring); ``stop()`` is asked
    before each Newton step. Returns the parts (time reached, length, status) and the last part's
    two results."""
    dt, max_cuts = step
    target, cuts, parts = state.time + dt, 0, []
    while True:
        remaining = target - state.time
        tau = remaining * 0.5**cuts
        projection, result = integrator.step(state, u, tau, stop)
        last = result if projection.converged else projection
        parts.append({"time": state.time if last.converged else state.time + tau, "dt": tau,
                      "status": str(last.status)})
        if last.converged:
            if cuts == 0:
                state.time = target  # the parts add up to dt to round-off; the step ends at t_n + dt
                return parts, projection, result
            cuts -= 1
            continue
        if last.status == Status.INTERRUPTED or cuts >= max_cuts:
            return parts, projection, result
        cuts += 1
        warn(problem.comm, logger, "step_cut", f"time step {state.done + 1}: {last.status} with dt = {tau:.6g} "
             f"s at t = {state.time:.9g} s; halved to {remaining * 0.5**cuts:.6g} s", step=state.done + 1,
             time=state.time, dt=remaining * 0.5**cuts)


def _entry(problem: ContactProblem, state: DynamicState, projection: SCDNewtonResult, result: SCDNewtonResult,
           integrator: StabilisedNewmark) -> dict[str, typing.Any]:
    """The summary entry of the time step just recorded in ``state``, with the load factor and the
    obstacles' motion of the integrator's time points at its time. The contact force is the
    step's mean (:attr:`~contactqvi.contact.dynamics.DynamicState.contact_forces`; half the
    multiplier of the step's GE for Newmark's rule, docs/dynamics.md Sect. 3)."""
    mean = dataclasses.replace(result, normal_force=state.contact_forces[0], friction_force=state.contact_forces[1])
    logger.info("time step %d, t = %.6g s: %d + %d Newton steps; kinetic %.6g J, elastic %.6g J, balance error "
                "%.3g J", state.done, state.time, projection.iterations, result.iterations,
                state.energy["kinetic"], state.energy["elastic"], state.energy["balance_error"])
    motion = integrator.motion
    return {"step": state.done, "time": state.time, **at_time(integrator.path, state.time).summary(),
            **result.summary(),
            "predictor": {"iterations": projection.iterations, "inner_iterations": projection.inner_iterations},
            "energy": dict(state.energy), "body_velocity": motion.velocities(state.velocity),
            "body_displacement": integrator.mean_displacements(state),
            "body_acceleration": motion.velocities(state.acceleration),
            **contact_resultants(problem, mean)}


def _density(case: ContactCase, problem: ContactProblem) -> float | fem.Function:
    """rho of the one body, or a DG0 function of the bodies' densities (kg/m^3)."""
    if not case.bodies:
        return case.material.density
    return cellwise(problem.V.mesh, problem.body.cell_tags, {b.name: b.material.density for b in case.bodies},
                    "density")


def _initial_velocity(case: ContactCase, problem: ContactProblem) -> PETSc.Vec:
    """The initial velocity in the solver's variables (each body's vector, zero where none)."""
    field = fem.Function(problem.V)
    values = field.x.array.reshape(-1, 3)
    if not case.bodies:
        values[:] = case.dynamics.initial_velocity or (0.0, 0.0, 0.0)
    else:
        for k, body in enumerate(case.bodies):
            tag = list(problem.body.cell_tags.names).index(body.name)
            values[problem.node_body == tag] = body.initial_velocity or (0.0, 0.0, 0.0)
    return problem.solver_variables(field, problem.A.createVecRight())


def write_dynamic_checkpoint(problem: ContactProblem, out: pathlib.Path, state: DynamicState,
                             summary: dict[str, typing.Any]) -> None:
    """Checkpoint ``state``: w_n, v_n, the last acceleration, Newmark's a_n and m_n in the
    solver's variables and the physical u_n (:data:`STATE_FIELDS`, against the mesh's input
    order) and a marker with the step, time, energies and the summary, written last
    (:func:`~contactqvi.contact.checkpoint.write_step_file`). Collective."""
    comm = problem.comm
    tables.prepare_output_dir(comm, out / DIRECTORY)
    name = f"time_{state.done:06d}.bp"
    write_step_file(comm, out, name, _state_functions(problem.V, state, fill=True), state.done, _MARKER,
                    {"step": state.done, "time": state.time, "file": name, "fields": list(STATE_FIELDS),
                     "energy": state.energy, "initial_energy": state.initial_energy,
                     "translation": state.translation.tolist(), "summary": summary})


def _state_functions(V: fem.FunctionSpace, state: DynamicState, fill: bool) -> list[fem.Function]:
    """Functions on ``V`` for the vectors of :func:`_state_vectors`, holding them if ``fill``."""
    fields = [fem.Function(V, name=name) for name in STATE_FIELDS]
    if fill:
        for field, vector in zip(fields, _state_vectors(state)):
            field.x.array[: vector.getLocalSize()] = vector.array
            field.x.scatter_forward()
    return fields


def _state_vectors(state: DynamicState) -> tuple[PETSc.Vec, ...]:
    """The vectors of ``state`` a checkpoint holds, in the order of :func:`_state_functions`."""
    return (state.displacement, state.physical, state.velocity, state.acceleration, state.newmark_acceleration,
            state.inertial_force)


def read_dynamic_checkpoint(problem: ContactProblem, out: pathlib.Path, case: ContactCase, state: DynamicState,
                            summary: dict[str, typing.Any]) -> dict[str, typing.Any]:
    """Fill ``state`` from the last checkpoint in ``out`` and return its summary (``summary``
    unchanged when there is none). Any number of ranks. Collective."""
    comm = problem.comm
    data = read_marker(comm, out, _MARKER, case.to_dict())
    if data is None:
        logger.warning("no checkpoint in %s: the run starts at time 0", out)
        return summary
    if data.get("fields") != list(STATE_FIELDS):
        raise ParameterError("--restart", f"the checkpoint in {out / DIRECTORY} was written by an older contactqvi "
                             f"(without {', '.join(sorted(set(STATE_FIELDS) - set(data.get('fields', ()))))}); "
                             "run again without --restart, or into a new --output directory")
    fields = _state_functions(problem.V, state, fill=False)
    for field, vector in zip(fields, _state_vectors(state)):
        adios4dolfinx.read_function(out / DIRECTORY / data["file"], field, engine=ENGINE, time=float(data["step"]),
                                    name=field.name)
        vector.array[:] = field.x.array[: vector.getLocalSize()]
    state.done, state.time = int(data["step"]), float(data["time"])
    state.energy, state.initial_energy = {k: float(data["energy"][k]) for k in ENERGY_TERMS}, data["initial_energy"]
    state.translation[:] = data.get("translation", 0.0)  # none before session 41: w_n held the whole motion
    data["summary"].setdefault("restarts", []).append({"after_step": state.done, "mpi_size": comm.size})
    return data["summary"]


def plot_energy(path: pathlib.Path, steps: list[dict[str, typing.Any]], comm: MPI.Comm) -> bool:
    """``energy.png``: kinetic, elastic, their sum, the loads' work, the friction dissipation, the
    contact's work and the balance error over time, drawn on rank 0. Returns whether it was written."""
    return draw_on_rank_0(comm, path, lambda tmp: _draw_energy(tmp, steps))


def _draw_energy(path: pathlib.Path, steps: list[dict[str, typing.Any]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    done = [s for s in steps if "energy" in s]
    time = [s["time"] for s in done]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for term in ENERGY_TERMS:
        ax.plot(time, [s["energy"][term] for s in done], label=term.replace("_", " "))
    ax.plot(time, [s["energy"]["kinetic"] + s["energy"]["elastic"] for s in done], "k--", label="kinetic + elastic")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("energy (J)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=120)
    plt.close(fig)
