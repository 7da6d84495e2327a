"""Fields on the contact surface for output: state, pressure, friction traction, slip, gap."""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult

__all__ = ["NOT_ON_CONTACT_SURFACE", "contact_fields"]

#: Value of the ``contact_state`` field away from the contact surface.
NOT_ON_CONTACT_SURFACE = -1


def contact_fields(problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult) -> list[fem.Function]:
    """Named Q1 functions describing a solution ``u`` (shifted displacements).

    Vector fields: ``displacement`` u~ (m), ``friction_traction`` (Pa; the tangential
    traction of the foundation on the body, opposite to the slip when sliding) and
    ``slip`` (m; tangential displacement of contact nodes). Scalar fields:
    ``contact_state`` (:class:`~contactqvi.contact.nodal.State` values, -1 away from
    the contact surface), ``contact_pressure`` (Pa; normal force over the lumped
    nodal area) and ``gap`` (m; distance to the foundation after deformation).
    Forces are the last approximation step's graph point, the tractions are nodal
    forces divided by the lumped nodal area.
    """
    V = problem.V
    msh = V.mesh
    S = fem.functionspace(msh, ("Lagrange", 1))
    blk = problem.contact_blk

    displacement = fem.Function(V, name="displacement")
    problem.physical_displacement(u, displacement)
    traction = fem.Function(V, name="friction_traction")
    slip = fem.Function(V, name="slip")
    state = fem.Function(S, name="contact_state")
    pressure = fem.Function(S, name="contact_pressure")
    gap = fem.Function(S, name="gap")

    u_contact = u.array.reshape(-1, 3)[blk]
    state.x.array[:] = NOT_ON_CONTACT_SURFACE
    state.x.array[blk] = result.states
    pressure.x.array[blk] = result.normal_force / problem.contact_area
    traction.x.array.reshape(-1, 3)[blk, :2] = result.friction_force / problem.contact_area[:, None]
    slip.x.array.reshape(-1, 3)[blk, :2] = u_contact[:, :2]
    gap.x.array[blk] = u_contact[:, 2]
    for f in (traction, slip, state, pressure, gap):
        f.x.scatter_forward()
    return [displacement, traction, slip, state, pressure, gap]
