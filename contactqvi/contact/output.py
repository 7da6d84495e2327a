"""Result files of a solved contact problem, shared by the demo and the case runner."""

from __future__ import annotations

import pathlib
import typing

from petsc4py import PETSc

from dolfinx import fem

from contactqvi import io
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.postprocess import contact_fields, plot_contact_states
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonResult

__all__ = ["write_contact_results"]


def write_contact_results(
    out: pathlib.Path, problem: ContactProblem, u: PETSc.Vec, result: SCDNewtonResult, plot: bool = True
) -> dict[str, typing.Any]:
    """Write the ParaView files, ``solution.npz`` and (optionally) the contact-state PNG to ``out``.

    Files: ``displacement.bp`` (VTX) and ``contact.xdmf`` (displacement u~, m),
    ``contact_surface.xdmf`` (fields on the contact surface), ``solution.npz``
    (``x``, ``u`` gathered on rank 0). Collective.

    Returns:
        Summary entries: resultants (contact force in N, areas in m^2), the global
        l2 norm of u~ and the plot status.
    """
    displacement = problem.physical_displacement(u, fem.Function(problem.V, name="displacement"))
    io.write_vtx(out / "displacement.bp", [displacement])
    io.write_xdmf(out / "contact.xdmf", problem.V.mesh, [displacement])
    surface = contact_fields(problem, u, result)
    io.write_xdmf(out / "contact_surface.xdmf", surface.mesh, surface.functions)
    io.write_solution_npz(out / "solution.npz", displacement)
    entries = {**contact_resultants(problem, result), "displacement_norm": displacement.x.petsc_vec.norm()}
    if plot:
        entries["plot"] = plot_contact_states(str(out / "contact_states.png"), surface)
    return entries
