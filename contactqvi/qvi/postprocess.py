"""Output of a QVI run: ParaView file, solution.npz and the figures of seed 003 (Figs. 1, 3, 4).

Fields are gathered on rank 0 (:func:`contactqvi.tables.gather_vertex_values`);
matplotlib runs there with the Agg backend (no display needed), never inside
solvers. The problems of seed 003 are nondimensional: the axes name the
quantities and say so.
"""

from __future__ import annotations

import pathlib

import numpy as np

from dolfinx import fem

from contactqvi import paraview, tables
from contactqvi.qvi.outer import QVIResult

__all__ = ["result_fields", "write_results", "plot_surface", "plot_profile", "plot_slice", "plot_convergence"]

#: y label of profiles and slices: membrane, mould and temperature share one axis
VALUE_LABEL = "value (nondimensional)"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def result_fields(result: QVIResult) -> list[fem.Function]:
    """Membrane u, mould (the obstacle of the last evaluation) and, for QVIs, the temperature T."""
    ev = result.evaluation
    fields = [result.solution]
    for name, f in (("mould", ev.obstacle), ("temperature", ev.temperature)):
        if f is not None:
            copy = fem.Function(f.function_space, name=name)
            copy.x.array[:] = f.x.array
            fields.append(copy)
    return fields


def write_results(
    out: pathlib.Path, result: QVIResult, Phi0: fem.Function, histories: dict[str, list[float]], title: str,
    plots: bool = True,
) -> None:
    """``thermoforming.bp`` (u, mould, T), ``solution.npz`` (x, u, mould, T, Phi0) and PNGs (collective).

    PNGs: 2D, ``membrane.png``, ``mould.png``, ``slice.png`` (x2 = 1/2), Fig. 3; 1D, ``solution.png``;
    both ``convergence.png`` (``histories``: label -> residuals).
    """
    fields = result_fields(result)
    comm = Phi0.function_space.mesh.comm
    paraview.write_vtx(out / "thermoforming.bp", fields)
    gathered = {f.name: tables.gather_vertex_values(f)[1] for f in fields[1:] + [Phi0]}
    x, u = tables.gather_vertex_values(fields[0])
    tables.write_solution_npz(out / "solution.npz", fields[0], **{k: v[:, 0] for k, v in gathered.items() if v is not None})
    if plots and comm.rank == 0:
        values = {"u": u[:, 0], **{k: v[:, 0] for k, v in gathered.items()}}
        _plot(out, x, values, Phi0.function_space.mesh.topology.dim, title)
        plot_convergence(out / "convergence.png", histories, title)
    comm.Barrier()


def _plot(out: pathlib.Path, x: np.ndarray, values: dict[str, np.ndarray], dim: int, title: str) -> None:
    mould = r"mould $\Phi_0 + \varphi T$"
    if dim == 1:
        curves = {"membrane $u$": values["u"], "obstacle": values["mould"]}
        if "temperature" in values:
            curves["temperature $T$"] = values["temperature"]
        plot_profile(out / "solution.png", x[:, 0], curves, title, "$x$")
        return
    plot_surface(out / "membrane.png", x, values["u"], "membrane $u$")
    plot_surface(out / "mould.png", x, values["mould"], mould)
    curves = {"membrane $u$": values["u"], mould: values["mould"]}
    if "temperature" in values:
        curves["temperature $T$"] = values["temperature"]
        curves[r"deformation $\varphi T$"] = values["mould"] - values["Phi0"]
    plot_slice(out / "slice.png", x, curves, 0.5)


def plot_surface(path: pathlib.Path, x: np.ndarray, values: np.ndarray, title: str) -> None:
    """Surface plot of a 2D nodal field (Fig. 3(a), (b))."""
    plt = _pyplot()
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    ax.plot_trisurf(x[:, 0], x[:, 1], values, cmap="viridis", linewidth=0)
    ax.set_xlabel("$x_1$")
    ax.set_ylabel("$x_2$")
    ax.set_zlabel("height (nondimensional)")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_profile(
    path: pathlib.Path, t: np.ndarray, curves: dict[str, np.ndarray], title: str, xlabel: str, ylabel: str = VALUE_LABEL
) -> None:
    """Line plot of several nodal fields along a line (Fig. 3(c); 1D solutions, Figs. 1, 4)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, values in curves.items():
        ax.plot(t, values, label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_slice(path: pathlib.Path, x: np.ndarray, fields: dict[str, np.ndarray], x2: float = 0.5) -> None:
    """Slice of 2D nodal fields at x_2 = ``x2`` (nodes on that line), Fig. 3(c)."""
    on_line = np.isclose(x[:, 1], x2, atol=1e-10)
    order = np.argsort(x[on_line, 0])
    t = x[on_line, 0][order]
    curves = {label: values[on_line][order] for label, values in fields.items()}
    plot_profile(path, t, curves, f"slice at $x_2$ = {x2:g}", "$x_1$")


def plot_convergence(path: pathlib.Path, histories: dict[str, list[float]], title: str) -> None:
    """Outer residual ||R(u_i)||_H1 against i (Fig. 3(d))."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, residuals in histories.items():
        r = np.asarray(residuals, dtype=float)
        ax.semilogy(np.arange(r.size), np.maximum(r, 1e-16), marker="o", ms=3, label=label)
    ax.set_xlabel("outer iteration $i$")
    ax.set_ylabel(r"$\|R(u_i)\|_{H^1}$")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
