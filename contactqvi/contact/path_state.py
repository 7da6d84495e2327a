"""The state of a quasi-static load path between two steps: all that a step reads from the step before.

A load step of :func:`~contactqvi.contact.load_path.solve_load_path` depends on the
steps before it only through a :class:`PathState`, which the path updates after each
converged step (:meth:`PathState.record`) and a checkpoint writes and reads whole
(:mod:`contactqvi.contact.checkpoint`), so that a restart continues with exactly the
state the uninterrupted run had. What each field is read for:

==================  ===========================================================================
field               read by
==================  ===========================================================================
``done``            the load path: the next step to solve
``solved``          the first solve starts from the given guess (or rest), any later one from
                    the predictor
``load``,           :meth:`~contactqvi.contact.problem.ContactProblem.set_step` of the next step:
``translation``,    the obstacles' surface motion since the step before (its slip reference
``rotation``,       on a rigid obstacle: the displacement of the obstacle's material points,
``fit``             :func:`~contactqvi.load_steps.rigid_increment`), and the search of a pair
                    searched each step (the obstacles' position there): the
                    prescribed and moved parts of ``displacement`` at the step before (the
                    moved groups' rigid motion (Q - I)(X - c) + t) and the interference it
                    had resolved; a cut step (``max_cuts``) starts its parts from them
``variables``       the next step's slip reference and predictor (``_continue``); a problem
                    searched each step recomputes it from ``displacement`` after its search
``displacement``    the configuration x + u~ in which pairs searched each step are searched
                    before the next step; with ``until_settled``, the reference of the next
                    step's increment (``_settle``)
``node_states``     the predictor: touching nodes start the next step without a slip increment
                    where it is not extrapolated
``target``          the stopping target ||y^|| of every later step (the first step's)
``increment``,      the predictor of a hyperelastic body's step that continues the last solve:
``stride``          the last solve's change of the displacement, extrapolated along its change
                    of load, translation and rotation (:meth:`PathState.extrapolation`)
==================  ===========================================================================

The Newton-step solver's preconditioner is not part of the state: it is solver data,
set up again by a restarted run (a direct solver, or one set up per Newton step, gives
the restarted run bitwise; a multigrid hierarchy kept between steps agrees with the
uninterrupted run's to round-off, so its Krylov counts may differ by one).
"""

from __future__ import annotations

import dataclasses
import typing

from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult
from contactqvi.lifetime import PETScOwner
from contactqvi.load_steps import Rotation

__all__ = ["PathState"]


@dataclasses.dataclass
class PathState(PETScOwner):
    """A load path after its first ``done`` steps, which converged.

    Attributes:
        done: number of converged steps.
        solved: number of converged solves: the steps and the parts of cut steps.
        load: load factor of the last converged solve (0 at rest): step ``done``, or a part
            of the step after it when that step was cut.
        translation: total translation of the obstacles and moved groups there (m).
        rotation: total rotation of the obstacles and moved groups there
            (:class:`~contactqvi.load_steps.Rotation`), None: none.
        variables: u~ = u - d of step ``done`` in the problem's current solver variables.
        displacement: u~ of step ``done`` in global components (m; ghosts updated).
        node_states: :class:`~contactqvi.contact.nodal.State` of each local node (ghosts
            included) at step ``done``; -1 where it was no contact node.
        target: the first step's stopping target ||y^|| (N); 0 before it.
        fit: the fraction of the declared interferences resolved there (0 at rest).
        increment: the change of u~ in the last converged solve (m; zero at rest).
        stride: the change of (load factor, translation (m), rotation vector (rad)) in it, (7,).
    """

    done: int
    solved: int
    load: float
    translation: np.ndarray
    variables: PETSc.Vec
    displacement: fem.Function
    node_states: np.ndarray
    target: float
    rotation: Rotation | None = None
    fit: float = 0.0
    increment: fem.Function | None = None
    stride: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(7))

    def __post_init__(self) -> None:
        if self.increment is None:
            self.increment = fem.Function(self.displacement.function_space, name="increment")

    @classmethod
    def at_rest(cls, problem: ContactProblem) -> PathState:
        """The state before the first step: the bodies at rest, the obstacles where meshed."""
        index_map = problem.V.dofmap.index_map
        return cls(done=0, solved=0, load=0.0, translation=np.zeros(3), variables=problem.A.createVecRight(),
                   displacement=fem.Function(problem.V, name="displacement"),
                   node_states=np.full(index_map.size_local + index_map.num_ghosts, -1, dtype=np.int8), target=0.0)

    def petsc_objects(self) -> list[typing.Any]:
        return [self.variables]

    def record(self, problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult, complete: bool = True) -> None:
        """The state after the step just solved: ``problem`` set at that step, ``u`` its
        solution (shifted, solver variables), ``result`` its converged result; ``complete``:
        a whole load step, not a part of a cut one."""
        self.done += int(complete)
        self.solved += 1
        before = self.position
        self.increment.x.array[:] = -self.displacement.x.array
        self.load, self.translation = problem.load_factor, problem.translation.copy()
        self.rotation, self.fit = problem.step_rotation, problem.fit
        self.variables.waxpy(-1.0, problem.shift, u)
        problem.physical_displacement(u, self.displacement)
        self.increment.x.array[:] += self.displacement.x.array
        self.stride = self.position - before
        self.node_states[:] = -1
        self.node_states[problem.contact_blk] = result.states
        if self.solved == 1:
            self.target = result.target

    @property
    def position(self) -> np.ndarray:
        """(7,) load factor, translation (m) and rotation vector (rad) of the last converged solve."""
        return _position(self.load, self.translation, self.rotation)

    def extrapolation(self, load: float, translation: typing.Sequence[float], rotation: Rotation | None,
                      turns_only: bool) -> float:
        """The factor of :attr:`increment` that extrapolates the last solve to a step to ``load``,
        ``translation`` and ``rotation``: its change along the last solve's :attr:`stride`, relative
        to it (0 at rest or for a step that does not continue it; a fit over several steps is not
        extrapolated). The predictor
        u~ + factor x increment is the linear extrapolation of Abaqus/Standard's default and of
        Code_Aster's ``PREDICTION = 'EXTRAPOLE'``; a node that turns is turned on (:meth:`extrapolated`).
        ``turns_only``: only a stride that turns is extrapolated (the predictor of pairs searched
        ``"newton"``, whose alternative is the tangent's response): a rigid turn moves every node
        alike from one step to the next, while under a die that slides the displacement field is no
        translate of its last increment (the shipped ironing's slide steps took 24-127 Newton steps
        and cuts extrapolated, 19-30 without; docs/finite_strain.md Sect. 14)."""
        length = float(self.stride @ self.stride)
        if length == 0.0 or (turns_only and not self.stride[4:].any()):
            return 0.0
        change = _position(load, translation, rotation) - self.position
        return max(float(change @ self.stride) / length, 0.0)

    def extrapolated(self, factor: float, translation: typing.Sequence[float], rotation: Rotation | None,
                     points: np.ndarray) -> np.ndarray:
        """The predictor u~ (local nodes, (N, 3)) of a step to ``translation``, ``rotation`` that continues
        the last solve's turn, :meth:`extrapolation`'s ``factor`` of its stride; ``points`` the nodes'
        reference positions X. With x = X + u~, a node is either extrapolated linearly,
        x_n + factor (x_n - x_{n-1}), or turned on with the moved groups,

            x_pred = Q_next (x_n - c - t_n + factor s) + c + t_next,
            s = x_n - (Q_last (x_{n-1} - c - t_{n-1}) + c + t_n),

        Q_last and Q_next the turns of the last solve and of this step (Q_next = Q Q_n^T), c the centre,
        t the translations, s the part of the last increment the turn does not explain: whichever of s
        and the increment is the smaller at that node. A node turned rigidly is predicted exactly, a node
        at rest stays; extrapolated linearly, a 9-degree turn's chord left the rim of the turned blocks
        2.5 cm off its arc (docs/finite_strain.md Sect. 14). A path without rotation (``rotation`` None)
        translates: a node carried by the moved groups or an obstacle is moved on with them."""
        rotation = Rotation() if rotation is None else rotation
        centre = np.asarray(rotation.centre, dtype=float)
        t_last = np.asarray(self.translation, dtype=float) - self.stride[1:4]
        last = _turn(self.position[4:]) @ _turn(self.position[4:] - self.stride[4:]).T
        x = points + self.displacement.x.array.reshape(-1, 3)
        increment = self.increment.x.array.reshape(-1, 3)
        rest = x - ((x - increment - centre - t_last) @ last.T + centre + self.translation)
        turned = self.turned(translation, rotation, points, factor * rest) + points
        linear = x + factor * increment
        rigid = np.linalg.norm(rest, axis=1) < np.linalg.norm(increment, axis=1)
        return np.where(rigid[:, None], turned, linear) - points

    def turns_to(self, rotation: Rotation | None) -> bool:
        """Whether a step to ``rotation`` turns the moved groups on from the last solve."""
        return bool(np.any(_position(0.0, np.zeros(3), rotation)[4:] != self.position[4:]))

    def turned(self, translation: typing.Sequence[float], rotation: Rotation | None, points: np.ndarray,
               along: np.ndarray | float = 0.0) -> np.ndarray:
        """u~ (local nodes, (N, 3)) of the last solve turned on rigidly with the moved groups to a step
        to ``translation``, ``rotation``: x_pred = Q_next (x_n - c - t_n + ``along``) + c + t_next
        (:meth:`extrapolated`'s turned node; ``points`` the reference positions X)."""
        rotation = Rotation() if rotation is None else rotation
        centre = np.asarray(rotation.centre, dtype=float)
        next_ = rotation.matrix() @ _turn(self.position[4:]).T
        x = points + self.displacement.x.array.reshape(-1, 3)
        moved = (x - centre - self.translation + along) @ next_.T + centre + np.asarray(translation, dtype=float)
        return moved - points

    def contact_states(self, problem: ContactProblem) -> np.ndarray:
        """The states of ``problem``'s contact nodes (a node without one is not in contact)."""
        states = self.node_states[problem.contact_blk]
        return np.where(states < 0, State.NO_CONTACT, states).astype(np.int8)


def _turn(vector: np.ndarray) -> np.ndarray:
    """Q of a rotation vector (angle times axis, rad)."""
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return np.eye(3)
    return Rotation(tuple(vector / angle), np.degrees(angle)).matrix()


def _position(load: float, translation: typing.Sequence[float], rotation: Rotation | None) -> np.ndarray:
    """(7,) a step's load factor, translation (m) and rotation vector (angle times axis, rad)."""
    turn = np.zeros(3) if rotation is None else np.radians(rotation.angle) * np.asarray(rotation.axis, dtype=float)
    return np.array([load, *translation, *turn])
