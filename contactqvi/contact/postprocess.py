"""Fields on the contact surface for output: state, pressure, friction traction, slip, gap.

The fields live on a surface mesh of the contact facets (``dolfinx.mesh.create_submesh``
of dimension 2), as P1 functions (vector P1 with three components, the normal one
zero, for the friction traction and the slip, so ParaView shows them as vectors).
Its vertices are the contact nodes of :class:`~contactqvi.contact.problem.ContactProblem`
and the nodes on the edge of the contact boundary that is clamped (Dirichlet); the
latter carry no contact condition and get state ``NO_CONTACT``, zero pressure,
traction and slip, and their (unchanged) initial gap.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.contact.nodal import State
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult

__all__ = ["ContactSurfaceFields", "contact_fields", "plot_contact_states"]

@dataclasses.dataclass
class ContactSurfaceFields:
    """Named P1 functions on the contact surface mesh (seed 000, Sect. 7 output).

    Attributes:
        state: ``contact_state``, a :class:`~contactqvi.contact.nodal.State` value
            (0 no contact, 1 sliding, 2 sticking, 3-5 weak states).
        pressure: ``contact_pressure`` (Pa): normal force over the lumped nodal area.
        traction: ``friction_traction`` (Pa, tangential vector): friction force of the
            foundation on the body over the lumped nodal area; opposite to the slip
            when sliding.
        slip: ``slip`` (m, tangential vector): tangential displacement.
        gap: ``gap`` (m): distance to the foundation x3 = 0 after deformation.
        nodal_area: ``nodal_area`` (m^2): lumped area of each surface node, so that
            the sum of pressure * nodal_area is the total normal force.
    """

    state: fem.Function
    pressure: fem.Function
    traction: fem.Function
    slip: fem.Function
    gap: fem.Function
    nodal_area: fem.Function

    @property
    def mesh(self) -> dmesh.Mesh:
        """The surface mesh of the contact facets."""
        return self.state.function_space.mesh

    @property
    def functions(self) -> list[fem.Function]:
        """All fields, for writing to one file."""
        return [getattr(self, field.name) for field in dataclasses.fields(self)]


def _vertex_blocks(V: fem.FunctionSpace) -> np.ndarray:
    """Local block (node) index of each local vertex, for a degree-1 Lagrange space.

    The i-th dof of a cell of a degree-1 Lagrange space sits at the cell's i-th vertex.
    """
    msh = V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim, 0)
    cell_vertices = msh.topology.connectivity(tdim, 0).array
    index_map = msh.topology.index_map(0)
    blocks = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
    blocks[cell_vertices] = V.dofmap.list.ravel()
    return blocks


def contact_fields(problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult) -> ContactSurfaceFields:
    """Contact state, pressure, friction traction, slip and gap on the contact surface.

    Forces and states are those of the last approximation step's graph point
    (``result``), divided by the problem's lumped nodal area; slip and gap come from
    the solution ``u`` (shifted displacements, u~ = u - d). Each rank fills the
    surface vertices it owns (their parent nodes are owned by the same rank) and
    scatters to the ghosts.

    Args:
        problem: the contact problem that was solved.
        u: its solution (shifted displacements).
        result: the solver's result for ``u``.
    """
    V = problem.V
    msh, comm = V.mesh, problem.comm
    surface, _, vertex_map, _ = dmesh.create_submesh(msh, msh.topology.dim - 1, problem.contact_facets)
    scalars = fem.functionspace(surface, ("Lagrange", 1))
    vectors = fem.functionspace(surface, ("Lagrange", 1, (3,)))

    n_vertices = surface.topology.index_map(0).size_local
    parent_blk = _vertex_blocks(V)[vertex_map[:n_vertices]]
    n_owned = V.dofmap.index_map.size_local
    # create_submesh (DOLFINx 0.9) keeps the owner of every vertex; the forces exist on owned nodes only.
    if comm.allreduce(int(np.any(parent_blk >= n_owned)), op=MPI.MAX):
        raise RuntimeError("contact surface: an owned surface vertex has a parent node owned by another rank")
    position = np.full(n_owned, -1, dtype=np.int64)
    position[problem.contact_blk] = np.arange(len(problem.contact_blk))
    index = position[parent_blk]
    is_contact = index >= 0
    index = index[is_contact]
    area = problem.contact_area[index]

    state = np.full(n_vertices, State.NO_CONTACT, dtype=np.float64)
    state[is_contact] = result.states[index]
    pressure = np.zeros(n_vertices)
    pressure[is_contact] = result.normal_force[index] / area
    traction = np.zeros((n_vertices, 3))
    traction[is_contact, :2] = result.friction_force[index] / area[:, None]
    displacement = (u.array - problem.shift.array).reshape(-1, 3)[parent_blk]  # u~, owned nodes
    slip = displacement.copy()
    slip[:, 2] = 0.0
    scalar_blk = _vertex_blocks(scalars)[:n_vertices]
    vector_blk = _vertex_blocks(vectors)[:n_vertices]
    gap = scalars.tabulate_dof_coordinates()[scalar_blk, 2] + displacement[:, 2]

    def field(name: str, values: np.ndarray) -> fem.Function:
        space, blk = (vectors, vector_blk) if values.ndim == 2 else (scalars, scalar_blk)
        f = fem.Function(space, name=name)
        bs = space.dofmap.index_map_bs
        f.x.array.reshape(-1, bs)[blk] = values.reshape(-1, bs)
        f.x.scatter_forward()
        return f

    nodal_area = fem.Function(scalars, name="nodal_area")
    fem.assemble_vector(nodal_area.x.array, fem.form(ufl.TestFunction(scalars) * ufl.dx))
    nodal_area.x.scatter_reverse(la.InsertMode.add)
    nodal_area.x.scatter_forward()
    return ContactSurfaceFields(
        state=field("contact_state", state),
        pressure=field("contact_pressure", pressure),
        traction=field("friction_traction", traction),
        slip=field("slip", slip),
        gap=field("gap", gap),
        nodal_area=nodal_area,
    )


def plot_contact_states(path: str, fields: ContactSurfaceFields) -> bool:
    """PNG of the contact surface coloured by contact state (seed 000, Fig. 2).

    The reference (undeformed) surface is drawn, one colour per state. Gathers the
    surface pieces on rank 0 (output only). Returns False, with a logged reason,
    when no display can be had.
    """
    import dolfinx.plot

    from contactqvi.io import start_virtual_display

    comm = fields.mesh.comm
    topology, cell_types, x = dolfinx.plot.vtk_mesh(fields.state.function_space)  # owned cells
    pieces = comm.gather((topology, cell_types, x, fields.state.x.array.copy()), root=0)
    ok = start_virtual_display() if comm.rank == 0 else None
    if comm.rank == 0 and ok:
        import pyvista

        plotter = pyvista.Plotter(off_screen=True, window_size=(1200, 700))
        for topology, cell_types, x, state in pieces:
            grid = pyvista.UnstructuredGrid(topology, cell_types, x)
            grid.point_data["contact_state"] = state
            plotter.add_mesh(grid, scalars="contact_state", cmap="viridis", n_colors=len(State),
                             clim=(-0.5, len(State) - 0.5), show_edges=True)
        plotter.view_xy()
        plotter.add_text("contact state: 0 no contact, 1 sliding, 2 sticking, 3-5 weak, 6 separated sticking (Tresca)", font_size=10)
        plotter.screenshot(path)
        plotter.close()
    return bool(comm.bcast(ok, root=0))
