"""Output of a seed-002 solution: ParaView file, solution.npz and a surface plot of y (Fig. 6.1/6.2).

The problem of seed 002 is stated without units (unit square, scalar
displacement y, friction bound g); the files and the figure say so.
"""

from __future__ import annotations

import os
import pathlib

from mpi4py import MPI

import numpy as np

from dolfinx import fem

from contactqvi import paraview, tables
from contactqvi.friction.problem import FrictionProblem

__all__ = ["boundary_function", "write_solution", "plot_surface"]


def boundary_function(problem: FrictionProblem, values: np.ndarray, name: str) -> fem.Function:
    """A function of V equal to ``values`` at the owned friction nodes and 0 elsewhere (for ParaView)."""
    u = fem.Function(problem.V, name=name)
    u.x.array[problem.boundary_dofs] = values
    u.x.scatter_forward()
    return u


def write_solution(out: pathlib.Path, problem: FrictionProblem, y: fem.Function, lam: np.ndarray,
                   states: np.ndarray) -> None:  # fmt: skip
    """``solution.bp`` (y, lambda and the nodal set -1/0/+1 for A-/I/A+) and ``solution.npz``.

    The npz holds ``x``, ``u`` (y at all vertices) and, on Gamma_f, ``boundary_x``,
    ``lam`` and ``active_set``, gathered on rank 0 and sorted by coordinates.
    """
    fields = {
        "lambda": boundary_function(problem, lam, "lambda"),
        "active_set": boundary_function(problem, states.astype(float), "active_set"),
        "mask": boundary_function(problem, np.ones(len(lam)), "mask"),
    }
    paraview.write_vtx(out / "solution.bp", [y, fields["lambda"], fields["active_set"]])
    gathered = {name: tables.gather_vertex_values(u) for name, u in fields.items()}
    extra = {}
    if problem.comm.rank == 0:
        on_boundary = gathered["mask"][1][:, 0] == 1.0
        extra = {"boundary_x": gathered["mask"][0][on_boundary], "lam": gathered["lambda"][1][on_boundary, 0],
                 "active_set": gathered["active_set"][1][on_boundary, 0].astype(np.int8)}  # fmt: skip
    tables.write_solution_npz(out / "solution.npz", y, **extra)


def plot_surface(path: str | os.PathLike, y: fem.Function, title: str) -> None:
    """Surface plot of y over the unit square, like Fig. 6.1/6.2 (rendered on rank 0 with matplotlib, no display).

    Collective: y is gathered on rank 0 (:func:`contactqvi.tables.gather_vertex_values`).
    """
    comm: MPI.Comm = y.function_space.mesh.comm
    x, values = tables.gather_vertex_values(y)
    with tables.atomic_path(comm, path) as tmp:
        if comm.rank == 0:
            _render(tmp, x, values[:, 0], title)


def _render(path: pathlib.Path, x: np.ndarray, values: np.ndarray, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    n = int(round(np.sqrt(len(values))))  # vertices sorted by (x2, x1): row = x2, column = x1
    x1, x2, surface = (a.reshape(n, n) for a in (x[:, 0], x[:, 1], values))
    span = max(float(np.ptp(values)), float(np.abs(values).max()), 1e-300)
    # Ticks at round numbers; a tick that is zero up to round-off (e.g. 2.2e-16) reads 0.
    ticks = FuncFormatter(lambda v, _: f"{0.0 if abs(v) < 1e-9 * span else v:.3g}")
    fig = plt.figure(figsize=(8.0, 6.0), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    mappable = ax.plot_surface(x1, x2, surface, cmap="viridis", linewidth=0, antialiased=False, rcount=n, ccount=n)
    ax.set_xlabel("$x_1$ (dimensionless)")
    ax.set_ylabel("$x_2$ (dimensionless)")
    ax.set_zlabel("$y$ (dimensionless)", labelpad=12)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(5))
        axis.set_major_formatter(ticks)
    ax.set_title(title)
    bar = fig.colorbar(mappable, ax=ax, shrink=0.6, pad=0.12, format=ticks)
    bar.set_label("$y$ (dimensionless)")
    fig.savefig(path, dpi=120, format="png")
    plt.close(fig)
