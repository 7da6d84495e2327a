"""Load steps of a quasi-static path: problem data shared by case files and the load-path solver."""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from contactqvi.parameters import require, require_positive

__all__ = ["SEARCHES", "LoadStep", "check_steps"]

#: When a pair of meshed bodies is searched along the load path: before every load step
#: after the first, in the configuration the step before ended in; as that, and again
#: after each step in the configuration it reached, the step solved again until that
#: configuration settles; or once, in the reference configuration
#: (:class:`~contactqvi.contact.interface.BodyPair`).
SEARCHES = ("every_step", "until_settled", "once")


@dataclasses.dataclass(frozen=True)
class LoadStep:
    """One step of a load path.

    Attributes:
        load: factor on tractions, body force and prescribed displacements.
        translation: total rigid translation (m) of the obstacles, and of the groups
            moved with them, from their initial position.
    """

    load: float = 1.0
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)


def check_steps(steps: typing.Sequence[LoadStep]) -> None:
    """Raise :class:`~contactqvi.parameters.ParameterError` for a negative load or a bad translation."""
    for i, step in enumerate(steps):
        require_positive(f"steps[{i}].load", step.load, allow_zero=True)
        array = np.asarray(step.translation, dtype=float)
        require(array.shape == (3,) and bool(np.all(np.isfinite(array))), f"steps[{i}].translation",
                f"must be 3 finite numbers (m), got {step.translation!r}")
