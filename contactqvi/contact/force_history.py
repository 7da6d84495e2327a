"""The forces of a load path as a table (``forces.csv``) and a picture (``forces.png``).

What a contact analyst plots first: the force each contact pair carries and the reaction of
each support, step by step, against what drives the path. The columns come from the
summary's steps (``pair_forces``: the force of a pair's master side or obstacle on its slave
surface; ``reaction_forces``: the force of each support on its body; N, global components),
so the table and the picture are the summary's numbers and nothing else. The abscissa of the
picture is the translation component of the obstacles and moved groups that changes most
along the path (m) when the path moves them, else their rotation angle (degrees) when the path
turns them (a torque path), else the load factor.
"""

from __future__ import annotations

import csv
import io
import os
import typing

from mpi4py import MPI

import numpy as np

from contactqvi.tables import atomic_path

__all__ = ["force_columns", "plot_force_history", "write_force_table"]

_AXES = "xyz"


def force_columns(steps: typing.Sequence[dict[str, typing.Any]]) -> dict[str, np.ndarray]:
    """The path's columns, by name: ``step``, ``load``, ``translation_x/y/z`` (m), ``rotation_angle``
    (degrees about the steps' axis, 0 without a rotation), and per pair
    and per support its force components (``"block.top/ball.sphere F_z"``, ``"ball.load R_z"``; N).
    Only converged steps (a failed step's forces are not a solution)."""
    steps = [s for s in steps if s.get("converged")]
    columns: dict[str, np.ndarray] = {
        "step": np.array([s["step"] for s in steps], dtype=float),
        "load": np.array([s["load"] for s in steps], dtype=float),
    }
    translation = np.array([s.get("translation", (0.0, 0.0, 0.0)) for s in steps], dtype=float).reshape(-1, 3)
    columns.update({f"translation_{a}": translation[:, i] for i, a in enumerate(_AXES)})
    columns["rotation_angle"] = np.array([(s.get("rotation") or {}).get("angle", 0.0) for s in steps], dtype=float)
    for key, symbol in (("pair_forces", "F"), ("reaction_forces", "R")):
        names = list(dict.fromkeys(name for s in steps for name in s.get(key, {})))
        for name in names:
            values = np.array([s.get(key, {}).get(name, (np.nan,) * 3) for s in steps], dtype=float).reshape(-1, 3)
            columns.update({f"{name} {symbol}_{a} [N]": values[:, i] for i, a in enumerate(_AXES)})
    return columns


def write_force_table(comm: MPI.Comm, path: str | os.PathLike, steps: typing.Sequence[dict[str, typing.Any]]) -> None:
    """``forces.csv``: one row per converged step, the :func:`force_columns`. Written
    atomically on rank 0 (every rank holds the summary). Collective."""
    columns = force_columns(steps)
    text = io.StringIO()
    writer = csv.writer(text)
    writer.writerow(columns)
    writer.writerows(zip(*(values.tolist() for values in columns.values())))
    with atomic_path(comm, path) as tmp:
        if comm.rank == 0:
            tmp.write_text(text.getvalue())


def plot_force_history(path: str | os.PathLike, steps: typing.Sequence[dict[str, typing.Any]]) -> None:
    """``forces.png``: the contact forces of the pairs (top) and the supports' reactions
    (bottom), each component that is not negligible (above 1 % of the largest force of the
    path), against the path's abscissa (module docstring). Called on one rank."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = force_columns(steps)
    abscissa, label = _abscissa(columns)
    forces = {name: values for name, values in columns.items() if name.endswith("[N]")}
    largest = max((float(np.nanmax(np.abs(v), initial=0.0)) for v in forces.values()), default=0.0)
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    try:
        for ax, symbol, title in zip(axes, ("F", "R"), ("Contact forces: master side (or obstacle) on the slave "
                                                       "surface", "Reactions: support on its body")):
            for name, values in forces.items():
                if f" {symbol}_" in name and np.nanmax(np.abs(values), initial=0.0) > 1e-2 * largest:
                    ax.plot(abscissa, values, marker="o", markersize=3, label=name.removesuffix(" [N]"))
            ax.set_title(title, fontsize=10)
            ax.set_ylabel("force [N]")
            ax.grid(True, alpha=0.3)
            if ax.lines:
                ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        axes[-1].set_xlabel(label)
        fig.tight_layout()
        fig.savefig(path, dpi=150, format="png")
    finally:
        plt.close(fig)


def _abscissa(columns: dict[str, np.ndarray]) -> tuple[np.ndarray, str]:
    """The translation component that changes most along the path, else the rotation angle if it
    changes, else the load factor."""
    def spread(name: str) -> float:
        return float(np.ptp(columns[name])) if len(columns["step"]) else 0.0

    ranges = [spread(f"translation_{a}") for a in _AXES]
    if max(ranges) > 0.0:
        a = _AXES[int(np.argmax(ranges))]
        return columns[f"translation_{a}"], f"translation of the obstacles and moved groups along {a} [m]"
    if spread("rotation_angle") > 0.0:
        return columns["rotation_angle"], "rotation of the obstacles and moved groups [degrees]"
    return columns["load"], "load factor"
