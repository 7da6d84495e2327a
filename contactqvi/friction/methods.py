"""The four methods of seed 002 behind one name each, and their command-line options.

``pdas`` (Algorithm 1), ``ss`` (PDAS with sigma = 1/gamma), ``alm`` (Algorithm 3)
and ``uzawa`` take their parameters from the tables of their modules; on the
command line the (PDAS) options are ``--gamma``, ``--sigma``, ``--max-iterations``
(also the inner (PDAS) of ``alm``), the other methods' options carry their prefix
(``--alm-inner``, ``--uzawa-gamma``, ...).
"""

from __future__ import annotations

import argparse
import typing

import numpy as np

from contactqvi.friction import alm, pdas, uzawa
from contactqvi.friction.pdas import ActiveSetResult, FrictionActiveSetSolver, semismooth_newton_sigma
from contactqvi.friction.problem import FrictionProblem
from contactqvi.friction.uzawa import UzawaSolver
from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import Parameters, require_choice
from contactqvi.problems.stadler import REFERENCE_GAMMA
from contactqvi.result import Result

__all__ = ["METHODS", "FrictionSolvers", "add_arguments", "checked_parameters", "nodal_states"]

METHODS = ("pdas", "ss", "alm", "uzawa")

#: (prefix on the command line, table, names) of the options of each method.
_OPTIONS = {
    "pdas": ("", pdas.PARAMETERS, ("gamma", "sigma", "max_iterations", "residual_reduction")),
    "alm": ("alm_", alm.PARAMETERS, ("inner", "schedule", "tol", "max_outer", "residual_reduction")),
    "uzawa": ("uzawa_", uzawa.PARAMETERS, ("gamma", "tol", "max_iterations")),
}


def _prefixed(method: str) -> Parameters:
    prefix, table, names = _OPTIONS[method]
    return Parameters({prefix + name: table[name] for name in names})


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of every method, one argument group per table."""
    notes = {"pdas": "pdas and ss (sigma = 1/gamma)", "alm": "gamma, sigma and --max-iterations (per step): pdas options"}
    for method in _OPTIONS:
        _prefixed(method).add_arguments(parser.add_argument_group(f"{method} options", notes.get(method)))


def checked_parameters(args: argparse.Namespace, method: str) -> dict[str, typing.Any]:
    """The checked parameters of ``method`` from the command line (names without prefix).

    ``ss`` is (PDAS) with sigma = 1/gamma; ``alm`` takes gamma, sigma and its inner
    iteration bound from the (PDAS) options.
    """
    require_choice("method", method, METHODS)
    checked = {}  # every option is checked, also those of the other methods
    for solver, (prefix, _, _) in _OPTIONS.items():
        values = _prefixed(solver).from_namespace(args)
        checked[solver] = {name[len(prefix):]: value for name, value in values.items()}
    if method == "alm":
        shared = checked["pdas"]
        values = {**checked["alm"], "gamma": shared["gamma"], "sigma": shared["sigma"]}
        return alm.PARAMETERS.check({**values, "max_inner": shared["max_iterations"]})
    if method == "ss":
        return {**checked["pdas"], "sigma": semismooth_newton_sigma(checked["pdas"]["gamma"])}
    return checked[method]


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

    def petsc_objects(self) -> list[typing.Any]:
        return [solver for solver in (self._pdas, self._uzawa) if solver is not None]

    def reference(self) -> ActiveSetResult:
        """lambda_bar = lambda_gamma with gamma = :data:`REFERENCE_GAMMA` by (PDAS), sigma = 1 (Sect. 6)."""
        return self.pdas.solve(gamma=REFERENCE_GAMMA, sigma=1.0, max_iterations=100)

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
