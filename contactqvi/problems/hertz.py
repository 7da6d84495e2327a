"""Closed-form solutions for a rigid sphere on an elastic half-space (SI units: m, Pa, N).

Hertz (normal, frictionless) and Cattaneo-Mindlin (tangential, Coulomb friction at
constant normal load) after K. L. Johnson, *Contact Mechanics*, Cambridge
University Press 1985: Sect. 4.2 (Hertz theory, solids of revolution) and
Sect. 7.2 (incipient sliding of spheres, Cattaneo 1938, Mindlin 1949). The
indenter is rigid, so only the elastic body's E, nu (or G = E/(2(1 + nu))) enter.

Notation: R sphere radius, delta indentation depth (approach), a contact radius,
P normal force, p0 peak pressure, mu friction coefficient, Q tangential force,
s tangential displacement of the sphere relative to the far field, c stick radius.
Functions are vectorised over numpy arrays where that makes sense.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "contact_force",
    "contact_radius",
    "depth_for_force",
    "dundurs_beta",
    "effective_modulus",
    "mindlin_force",
    "mindlin_displacement",
    "peak_pressure",
    "pressure",
    "shear_modulus",
    "combined_modulus",
    "sliding_displacement",
    "stick_radius",
]


def effective_modulus(young: float, poisson: float) -> float:
    """Contact modulus E* = E / (1 - nu^2) of an elastic body against a rigid one.

    Johnson, Sect. 4.2: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2, with E2 -> infinity.
    """
    return young / (1.0 - poisson**2)


def combined_modulus(young1: float, poisson1: float, young2: float, poisson2: float) -> float:
    """E* of two elastic bodies: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (Johnson, Sect. 4.2).

    The formulas below take (young, poisson) of a body against a rigid one; for two
    elastic bodies pass ``young = combined_modulus(...)`` and ``poisson = 0``.
    """
    return 1.0 / (1.0 / effective_modulus(young1, poisson1) + 1.0 / effective_modulus(young2, poisson2))


def shear_modulus(young: float, poisson: float) -> float:
    """G = E / (2 (1 + nu))."""
    return young / (2.0 * (1.0 + poisson))


def contact_radius(radius: float, depth: float) -> float:
    """Hertz contact radius a = sqrt(R delta) (Johnson, Sect. 4.2: delta = a^2 / R)."""
    return np.sqrt(radius * depth)


def contact_force(young: float, poisson: float, radius: float, depth: float) -> float:
    """Hertz normal force P = (4/3) E* sqrt(R) delta^(3/2) (Johnson, Sect. 4.2:
    a^3 = 3 P R / (4 E*) with a^2 = R delta)."""
    return 4.0 / 3.0 * effective_modulus(young, poisson) * np.sqrt(radius) * depth**1.5


def depth_for_force(young: float, poisson: float, radius: float, force: float) -> float:
    """Indentation depth under the force P: delta = (9 P^2 / (16 R E*^2))^(1/3)
    (Johnson, Sect. 4.2; the inverse of :func:`contact_force`)."""
    e_star = effective_modulus(young, poisson)
    return (9.0 * force**2 / (16.0 * radius * e_star**2)) ** (1.0 / 3.0)


def peak_pressure(young: float, poisson: float, radius: float, depth: float) -> float:
    """Hertz peak pressure p0 = 2 E* sqrt(delta / R) / pi = 3 P / (2 pi a^2) (Johnson, Sect. 4.2)."""
    return 2.0 * effective_modulus(young, poisson) * np.sqrt(depth / radius) / np.pi


def pressure(r: np.ndarray, young: float, poisson: float, radius: float, depth: float) -> np.ndarray:
    """Hertz pressure p(r) = p0 sqrt(1 - r^2/a^2) for r < a, 0 outside (Johnson, Sect. 4.2)."""
    a = contact_radius(radius, depth)
    r = np.asarray(r, dtype=float)
    return peak_pressure(young, poisson, radius, depth) * np.sqrt(np.clip(1.0 - (r / a) ** 2, 0.0, None))


def stick_radius(a: float, tangential_force: np.ndarray, friction: float, normal_force: float) -> np.ndarray:
    """Cattaneo-Mindlin stick radius c = a (1 - Q/(mu P))^(1/3) for 0 <= Q <= mu P
    (Johnson, Sect. 7.2); 0 once the whole contact slides."""
    ratio = np.clip(np.asarray(tangential_force, dtype=float) / (friction * normal_force), 0.0, 1.0)
    return a * (1.0 - ratio) ** (1.0 / 3.0)


def sliding_displacement(friction: float, normal_force: float, shear: float, poisson: float, a: float) -> float:
    """Tangential displacement at which the whole contact slides (Q = mu P):
    s* = 3 mu P (2 - nu) / (16 G a) (Mindlin's law, :func:`mindlin_displacement`, at Q = mu P)."""
    return 3.0 * friction * normal_force * (2.0 - poisson) / (16.0 * shear * a)


def mindlin_displacement(
    tangential_force: np.ndarray, friction: float, normal_force: float, shear: float, poisson: float, a: float
) -> np.ndarray:
    """Mindlin's tangential force-displacement law for monotone loading at constant P,
    rigid sphere on an elastic half-space with G, nu (Johnson, Sect. 7.2):

        s(Q) = 3 mu P (2 - nu) / (16 G a) [1 - (1 - Q/(mu P))^(2/3)],   0 <= Q <= mu P.

    Its slope at Q = 0 is the no-slip tangential stiffness Q/s = 8 G a / (2 - nu).
    """
    ratio = np.clip(np.asarray(tangential_force, dtype=float) / (friction * normal_force), 0.0, 1.0)
    s_star = sliding_displacement(friction, normal_force, shear, poisson, a)
    return s_star * (1.0 - (1.0 - ratio) ** (2.0 / 3.0))


def mindlin_force(
    displacement: np.ndarray, friction: float, normal_force: float, shear: float, poisson: float, a: float
) -> np.ndarray:
    """Inverse of :func:`mindlin_displacement`: Q(s) = mu P [1 - (1 - s/s*)^(3/2)] for
    0 <= s <= s* (:func:`sliding_displacement`), mu P beyond (gross sliding)."""
    s_star = sliding_displacement(friction, normal_force, shear, poisson, a)
    ratio = np.clip(np.asarray(displacement, dtype=float) / s_star, 0.0, 1.0)
    return friction * normal_force * (1.0 - (1.0 - ratio) ** 1.5)


def dundurs_beta(poisson: float) -> float:
    """Dundurs' second constant of an elastic body (nu) against a rigid one:
    beta = (1 - 2 nu) / (2 (1 - nu)).

    The general beta = [(1 - 2 nu1)/G1 - (1 - 2 nu2)/G2] / (2 [(1 - nu1)/G1 + (1 - nu2)/G2])
    (Dundurs 1969; Johnson, ch. 5, frictional normal indentation) with G2 -> infinity.
    beta measures the coupling of normal pressure and tangential displacement: the
    Hertz and Cattaneo-Mindlin solutions assume beta = 0 (e.g. nu = 0.5, or two
    bodies of the same material); beta = 2/7 at nu = 0.3, 1/11 at nu = 0.45.
    """
    return (1.0 - 2.0 * poisson) / (2.0 * (1.0 - poisson))
