"""The four methods of seed 002 behind one name each, and their parameter tables.

``pdas`` (Algorithm 1), ``ss`` (PDAS with sigma = 1/gamma), ``alm`` (Algorithm 3)
and ``uzawa`` take their parameters from the tables of their modules
(:func:`parameters_of`); a program puts the table of the method it runs on the
command line under the table's own names (``--gamma``, ``--max-iterations``, ...),
as every table of contactqvi is.
"""

from __future__ import annotations

import typing

import numpy as np

from contactqvi.friction import alm, pdas, uzawa
from contactqvi.friction.pdas import ActiveSetResult, FrictionActiveSetSolver, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionProblem
from contactqvi.friction.uzawa import UzawaSolver
from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import Parameters, require_choice
from contactqvi.result import Result

__all__ = ["METHODS", "FrictionSolvers", "checked_parameters", "nodal_states", "parameters_of"]

METHODS = ("pdas", "ss", "alm", "uzawa")


def parameters_of(method: str) -> Parameters:
    """The parameter table of ``method``; ``ss`` has (PDAS)'s without sigma (it is 1/gamma)."""
    require_choice("method", method, METHODS)
    if method == "ss":
        return Parameters({name: p for name, p in pdas.PARAMETERS.items() if name != "sigma"})
    return {"pdas": pdas.PARAMETERS, "alm": alm.PARAMETERS, "uzawa": uzawa.PARAMETERS}[method]


def checked_parameters(method: str, given: typing.Mapping[str, typing.Any]) -> dict[str, typing.Any]:
    """The checked parameters of ``method`` (with sigma = 1/gamma for ``ss``)."""
    params = parameters_of(method).check(given)
    if method == "ss":
        params["sigma"] = semismooth_newton_sigma(params["gamma"])
    return params


def nodal_states(problem: FrictionProblem, lam: np.ndarray) -> np.ndarray:
    """-1 on A-, +1 on A+, 0 on I as read from lambda (|lambda| = g on the active sets)."""
    return np.where(np.abs(lam) >= problem.g, np.sign(lam), 0).astype(np.int8)


class FrictionSolvers(PETScOwner):
    """The solvers of one problem, created on first use: (PDAS) (pdas, ss, alm, lambda_bar) and Uzawa's."""

    def __init__(self, problem: FrictionProblem):
        self.problem = problem
        self._pdas: FrictionActiveSetSolver | None = None
        self._uzawa: UzawaSolver | None = None

    @property
    def pdas(self) -> FrictionActiveSetSolver:
        if self._pdas is None:
            self._pdas = FrictionActiveSetSolver(self.problem)
        return self._pdas

    def petsc_objects(self) -> list[PETScOwner | None]:
        return [self._pdas, self._uzawa]

    def reference(self, gamma: float) -> ActiveSetResult:
        """lambda_bar = lambda_gamma for a large ``gamma`` by (PDAS), sigma = 1 (Sect. 6: gamma = 1e16)."""
        return self.pdas.solve(gamma=gamma, sigma=1.0, max_iterations=100)

    def solve(self, method: str, parameters: dict[str, typing.Any], reference: np.ndarray | None) -> Result:
        """Run ``method`` with the parameters of :func:`checked_parameters`; d_lambda against ``reference``."""
        require_choice("method", method, METHODS)
        if method == "alm":
            return alm.augmented_lagrangian(self.pdas, reference=reference, **parameters)
        if method == "uzawa":
            if self._uzawa is None:
                self._uzawa = UzawaSolver(self.problem)
            return self._uzawa.solve(reference=reference, **parameters)
        return self.pdas.solve(reference=reference, **parameters)
