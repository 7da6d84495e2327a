"""Coulomb friction, the law of seed 000: the friction force is at most F times the normal force."""

from __future__ import annotations

import dataclasses

import numpy as np

from contactqvi.laws.base import ContactLaw, LawParameter, LinearSlipBound

__all__ = ["Coulomb"]


@dataclasses.dataclass(frozen=True)
class Coulomb(ContactLaw):
    """Coulomb friction ``law = "coulomb"``: b(lambda) = F lambda (seed 000, (6.5)).

    Attributes:
        friction: the coefficient F >= 0 (0: frictionless contact).
    """

    name = "coulomb"
    parameters = {"friction": LawParameter("a friction coefficient")}

    friction: float

    def lumped(self, area: float | np.ndarray) -> LinearSlipBound:
        """F lambda at every node (the area does not enter)."""
        return LinearSlipBound(friction=self.friction)
