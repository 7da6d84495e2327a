"""Tresca friction: a given bound on the friction traction, whatever the normal force."""

from __future__ import annotations

import dataclasses

import numpy as np

from contactqvi.laws.base import ContactLaw, LawParameter, LinearSlipBound

__all__ = ["Tresca"]


@dataclasses.dataclass(frozen=True)
class Tresca(ContactLaw):
    """Tresca friction ``law = "tresca"``: the friction traction is at most ``slip_bound``.

    The VI of the second kind of seed 000, refs. [15, 16]; friction acts also where
    the surfaces do not touch (state ``SEPARATED_STICKING`` of
    :class:`~contactqvi.contact.nodal.State`).

    Attributes:
        slip_bound: the bound tau > 0 on the friction traction (Pa).
    """

    name = "tresca"
    parameters = {"slip_bound": LawParameter("a slip bound", "Pa", allow_zero=False)}

    slip_bound: float

    def lumped(self, area: float | np.ndarray) -> LinearSlipBound:
        """s_i = tau area_i (N), independent of the normal force."""
        return LinearSlipBound(given=self.slip_bound * np.asarray(area, dtype=float))
