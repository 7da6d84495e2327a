"""Test helper: does an owner's ``destroy()`` free every PETSc object it created?

Two independent audits: Python objects wrapping a live PETSc handle (gc), and
PETSc's own log of objects created minus destroyed per type (as ``-log_view``
prints it), which also sees objects Python no longer references (in parallel they
only go to petsc4py's garbage list).
"""

from __future__ import annotations

import gc
import pathlib
import re
import typing

from mpi4py import MPI
from petsc4py import PETSc

import dolfinx.la

__all__ = ["assert_frees_petsc_objects"]


def _live_objects() -> list[PETSc.Object]:
    # ``type()``, not ``isinstance``: the latter raises on dead weak proxies (pyvista keeps some)
    return [o for o in gc.get_objects() if issubclass(type(o), PETSc.Object) and o.handle]


def _dolfinx_wrappers() -> set[int]:
    """ids of the PETSc vectors DOLFINx created around Function arrays (freed with the Function)."""
    vectors = (v for v in gc.get_objects() if issubclass(type(v), dolfinx.la.Vector))
    return {id(v._petsc_x) for v in vectors if v._petsc_x is not None}


def _object_balance(path: pathlib.Path) -> dict[str, int]:
    """Objects created minus destroyed per PETSc type, from PETSc's log (all stages summed)."""
    comm = MPI.COMM_WORLD
    viewer = PETSc.Viewer().createASCII(str(path), comm=comm)
    PETSc.Log.view(viewer)
    viewer.destroy()
    text = comm.bcast(path.read_text() if comm.rank == 0 else None, root=0)
    balance: dict[str, int] = {}
    for line in text.split("Object Type")[1].split("=" * 20)[0].splitlines():
        match = re.match(r"^\s*(\S.*?)\s+(\d+)\s+(\d+)\s*$", line)
        if match and match[1] != "Viewer":
            balance[match[1]] = balance.get(match[1], 0) + int(match[2]) - int(match[3])
    return balance


def assert_frees_petsc_objects(run: typing.Callable[[], list], tmp: pathlib.Path) -> None:
    """``run()`` builds and solves and returns its owners; their ``destroy()`` must free everything."""
    PETSc.Log.begin()
    gc.collect()
    PETSc.garbage_cleanup(MPI.COMM_WORLD)
    before = _live_objects()  # kept referenced: their ids stay unique
    known = {id(o) for o in before}
    balance = _object_balance(tmp / "before.log")
    owners = run()
    owner = None
    for owner in owners:
        owner.destroy()
    del owner  # the owners stay referenced by ``owners`` until their objects are audited
    gc.collect()
    wrappers = _dolfinx_wrappers()
    alive = [o for o in _live_objects() if id(o) not in known and id(o) not in wrappers]
    assert not alive, [(o.getType(), o.getOptionsPrefix()) for o in alive]
    del owners, alive
    gc.collect()
    after = _object_balance(tmp / "after.log")
    leaked = {name: n - balance.get(name, 0) for name, n in after.items() if n != balance.get(name, 0)}
    assert not leaked, leaked
