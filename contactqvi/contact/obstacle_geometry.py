"""The contact geometry of a rigid obstacle in the current configuration, inside the Newton iteration.

An obstacle pair with ``search = "newton"`` (docs/finite_strain.md, Sect. 18) takes its normals,
frames and gaps at the current positions x_i = X_i + u~_i of every Newton iterate and trial point,
the obstacle placed where the load step puts it (rotated, then translated; fixed during the step).
With g the obstacle's signed distance, n its unit normal, pi(x) = x - g(x) n(x) the closest point
and (t_1, t_2, n)_i the frame of :func:`~contactqvi.obstacles.tangent_frames` (aligned with the
rollers), the law's variables of slave node i are

    v_i,n = g(x_i),   v_i,a = t_a,i . (pi(x_i) - pi_i^start),   a = 1, 2,                      (18.1)

pi_i^start the obstacle's material point that node i's closest point was at the start of the load
step, carried with the obstacle to its place at this step: the slip relative to the obstacle's
surface, objective (a rigid motion of body and obstacle together moves pi and pi^start alike). The
derivatives with respect to x_i, with H = dn/dx the Hessian of g
(:meth:`~contactqvi.obstacles.Obstacle.curvature`), are

    dv_n = n . dx,   dv_a = t_a . (I - n n^T - g H) dx + dt_a . (pi - pi^start),                (18.2)

dt_a from dn = H dx through the construction of the frames
(:func:`~contactqvi.contact.kinematics.frame_derivatives`), and the forces' term Gamma of the
Newton matrix (13.3) at a slave node is the frames' turn d(R_i^T r_i) = dR_i^T r_i at fixed r. A
node's own coordinates are its only ones: there is no master body.
"""

from __future__ import annotations

import numpy as np

from contactqvi.contact.kinematics import frame_derivatives, roller_aligned
from contactqvi.load_steps import Rotation, initial_points, placed, placed_points
from contactqvi.obstacles import Obstacle, tangent_frames

__all__ = ["ObstacleGeometry", "start_points"]


def start_points(obstacle: Obstacle, x: np.ndarray, translation: np.ndarray, rotation: Rotation | None) -> np.ndarray:
    """(m, 3) the obstacle's material points (in its initial position) closest to the points ``x``
    (m, 3), the obstacle placed by ``translation`` and ``rotation``: pi^start of (18.1) at the start
    of a load step."""
    gap, normal = placed(obstacle, translation, rotation).distance(x)
    return initial_points(x - gap[:, None] * normal, translation, rotation)


class ObstacleGeometry:
    """(18.1)-(18.2) at the slave nodes of one obstacle pair.

    Args:
        obstacle: the obstacle in its initial position.
        x: (m, 3) the slave nodes' current positions.
        constrained: (m, 3) their prescribed components (rollers: t_1 along the first one).
        start: (m, 3) pi^start of each node in the obstacle's initial position (:func:`start_points`).
        translation, rotation: the obstacle's place at the load step.
    """

    def __init__(self, obstacle: Obstacle, x: np.ndarray, constrained: np.ndarray, start: np.ndarray,
                 translation: np.ndarray, rotation: Rotation | None):
        placed_obstacle = placed(obstacle, translation, rotation)
        self.gap, self.normal = placed_obstacle.distance(x)
        self.curvature = placed_obstacle.curvature(x)
        self.constrained = constrained
        self.frames = roller_aligned(tangent_frames(self.normal), constrained)
        self.slip = x - self.gap[:, None] * self.normal - placed_points(start, translation, rotation)

    def variables(self) -> np.ndarray:
        """(m, 3) v of (18.1) in (t_1, t_2, n) components."""
        return np.column_stack([np.einsum("ij,ij->i", self.frames[:, 0], self.slip),
                                np.einsum("ij,ij->i", self.frames[:, 1], self.slip), self.gap])

    def derivatives(self, forces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The derivatives of (18.2) and of the frames' turn R_i^T ``forces`` (m, 3; held fixed) with
        respect to each node's own coordinates: ``(nodes, components, dv, dR^T r)``, (3m,) the node
        and (3m,) the coordinate c of each entry, (3m, 3) the (t_1, t_2, n) components of each."""
        m = len(self.gap)
        nodes, components = np.repeat(np.arange(m), 3), np.tile(np.arange(3), m)
        normal = self.normal[nodes]
        dn = self.curvature[nodes, :, components]  # H e_c
        dframes = frame_derivatives(normal, dn, self.constrained[nodes])
        n_c = normal[np.arange(3 * m), components]
        closest = np.eye(3)[components] - n_c[:, None] * normal - self.gap[nodes, None] * dn  # (I - n n^T - g H) e_c
        frames, slip = self.frames[nodes], self.slip[nodes]
        dv = np.column_stack([np.einsum("ij,ij->i", frames[:, 0], closest) + np.einsum("ij,ij->i", dframes[:, 0], slip),
                              np.einsum("ij,ij->i", frames[:, 1], closest) + np.einsum("ij,ij->i", dframes[:, 1], slip),
                              n_c])
        return nodes, components, dv, np.einsum("eaj,ej->ea", dframes, forces[nodes])
