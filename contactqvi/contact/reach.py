"""Whether each contact pair can touch at all along a load path: checked before any solve.

A rigid obstacle whose normal points away from the body, or a contact group on the
wrong face, gives a pair that no slave node ever approaches: the load path then runs
to "converged" with zero contact force. :func:`check_reach` makes such a pair an error
before the first solve. A pair can never touch when, at every step, its smallest gap
(each obstacle at that step's position, :meth:`~contactqvi.contact.problem.ContactProblem.gap`)
exceeds :data:`REACH_MARGIN` times a bound on how far the step moves the bodies
(:func:`body_travel`): the prescribed displacements, the moved groups' rigid motion
and how deep the other pairs' obstacles reach into the bodies at rest. A force on a
body (traction, pressure, body force) can move it any distance: then nothing is
checked. Everything is reduced over the communicator; no surface is gathered.
"""

from __future__ import annotations

import dataclasses
import math
import typing

from mpi4py import MPI

import numpy as np

from contactqvi.contact.interface import Interface
from contactqvi.contact.load_path import step_position
from contactqvi.contact.problem import ContactProblem
from contactqvi.load_steps import LoadStep, placed
from contactqvi.parameters import ParameterError

__all__ = ["REACH_MARGIN", "body_travel", "check_reach"]

#: A pair can never touch when its smallest gap exceeds this times the bodies' travel:
#: elasticity has no maximum principle, and a node far from a support may move more than
#: the support itself (a lever), so the travel is a bound only up to such a factor.
REACH_MARGIN = 2.0


@dataclasses.dataclass(frozen=True)
class _Approach:
    """How near a pair's slave nodes come to what they may touch along the path.

    Attributes:
        gap: the smallest gap over the steps and the slave nodes (m; inf without nodes).
        step: index of the step at which it occurs.
    """

    gap: float
    step: int


def check_reach(problem: ContactProblem, steps: typing.Sequence[LoadStep], prescribed: float = 0.0,
                keys: typing.Sequence[tuple[str, str | None]] | None = None) -> None:
    """Raise unless every contact pair of ``problem`` can touch along ``steps``, whose prescribed
    displacements are at most ``prescribed`` (m, their largest length at load factor 1). Collective.

    Args:
        keys: each interface's key in the case file and its obstacle's
            (:attr:`~contactqvi.case.ContactCase.pair_keys`: ``("contacts[0]", "contacts[0].obstacle")``),
            which the error names; None: the pairs' names (``top/obstacle``) and ``obstacle``.

    Raises:
        ParameterError: named by the pair's key (``contact``, ``contacts[0]``): the pair
            (``top/obstacle``), its smallest gap and the step of it, the obstacle's travel, the
            bodies' travel and the likely cause (an obstacle facing away from the body, a
            contact group on the wrong face).
    """
    base = body_travel(problem, steps, prescribed) if steps else None
    if base is None:
        return
    assert keys is None or len(keys) == len(problem.interfaces), "a key for each interface"
    approaches = [_approach(problem, steps, k) for k in range(len(problem.interfaces))]
    pushes = [max(0.0, -a.gap) for a in approaches]
    for k, (interface, approach) in enumerate(zip(problem.interfaces, approaches)):
        travel = base + sum(push for j, push in enumerate(pushes) if j != k)
        if math.isfinite(approach.gap) and approach.gap > REACH_MARGIN * travel:
            key, obstacle = keys[k] if keys is not None else (interface.pair.name, "obstacle")
            pair = f" {interface.pair.name}" if keys is not None else ""  # else the error's name
            raise ParameterError(key, f"the pair{pair} can never touch: "
                                 + _never_text(problem, steps, interface, approach, travel,
                                               _CaseKeys(obstacle, key if keys is not None else None)))


def body_travel(problem: ContactProblem, steps: typing.Sequence[LoadStep], prescribed: float = 0.0) -> float | None:
    """A bound (m) on how far ``steps`` move the bodies' nodes by prescribed displacements (at most
    ``prescribed`` m at load factor 1) and the moved groups' rigid motion, or None when a force
    acts on a body (unbounded). Collective."""
    loads = [step.load for step in steps]
    if max(loads) > 0.0 and _forces(problem):
        return None
    travel = prescribed * max(loads)
    if problem.translated:
        radius = _radius(problem, steps)
        travel += max(float(np.linalg.norm(step.translation)) + _chord(step, radius) for step in steps)
    return travel


def _forces(problem: ContactProblem) -> bool:
    """Whether a traction, pressure or body force of ``problem`` is nonzero."""
    body = problem.body
    forces = list(body.tractions.values()) + [[p] for p in body.pressures.values()]
    if isinstance(body.body_force, dict):
        forces += list(body.body_force.values())
    elif body.body_force is not None:
        forces.append(body.body_force)
    return any(np.any(np.asarray(force, dtype=float) != 0.0) for force in forces)


def _radius(problem: ContactProblem, steps: typing.Sequence[LoadStep]) -> float:
    """The largest distance (m) of a node from the rotations' centre (0 without rotations)."""
    rotation = next((step.rotation for step in steps if step.rotation is not None), None)
    if rotation is None:
        return 0.0
    x = problem.V.mesh.geometry.x
    local = float(np.linalg.norm(x - np.asarray(rotation.centre), axis=1).max(initial=0.0))
    return problem.comm.allreduce(local, op=MPI.MAX)


def _chord(step: LoadStep, radius: float) -> float:
    """The largest displacement (m) of a point within ``radius`` of the centre by the step's rotation."""
    return 0.0 if step.rotation is None else 2.0 * radius * abs(math.sin(math.radians(step.rotation.angle) / 2.0))


def _approach(problem: ContactProblem, steps: typing.Sequence[LoadStep], k: int) -> _Approach:
    """The smallest gap of the slave nodes of interface ``k`` over ``steps``, the bodies at rest."""
    interface = problem.interfaces[k]
    gaps = [problem.comm.allreduce(float(interface.gap(interface.position, np.asarray(step.translation, dtype=float), step.rotation,
                                                       step.fit_fraction).min(initial=np.inf)), op=MPI.MIN)
            for step in steps]
    step = int(np.argmin(gaps))
    return _Approach(gaps[step], step)


class _CaseKeys(typing.NamedTuple):
    """The keys a likely cause names: the obstacle's (``contacts[0].obstacle``; None for a body
    pair) and the pair's (``contacts[0]``, ``contact``; None: none, the Python API)."""

    obstacle: str | None
    pair: str | None

    def group(self, side: str) -> str | None:
        """The key that selects the pair's ``side`` ("slave", "master") group: ``contacts[0].slave``,
        [contact]'s ``contact.surface``; None without keys."""
        if self.pair is None:
            return None
        return "contact.surface" if self.pair == "contact" else f"{self.pair}.{side}"


def _never_text(problem: ContactProblem, steps: typing.Sequence[LoadStep], interface: Interface,
                approach: _Approach, travel: float, keys: _CaseKeys) -> str:
    """Why a pair can never touch: gap, travels, likely cause (naming the keys to change)."""
    obstacle = interface.obstacle is not None
    moved = max(float(np.linalg.norm(step.translation)) for step in steps)
    turned = max(abs(step.rotation.angle) if step.rotation is not None else 0.0 for step in steps)
    travels = f"; the obstacle travels up to {moved:.4g} m" if obstacle else ""
    travels += f" and turns up to {turned:g} degrees" if obstacle and turned else ""
    return (f"no node of {interface.slave_surface!r} comes nearer than {approach.gap:.4g} m "
            f"to {'the obstacle' if obstacle else 'the master surface'} in the {len(steps)} load steps (the smallest "
            f"gap, at step {approach.step + 1}{travels}), and nothing moves the bodies more than {travel:.4g} m "
            "(prescribed displacements, moved groups, the other pairs; no force acts). "
            f"Likely cause: {_cause(problem, steps[approach.step], interface, approach.gap, keys)}")


def _cause(problem: ContactProblem, step: LoadStep, interface: Interface, gap: float, keys: _CaseKeys) -> str:
    """Why a pair's slave nodes stay ``gap`` away at ``step``: an obstacle facing away from the
    slave body (part of it lies behind the obstacle's surface), nodes off the contact group nearer
    to the obstacle than it (a wrong group), or an obstacle placed away from the body."""
    if interface.obstacle is None:
        groups = "the slave or the master surface"
        if keys.pair is not None:
            groups = f"{keys.group('slave')} or {keys.group('master')}"
        return f"a wrong group ({groups}), or a load or a motion missing that brings the surfaces together"
    comm = problem.comm
    n_owned = problem.V.dofmap.index_map.size_local
    x = problem.V.tabulate_dof_coordinates()[:n_owned]
    if problem.node_body is not None:  # the slave's body only
        slave_body = np.zeros(comm.allreduce(int(problem.node_body.max(initial=-1)) + 1, op=MPI.MAX), dtype=bool)
        slave_body[problem.node_body[interface.blk]] = True
        comm.Allreduce(MPI.IN_PLACE, slave_body, op=MPI.LOR)  # (allreduce of the pickled array: a bool)
        x = x[slave_body[problem.node_body[:n_owned]]]
    distance = placed(interface.obstacle, step.translation, step.rotation).distance(x)[0]
    behind = comm.allreduce(int(np.count_nonzero(distance < -1e-12 * max(gap, 1e-300))), op=MPI.SUM)
    total = comm.allreduce(len(distance), op=MPI.SUM)
    deepest = comm.allreduce(float(distance.min(initial=np.inf)), op=MPI.MIN)
    if behind:
        return (f"the obstacle faces away from the body: {behind} of its {total} nodes lie behind the obstacle's "
                f"surface (signed distance down to {deepest:.4g} m, at {step_position(step)}); a plane's normal "
                f"must point into the body's side (flip {keys.obstacle}.normal)")
    if deepest < gap:
        where = "" if keys.pair is None else f" in {keys.group('slave')}"
        return (f"a wrong contact group: nodes of the body off {interface.slave_surface!r} come within "
                f"{deepest:.4g} m of the obstacle, nearer than the group; name the face that meets it{where}")
    return "the obstacle is placed (point, translation) away from the body, or moves away from it"
