"""Why a load step did not converge, in words and numbers, for the log and ``summary.json``.

A status (``diverged_line_search``) says what the solver saw, not why: a block pushed
sideways past what friction holds ended in a bare ``diverged_line_search`` (issue 46).
:func:`failure_cause` names the cause: for a step whose Newton iteration stalled (no
step size accepted, or out of iterations) with every node of a frictional pair that
touches sliding at its bound, it compares the load along the pair's contact plane that
no support takes with what friction holds at the iterate's normal force; otherwise it
states the status's own cause with the numbers of the last Newton step and, for a step cut
until its cuts ran out, how far its parts got and the nearest attempt beyond that failed (the
path's likely end at a limit point, docs/finite_strain.md Sect. 11). Collective.
"""

from __future__ import annotations

import dataclasses
import typing

from mpi4py import MPI

import numpy as np

from contactqvi.contact.interface import Interface
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.postprocess import ElasticBody, applied_force
from contactqvi.result import Status

__all__ = ["failure_cause", "tangential_load"]

#: Statuses of a Newton iteration that ran without getting near the solution.
STALLED = (Status.DIVERGED_LINE_SEARCH, Status.DIVERGED_MAX_IT, Status.DIVERGED_STALLED)
#: A node that changed its contact state this often in a solve that stalled is named in its cause.
CYCLING = 5
#: States of a touching node that friction holds in place.
HOLDING = (State.STICKING, State.WEAK_STICKING, State.WEAK_CONTACT_STICKING)


def failure_cause(problem: ContactProblem, result: SCDNewtonResult) -> str | None:
    """The cause of a step that did not converge (None if it did), ``problem`` at that step. Collective."""
    if result.converged:
        return None
    relaxation = _relaxation_end(result)
    if relaxation is not None:
        return relaxation
    if result.status in STALLED:
        for k in range(len(problem.interfaces)):
            overload = _friction_overload(problem, result, k)
            if overload is not None:
                return overload
    stalled = result.status in STALLED
    return _status_cause(result) + (_cycling(problem, result) + _path_end(result) if stalled else "")


def _relaxation_end(result: SCDNewtonResult) -> str | None:
    """Why a step that relaxed past a limit point (its history's ``relaxation`` marks,
    :mod:`contactqvi.contact.relaxation`) ended without an equilibrium; None if it did not relax or
    was interrupted."""
    relaxed = [entry for entry in result.history if "relaxation" in entry]
    if not relaxed or result.status == Status.INTERRUPTED:
        return None
    plain = len({entry["substep"] for entry in relaxed if entry["viscosity"] == 0.0})
    tried = "it never slowed down to a tenth of its largest move"
    if plain:
        tried = f"{plain} solve{'s' * (plain > 1)} without the viscous term from where it slowed down failed"
    return (f"the step stalled (or failed with its cuts used up), and the body relaxed past the limit point for "
            f"{relaxed[-1]['relaxation']} steps without reaching an equilibrium: {tried} "
            "(docs/finite_strain.md, Sect. 15)")


def _path_end(result: SCDNewtonResult) -> str:
    """Where the parts of a cut step stopped (from the history's ``substep`` marks of
    :func:`~contactqvi.contact.load_path.solve_load_path`): the last converged part and the
    nearest attempt beyond it, which failed; "" for a step that was not cut."""
    parts = {entry["substep"]: entry for entry in result.history if "substep_status" in entry}
    done = [j for j, entry in parts.items() if entry["substep_status"].startswith("converged")]
    failed = [entry for j, entry in parts.items() if j > max(done, default=-1)]
    if len(parts) < 2 or not failed:
        return ""
    start = parts[max(done)] if done else None

    def position(entry: dict) -> str:
        return (f"load factor {entry['substep_load']:.7g}, translation "
                f"({', '.join(f'{t:.7g}' for t in entry['substep_translation'])}) m")

    def distance(entry: dict) -> float:
        if start is None:
            return abs(entry["substep_load"])
        moved = np.subtract(entry["substep_translation"], start["substep_translation"])
        return float(np.linalg.norm(moved)) + abs(entry["substep_load"] - start["substep_load"])

    nearest = min(failed, key=distance)
    reached = "no part of the step converged" if start is None else f"its parts converged up to {position(start)}"
    return (f"; {len(failed)} attempts failed after the step was cut: {reached}, and the nearest attempt "
            f"beyond, to {position(nearest)}, failed too. A path that cannot move on by so little most likely "
            "ends at a limit point of the quasi-static problem, where no equilibrium lies near the last one "
            "(a snap, or a frictional stick-slip event: docs/finite_strain.md, Sect. 11); for a hyperelastic "
            "body, solver.limit_points = \"relax\" goes on through the snap (Sect. 15)")


def _cycling(problem: ContactProblem, result: SCDNewtonResult) -> str:
    """The contact nodes that changed their state back and forth in the last solve (at least
    :data:`CYCLING` times), the most changing one by its place, pair and two states; "" if none.

    Measured: the strip on its steel base searched ``"newton"`` (docs/finite_strain.md Sect. 19)
    stalls at 21 % with one node near the strip's bottom corner changing between no contact and
    sliding at every Newton step, with gaps of 1e-8 ... 3e-7 m and forces of 1e-4 N: a node where the
    contact ends, which the nearby iterates put on either side."""
    comm = problem.comm
    if comm.allreduce(len(result.switches) != len(problem.contact_blk), op=MPI.LOR):
        return ""
    many = comm.allreduce(int(np.count_nonzero(result.switches >= CYCLING)), op=MPI.SUM)
    if many == 0:
        return ""
    i = int(np.argmax(result.switches)) if len(result.switches) else -1
    count, owner = comm.allreduce((int(result.switches[i]) if i >= 0 else -1, comm.rank), op=MPI.MAXLOC)
    node = None
    if comm.rank == owner:
        pair = problem.interfaces[problem.interface_of_node[i]].pair
        x = problem.V.tabulate_dof_coordinates()[problem.contact_blk[i]]
        node = (x, pair.name, State(result.switched_from[i]).name, State(result.states[i]).name)
    x, pair, before, now = comm.bcast(node, root=owner)
    others = f" ({many - 1} other node{'s' * (many > 2)} {CYCLING} times or more)" if many > 1 else ""
    return (f"; the contact state cycles: the node at {_point(x)} m of {pair} changed its "
            f"state {count} times in its last {result.history[-1]['k']} Newton steps, between "
            f"{before.lower().replace('_', ' ')} and {now.lower().replace('_', ' ')}{others}")


def _point(x: np.ndarray) -> str:
    """``(x, y, z)`` to six digits, a coordinate below 1e-9 of the point's distance from the origin
    written 0 (a mesh's round-off, 2e-20 m on a plane z = 0)."""
    return f"({', '.join(f'{c:.6g}' for c in np.where(np.abs(x) > 1e-9 * np.linalg.norm(x), x, 0.0))})"


def _status_cause(result: SCDNewtonResult) -> str:
    """What the status means, with the last Newton step's numbers."""
    last = result.history[-1] if result.history else {}
    k, norm = last.get("k", 0), last.get("residual", float("nan"))
    where = f"||y^|| = {norm:.3e} N at Newton step {k}, {last.get('relative_residual', float('nan')):.2e} of the start"
    causes = {
        Status.DIVERGED_LINE_SEARCH: f"the line search accepted no step size ({where}; target {result.target:.3e} N)",
        Status.DIVERGED_MAX_IT: (f"the configuration did not settle in its searches ({where})" if norm <= result.target
                                 else f"out of Newton steps ({where}; target {result.target:.3e} N)"),
        Status.DIVERGED_LINEAR_SOLVE: (f"the linear solve of Newton step {k} failed: {last.get('ksp_reason')} after "
                                       f"{last.get('krylov_iterations')} Krylov iterations"
                                       + (f", and the direct solve after it: {last['direct_reason']}"
                                          if "direct_reason" in last else "")),
        Status.DIVERGED_FUNCTION_DOMAIN: ("the residual is undefined at the step's initial guess: an element is "
                                          "inverted (det F <= 0), or a deformed contact facet leaves the contact "
                                          "geometry undefined (the log says so); take smaller load steps "
                                          "(solver.max_cuts)"),
        Status.DIVERGED_STALLED: f"stalled: ||y^|| did not halve over the last Newton steps ({where}; target "
                                 f"{result.target:.3e} N)",
        Status.INTERRUPTED: "stopped from outside (SIGTERM, SIGINT) or after the step asked for (--stop-after)",
    }
    return causes.get(result.status, str(result.status))


def _friction_overload(problem: ContactProblem, result: SCDNewtonResult, k: int) -> str | None:
    """The cause text when every touching node of frictional pair ``k`` slides and the load along
    its contact plane exceeds the friction bound at the iterate's normal force, else None."""
    interface = problem.interfaces[k]
    if not interface.pair.law.frictional or len(result.states) != len(problem.contact_blk):
        return None
    comm = problem.comm
    mine = problem.interface_of_node == k
    states = result.states[mine]
    sliding = comm.allreduce(int(np.count_nonzero(states == State.SLIDING)), op=MPI.SUM)
    holding = comm.allreduce(int(np.count_nonzero(np.isin(states, HOLDING))), op=MPI.SUM)
    if sliding == 0 or holding > 0:
        return None
    normal_force = comm.allreduce(float(result.normal_force[mine].sum()), op=MPI.SUM)
    bound = comm.allreduce(float(problem.law.bound(result.normal_force)[mine].sum()), op=MPI.SUM)
    load = tangential_load(problem, k)
    if load <= bound or normal_force <= 0.0:
        return None
    return (f"no equilibrium: the tangential load exceeds μ × the normal force on pair {interface.pair.name}: the "
            f"loads on {_body_name(problem, interface)} that no support takes push along the contact plane with "
            f"{load:.4g} N, and friction holds at most {bound / normal_force:.4g} × {normal_force:.4g} N = "
            f"{bound:.4g} N there ({sliding} nodes of {interface.slave_surface!r} slide at their bound, none "
            "sticks); lower the tangential load, raise the friction or hold the body along the plane")


def tangential_load(problem: ContactProblem, k: int) -> float:
    """The resultant (N) of the tractions, pressures and body force at the current load factor on the
    slave body of interface ``k``, its components that a support of that body prescribes left out,
    along the pair's contact plane (normal to the area-weighted mean of its nodes' normals). Collective."""
    comm, interface = problem.comm, problem.interfaces[k]
    name = None if problem.node_body is None else interface.slave_surface.split(".", 1)[0]
    body = _loads_of(problem.body, name)
    force = applied_force(problem.V.mesh, body, problem.load_factor)
    force[list(_held(body))] = 0.0
    mine = problem.interface_of_node == k
    normal = comm.allreduce(problem.contact_area[mine] @ problem.frames[mine, 2], op=MPI.SUM)
    normal = normal / np.linalg.norm(normal)
    return float(np.linalg.norm(force - (force @ normal) * normal))


def _loads_of(body: ElasticBody, name: str | None) -> ElasticBody:
    """``body`` with the loads and supports of the body ``name`` only (groups ``"name.group"``;
    None: one body, all of them)."""
    if name is None:
        return body

    def own(groups: dict[str, typing.Any]) -> dict[str, typing.Any]:
        return {group: value for group, value in groups.items() if group.split(".", 1)[0] == name}

    force = body.body_force
    force = force.get(name) if isinstance(force, dict) else force
    return dataclasses.replace(body, tractions=own(body.tractions), pressures=own(body.pressures),
                               body_force=None if force is None else {name: force},
                               supports=tuple(own(dict.fromkeys(body.supports))),
                               prescribed=own(body.prescribed))


def _held(body: ElasticBody) -> set[int]:
    """The components (0, 1, 2) some support of ``body`` prescribes (a support not listed in
    ``prescribed``: all three)."""
    return set().union(*(body.prescribed.get(support, (0, 1, 2)) for support in body.supports))


def _body_name(problem: ContactProblem, interface: Interface) -> str:
    """The slave body in a message."""
    return "the body" if problem.node_body is None else f"the body {interface.slave_surface.split('.', 1)[0]!r}"
