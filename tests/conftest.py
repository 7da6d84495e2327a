"""Shared fixtures: the same test files run serially and under ``mpirun -n 2``."""

from __future__ import annotations

import gc
import importlib.util
import pathlib
import tempfile
import types

from mpi4py import MPI
from petsc4py import PETSc

import pytest

# Tests create many prefixed solvers, some of whose defaults a direct solver ignores.
PETSc.Options()["options_left"] = "no"


@pytest.fixture(autouse=True)
def _collect_and_synchronise():
    """Free PETSc objects collectively and keep ranks in step between tests."""
    yield
    gc.collect()
    MPI.COMM_WORLD.Barrier()


@pytest.fixture
def mpi_tmp_path() -> pathlib.Path:
    """A temporary directory shared by all ranks (pytest's tmp_path differs per rank)."""
    comm = MPI.COMM_WORLD
    path = tempfile.mkdtemp(prefix="contactqvi-") if comm.rank == 0 else None
    yield pathlib.Path(comm.bcast(path, root=0))
    comm.Barrier()


@pytest.fixture
def load_demo():
    """Import ``demos/<name>.py`` as a module, to call its ``main(argv)``."""

    def load(name: str) -> types.ModuleType:
        path = pathlib.Path(__file__).resolve().parent.parent / "demos" / f"{name}.py"
        spec = importlib.util.spec_from_file_location(f"{name}_demo", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


def pytest_collection_modifyitems(config, items):
    """Tests marked ``serial`` are deselected when running on more than one rank."""
    if MPI.COMM_WORLD.size == 1:
        return
    selected = [item for item in items if "serial" not in item.keywords]
    deselected = [item for item in items if "serial" in item.keywords]
    if deselected:
        config.hook.pytest_deselected(items=deselected)
        items[:] = selected
