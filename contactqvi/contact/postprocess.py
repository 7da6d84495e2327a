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


def plot_contact_states(path: str, problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult) -> bool:
    """PNG of the deformed contact surface coloured by contact state (seed 000, Fig. 2).

    Gathers the contact nodes on rank 0 (output only). Returns False, with a
    logged reason, when no display can be had; never raises for plotting issues.
    """
    from contactqvi.io import start_virtual_display

    comm = problem.comm
    x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
    x = x + (u.array.reshape(-1, 3)[problem.contact_blk] - problem.shift.array.reshape(-1, 3)[problem.contact_blk])
    xs, states = comm.gather(x, root=0), comm.gather(result.states, root=0)
    ok = start_virtual_display() if comm.rank == 0 else None
    if comm.rank == 0 and ok:
        import pyvista

        cloud = pyvista.PolyData(np.vstack(xs))
        cloud["contact_state"] = np.concatenate(states).astype(float)
        surface = cloud.delaunay_2d()
        plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 700))
        plotter.add_mesh(surface, scalars="contact_state", cmap="viridis", clim=(0, 5), show_edges=True)
        plotter.view_xy()
        plotter.add_text("contact state: 0 no contact, 1 sliding, 2 sticking, 3-5 weak", font_size=10)
        plotter.screenshot(path)
        plotter.close()
    return bool(comm.bcast(ok, root=0))
