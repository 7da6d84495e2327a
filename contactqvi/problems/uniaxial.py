"""Closed forms of homogeneous uniaxial stress in compressible neo-Hookean blocks (SI units).

The neo-Hookean material of :class:`~contactqvi.materials.NeoHookean`,
P = mu (F - F^-T) + lambda ln J F^-T, parametrised by Young's modulus and Poisson's ratio
of its linearisation. A block on rollers (its bottom and two symmetry planes), the other
lateral faces free, compressed along z: F = diag(a, a, s) (docs/finite_strain.md):

* Sect. 6, one block: zero lateral stress (12.1) mu (a^2 - 1) + lambda ln(a^2 s) = 0 and the
  axial nominal stress (12.2) P33 = mu (s - 1/s) + lambda ln(a^2 s) / s = mu (s - a^2 / s);
* Sect. 12, blocks stacked along z with frictionless interfaces (issue 45): each block in
  uniaxial stress with the same axial nominal stress (12.3), the axial stretches adding up to
  the total shortening (12.4); the blocks expand alike (12.5) only for Poisson's ratios
  chosen for one shortening (:func:`matching_poisson`).

(12.1) is solved for s explicitly, s = a^-2 exp(-mu (a^2 - 1) / lambda), so every root below
is a one-dimensional bracketed root (Brent) of explicit monotone functions.
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import scipy.optimize

from contactqvi.elasticity import lame_parameters

__all__ = ["StackedCompression", "matching_poisson", "stacked_compression", "uniaxial_stress"]

#: A block's material: (Young's modulus (Pa), Poisson's ratio).
Elastic = tuple[float, float]
#: Tolerance of the roots in the stretches (of order 1; times mu for a stress): round-off.
_XTOL = 1e-15


def _axial_stretch(a: float, young: float, poisson: float) -> float:
    """s of lateral stretch ``a`` under zero lateral stress: (12.1) solved for s."""
    mu, lmbda = lame_parameters(young, poisson)
    return np.exp(-mu * (a * a - 1.0) / lmbda) / (a * a)


def _stress_of_lateral(a: float, young: float, poisson: float) -> float:
    """P33 (Pa) at lateral stretch ``a`` under zero lateral stress: (12.2) with (12.1),
    mu (s - a^2 / s), decreasing in a."""
    mu, _ = lame_parameters(young, poisson)
    s = _axial_stretch(a, young, poisson)
    return mu * (s - a * a / s)


def uniaxial_stress(s: float, young: float, poisson: float) -> tuple[float, float]:
    """Lateral stretch a (12.1) and axial nominal stress P33 (Pa, (12.2)) of uniaxial stress at axial stretch s."""
    mu, lmbda = lame_parameters(young, poisson)
    low, high = sorted((1.0, 1.0 / np.sqrt(s)))  # (12.1) changes sign between a = 1 and a = s^-1/2
    a = scipy.optimize.brentq(lambda a: mu * (a * a - 1.0) + lmbda * np.log(a * a * s), low, high, xtol=_XTOL)
    return a, mu * (s - 1.0 / s) + lmbda * np.log(a * a * s) / s


def _lateral_of_stress(stress: float, young: float, poisson: float) -> float:
    """The lateral stretch a >= 1 of a block compressed by the nominal stress ``stress`` <= 0 (Pa)."""
    high = 2.0
    while _stress_of_lateral(high, young, poisson) > stress:
        high *= 2.0
    return scipy.optimize.brentq(lambda a: _stress_of_lateral(a, young, poisson) - stress, 1.0, high, xtol=_XTOL)


@dataclasses.dataclass(frozen=True)
class StackedCompression:
    """Blocks stacked along z (block 0 at the bottom, on z = 0), each in uniaxial stress
    F_k = diag(a_k, a_k, s_k) under the common axial nominal stress P33 (docs/finite_strain.md, Sect. 12)."""

    heights: tuple[float, ...]  # H_k (m)
    axial_stretches: np.ndarray  # s_k
    lateral_stretches: np.ndarray  # a_k
    nominal_stress: float  # P33 (Pa), force per reference area, < 0 in compression

    @property
    def travel(self) -> float:
        """How far the top moved down: sum H_k (1 - s_k) (m)."""
        return float(np.dot(self.heights, 1.0 - self.axial_stretches))

    @property
    def cauchy_stress(self) -> np.ndarray:
        """sigma33 = P33 / a_k^2 of each block (Pa): force per deformed area."""
        return self.nominal_stress / self.lateral_stretches**2

    def displacement(self, x: np.ndarray, body: np.ndarray) -> np.ndarray:
        """u(X) = ((a_k - 1) X, (a_k - 1) Y, w_k + (s_k - 1)(Z - Z_k)) at the reference points ``x``
        (N, 3) of the blocks ``body`` (N,), with Z_k the bottom of block k and w_k its displacement."""
        bottoms = np.concatenate([[0.0], np.cumsum(self.heights)[:-1]])
        moved = np.concatenate([[0.0], np.cumsum(np.multiply(self.heights, self.axial_stretches - 1.0))[:-1]])
        a, s = self.lateral_stretches[body], self.axial_stretches[body]
        return np.column_stack([(a - 1.0) * x[:, 0], (a - 1.0) * x[:, 1],
                                moved[body] + (s - 1.0) * (x[:, 2] - bottoms[body])])


def stacked_compression(blocks: typing.Sequence[Elastic], heights: typing.Sequence[float],
                        shortening: float) -> StackedCompression:
    """The stack of ``blocks`` (Young's modulus, Poisson's ratio; bottom first) of ``heights`` (m)
    shortened by ``shortening`` (m, >= 0): the nominal stress P33 < 0 with
    sum H_k s_k(P33) = sum H_k - shortening, (12.3)-(12.4).

    Raises:
        ValueError: a negative shortening or one of the whole height, a Poisson's ratio outside
            (0, 0.5) (where a block compressed along z need not expand, a >= 1).
    """
    total = float(np.sum(heights))
    if not 0.0 <= shortening < total:
        raise ValueError(f"shortening must be in [0, {total:g}) m, got {shortening!r}")
    if not all(0.0 < poisson < 0.5 for _, poisson in blocks):
        raise ValueError(f"Poisson's ratios must be in (0, 0.5), got {[poisson for _, poisson in blocks]}")

    def length(stress: float) -> float:
        return sum(h * _axial_stretch(_lateral_of_stress(stress, *b), *b) for h, b in zip(heights, blocks))

    scale = max(lame_parameters(*b)[0] for b in blocks)
    low = -scale
    while length(low) > total - shortening:
        low *= 2.0
    stress = scipy.optimize.brentq(lambda p: length(p) - (total - shortening), low, 0.0, xtol=_XTOL * scale) \
        if shortening > 0.0 else 0.0
    a = np.array([_lateral_of_stress(stress, *b) for b in blocks])
    s = np.array([_axial_stretch(a_k, *b) for a_k, b in zip(a, blocks)])
    return StackedCompression(tuple(heights), s, a, stress)


def matching_poisson(lower: Elastic, upper_young: float, heights: tuple[float, float], shortening: float) -> float:
    """Poisson's ratio of the upper block (Young's modulus ``upper_young``) for which it expands
    like the ``lower`` one at ``shortening`` (m): a_0 = a_1 in :func:`stacked_compression`, (12.5),
    sought in [0.01, 0.4999]. At small strain nu_1 / E_1 = nu_0 / E_0.
    """
    def mismatch(nu: float) -> float:
        stack = stacked_compression([lower, (upper_young, nu)], heights, shortening)
        return float(np.subtract(*stack.lateral_stretches))

    return scipy.optimize.brentq(mismatch, 0.01, 0.4999, xtol=_XTOL)
