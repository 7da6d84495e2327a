"""Coulomb friction whose coefficient depends on the contact pressure.

Measured friction coefficients change with the contact pressure p: they fall for
polymers and elastomers and rise, then level off, for metals as the real contact
area grows. A form with both limits finite,

    F(p) = F0 + (F_inf - F0) p / (p + p0),

runs from F0 at light contact to F_inf under high pressure and is halfway between at
p = p0. It replaces the linear F0 + F1 p / p_ref (its first-order expansion at p = 0,
with F1 / p_ref = (F_inf - F0) / p0) because the bound then stays Lipschitz: at a
contact node of area a the pressure is lambda / a, and with r = p0 a (N)

    b(lambda) = lambda F(lambda / a) = lambda (F0 + (F_inf - F0) lambda / (lambda + r)),
    b'(lambda) = F0 + (F_inf - F0) (1 - r^2 / (lambda + r)^2),

so b' lies between F0 and F_inf for every lambda >= 0. Hence b >= 0 and b is
nondecreasing and Lipschitz with L = max(F0, F_inf), which is all the proof of
Prop. 6.4 (seed 000) uses: the resolvent is single-valued and Lipschitz with modulus
sqrt(2 (1 + L^2)) / gamma. The linear form has an unbounded slope, so only a local
Lipschitz bound. b is smooth (rational, hence semialgebraic: gph Q~ is subanalytic as
in Prop. 6.3), and the SCD bases of Cor. 6.7/6.8 are those of Coulomb with F lambda
replaced by b(lambda) and the coupling coefficient F by b'(lambda)
(:mod:`contactqvi.laws.base`, derived there; checked against finite differences of
the resolvent in ``tests/test_contact_nodal.py``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from contactqvi.laws.base import ContactLaw, LawParameter, NodalLaw

__all__ = ["PressureCoulombBound", "PressureDependentCoulomb"]


@dataclasses.dataclass(frozen=True)
class PressureDependentCoulomb(ContactLaw):
    """``law = "pressure_coulomb"``: Coulomb friction with F(p) = F0 + (F_inf - F0) p / (p + p0).

    Attributes:
        friction: F0 >= 0, the coefficient at vanishing pressure.
        friction_limit: F_inf >= 0, its limit at high pressure.
        pressure_scale: p0 > 0 (Pa), the pressure at which F is (F0 + F_inf) / 2.
    """

    name = "pressure_coulomb"
    parameters = {
        "friction": LawParameter("a friction coefficient"),
        "friction_limit": LawParameter("a friction coefficient at high pressure"),
        "pressure_scale": LawParameter("a pressure scale", "Pa", allow_zero=False),
    }

    friction: float
    friction_limit: float
    pressure_scale: float

    def coefficient(self, pressure: np.ndarray) -> np.ndarray:
        """F(p) at contact pressures p >= 0 (Pa)."""
        pressure = np.asarray(pressure, dtype=float)
        return self.friction + (self.friction_limit - self.friction) * pressure / (pressure + self.pressure_scale)

    def lumped(self, area: float | np.ndarray) -> PressureCoulombBound:
        """The bound with the pressure lambda / area_i: r_i = p0 area_i (N)."""
        return PressureCoulombBound(self.friction, self.friction_limit, self.pressure_scale * np.asarray(area, dtype=float))


@dataclasses.dataclass(frozen=True, eq=False)
class PressureCoulombBound(NodalLaw):
    """b(lambda) = lambda (F0 + (F_inf - F0) lambda / (lambda + r)) at each node.

    Attributes:
        friction, friction_limit: F0 and F_inf.
        force_scale: r = p0 a >= 0 (N), a number or one per node.
    """

    friction: float
    friction_limit: float
    force_scale: float | np.ndarray

    def _ratio(self, normal_force: np.ndarray) -> np.ndarray:
        """q = r / (lambda + r), 1 where lambda + r = 0; lambda / (lambda + r) = 1 - q."""
        total = np.asarray(normal_force, dtype=float) + self.force_scale
        scale = np.broadcast_to(self.force_scale, total.shape)
        return np.divide(scale, total, out=np.ones(total.shape), where=total > 0.0)

    def bound(self, normal_force: np.ndarray) -> np.ndarray:
        growth = 1.0 - self._ratio(normal_force)
        return normal_force * (self.friction + (self.friction_limit - self.friction) * growth)

    def slope(self, normal_force: np.ndarray) -> np.ndarray:
        q = self._ratio(normal_force)
        return self.friction + (self.friction_limit - self.friction) * (1.0 - q * q)

    @property
    def slope_bound(self) -> float:
        return max(self.friction, self.friction_limit)

    @property
    def frictional(self) -> bool:
        return self.friction > 0.0 or self.friction_limit > 0.0
