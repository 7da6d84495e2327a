"""Transfer of finite element functions between non-matching meshes."""

from __future__ import annotations

import numpy as np

from dolfinx import fem

__all__ = ["interpolate_nonmatching"]


def interpolate_nonmatching(u_from: fem.Function, V_to: fem.FunctionSpace, padding: float) -> fem.Function:
    """Interpolate ``u_from`` into ``V_to`` on another mesh covering the same body.

    Points of the target mesh outside the source mesh (a curved boundary resolved
    differently) take the value of the nearest source cell within ``padding``.
    """
    msh_to = V_to.mesh
    cells = msh_to.topology.index_map(msh_to.topology.dim)
    all_cells = np.arange(cells.size_local + cells.num_ghosts, dtype=np.int32)
    data = fem.create_interpolation_data(V_to, u_from.function_space, all_cells, padding=padding)
    u_to = fem.Function(V_to, name=u_from.name)
    u_to.interpolate_nonmatching(u_from, all_cells, data)
    u_to.x.scatter_forward()
    return u_to
