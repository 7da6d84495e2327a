"""Exact contact surfaces of a pair of meshed bodies: coaxial cylinders (a press fit's pin and bore).

A mesh's contact surfaces are its facets. Flat facets of a cylinder of radius R lie inside it by up
to h²/(8R) between their nodes; the 6-node facets of a second-order mesh by O(h³/R²). In a press fit
those deviations are of the order of the interference δ or a fraction of it, and the nodal contact
pressures take them amplified by about b/h (b the bore's radius): on the user's fit of 15 µm with
quadratic elements on 6-node facets of 1.0 / 1.5 mm, the pin as slave, they come out −6.4 … +2.7 % off
Lamé's (at 2 µm: −22 … +8.6 %), and within 0.33 % (0.19 %) between the exact cylinders. Abaqus' and
ANSYS' surface smoothing correct this for cylinders. The pair key

    cylinder = {axis = [0, 0, 1], point = [0, 0, 0]}

declares both surfaces coaxial cylinders about the axis through ``point``. Their radii are read from
the surfaces' vertices, which must lie on them (within :data:`RADIUS_TOL` of the radius), and the
weighted gap is measured between the exact cylinders
(:func:`contactqvi.contact.mortar.mortar_coupling`'s ``exact``; docs/press_fit.md, "Exact cylindrical
surfaces"). It is taken in the reference configuration, as the small-strain gap is: linear elasticity.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI

import numpy as np

from contactqvi.load_steps import finite_vector
from contactqvi.obstacles import Cylinder
from contactqvi.parameters import require

__all__ = ["RADIUS_TOL", "CoaxialCylinders", "check_cylinders"]

Vector = tuple[float, float, float]

#: The vertices of a surface declared a cylinder lie within this fraction of its radius of it
#: (gmsh puts them on the CAD cylinder to round-off: their radii span 5e-16 to 7e-16 of it on
#: meshes/press_fit.geo in first and second order and on the turn5 user's mesh, measured).
RADIUS_TOL = 1e-6


@dataclasses.dataclass(frozen=True)
class CoaxialCylinders:
    """The slave and master surfaces of a pair are cylinders about the line through ``point``
    along ``axis`` (m; any length but zero)."""

    axis: Vector = (0.0, 0.0, 1.0)
    point: Vector = (0.0, 0.0, 0.0)

    def surfaces(self, comm: MPI.Comm, slave: np.ndarray, master: np.ndarray, names: tuple[str, str],
                 key: str) -> tuple[Cylinder, Cylinder]:
        """The cylinders through the vertices ``slave`` and ``master`` ((n, 3) on each rank) of the
        surfaces ``names``: each radius the mean distance of its vertices from the axis. Raises a
        ParameterError named ``key`` if a vertex lies off it by more than :data:`RADIUS_TOL` of it.
        Collective."""
        axis = np.asarray(self.axis) / np.linalg.norm(self.axis)
        cylinders = []
        for x, name in zip((slave, master), names):
            offset = np.asarray(x, dtype=float).reshape(-1, 3) - np.asarray(self.point)
            radius = np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1)
            count = comm.allreduce(len(radius), op=MPI.SUM)
            require(count > 0, key, f"the surface {name!r} has no vertices")
            mean = comm.allreduce(float(radius.sum()), op=MPI.SUM) / count
            low = comm.allreduce(float(radius.min(initial=np.inf)), op=MPI.MIN)
            high = comm.allreduce(float(radius.max(initial=0.0)), op=MPI.MAX)
            require(mean > 0.0 and high - low <= 2.0 * RADIUS_TOL * mean, key,
                    f"the vertices of {name!r} lie {low:.9g} to {high:.9g} m from the axis through {self.point} "
                    f"along {self.axis}: not on one cylinder about it (to {RADIUS_TOL:g} of the radius)")
            cylinders.append(Cylinder(self.point, self.axis, mean))
        return cylinders[0], cylinders[1]


def check_cylinders(declared: CoaxialCylinders, path: str) -> CoaxialCylinders:
    """``declared`` with finite vectors and an axis of nonzero length; errors named ``path.axis`` and
    ``path.point``."""
    axis, point = finite_vector(declared.axis, f"{path}.axis"), finite_vector(declared.point, f"{path}.point")
    require(any(axis), f"{path}.axis", "must not be zero")
    return CoaxialCylinders(axis, point)
