"""Metric projection onto a closed H^1_0 ball and its Newton derivative (Lemma 2.9 of seed 003)."""

from __future__ import annotations

import math

from petsc4py import PETSc

import numpy as np

from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import require_positive

__all__ = ["BallProjection"]

class BallProjection(PETScOwner):
    """P_B for B = B_R(c) in H^1_0 with the inner product (grad v, grad w), (15)-(16).

    Args:
        inner: the Gram matrix of the H^1_0 inner product (stiffness matrix).
        radius: R > 0.
        center: owned values of c (None: the origin).
    """

    def __init__(self, inner: PETSc.Mat, radius: float, center: np.ndarray | None = None):
        require_positive("radius", radius)
        self.inner, self.radius = inner, radius
        self.work, self.image = inner.createVecs()
        self.center = np.zeros(self.work.getLocalSize()) if center is None else np.asarray(center, dtype=float)

    def petsc_objects(self) -> list[PETSc.Vec]:
        return [self.work, self.image]

    def dot(self, a: np.ndarray, b: np.ndarray) -> float:
        """(a, b)_{H^1_0} of owned coefficient arrays (collective)."""
        self.work.array[:] = b
        self.inner.mult(self.work, self.image)
        self.work.array[:] = a
        return self.work.dot(self.image)

    def norm(self, a: np.ndarray) -> float:
        return math.sqrt(max(self.dot(a, a), 0.0))

    def apply(self, x: np.ndarray) -> tuple[np.ndarray, float, np.ndarray | None]:
        """P_B(x), the factor s = min(1, R/||x - c||) and the unit direction e (None inside B).

        The Newton derivative (16) is G_PB(x) h = s (h - (e, h) e) outside B and h inside.
        """
        shift = x - self.center
        dist = self.norm(shift)
        if dist <= self.radius:
            return x.copy(), 1.0, None
        s = self.radius / dist
        return self.center + s * shift, s, shift / dist
