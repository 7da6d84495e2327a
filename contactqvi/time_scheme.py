"""The Newmark family of implicit time schemes a dynamic contact step takes (docs/dynamics.md, Sect. 3).

The generalized-α method of Chung and Hulbert (J. Appl. Mech. 60 (1993) 371, eqs. (1)-(4),
(25)) balances the forces at intermediate points of the step,

    M a_{n+1-α_m} + K u_{n+1-α_f} = F_{n+1-α_f} + (contact),    x_{n+1-α} = (1 - α) x_{n+1} + α x_n,

with Newmark's updates

    u_{n+1} = u_n + τ v_n + τ² ((1/2 - β) a_n + β a_{n+1}),    v_{n+1} = v_n + τ ((1 - γ) a_n + γ a_{n+1}).

Each member of the family is a choice of (α_m, α_f, β, γ):

* ``newmark``: the average acceleration rule, α_m = α_f = 0, β = 1/4, γ = 1/2 (no numerical
  dissipation, energy-conserving for a linear system);
* ``hht``: Hilber, Hughes and Taylor (Earthq. Eng. Struct. Dyn. 5 (1977) 283) in Chung and
  Hulbert's sign, α_m = 0, α_f = α in [0, 1/3], β = (1 + α)²/4, γ = 1/2 + α;
* ``generalized_alpha``: the spectral radius ρ∞ in [0, 1] at infinite frequency gives
  α_m = (2ρ∞ - 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), β = (1 - α_m + α_f)²/4, γ = 1/2 - α_m + α_f
  (Chung and Hulbert (25)): second order, unconditionally stable, the high frequencies damped
  to ρ∞ with the least damping of the low ones.

Every member is second-order accurate (γ = 1/2 - α_m + α_f) and unconditionally stable for a
linear system (α_m <= α_f <= 1/2, β >= 1/4 + (α_f - α_m)/2).
"""

from __future__ import annotations

import dataclasses

__all__ = ["SCHEMES", "TimeScheme"]

#: The names of ``[dynamics] scheme``.
SCHEMES = ("newmark", "hht", "generalized_alpha")


@dataclasses.dataclass(frozen=True)
class TimeScheme:
    """One member (α_m, α_f, β, γ) of the generalized-α family (module docstring).

    Attributes:
        name: one of :data:`SCHEMES`.
        alpha_m: the weight of a_n in the inertial force of the step.
        alpha_f: the weight of t_n in the elastic force and the loads.
        beta, gamma: Newmark's parameters.
    """

    name: str
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float

    @classmethod
    def newmark(cls) -> TimeScheme:
        """Newmark's average acceleration rule."""
        return cls("newmark", 0.0, 0.0, 0.25, 0.5)

    @classmethod
    def hht(cls, alpha: float) -> TimeScheme:
        """Hilber-Hughes-Taylor with α = α_f in [0, 1/3] (α = 0: :meth:`newmark`)."""
        return cls("hht", 0.0, alpha, (1.0 + alpha) ** 2 / 4.0, 0.5 + alpha)

    @classmethod
    def generalized_alpha(cls, rho_infinity: float) -> TimeScheme:
        """Chung-Hulbert's generalized-α with the spectral radius ``rho_infinity`` in [0, 1] at
        infinite frequency (ρ∞ = 1: the average acceleration rule in another form, Sect. 3 of docs/dynamics.md)."""
        alpha_m = (2.0 * rho_infinity - 1.0) / (rho_infinity + 1.0)
        alpha_f = rho_infinity / (rho_infinity + 1.0)
        return cls("generalized_alpha", alpha_m, alpha_f, (1.0 - alpha_m + alpha_f) ** 2 / 4.0, 0.5 - alpha_m + alpha_f)

    def inertia_coefficient(self, tau: float) -> float:
        """c = (1 - α_m) / ((1 - α_f) β τ²), the factor of M (w - w̄) in the step (3.3) (1/s²)."""
        return (1.0 - self.alpha_m) / ((1.0 - self.alpha_f) * self.beta * tau**2)

    @property
    def history_factor(self) -> float:
        """c_a = α_m - (1 - α_m)(1/2 - β)/β, the factor of the inertial force m_n of t_n in the
        step's balance (3.3) before it is divided by 1 - α_f (-1 for Newmark's rule)."""
        return self.alpha_m - (1.0 - self.alpha_m) * (0.5 - self.beta) / self.beta

    @property
    def carries_acceleration(self) -> bool:
        """Whether a step reads the Newmark acceleration a_n and the contact-free inertial force
        m_n of the step before (all but Newmark's rule, where m_n = F_n - K w_n and γ = 2β
        take a_n out of the velocity update)."""
        return not (self.alpha_m == 0.0 and self.alpha_f == 0.0 and self.gamma == 2.0 * self.beta)

    def parameters(self) -> dict[str, float]:
        """(α_m, α_f, β, γ) by name, for ``summary.json``."""
        return {"alpha_m": self.alpha_m, "alpha_f": self.alpha_f, "beta": self.beta, "gamma": self.gamma}
