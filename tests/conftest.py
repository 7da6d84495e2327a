"""Shared fixtures, and the split of the suite between the runs of ``make test``.

``make test`` runs every test serially (two pytest-xdist workers), then under
``mpirun -n 2`` every test not marked below, then ``RANK_TESTS`` on 3 and 4 ranks.
Running in parallel is the default; three markers (registered in pyproject.toml) take a
test out of the ranks' runs:

* ``serial``: the test cannot run under ``mpirun`` at all: it launches ``mpirun`` or a
  new venv in a subprocess, reads a distributed matrix as if local were global, or
  writes files the ranks would share into pytest's per-rank ``tmp_path``.
* ``one_rank(reason=...)``: the test is correct on any number of ranks, but every rank
  would repeat the same serial arithmetic (closed forms, nodal algebra, case-file
  parsing, parameter tables, static checks of the source). ``tests/test_architecture.py``
  checks that such a test reaches none of the names of code that runs differently in
  parallel (``PARALLEL_NAMES`` there); the reason is required.
* ``parallel_twin(twin, reason=...)``: the test reaches parallel code, but the same code as
  its twin, which runs on several ranks: the parameter set ``twin`` of the same test (its id
  in brackets, ``"d1-L1"``) or the test ``twin`` of the same module (``"test_..."``); the two
  differ only in what each rank computes alone (data of the nodal law, a material constant,
  a finer mesh of the same bodies, another closed form), said by the reason. A twin that
  does not run on several ranks (renamed, itself marked) is a usage error, so that no test
  leaves the parallel run unnoticed.

A test marked ``paraview`` renders with ParaView, which ``scripts/paraview/run.sh`` installs
from Debian: it runs where it is asked for (``-m paraview``, ``make paraview-dynamics``) and is
deselected (not skipped) in every other run, ``make test`` among them.

A fourth, ``ranks(*sizes)``, says on which numbers of ranks a test runs at all: a test
that compares N ranks with one runs where ranks without contact facets occur (``ranks(3,
4)``, ``RANK_TESTS`` of the Makefile), a restart written on N ranks where N -> M is asked
for; on other numbers of ranks, one rank among them, it is deselected (not skipped).
"""

from __future__ import annotations

import gc
import importlib.util
import pathlib
import tempfile
import types

from mpi4py import MPI
from petsc4py import PETSc

import pytest
from shipped_runs import ShippedRuns

# Tests create many prefixed solvers, some of whose defaults a direct solver ignores.
PETSc.Options()["options_left"] = "no"

#: Markers that take a test out of the runs on several ranks.
ONE_RANK_MARKERS = ("serial", "one_rank", "parallel_twin")


@pytest.fixture(autouse=True)
def _collect_and_synchronise():
    """Free PETSc objects collectively and keep ranks in step between tests.

    What survives the collection is then frozen (``gc.freeze``), so that the next
    collection walks only what the next test made: walking everything alive (DOLFINx, UFL,
    the sources test_architecture.py parsed, what earlier tests left in caches and module
    fixtures) took 0.07-0.9 s per test, a third of the suite's time. Reference counting
    still frees frozen objects; only a reference cycle among them that a later test drops
    is never collected (its PETSc objects are then never destroyed, on any rank)."""
    yield
    gc.collect()
    gc.freeze()
    MPI.COMM_WORLD.Barrier()


@pytest.fixture
def mpi_tmp_path() -> pathlib.Path:
    """A temporary directory shared by all ranks (pytest's tmp_path differs per rank)."""
    comm = MPI.COMM_WORLD
    path = tempfile.mkdtemp(prefix="contactqvi-") if comm.rank == 0 else None
    yield pathlib.Path(comm.bcast(path, root=0))
    comm.Barrier()


@pytest.fixture(scope="session")
def shipped_runs(tmp_path_factory) -> ShippedRuns:
    """The shipped cases' runs, each made when a test first asks for it (tests/shipped_runs.py)."""
    comm = MPI.COMM_WORLD
    base = comm.bcast(str(tmp_path_factory.mktemp("shipped")) if comm.rank == 0 else None, root=0)
    return ShippedRuns(pathlib.Path(base), comm)


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


def _shares_a_module_fixture(item: pytest.Item) -> bool:
    """Whether the test uses a fixture computed once per module (or class, package)."""
    return any(d.scope in ("module", "class", "package") for defs in item._fixtureinfo.name2fixturedefs.values()
               for d in defs)  # fmt: skip


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(config, items):
    """A ``one_rank`` marker needs its reason; on more than one rank the tests marked
    ``serial`` or ``one_rank`` are deselected. Under pytest-xdist (``--dist loadgroup``)
    the tests of a module that share a module-scoped fixture go to one worker, so that
    the fixture (all shipped cases, say) is computed once; the other tests go one by one."""
    for item in items:
        for name in ("one_rank", "parallel_twin"):
            mark = item.get_closest_marker(name)
            if mark is not None and not mark.kwargs.get("reason"):
                raise pytest.UsageError(f"{item.nodeid}: {name} needs a reason, {name}(..., reason=...)")
        if config.pluginmanager.hasplugin("xdist") and _shares_a_module_fixture(item):
            item.add_marker(pytest.mark.xdist_group(item.path.name))
    if "paraview" not in (config.option.markexpr or ""):
        items_without = [item for item in items if item.get_closest_marker("paraview") is None]
        config.hook.pytest_deselected(items=[item for item in items if item.get_closest_marker("paraview")])
        items[:] = items_without
    selected = [item for item in items if not any(item.get_closest_marker(m) for m in ONE_RANK_MARKERS)]
    _check_twins(config, items, selected)
    if MPI.COMM_WORLD.size == 1:
        selected = items
    selected = [item for item in selected if _on_these_ranks(item)]
    kept = {id(item) for item in selected}
    deselected = [item for item in items if id(item) not in kept]
    if deselected:
        config.hook.pytest_deselected(items=deselected)
        items[:] = selected


def _on_these_ranks(item: pytest.Item) -> bool:
    """Whether the test runs on this number of ranks (``ranks`` marker: the sizes it runs on)."""
    mark = item.get_closest_marker("ranks")
    return mark is None or MPI.COMM_WORLD.size in mark.args


def _check_twins(config: pytest.Config, items: list[pytest.Item], selected: list[pytest.Item]) -> None:
    """Each ``parallel_twin`` names a parameter set of its own test, or a test of its module, that
    runs on several ranks (``-k`` selects later; a run of chosen test ids may leave the twin out)."""
    collected, running = {item.nodeid for item in items}, {item.nodeid for item in selected}
    chosen = any("::" in str(arg) for arg in config.args)
    for item in items:
        mark = item.get_closest_marker("parallel_twin")
        if mark is None:
            continue
        name = mark.args[0]
        twin = f"{item.nodeid.split('::')[0]}::{name}" if name.startswith("test_") else \
            f"{item.nodeid.split('[')[0]}[{name}]"
        if twin not in running and (twin in collected or not chosen):
            raise pytest.UsageError(f"{item.nodeid}: its parallel_twin {twin} does not run on several ranks")
