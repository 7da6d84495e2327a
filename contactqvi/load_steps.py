"""Load steps of a quasi-static path, and the time points of a dynamic one: problem data shared by
case files, the load-path solver and the time integration.

A step moves the groups ``boundary.moved`` and the rigid obstacles together rigidly: by a
translation t and, optionally, a rotation Q about a centre c, both total from the initial
position, first the rotation about c, then the translation,

    x = phi(X) = Q (X - c) + c + t,   u = (Q - I)(X - c) + t   at the moved nodes X,

which is linear in t and in the nine entries of Q - I (docs/finite_strain.md, "Prescribed
rotations"); an obstacle's points and directions go along (:func:`placed`). The centre is a
point fixed in space for the whole path: every step that rotates names the same one
(:func:`check_steps`).

With ``[dynamics]`` each step is a time point (its ``time``, s): the load factor and the
translation are linear in time between the points, from load factor 0 and no translation at
t = 0 (unless a point is at t = 0), and constant after the last (:func:`at_time`,
docs/dynamics.md Sect. 1).
"""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np

from contactqvi.obstacles import Obstacle
from contactqvi.parameters import require, require_positive

__all__ = ["SEARCHES", "LoadStep", "Rotation", "at_time", "check_fit", "check_rotation", "check_steps", "finite_vector",
           "initial_points", "interpolated", "placed", "placed_points", "rigid_increment", "rotates"]

#: When a contact pair is searched along the load path: before every load step
#: after the first, in the configuration the step before ended in; as that, and again
#: after each step in the configuration it reached, the step solved again until that
#: configuration settles; inside the Newton iteration, the geometry a function of the
#: iterate (``newton``, hyperelastic bodies); or once, in the reference configuration
#: (:class:`~contactqvi.contact.interface.BodyPair`, :class:`~contactqvi.contact.interface.ObstaclePair`).
SEARCHES = ("every_step", "until_settled", "newton", "once")


@dataclasses.dataclass(frozen=True)
class Rotation:
    """A rigid rotation of the moved groups and the rigid obstacles, total from the initial position.

    Attributes:
        axis: direction of the axis (normalised by :func:`check_rotation`).
        angle: angle in degrees, right-handed about ``axis``.
        centre: a point on the axis (m), the same for every step of a path.
    """

    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    angle: float = 0.0
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def matrix(self) -> np.ndarray:
        """Q of the rotation (Rodrigues' formula)."""
        a = np.asarray(self.axis, dtype=float)
        a = a / np.linalg.norm(a)
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        theta = math.radians(self.angle)
        return np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * K @ K


@dataclasses.dataclass(frozen=True)
class LoadStep:
    """One step of a load path.

    Attributes:
        load: factor on tractions, body force and prescribed displacements.
        translation: total rigid translation (m) of the obstacles, and of the groups
            moved with them, from their initial position.
        rotation: total rigid rotation of the obstacles and the moved groups from their
            initial position (about its centre, then translated: x = Q (X - c) + c + t);
            None: none.
        fit: the fraction in [0, 1] of the contact pairs' declared interferences resolved at
            this step: the gap is g + (1 - fit) δ(x) (docs/press_fit.md, "A fit over several
            steps"); None: 1, the whole fit (not scaled by ``load``).
        time: the time (s) at which the step's values hold, with ``[dynamics]`` only
            (:func:`at_time`); None on a quasi-static path.
    """

    load: float = 1.0
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: Rotation | None = None
    fit: float | None = None
    time: float | None = None

    @property
    def fit_fraction(self) -> float:
        """``fit``, 1 when not given."""
        return 1.0 if self.fit is None else self.fit

    def summary(self) -> dict[str, typing.Any]:
        """The load factor, translation and rotation (if any) as a step of ``summary.json`` records
        them (a time step at its time: the obstacles' place drawn in ParaView's views over time)."""
        entry = {"load": self.load, "translation": list(self.translation)}
        if self.rotation is not None:
            entry["rotation"] = dataclasses.asdict(self.rotation)
        return entry


def at_time(steps: typing.Sequence[LoadStep], time: float) -> LoadStep:
    """The load factor, translation and rotation at ``time`` (s) of the time points ``steps``
    (their ``time`` increasing): linear between the points (the rotation as a cut step's,
    :func:`interpolated`), through load factor 0, no translation and no rotation at t = 0
    unless the first point is at 0, constant after the last point. Steps without times (the
    default path of one step) hold from t = 0: constant loads."""
    if steps[0].time is None:
        return dataclasses.replace(steps[0], time=time)
    points = list(steps) if steps[0].time == 0.0 else [LoadStep(0.0, time=0.0), *steps]
    times = np.array([point.time for point in points], dtype=float)
    values = np.array([[point.load, *point.translation] for point in points], dtype=float)
    load, *translation = (float(np.interp(time, times, column)) for column in values.T)
    k = min(int(np.searchsorted(times, time, side="right")) - 1, len(points) - 1)
    rotation = points[k].rotation if k == len(points) - 1 else interpolated(
        points[k].rotation, points[k + 1].rotation, (time - times[k]) / (times[k + 1] - times[k]))
    return LoadStep(load, tuple(translation), rotation, time=float(time))


def finite_vector(value: typing.Any, name: str) -> tuple[float, float, float]:
    """``value`` as 3 floats; :class:`~contactqvi.parameters.ParameterError` ``name`` unless 3 finite numbers."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        array = np.empty(0)
    require(array.shape == (3,) and bool(np.all(np.isfinite(array))), name,
            f"must be 3 finite numbers [x, y, z], got {value!r}")
    return tuple(float(v) for v in array)


def check_rotation(rotation: typing.Any, path: str) -> Rotation:
    """``rotation`` checked, its axis a unit vector; errors named ``PATH.axis``, ``PATH.angle``, ``PATH.centre``."""
    require(isinstance(rotation, Rotation), path, f"must be a table {{axis, angle, centre}}, got {rotation!r}")
    axis = finite_vector(rotation.axis, f"{path}.axis")
    length = math.sqrt(sum(a * a for a in axis))
    require(length > 0.0, f"{path}.axis", f"must have nonzero length, got {list(axis)!r}")
    angle = rotation.angle
    ok = isinstance(angle, (int, float)) and not isinstance(angle, bool) and math.isfinite(angle)
    require(ok, f"{path}.angle", f"must be a finite number (degrees), got {angle!r}")
    unit = axis if math.isclose(length, 1.0, rel_tol=1e-15) else tuple(a / length for a in axis)
    return Rotation(unit, float(angle), finite_vector(rotation.centre, f"{path}.centre"))


def check_steps(steps: typing.Sequence[LoadStep]) -> None:
    """Raise :class:`~contactqvi.parameters.ParameterError` for a negative load, a fit outside
    [0, 1], a bad translation or rotation, or a centre of rotation that changes between steps."""
    centre = None
    for i, step in enumerate(steps):
        require_positive(f"steps[{i}].load", step.load, allow_zero=True)
        finite_vector(step.translation, f"steps[{i}].translation")
        check_fit(step.fit, f"steps[{i}].fit")
        if step.rotation is None:
            continue
        rotation = check_rotation(step.rotation, f"steps[{i}].rotation")
        centre = rotation.centre if centre is None else centre
        require(rotation.centre == centre, f"steps[{i}].rotation.centre", f"must be the centre of the steps "
                f"before, {list(centre)!r} (a point fixed for the whole path), got {list(rotation.centre)!r}")


def rotates(steps: typing.Sequence[LoadStep]) -> int | None:
    """Index of the first step of ``steps`` with a rotation, None if none has one."""
    return next((i for i, step in enumerate(steps) if step.rotation is not None), None)


def placed(obstacle: Obstacle, translation: typing.Sequence[float], rotation: Rotation | None) -> Obstacle:
    """``obstacle`` (in its initial position) at a step: rotated by ``rotation`` about its
    centre, then translated by ``translation`` (m), x -> Q (x - c) + c + t."""
    turned = obstacle if rotation is None else obstacle.rotated(rotation.matrix(), rotation.centre)
    return turned.translated(np.asarray(translation, dtype=float))


def rigid_increment(points: np.ndarray, translation: typing.Sequence[float], rotation: Rotation | None,
                    previous_translation: typing.Sequence[float], previous_rotation: Rotation | None) -> np.ndarray:
    """Displacement (m, 3) since the step before of the material points of a rigidly moved
    body (an obstacle) that lie at ``points`` (m, 3) at this step:

        p - phi_0(phi_1^-1(p)),   phi_k(X) = Q_k (X - c) + c + t_k,   phi_1^-1(p) = Q_1^T (p - c - t_1) + c,

    phi_1 this step's rigid motion (``translation``, ``rotation``), phi_0 the step before's
    (total, from the initial position; None: no rotation). Without rotations t_1 - t_0 at
    every point, whatever ``points``; about one axis with a fixed centre, the chord of each
    point's circle, turned by the angle increment, plus t_1 - t_0."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    shift = np.asarray(translation, dtype=float) - np.asarray(previous_translation, dtype=float)
    if rotation is None and previous_rotation is None:
        return np.broadcast_to(shift, points.shape).copy()
    return points - placed_points(initial_points(points, translation, rotation), previous_translation,
                                  previous_rotation)


def initial_points(points: np.ndarray, translation: typing.Sequence[float], rotation: Rotation | None) -> np.ndarray:
    """phi^-1(p) = Q^T (p - c - t) + c (m, 3): where the material points of a rigidly moved body (an
    obstacle) that lie at ``points`` (m, 3) when it is placed by ``translation`` and ``rotation``
    (:func:`placed`) lie in its initial position."""
    points = np.asarray(points, dtype=float).reshape(-1, 3) - np.asarray(translation, dtype=float)
    if rotation is None:
        return points
    centre = np.asarray(rotation.centre, dtype=float)
    return (points - centre) @ rotation.matrix() + centre


def placed_points(initial: np.ndarray, translation: typing.Sequence[float], rotation: Rotation | None) -> np.ndarray:
    """phi(X) = Q (X - c) + c + t (m, 3) of material points at ``initial`` (m, 3) of a rigid body
    placed by ``translation`` and ``rotation`` (:func:`placed`); the inverse of :func:`initial_points`."""
    initial = np.asarray(initial, dtype=float).reshape(-1, 3)
    if rotation is not None:
        centre = np.asarray(rotation.centre, dtype=float)
        initial = (initial - centre) @ rotation.matrix().T + centre
    return initial + np.asarray(translation, dtype=float)


def check_fit(fit: typing.Any, name: str) -> float | None:
    """A step's ``fit``: None or a number in [0, 1] (:class:`LoadStep`)."""
    if fit is not None:
        ok = isinstance(fit, (int, float)) and not isinstance(fit, bool) and 0.0 <= fit <= 1.0
        require(ok, name, f"must be a number in [0, 1] (the fraction of the interference resolved), got {fit!r}")
        return float(fit)
    return None


def interpolated(start: Rotation | None, end: Rotation | None, fraction: float) -> Rotation | None:
    """The rotation ``fraction`` of the way from ``start`` to ``end`` (None: none), its rotation
    vector (angle times axis) interpolated linearly: about the common axis when both share it."""
    if start is None and end is None:
        return None
    known = end if end is not None else start
    if start is None or end is None or start.axis == end.axis:  # about one axis: the angle alone
        angles = [0.0 if r is None else r.angle for r in (start, end)]
        return Rotation(known.axis, angles[0] + fraction * (angles[1] - angles[0]), known.centre)
    vectors = [np.zeros(3) if r is None else r.angle * np.asarray(r.axis) for r in (start, end)]
    vector = vectors[0] + fraction * (vectors[1] - vectors[0])
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return Rotation(known.axis, 0.0, known.centre)
    axis = vector / angle
    if np.dot(axis, known.axis) < 0.0:  # keep the axis's sense, the angle negative
        axis, angle = -axis, -angle
    return Rotation(tuple(float(a) for a in axis), angle, known.centre)
