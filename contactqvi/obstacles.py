"""Rigid obstacles given analytically: signed distance, normal and nodal frames.

An obstacle tells, for points x of the body, the signed distance g(x) to its
surface (positive on the body's side) and the unit normal n(x) at the closest
point, pointing into the body's side. The contact problem of seed 000, Sect. 6,
needs per contact node the gap g and an orthonormal frame (t1, t2, n) in which the
nodal law acts: the normal component is the gap direction, the two tangential
ones span the tangent plane. Small deformations as in the seed: gaps and frames
are taken at the nodes' reference positions, frames fixed in the reference
configuration; a rigid translation c of the obstacle changes the gap to
g(x - c) (exact for the translated shape), a rigid rotation Q about a centre c,
x -> Q (x - c) + c, rotates its points and directions (:meth:`Obstacle.rotated`), so that
g and n of the rotated shape are exact too (docs/finite_strain.md, "Rotated obstacles").

The plane x3 = 0 with normal e3 gives g = x3 and the frames (e1, e2, e3), the
foundation of seed 000, Sect. 7.
"""

from __future__ import annotations

import abc
import dataclasses
import typing

import numpy as np

from contactqvi.parameters import require

__all__ = ["Cylinder", "Obstacle", "Plane", "Sphere", "frame_axes", "tangent_frames"]

Vector = typing.Sequence[float] | np.ndarray


def _unit(name: str, vector: Vector) -> np.ndarray:
    array = np.asarray(vector, dtype=float)
    require(array.shape == (3,) and bool(np.all(np.isfinite(array))), name, f"must be 3 finite numbers, got {vector!r}")
    length = float(np.linalg.norm(array))
    require(length > 0.0, name, "must not have zero length")
    return array / length


def _point(name: str, vector: Vector) -> np.ndarray:
    array = np.asarray(vector, dtype=float)
    require(array.shape == (3,) and bool(np.all(np.isfinite(array))), name, f"must be 3 finite numbers, got {vector!r}")
    return array


def _rotated_point(matrix: np.ndarray, centre: Vector, point: np.ndarray) -> np.ndarray:
    """Q (x - c) + c of a point x."""
    centre = _point("rotation.centre", centre)
    return np.asarray(matrix, dtype=float) @ (point - centre) + centre


def _projector(normal: np.ndarray) -> np.ndarray:
    """(m, 3, 3) I - n n^T of unit normals ``normal`` (m, 3)."""
    return np.eye(3) - normal[:, :, None] * normal[:, None, :]


def frame_axes(normals: np.ndarray) -> np.ndarray:
    """(m, 3) the fixed axis of :func:`tangent_frames` for each unit normal (m, 3): e1, or e2
    where the normal is within 25 degrees of e1."""
    axis = np.zeros_like(normals)
    near_e1 = np.abs(normals[:, 0]) > 0.9
    axis[~near_e1, 0] = 1.0
    axis[near_e1, 1] = 1.0
    return axis


def tangent_frames(normals: np.ndarray) -> np.ndarray:
    """Right-handed orthonormal frames (rows t1, t2, n) for unit normals ``normals`` (m, 3).

    t1 is e1 projected onto the tangent plane (e2 where n is within 25 degrees of
    e1), t2 = n x t1; for n = e3 this gives (e1, e2, e3) exactly.
    """
    normals = np.asarray(normals, dtype=float).reshape(-1, 3)
    axis = frame_axes(normals)
    t1 = axis - np.einsum("ij,ij->i", axis, normals)[:, None] * normals
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(normals, t1)
    return np.stack([t1, t2, normals], axis=1)


class Obstacle(abc.ABC):
    """A rigid obstacle; the body lies where the signed distance is >= 0."""

    @abc.abstractmethod
    def distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance g (m,) and unit normal n (m, 3) at points ``x`` (m, 3); the
        normal is nan where it is undefined (a sphere's centre, a cylinder's axis)."""

    @abc.abstractmethod
    def translated(self, c: Vector) -> Obstacle:
        """The obstacle moved rigidly by ``c``."""

    @abc.abstractmethod
    def rotated(self, matrix: np.ndarray, centre: Vector) -> Obstacle:
        """The obstacle rotated rigidly by ``matrix`` (Q, orthogonal) about ``centre`` (c):
        its points x go to Q (x - c) + c, its directions d to Q d."""

    @abc.abstractmethod
    def curvature(self, x: np.ndarray) -> np.ndarray:
        """(m, 3, 3) derivative dn/dx of the unit normal at points ``x`` (m, 3), the Hessian of
        the signed distance: symmetric, with n in its null space (docs/finite_strain.md, Sect. 18)."""

    def frames(self, x: np.ndarray) -> np.ndarray:
        """Nodal frames (m, 3, 3), rows t1, t2, n, at points ``x``."""
        return tangent_frames(self.distance(x)[1])


@dataclasses.dataclass(frozen=True)
class Plane(Obstacle):
    """The half-space {(x - point) . normal <= 0}; the body lies on the side ``normal`` points to."""

    point: np.ndarray
    normal: np.ndarray

    def __init__(self, point: Vector, normal: Vector):
        object.__setattr__(self, "point", _point("obstacle.point", point))
        object.__setattr__(self, "normal", _unit("obstacle.normal", normal))

    def distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        return (x - self.point) @ self.normal, np.broadcast_to(self.normal, x.shape).copy()

    def curvature(self, x: np.ndarray) -> np.ndarray:
        return np.zeros((len(np.asarray(x).reshape(-1, 3)), 3, 3))

    def translated(self, c: Vector) -> Plane:
        return Plane(self.point + _point("translation", c), self.normal)

    def rotated(self, matrix: np.ndarray, centre: Vector) -> Plane:
        return Plane(_rotated_point(matrix, centre, self.point), matrix @ self.normal)


@dataclasses.dataclass(frozen=True)
class Sphere(Obstacle):
    """A rigid ball; the body lies outside it."""

    center: np.ndarray
    radius: float

    def __init__(self, center: Vector, radius: float):
        require(np.isfinite(radius) and radius > 0, "obstacle.radius", f"must be > 0, got {radius!r}")
        object.__setattr__(self, "center", _point("obstacle.center", center))
        object.__setattr__(self, "radius", float(radius))

    def distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        offset = np.asarray(x, dtype=float).reshape(-1, 3) - self.center
        length = np.linalg.norm(offset, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):  # a point at the centre: nan normal
            return length - self.radius, offset / length[:, None]

    def curvature(self, x: np.ndarray) -> np.ndarray:
        gap, normal = self.distance(x)
        return _projector(normal) / (gap + self.radius)[:, None, None]

    def translated(self, c: Vector) -> Sphere:
        return Sphere(self.center + _point("translation", c), self.radius)

    def rotated(self, matrix: np.ndarray, centre: Vector) -> Sphere:
        return Sphere(_rotated_point(matrix, centre, self.center), self.radius)


@dataclasses.dataclass(frozen=True)
class Cylinder(Obstacle):
    """A rigid infinite circular cylinder; the body lies outside it."""

    point: np.ndarray
    axis: np.ndarray
    radius: float

    def __init__(self, point: Vector, axis: Vector, radius: float):
        require(np.isfinite(radius) and radius > 0, "obstacle.radius", f"must be > 0, got {radius!r}")
        object.__setattr__(self, "point", _point("obstacle.point", point))
        object.__setattr__(self, "axis", _unit("obstacle.axis", axis))
        object.__setattr__(self, "radius", float(radius))

    def distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        offset = np.asarray(x, dtype=float).reshape(-1, 3) - self.point
        radial = offset - (offset @ self.axis)[:, None] * self.axis
        length = np.linalg.norm(radial, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):  # a point on the axis: nan normal
            return length - self.radius, radial / length[:, None]

    def curvature(self, x: np.ndarray) -> np.ndarray:
        gap, normal = self.distance(x)
        along = np.outer(self.axis, self.axis)
        return (_projector(normal) - along) / (gap + self.radius)[:, None, None]

    def translated(self, c: Vector) -> Cylinder:
        return Cylinder(self.point + _point("translation", c), self.axis, self.radius)

    def rotated(self, matrix: np.ndarray, centre: Vector) -> Cylinder:
        return Cylinder(_rotated_point(matrix, centre, self.point), matrix @ self.axis, self.radius)
