"""Frictionless contact: the Signorini problem."""

from __future__ import annotations

import dataclasses

import numpy as np

from contactqvi.laws.base import ContactLaw, LinearSlipBound

__all__ = ["Frictionless"]


@dataclasses.dataclass(frozen=True)
class Frictionless(ContactLaw):
    """Frictionless contact ``law = "frictionless"``: b = 0, no tangential force."""

    name = "frictionless"

    def lumped(self, area: float | np.ndarray) -> LinearSlipBound:
        """b = 0 at every node."""
        return LinearSlipBound()
