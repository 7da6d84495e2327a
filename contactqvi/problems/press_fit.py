"""Closed-form solution of a press (shrink) fit: Lamé, plane strain (SI units: m, Pa).

A solid pin (E_p, nu_p) in a ring (the hub: E_h, nu_h) with hole radius b and outer
radius c, radial interference delta, linear elasticity in plane strain, frictionless or
not (no tangential traction by symmetry). Derivation and the check of the same-material
limit in docs/press_fit.md. Plane-strain moduli enter the plane-stress formulas:
E' = E / (1 - nu^2), nu' = nu / (1 - nu) (:func:`plane_strain`).

Notation: p contact pressure at r = b, u_r radial displacement. Materials are
(young, poisson) pairs.
"""

from __future__ import annotations

__all__ = ["contact_pressure", "pin_displacement", "plane_strain", "ring_displacement"]

Material = tuple[float, float]


def plane_strain(young: float, poisson: float) -> tuple[float, float]:
    """(E', nu') = (E / (1 - nu^2), nu / (1 - nu)): plane strain in plane-stress formulas."""
    return young / (1.0 - poisson**2), poisson / (1.0 - poisson)


def contact_pressure(delta: float, b: float, c: float, pin: Material, hub: Material, plane: str = "strain") -> float:
    """p from delta = u_hub(b) - u_pin(b) (docs/press_fit.md, (3)):
    p = delta / (b / E_h' ((c^2 + b^2) / (c^2 - b^2) + nu_h') + b (1 - nu_p') / E_p');
    one material: p = E' delta (c^2 - b^2) / (2 b c^2). ``plane = "stress"``: with E, nu
    themselves (a thin disc with free faces)."""
    moduli = plane_strain if plane == "strain" else lambda young, poisson: (young, poisson)
    (E_h, nu_h), (E_p, nu_p) = moduli(*hub), moduli(*pin)
    return delta / (b / E_h * ((c**2 + b**2) / (c**2 - b**2) + nu_h) + b * (1.0 - nu_p) / E_p)


def ring_displacement(r: float, pressure: float, b: float, c: float, hub: Material) -> float:
    """u_r(r) = p b^2 / (E_h' (c^2 - b^2)) ((1 - nu_h') r + (1 + nu_h') c^2 / r) of the ring
    under the inner pressure p, outer surface free (docs/press_fit.md, (1))."""
    E_h, nu_h = plane_strain(*hub)
    return pressure * b**2 / (E_h * (c**2 - b**2)) * ((1.0 - nu_h) * r + (1.0 + nu_h) * c**2 / r)


def pin_displacement(pressure: float, b: float, pin: Material) -> float:
    """u_r(b) = -p b (1 - nu_p') / E_p' of the solid pin under the outer pressure p
    (docs/press_fit.md, (2)); u_r is linear in r."""
    E_p, nu_p = plane_strain(*pin)
    return -pressure * b * (1.0 - nu_p) / E_p
