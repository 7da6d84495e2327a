"""The declared interference of a contact pair (a press or shrink fit), uniform or linear in position.

A pin meshed overlapping its hole declares the overlap as ``[[contacts]] interference``
(docs/press_fit.md): one number δ (m), or a table for an interference that varies linearly
along a direction (a taper),

    δ(x) = value + slope · (x − at),                                                    (T)

with ``value`` the interference (m) at the point ``at`` (m) and ``slope`` its gradient
(m/m, a vector). The checks of the mesh and the gaps of a fit resolved over several steps
read δ at each slave node's reference position (:meth:`Interference.at_points`); δ must be
≥ 0 on the contact surface, which only the mesh can tell
(:mod:`contactqvi.contact.interface`). A number is the table with ``slope = 0``: the same
δ at every node, bit for bit.
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from contactqvi.load_steps import finite_vector
from contactqvi.parameters import require_number, require_positive

__all__ = ["Interference", "as_interference", "check_interference"]

Vector = tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class Interference:
    """δ(x) = value + slope · (x − at) (m), (T) of the module docstring.

    Attributes:
        value: the interference at ``at`` (m).
        at: the point where it is ``value`` (m).
        slope: its gradient (m/m): the change of δ per metre along each axis.
    """

    value: float
    at: Vector = (0.0, 0.0, 0.0)
    slope: Vector = (0.0, 0.0, 0.0)

    def at_points(self, x: np.ndarray) -> np.ndarray:
        """δ at the points ``x`` ((n, 3), m): value + (x − at) · slope, (T)."""
        return self.value + (np.asarray(x, dtype=float) - np.asarray(self.at)) @ np.asarray(self.slope)

    @property
    def uniform(self) -> bool:
        """Whether δ is the same everywhere (``slope`` = 0)."""
        return not any(self.slope)


def as_interference(declared: float | Interference | None) -> Interference:
    """The :class:`Interference` of a declaration: a number δ is δ everywhere, None is 0."""
    if isinstance(declared, Interference):
        return declared
    return Interference(0.0 if declared is None else float(declared))


def check_interference(declared: typing.Any, path: str) -> float | Interference:
    """A declared interference checked: a finite number ≥ 0 (m), or an :class:`Interference` of
    finite numbers; errors named ``path``, ``path.value``, ``path.at``, ``path.slope``. A number
    stays a number (the case as given)."""
    if not isinstance(declared, Interference):
        value = require_number(path, declared)
        require_positive(path, value, allow_zero=True)
        return value
    return Interference(require_number(f"{path}.value", declared.value), finite_vector(declared.at, f"{path}.at"),
                        finite_vector(declared.slope, f"{path}.slope"))
