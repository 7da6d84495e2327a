"""Figures of seed 003 (Figs. 1, 3, 4) from gathered vertex values (output only; rank 0 plots).

matplotlib with the Agg backend: no display needed, never used inside solvers.
"""

from __future__ import annotations

import pathlib

import numpy as np

__all__ = ["plot_surface", "plot_profile", "plot_slice", "plot_convergence"]

def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_surface(path: pathlib.Path, x: np.ndarray, values: np.ndarray, title: str) -> None:
    """Surface plot of a 2D nodal field (Fig. 3(a), (b))."""
    plt = _pyplot()
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    ax.plot_trisurf(x[:, 0], x[:, 1], values, cmap="viridis", linewidth=0)
    ax.set_xlabel("$x_1$")
    ax.set_ylabel("$x_2$")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_profile(path: pathlib.Path, t: np.ndarray, curves: dict[str, np.ndarray], title: str, xlabel: str) -> None:
    """Line plot of several nodal fields along a line (Fig. 3(c); 1D solutions, Figs. 1, 4)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, values in curves.items():
        ax.plot(t, values, label=label)
    ax.set_xlabel(xlabel)
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
