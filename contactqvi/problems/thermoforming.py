"""Paper data of seed 003, Sect. 4: Tests 1-4 (obstacle-type QVIs (58) and the semilinear VI (48)).

Only data live here, in the containers :class:`ObstacleQVIData` and
:class:`SemilinearVIData`; :func:`contactqvi.qvi.build.build` reads their fields and
turns them into solvers. Every field is a function of the spatial coordinate ``x``
(a UFL SpatialCoordinate) returning a UFL expression, so the same data serve the
forms and the nodal interpolation of obstacles and initial guesses.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import ufl

from contactqvi.parameters import Parameter, Parameters, require

__all__ = [
    "TEST_PARAMETERS",
    "PARAMETER_SETS",
    "Field",
    "ObstacleQVIData",
    "ScalarNonlinearity",
    "SemilinearVIData",
    "test1",
    "test2",
    "test3",
    "test4",
    "critical_radius",
    "make_test",
]

Field = typing.Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr]


@dataclasses.dataclass(frozen=True)
class ScalarNonlinearity:
    """A (possibly nonsmooth) scalar function g with a Newton derivative G_g, both on UFL expressions."""

    g: Field
    derivative: Field


@dataclasses.dataclass(frozen=True)
class ObstacleQVIData:
    """(58): u <= Phi0 + varphi T, -Lap u <= f; k T - Lap T = g(Psi0 + psi T - u), dT/dn = 0.

    ``initial`` None means u0 = (-Lap)^{-1} f; ``exact`` is the known solution, if any;
    ``atol`` the paper's stopping tolerance of ||R(u)||_H1.
    """

    dim: int
    k: float
    g: ScalarNonlinearity
    Phi0: Field
    f: Field
    varphi: Field
    Psi0: Field
    psi: Field
    initial: Field | None
    atol: float
    exact: Field | None = None


@dataclasses.dataclass(frozen=True)
class SemilinearVIData:
    """(48): u <= Phi0, -Lap u - b1(u) b2(u) - f >= 0 tested against v - u; ``atol`` as above."""

    dim: int
    b1: ScalarNonlinearity
    b2: ScalarNonlinearity
    f: Field
    Phi0: Field
    initial: Field
    atol: float


#: Test 1 parameter sets (alpha1, alpha2), Sect. 4.2.
PARAMETER_SETS = {"I": (1 + 1 / math.pi, 101 / 100), "II": (1e-2, 1e-2)}

#: The choice of a paper test (:func:`make_test`).
TEST_PARAMETERS = Parameters(
    test=Parameter(3, "paper test: 1-3 QVIs (58), 4 the semilinear VI (48) (Sects. 4.2-4.5)", type=int, minimum=1, maximum=4),
    parameter_set=Parameter("I", "Test 1: parameter set (alpha1, alpha2)", type=str, choices=tuple(PARAMETER_SETS)),
    initial=Parameter("zero", "Test 1: u0 = 0 (zero) or (-Lap)^{-1} f (poisson)", type=str, choices=("zero", "poisson")),
)


def test1(alpha1: float, alpha2: float, initial: str = "zero") -> ObstacleQVIData:
    """(69): 1D QVI with exact solution u = sin(pi x), T = alpha1 (Lemma 4.2).

    Args:
        alpha1, alpha2: the parameters (set (I): (1 + 1/pi, 1.01), set (II): (0.01, 0.01)).
        initial: ``zero`` (u0 = 0) or ``poisson`` (u0 = (-Lap)^{-1} f, solved by the builder).
    """
    require(alpha1 > 0, "alpha1", f"must be > 0, got {alpha1!r}")
    require(alpha2 > 0, "alpha2", f"must be > 0, got {alpha2!r}")
    TEST_PARAMETERS.check({"initial": initial})

    def g(s):
        return alpha1 + ufl.atan(ufl.min_value((1 - s) / 2, 1 - s) / alpha2)

    def dg(s):
        m = ufl.min_value((1 - s) / 2, 1 - s)
        return ufl.conditional(ufl.lt(s, 1), -0.5, -1.0) / (alpha2 * (1 + (m / alpha2) ** 2))

    pi = math.pi
    return ObstacleQVIData(
        dim=1,
        k=1.0,
        g=ScalarNonlinearity(g, dg),
        Phi0=lambda x: ufl.max_value(0, abs(x[0] - 0.5) - 0.25),
        f=lambda x: pi**2 * ufl.sin(pi * x[0]) + 100 * ufl.max_value(0, -abs(x[0] - 0.625) + 0.125),
        varphi=lambda x: ufl.sin(pi * x[0]) / alpha1,
        Psi0=lambda x: 1.0 + 0 * x[0],
        psi=lambda x: ufl.sin(pi * x[0]) / alpha1,
        initial=(lambda x: 0 * x[0]) if initial == "zero" else None,
        atol=1e-12,
        exact=lambda x: ufl.sin(pi * x[0]),
    )


def critical_radius(alpha1: float, alpha2: float) -> float:
    """R_{alpha1, alpha2} of (75): contraction of Test 2 on B_R(0) for R below it."""
    pi = math.pi
    return 3 * alpha1 / (10 * (1 + pi)) * (math.sqrt(((5 * alpha2 + 8) * pi**2 + 8 * pi) / (80 * alpha2)) - pi / 4)


def test2(alpha1: float = 10.0, alpha2: float = 1.5) -> ObstacleQVIData:
    """(72): 1D QVI with the two solutions u1 = 0 and u2 = alpha1 sin(pi x) (Lemma 4.3); u0 = 100 x (1 - x)."""
    require(alpha1 > 0, "alpha1", f"must be > 0, got {alpha1!r}")
    require(alpha2 >= 1, "alpha2", f"must be >= 1, got {alpha2!r}")
    pi = math.pi
    return ObstacleQVIData(
        dim=1,
        k=pi**2,
        g=ScalarNonlinearity(lambda s: 4 / alpha1 * ufl.min_value(0, s) ** 2, lambda s: 8 / alpha1 * ufl.min_value(0, s)),
        Phi0=lambda x: 0 * x[0],
        f=lambda x: alpha1 * pi**2 * ufl.sin(pi * x[0]),
        varphi=lambda x: alpha2 * 10 * pi**2 * ufl.sin(pi * x[0]) / (5 - ufl.cos(2 * pi * x[0])),
        Psi0=lambda x: 0 * x[0],
        psi=lambda x: 5 * pi**2 * ufl.sin(pi * x[0]) / (5 - ufl.cos(2 * pi * x[0])),
        initial=lambda x: 100 * (1 - x[0]) * x[0],
        atol=1e-13,
        exact=lambda x: 0 * x[0],
    )


def test3() -> ObstacleQVIData:
    """(78): thermoforming on (0,1)^2 with the pyramidal mould, f = 25, k = 1; u0 = 0."""
    pi = math.pi

    def Phi0(x):
        return 1 - 2 * ufl.max_value(abs(x[0] - 0.5), abs(x[1] - 0.5))

    def varphi(x):
        return ufl.sin(pi * x[0]) * ufl.sin(pi * x[1])

    def g(s):
        return ufl.conditional(ufl.le(s, 0), 0.2, ufl.conditional(ufl.lt(s, 1), (1 - s) / 5, 0.0))

    def dg(s):
        return ufl.conditional(ufl.And(ufl.gt(s, 0), ufl.lt(s, 1)), -0.2, 0.0)

    return ObstacleQVIData(
        dim=2,
        k=1.0,
        g=ScalarNonlinearity(g, dg),
        Phi0=Phi0,
        f=lambda x: 25.0 + 0 * x[0],
        varphi=varphi,
        Psi0=Phi0,
        psi=varphi,
        initial=lambda x: 0 * x[0],
        atol=1e-12,
    )


def test4() -> SemilinearVIData:
    """Table 3: the semilinear VI (48) on (0,1), f = 50 sin(2 pi x), b1 = max(0, s), b2 = s + cos s, Phi0 = 1, u0 = 0."""
    return SemilinearVIData(
        dim=1,
        b1=ScalarNonlinearity(lambda s: ufl.max_value(0, s), lambda s: ufl.conditional(ufl.gt(s, 0), 1.0, 0.0)),
        b2=ScalarNonlinearity(lambda s: s + ufl.cos(s), lambda s: 1 - ufl.sin(s)),
        f=lambda x: 50 * ufl.sin(2 * math.pi * x[0]),
        Phi0=lambda x: 1.0 + 0 * x[0],
        initial=lambda x: 0 * x[0],
        atol=1e-10,
    )


def make_test(test: int, parameter_set: str = "I", initial: str = "zero") -> ObstacleQVIData | SemilinearVIData:
    """Data of Test ``test`` (1-4); ``parameter_set`` and ``initial`` apply to Test 1 (:data:`TEST_PARAMETERS`)."""
    prm = TEST_PARAMETERS.check({"test": test, "parameter_set": parameter_set, "initial": initial})
    if prm["test"] == 1:
        return test1(*PARAMETER_SETS[prm["parameter_set"]], initial=prm["initial"])
    return {2: test2, 3: test3, 4: test4}[prm["test"]]()

