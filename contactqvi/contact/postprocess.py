"""Results of a solved contact problem: force balance and files, step by step.

Files (:class:`ContactResultsWriter`, :func:`write_contact_results`), one dataset
each, written by every rank in parallel (:mod:`contactqvi.paraview`: each rank its
owned cells, ParaView appends them into the dataset a serial run writes):

* ``body.bp`` (VTX): point data ``displacement [m]``; cell data ``stress [Pa]``
  (cell average of the Cauchy stress, 3 x 3) and ``von_mises [Pa]`` (of it).
* ``contact_surface.bp`` (VTX): the contact surface cut into tributary patches
  (:class:`~contactqvi.contact.surface.ContactSurface`). Point data, the P1 fields
  interpolated (exactly for bilinear/linear facets; with quadratic elements the edge points
  take the midside nodes' own values): ``displacement [m]``,
  ``contact_pressure [Pa]``, ``friction_traction [Pa]``, ``slip [m]``,
  ``tangential_displacement [m]``, ``gap [m]``. Cell data, the value of the
  patch's node, so ParaView draws categories without blending them:
  ``contact_state`` (:class:`State` value) and the indicators ``is_open``,
  ``is_in_contact``, ``is_sliding``, ``is_sticking`` (0/1; at a supported node the share of its facet's
  nodes in that state); integrating an indicator over the surface gives that area.
* ``solution.npz``: ``x`` (N, 3) and ``u`` (N, 3), the displacement u~ gathered on
  rank 0, for at most :data:`contactqvi.tables.GATHER_MAX_NODES` nodes unless
  asked for.

Summary entries (:func:`contact_summary`; each defined in README.md, Results), SI units
listed under ``units``: total contact force, the sum over the contact pairs of the master
side's force on the slave body (N, global components; per pair ``pair_forces``), reaction force
of each support (N; where supports meet, each prescribed component's reaction goes to
the groups prescribing it, shared equally, :func:`~contactqvi.postprocess.reaction_forces`,
so it does not depend on the order of the groups), applied force (N) and the relative
equilibrium error of their sum with the rigid obstacles' forces, each body's force
balance (several bodies), contact/sticking/sliding areas (m^2, the slave facets by the
share of their nodes in each state, projected on the contact plane,
:func:`~contactqvi.contact.surface.contact_facet_areas`; at finite strain also on the deformed
surface), node counts per state (named for each pair's law), the contact pressure's facet and
nodal maxima, robust range and measure (:func:`~contactqvi.contact.surface.pressure_summary`),
the largest von Mises stress (Pa), the global l2 norm of u~ (m; the number demos print to
compare runs).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.contact.figures import plot_contact_states, plot_deformed_bodies
from contactqvi.contact.interface import MESHED_INTERFERENCE
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.contact.surface import (STATE_NAMES, UNITS, ContactSurface, contact_facet_areas, labelled,
                                        pressure_summary, state_names)
from contactqvi.lifetime import unwind_together
from contactqvi.paraview import MeshPiece, VTXDatasetWriter
from contactqvi.postprocess import StressFields, applied_force, reaction_forces
from contactqvi.records import warn
from contactqvi.tables import prepare_output_dir, write_solution_npz

__all__ = [
    "STATE_NAMES",
    "UNITS",
    "ContactResultsWriter",
    "contact_summary",
    "fit_separations",
    "warn_solved_fits",
    "write_contact_results",
]

logger = logging.getLogger(__name__)


def contact_summary(
    problem: ContactProblem,
    u: PETSc.Vec,
    result: SCDNewtonResult,
    von_mises: fem.Function | None = None,
    displacement: fem.Function | None = None,
) -> dict[str, typing.Any]:
    """Force balance, areas and extreme values of a solved step, with ``units``. Collective.

    Args:
        problem, u, result: the solved problem at its current step, its solution
            (shifted displacements) and the solver's result.
        von_mises: the von Mises field (DG0) if computed, for its maximum.
        displacement: the physical displacement of ``u`` if computed already.
    """
    comm = problem.comm
    if displacement is None:
        displacement = problem.physical_displacement(u, fem.Function(problem.V))
    reactions = reaction_forces(displacement, problem.body, problem.load_factor, problem.dirichlet_dofs_loc,
                                problem.nodal_contact_forces(result.normal_force, result.friction_force))
    applied = applied_force(problem.V.mesh, problem.body, problem.load_factor, displacement)
    finite_strain = problem.hyperelastic is not None
    resultants = contact_resultants(problem, result, displacement if finite_strain else None)
    obstacle_force = np.asarray(resultants["obstacle_force"])  # forces between bodies cancel in the sum
    total = sum(reactions.values(), np.zeros(3)) + obstacle_force + applied
    scale = max([np.linalg.norm(applied), np.linalg.norm(obstacle_force)]
                + [np.linalg.norm(r) for r in reactions.values()])
    summary = {
        "contact_force": resultants["contact_force"],
        "pair_forces": resultants["pair_forces"],
        "reaction_forces": {name: r.tolist() for name, r in reactions.items()},
        "applied_force": applied.tolist(),
        "equilibrium_error": float(np.linalg.norm(total) / scale) if scale > 0 else 0.0,
        "contact_area": resultants["contact_area"],
        "sticking_area": resultants["sticking_area"],
        "sliding_area": resultants["sliding_area"],
        "state_counts": _state_counts(problem, result.states),
        **pressure_summary(problem, result),
        "displacement_norm": displacement.x.petsc_vec.norm(),
    }
    if finite_strain:
        summary["deformed_contact_area"] = comm.allreduce(
            float(contact_facet_areas(problem, result.states, displacement, deformed=True).sum()), op=MPI.SUM)
    if problem.node_body is not None:
        summary["body_equilibrium_errors"] = _body_equilibrium(problem, reactions, resultants["pair_forces"],
                                                               displacement)
    if von_mises is not None:
        n_cells = von_mises.function_space.mesh.topology.index_map(3).size_local
        summary["max_von_mises"] = comm.allreduce(float(von_mises.x.array[:n_cells].max(initial=0.0)), op=MPI.MAX)
    summary["units"] = {name: UNITS[name] for name in summary if name in UNITS}
    return summary


def fit_separations(problem: ContactProblem, u: PETSc.Vec) -> dict[str, dict[str, float]]:
    """How far a solved step that takes up the whole fit pushed the surfaces of each body pair
    with a declared interference apart (m; docs/press_fit.md, "How wrong a faceted fit is").
    Collective.

    Per pair: ``overlap``, the mean overlap as meshed (:class:`~contactqvi.contact.interface.MeshedFit`);
    ``opening``, the mean gap after deformation of its slave nodes, sum_i D_ii g~_i / sum_i D_ii
    (g~_i the third component of the solver's variables ``u``, the weighted gap after deformation:
    0 where a node touches, > 0 where it was left open); ``separation``, their sum, the mean
    normal displacement of the slave surface relative to the master; ``declared``, the mean declared
    interference; ``pressure_error`` = ``separation`` / ``declared`` - 1. The problem is linear in
    the fit, so the pressures are those of the declared fit times 1 + ``pressure_error``.
    """
    gap_after = u.array.reshape(-1, 3)[problem.contact_blk, 2]
    out = {}
    for k, interface in enumerate(problem.interfaces):
        fit = interface.meshed_fit
        if fit is None:
            continue
        mine = problem.interface_of_node == k
        area = problem.comm.allreduce(float(problem.contact_area[mine].sum()), op=MPI.SUM)
        opening = problem.comm.allreduce(float(problem.contact_area[mine] @ gap_after[mine]), op=MPI.SUM) / area
        separation = fit.overlap + opening
        out[interface.pair.name] = {"overlap": fit.overlap, "opening": opening, "separation": separation,
                                    "declared": fit.declared, "pressure_error": separation / fit.declared - 1.0}
    return out


def warn_solved_fits(problem: ContactProblem, u: PETSc.Vec) -> None:
    """Warn (``solved_interference``, :func:`~contactqvi.records.warn`) for each pair of
    :func:`fit_separations` whose ``pressure_error`` exceeds
    :data:`~contactqvi.contact.interface.MESHED_INTERFERENCE` in size: the estimate of how far the
    pressures are off those of the declared fit. Collective."""
    for name, fit in fit_separations(problem, u).items():
        error = fit["pressure_error"]
        if abs(error) > MESHED_INTERFERENCE:
            warn(problem.comm, logger, "solved_interference",
                 f"{name}: the fit as solved pushed the surfaces apart by {fit['separation']:.4e} m on average, "
                 f"{100.0 * error:+.1f} % of the declared interference {fit['declared']:.4e} m (the overlap as "
                 f"meshed {fit['overlap']:.4e} m plus {fit['opening']:.4e} m of slave nodes left open where they "
                 f"cannot follow the master's facets): the contact pressures are about {100.0 * error:+.1f} % off "
                 "those of the declared fit; mesh in second-order tetrahedra (Mesh.ElementOrder = 2: curved "
                 "surfaces) or both surfaces in equal segments (docs/press_fit.md)", **fit)


def _state_counts(problem: ContactProblem, states: np.ndarray) -> dict[str, int]:
    """Number of contact nodes in each state, named for the law of each node's pair
    (:func:`~contactqvi.contact.surface.state_names`: a frictionless pair's touching nodes
    are "in contact", not "sliding"). Collective."""
    frictional = np.array([interface.pair.law.frictional for interface in problem.interfaces], dtype=bool)
    of_node = frictional[problem.interface_of_node]
    counts: dict[str, int] = {}
    for kind in sorted(set(frictional.tolist())):
        per_state = problem.comm.allreduce(np.bincount(states[of_node == kind].astype(np.int64), minlength=len(State)),
                                           op=MPI.SUM)
        for state, name in state_names(kind).items():
            counts[name] = counts.get(name, 0) + int(per_state[state])
    return counts


def _body_equilibrium(problem: ContactProblem, reactions: dict[str, np.ndarray],
                      pair_forces: dict[str, list[float]], displacement: fem.Function) -> dict[str, float]:
    """Relative force balance of each body (groups named ``"body.group"``): its tractions and
    pressures, its body force (``problem.body.body_force``, one per body: its weight), the reactions
    of its supports and the contact forces on it (a pair's force acts on its slave body
    and, opposite, on its master body)."""
    def body_of(group: str) -> str:
        return group.split(".", 1)[0]

    totals: dict[str, list[np.ndarray]] = {}
    msh, body = problem.V.mesh, problem.body
    loads = [(group, {"tractions": {group: traction}}) for group, traction in body.tractions.items()]
    loads += [(group, {"pressures": {group: value}}) for group, value in body.pressures.items()]
    if isinstance(body.body_force, dict):
        loads += [(name, {"body_force": {name: force}}) for name, force in body.body_force.items()]
    for group, load in loads:  # pressures on the deformed surface at finite strain
        alone = dataclasses.replace(body, **{"tractions": {}, "pressures": {}, "body_force": None, **load})
        totals.setdefault(body_of(group), []).append(applied_force(msh, alone, problem.load_factor, displacement))
    for group, reaction in reactions.items():
        totals.setdefault(body_of(group), []).append(np.asarray(reaction))
    for interface in problem.interfaces:
        force = np.asarray(pair_forces[interface.pair.name])
        totals.setdefault(body_of(interface.slave_surface), []).append(force)
        if interface.coupling is not None:
            totals.setdefault(body_of(interface.pair.master), []).append(-force)
    errors = {}
    for name, forces in totals.items():
        scale = max(np.linalg.norm(f) for f in forces)
        errors[name] = float(np.linalg.norm(np.sum(forces, axis=0)) / scale) if scale > 0 else 0.0
    return errors


class LastStep(typing.NamedTuple):
    """The fields of the last step a :class:`ContactResultsWriter` wrote (kept by it)."""

    displacement: fem.Function
    surface: ContactSurface
    von_mises: fem.Function


class ContactResultsWriter:
    """Writes the steps of a contact solve to ``body.bp`` and ``contact_surface.bp``.

    One call of :meth:`write` per (load) step, each a time step of both files
    (time = step number unless given). The body's piece, its stress fields and
    the contact surface (:class:`~contactqvi.contact.surface.ContactSurface`) are
    made at the first step and kept. Collective; use in a ``with`` block or call :meth:`close`.

    Args:
        out: output directory (created if needed).
        keep: continue the files of an earlier run of ``out`` after its first ``keep``
            steps (a restart, :class:`~contactqvi.paraview.VTXDatasetWriter`).

    Attributes:
        last: the displacement (u~), the contact surface and the von Mises stress of the
            last step written (:class:`LastStep`).
    """

    def __init__(self, out: str | os.PathLike, comm: MPI.Comm = MPI.COMM_WORLD, keep: int = 0):
        self.out = prepare_output_dir(comm, out)
        self.comm = comm
        self._body_file = VTXDatasetWriter(comm, self.out / "body.bp", keep)
        self._surface_file = VTXDatasetWriter(comm, self.out / "contact_surface.bp", keep)
        self._steps = keep
        self._problem: ContactProblem | None = None
        self.last: LastStep | None = None

    def _start(self, problem: ContactProblem) -> None:
        """What every step of ``problem`` writes into: made once."""
        self._problem = problem
        self._displacement = fem.Function(problem.V, name="displacement")
        self._stress = StressFields(self._displacement, problem.body.young, problem.body.poisson,
                                    problem.body.material, problem.body.nodal)
        self._body = MeshPiece(problem.V.mesh)
        self._surface = ContactSurface(problem)
        self._cell_data = {}
        if problem.node_body is not None:  # several bodies: each cell's body index (0, 1, ...)
            body = fem.Function(fem.functionspace(problem.V.mesh, ("DG", 0)), name="body")
            body.x.array[:] = problem.node_body[problem.V.dofmap.list[:, 0]]
            self._cell_data[labelled("body")] = body

    def write(
        self, problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult, t: float | None = None
    ) -> dict[str, typing.Any]:
        """Write one step; returns its :func:`contact_summary` entries."""
        t = float(self._steps if t is None else t)
        if problem is not self._problem:
            self._start(problem)
        displacement = problem.physical_displacement(u, self._displacement)
        stress, von_mises = self._stress.update()
        volume = self._body.dataset(
            {labelled("displacement"): displacement},
            {labelled("stress"): stress, labelled("von_mises"): von_mises, **self._cell_data},
        )
        self._body_file.write(volume, t)
        self._surface.update(u, result, displacement)
        self._surface_file.write(self._surface.dataset(), t)
        self._steps += 1
        self.last = LastStep(displacement, self._surface, von_mises)
        return contact_summary(problem, u, result, von_mises, displacement)

    def close(self, ok: bool = True) -> None:
        """Finish both files (collective); ``ok=False`` discards them."""
        self._body_file.close(ok)
        self._surface_file.close(ok)

    def __enter__(self) -> ContactResultsWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object) -> None:
        unwind_together(exc)
        self.close(ok=exc_type is None)


def write_contact_results(
    out: str | os.PathLike,
    problem: ContactProblem,
    u: PETSc.Vec,
    result: SCDNewtonResult,
    plot: bool = True,
    solution_npz: bool | None = None,
) -> dict[str, typing.Any]:
    """Write ``body.bp``, ``contact_surface.bp``, ``solution.npz``, ``contact_states.png`` and ``bodies.png``.

    Collective. ``solution.npz`` (gathered on rank 0) is written for at most
    :data:`~contactqvi.tables.GATHER_MAX_NODES` nodes when ``solution_npz`` is None,
    always when True, never when False; the PNGs (``plot``) for surfaces of at most
    as many nodes (:mod:`contactqvi.contact.figures`).

    Returns:
        The :func:`contact_summary` entries, with ``files`` (names written) and
        ``plot`` (whether the PNG was made) added.
    """
    with ContactResultsWriter(out, problem.comm) as writer:
        summary = writer.write(problem, u, result)
    displacement, surface, von_mises = writer.last
    files = ["body.bp", "contact_surface.bp"]
    if solution_npz is not False and write_solution_npz(writer.out / "solution.npz", displacement, bool(solution_npz)):
        files.append("solution.npz")
    if plot:
        summary["plot"] = plot_contact_states(writer.out / "contact_states.png", surface)
        if summary["plot"]:
            files.append("contact_states.png")
        if plot_deformed_bodies(writer.out / "bodies.png", displacement, von_mises, surface):
            files.append("bodies.png")
    summary["files"] = files
    return summary
