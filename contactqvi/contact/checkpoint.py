"""Checkpoints of a load path: what a run needs to continue after its last converged step.

A checkpoint is the load path's :class:`~contactqvi.contact.path_state.PathState` after
a converged step, written whole (its fields and where each is read are listed there).
After every converged load step the runner writes, into ``OUTPUT/checkpoint/``
(adios4dolfinx, ADIOS2 BP4):

* ``mesh.bp``, once: the mesh in its input order (``adios4dolfinx.read_mesh`` reads it
  on any number of ranks, for users who want the fields without the case file);
* ``step_0007.bp`` after step 7: ``displacement`` (u~, global components, m),
  ``solver_variables`` (u - d, the SCD solver's unknowns: nodal frames at the contact
  nodes, the mortar relative displacement at slave nodes of body pairs) and
  ``contact_state`` (the :class:`~contactqvi.contact.nodal.State` of each contact
  node, -1 elsewhere) and ``increment`` (the last solve's change of ``displacement``, m);
* ``checkpoint.json``, written last and atomically: the step, its file, the step's load
  factor, translation (the obstacles' position the next step's slip is measured
  from), rotation of the obstacles and moved groups (``{axis, angle, centre}`` or null)
  and fraction of the declared interferences resolved (``fit``), the last solve's change of
  load factor, translation and rotation (``stride``), the first step's stopping target and the
  summary so far.

A checkpoint exists only once ``checkpoint.json`` names it: a step file being written
when the run died is never read, and the one before is removed only after the marker
has moved on. The fields are written against the mesh's input cell order
(``write_function_on_input_mesh``), which does not depend on the partition, so
``read_function`` fills them into the mesh that the case file builds on any number of
ranks (N-to-M restart). On the same number of ranks the partition and the dof
numbering are those of the interrupted run and the restored vectors are bitwise
the ones it held; the marker's numbers are exact (JSON keeps a float's shortest repr).
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import shutil
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import adios4dolfinx
from dolfinx import fem

from contactqvi.contact.path_state import PathState
from contactqvi.contact.problem import ContactProblem
from contactqvi.load_steps import Rotation
from contactqvi.parameters import ParameterError
from contactqvi.tables import atomic_path, prepare_output_dir, to_builtin, write_summary

__all__ = ["DIRECTORY", "ENGINE", "Checkpoint", "CheckpointWriter", "read_checkpoint", "read_marker", "remove_checkpoints",
           "write_step_file"]

#: Subdirectory of the output directory holding the checkpoints.
DIRECTORY = "checkpoint"
_MARKER = "checkpoint.json"
#: ADIOS2 engine of the checkpoint files.
ENGINE = "BP4"


@dataclasses.dataclass(frozen=True)
class Checkpoint:
    """The last complete checkpoint of an output directory.

    Attributes:
        step: number of converged load steps it holds (1-based index of the last).
        solved: number of converged solves (steps and parts of cut steps).
        path: its step file (``step_XXXX.bp``).
        load, translation: load factor and translation (m) of that step.
        rotation: the obstacles' and moved groups' rotation at that step, or None.
        fit: the fraction of the declared interferences resolved at that step.
        target: the first step's stopping target ||y^|| (N), the accuracy of every later step.
        summary: ``summary.json`` as it was after that step.
    """

    step: int
    solved: int
    path: pathlib.Path
    load: float
    translation: tuple[float, float, float]
    target: float
    summary: dict[str, typing.Any]
    rotation: Rotation | None = None
    fit: float = 1.0
    stride: tuple[float, ...] = (0.0,) * 7

    def resume(self, problem: ContactProblem) -> PathState:
        """The load path's state after :attr:`step`, read into ``problem``'s space (collective;
        the caller destroys it)."""
        state = PathState.at_rest(problem)
        V = problem.V
        S, node_of_dof = _state_space(V)
        states, variables = fem.Function(S, name="contact_state"), fem.Function(V, name="solver_variables")
        for f in (states, variables, state.displacement, state.increment):
            adios4dolfinx.read_function(self.path, f, engine=ENGINE, time=float(self.step), name=f.name)
        state.node_states[node_of_dof] = np.rint(states.x.array)
        n_owned = state.variables.getLocalSize()
        state.variables.array[:] = variables.x.array[:n_owned]
        state.done, state.solved = self.step, self.solved
        state.load, state.translation, state.rotation = self.load, np.array(self.translation), self.rotation
        state.fit, state.stride = self.fit, np.array(self.stride)
        state.target = self.target
        missing = problem.comm.allreduce(int(np.count_nonzero(state.node_states[problem.contact_blk] < 0)),
                                         op=MPI.SUM)
        if missing and not problem.searched_each_step:  # a search finds its own contact nodes
            state.destroy()
            raise ParameterError("--restart", f"{missing} contact nodes of the case have no state in the checkpoint "
                                 f"{self.path}: it was written for another contact surface")
        return state


def remove_checkpoints(comm: MPI.Comm, output: str | os.PathLike) -> None:
    """Remove the checkpoints of an earlier run of ``output`` (a new run starts). Collective."""
    if comm.rank == 0:
        shutil.rmtree(pathlib.Path(output) / DIRECTORY, ignore_errors=True)
    comm.Barrier()


def read_marker(comm: MPI.Comm, output: str | os.PathLike, marker: str,
                case: dict[str, typing.Any]) -> dict[str, typing.Any] | None:
    """The marker file ``marker`` of the checkpoints in ``output`` (read on rank 0, broadcast),
    or None when there is none.

    Raises :class:`ParameterError` (``--restart``) when it was written for another case (its
    summary's ``case`` differs from ``case``, the case file's dictionary). Collective.
    """
    path = pathlib.Path(output) / DIRECTORY / marker
    data = comm.bcast(json.loads(path.read_text()) if comm.rank == 0 and path.exists() else None, root=0)
    if data is None:
        return None
    written = data["summary"].get("case", {})
    if written != to_builtin(case):
        changed = sorted(k for k in set(case) | set(written) if to_builtin(case.get(k)) != written.get(k))
        raise ParameterError("--restart", f"the checkpoint in {path.parent} was written for another case "
                             f"(different: {', '.join(changed) or 'the case'}); use a new --output directory")
    return data


def write_step_file(comm: MPI.Comm, output: str | os.PathLike, name: str, functions: typing.Sequence[fem.Function],
                    step: int, marker: str, data: dict[str, typing.Any]) -> None:
    """Write ``functions`` (against the mesh's input order) into the step file ``name``
    (``<prefix>_<step>.bp``), then the marker ``marker`` holding ``data``, then remove the
    older step files of the same prefix: a step file counts once the marker names it
    (module docstring). Collective."""
    directory = pathlib.Path(output) / DIRECTORY
    with atomic_path(comm, directory / name) as tmp:
        for f in functions:  # appended to a new file
            adios4dolfinx.write_function_on_input_mesh(tmp, f, engine=ENGINE, time=float(step), name=f.name)
    write_summary(comm, directory / marker, data)
    if comm.rank == 0:  # the marker has moved on: older step files are garbage
        prefix = name.split("_")[0]
        for old in directory.glob(f"{prefix}_*.bp"):
            if old.name != name:
                shutil.rmtree(old, ignore_errors=True)
    comm.Barrier()


def read_checkpoint(comm: MPI.Comm, output: str | os.PathLike, case: dict[str, typing.Any]) -> Checkpoint | None:
    """The last complete checkpoint in ``output``, or None when there is none.

    Raises :class:`ParameterError` (``--restart``) when it was written for another case
    (:func:`read_marker`). Collective.
    """
    data = read_marker(comm, output, _MARKER, case)
    if data is None:
        return None
    marker = pathlib.Path(output) / DIRECTORY / _MARKER
    summary = data["summary"]
    if "stride" not in data:
        raise ParameterError("--restart", f"the checkpoint in {marker.parent} was written by an older contactqvi "
                             "without the last step's increment; use a new --output directory")
    rotation = data["rotation"]
    rotation = None if rotation is None else Rotation(tuple(rotation["axis"]), float(rotation["angle"]),
                                                      tuple(rotation["centre"]))
    return Checkpoint(int(data["step"]), int(data["solved"]), marker.parent / data["file"], float(data["load"]),
                      tuple(float(t) for t in data["translation"]), float(data["target"]), summary, rotation,
                      float(data["fit"]), tuple(float(t) for t in data["stride"]))


class CheckpointWriter:
    """Writes the checkpoint of each converged step of one run (collective calls).

    Args:
        output: the run's output directory.
        problem: the contact problem being solved.
        step: the last step checkpointed, when a restart continues a checkpoint.
    """

    def __init__(self, output: str | os.PathLike, problem: ContactProblem, step: int = 0):
        self.directory = pathlib.Path(output) / DIRECTORY
        self.step = step  # the last step checkpointed (0: none yet)
        self.comm = problem.comm
        V = problem.V
        S, self._node_of_dof = _state_space(V)
        self._variables = fem.Function(V, name="solver_variables")
        self._states = fem.Function(S, name="contact_state")
        prepare_output_dir(self.comm, self.directory)
        mesh_file = self.directory / "mesh.bp"
        if not self.comm.bcast(mesh_file.exists() if self.comm.rank == 0 else None, root=0):
            with atomic_path(self.comm, mesh_file) as tmp:
                adios4dolfinx.write_mesh_input_order(tmp, V.mesh, engine=ENGINE)

    def write(self, state: PathState, summary: dict[str, typing.Any]) -> None:
        """Checkpoint the load path's ``state`` after its last converged step; ``summary`` the run's."""
        n_owned = state.variables.getLocalSize()
        self._variables.x.array[:n_owned] = state.variables.array
        self._variables.x.scatter_forward()
        self._states.x.array[:] = state.node_states[self._node_of_dof]
        self._states.x.scatter_forward()
        name = f"step_{state.done:04d}.bp"
        write_step_file(self.comm, self.directory.parent, name,
                        (state.displacement, state.increment, self._variables, self._states), state.done, _MARKER,
                        {"step": state.done, "solved": state.solved, "file": name, "load": state.load,
                         "translation": [float(t) for t in state.translation], "target": state.target,
                         "rotation": None if state.rotation is None else dataclasses.asdict(state.rotation),
                         "fit": state.fit, "stride": state.stride.tolist(), "summary": summary})
        self.step = state.done


def _state_space(V: fem.FunctionSpace) -> tuple[fem.FunctionSpace, np.ndarray]:
    """The scalar space of V's first component (one dof per node) and, for each of its
    dofs (ghosts included), V's node (block) index."""
    S, dofs = V.sub(0).collapse()
    return S, np.asarray(dofs) // 3
