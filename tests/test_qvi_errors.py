"""A PETSc error inside the thermoforming solver reaches the caller as a PETSc error, not as a status.

Non-convergence of an inner solver ends the outer method with ``DIVERGED_INNER``
(:class:`~contactqvi.result.InnerSolveError`); an error is a fault and must stay one,
also when it happens inside an outer step (the initial evaluation was never guarded).
"""

from __future__ import annotations

import traceback

from mpi4py import MPI
from petsc4py import PETSc

import pytest

from contactqvi.problems import thermoforming
from contactqvi.qvi import build, create_mesh


class _FailingSNES:
    """The Phi map's SNES, raising a PETSc error (out of memory) from its ``solve`` after ``good`` solves."""

    def __init__(self, snes: PETSc.SNES, good: int):
        self._snes, self._good = snes, good

    def solve(self, b: PETSc.Vec | None, x: PETSc.Vec) -> None:
        if self._good == 0:
            raise PETSc.Error(55)  # PETSC_ERR_MEM
        self._good -= 1
        self._snes.solve(b, x)

    def __getattr__(self, name: str):
        return getattr(self._snes, name)


def _frames(error: BaseException) -> list[str]:
    return [frame.filename for frame in traceback.extract_tb(error.__traceback__)]


def _setup():
    data = thermoforming.make_test(3)
    msh, _ = create_mesh(MPI.COMM_WORLD, data.dim, 0.1)
    return build(data, msh, "alg1", {"max_iterations": 3})


def test_a_petsc_error_in_the_phi_solve_propagates():
    """The error is planted in the Phi solve of the first Newton step (its first solve, of u0, succeeds)."""
    with _setup() as setup:
        temperature = setup.fmap.temperature
        temperature.snes = _FailingSNES(temperature.snes, good=1)
        with pytest.raises(PETSc.Error) as info:
            setup.solver.solve(setup.initial)
    assert info.value.ierr == 55 and any(name.endswith("temperature.py") for name in _frames(info.value))


def test_a_petsc_error_in_the_newton_system_propagates():
    """A direct solver package that does not exist, given as a user would (under ``qvi_newton_``)."""
    opts = PETSc.Options()
    opts["qvi_newton_pc_factor_mat_solver_type"] = "no_such_package"
    try:
        setup = _setup()
        with setup, pytest.raises(PETSc.Error) as info:
            setup.solver.solve(setup.initial)
    finally:
        opts.delValue("qvi_newton_pc_factor_mat_solver_type")
    assert any(name.endswith("newton_system.py") for name in _frames(info.value))
