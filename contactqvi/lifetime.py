"""Ownership of PETSc objects: one collective ``destroy()`` and ``with`` support.

PETSc objects on a parallel communicator must be destroyed collectively; left to
Python's garbage collector they end up in PETSc's garbage list (petsc4py's delayed
destruction) or are freed in a rank-dependent order. The one rule of contactqvi:
every class that holds PETSc objects derives from :class:`PETScOwner` and names
them, and the owners it holds, in :meth:`PETScOwner.petsc_objects`;
:meth:`PETScOwner.destroy` frees exactly those. ``tests/test_architecture.py``
checks the rule, ``tests/petsc_audit.py`` that ``destroy()`` leaves nothing alive.

A collective clean-up while an exception unwinds (the ``destroy()`` at the end of a ``with``
block, the runner closing its output files) waits for every rank. An error raised on one rank
alone (a bug, a failed write) would leave that rank in the clean-up and the others in the next
collective call of the run, for ever: under :func:`abort_alone`, which a program's
:func:`~contactqvi.cli.abort_on_error` sets on several ranks, such a clean-up first asks whether
every rank is unwinding too (:func:`unwind_together`) and ends the job if not.
"""

from __future__ import annotations

import contextlib
import dataclasses
import sys
import time
import traceback
import typing

__all__ = ["UNWIND_TIMEOUT", "PETScOwner", "VectorSet", "abort_alone", "unwind_together"]

#: How long (s) a rank unwinding an exception waits at a collective clean-up, under
#: :func:`abort_alone`, for the other ranks to unwind one too. An error every rank raises alike
#: (bad input: raised from reduced values) reaches the clean-up on all of them within
#: milliseconds; one the others have not met by then was raised on this rank alone.
UNWIND_TIMEOUT = 10.0

#: The communicators of the active :func:`abort_alone` blocks and their timeouts, innermost last.
_agreements: list[tuple[typing.Any, float]] = []


@contextlib.contextmanager
def abort_alone(comm: typing.Any, timeout: float | None = None) -> typing.Iterator[None]:
    """Within the block an exception raised on some ranks of ``comm`` only ends the job at the
    first collective clean-up it meets (:func:`unwind_together`, after ``timeout`` s, default
    :data:`UNWIND_TIMEOUT`) instead of leaving the ranks in collective calls that never match.
    Collective (the agreements use a duplicate of ``comm``)."""
    agreement = comm.Dup()
    _agreements.append((agreement, UNWIND_TIMEOUT if timeout is None else timeout))
    try:
        yield
    finally:
        _agreements.pop()
    agreement.Free()  # not after an exception: it ends the job (abort_on_error) or was every rank's


def unwind_together(exc: BaseException | None) -> None:
    """Called by a collective clean-up before it communicates, with the exception ``exc`` in flight
    (None: none): return once every rank is unwinding an exception too (an error raised on every rank
    alike: the clean-up may communicate), else print ``exc`` and end the job (``MPI_Abort``, code 1)
    after the timeout of :func:`abort_alone`. Nothing to wait for outside :func:`abort_alone`, nor for a
    ``KeyboardInterrupt`` or ``SystemExit`` (not an ``Exception``: every rank gets the signal)."""
    if not isinstance(exc, Exception) or not _agreements:
        return
    agreement, timeout = _agreements[-1]
    request = agreement.Ibarrier()
    deadline = time.monotonic() + timeout
    while not request.Test():
        if time.monotonic() > deadline:
            traceback.print_exception(exc)
            print(f"rank {agreement.rank}: no other rank met an error within {timeout:g} s: the one above was "
                  "raised on this rank alone; ending the job", file=sys.stderr, flush=True)
            agreement.Abort(1)
        time.sleep(0.01)


class PETScOwner:
    """Owns PETSc objects and other owners; :meth:`destroy` frees them, also at the end of a ``with`` block."""

    def petsc_objects(self) -> typing.Iterable[typing.Any]:
        """The PETSc objects and owners held (anything with a collective ``destroy()``; None is skipped)."""
        return []

    def destroy(self) -> None:
        """Free everything :meth:`petsc_objects` names, in its order (collective; destroying
        twice is harmless: a destroyed petsc4py object ignores a second ``destroy()``)."""
        for obj in self.petsc_objects():
            if obj is not None:
                obj.destroy()

    def __enter__(self) -> typing.Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: object) -> None:
        unwind_together(exc)
        self.destroy()


class VectorSet(PETScOwner):
    """A dataclass of named work vectors of one layout, each field a ``PETSc.Vec`` (a solver's
    vectors, reused by its every iteration); :meth:`create` makes them, :meth:`destroy` frees them."""

    @classmethod
    def create(cls, like: typing.Any) -> typing.Self:
        """One new vector per field: of ``like``'s column layout (a matrix), or a duplicate of ``like``
        (a vector)."""
        make = like.createVecRight if hasattr(like, "createVecRight") else like.duplicate
        return cls(*(make() for _ in dataclasses.fields(cls)))

    def petsc_objects(self) -> list[typing.Any]:
        return [getattr(self, field.name) for field in dataclasses.fields(self)]
