"""Ownership of PETSc objects: one collective ``destroy()`` and ``with`` support.

PETSc objects on a parallel communicator must be destroyed collectively; left to
Python's garbage collector they end up in PETSc's garbage list (petsc4py's delayed
destruction) or are freed in a rank-dependent order. The one rule of contactqvi:
every class that holds PETSc objects derives from :class:`PETScOwner` and names
them, and the owners it holds, in :meth:`PETScOwner.petsc_objects`;
:meth:`PETScOwner.destroy` frees exactly those. ``tests/test_architecture.py``
checks the rule, ``tests/petsc_audit.py`` that ``destroy()`` leaves nothing alive.
"""

from __future__ import annotations

import dataclasses
import typing

__all__ = ["PETScOwner", "VectorSet"]


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

    def __exit__(self, *exc: object) -> None:
        self.destroy()


class VectorSet(PETScOwner):
    """A dataclass of named work vectors of one matrix's column layout, each field a ``PETSc.Vec``
    (a solver's vectors, reused by its every iteration); :meth:`create` makes them, :meth:`destroy` frees them."""

    @classmethod
    def create(cls, A: typing.Any) -> typing.Self:
        """One new vector of A's column layout per field."""
        return cls(*(A.createVecRight() for _ in dataclasses.fields(cls)))

    def petsc_objects(self) -> list[typing.Any]:
        return [getattr(self, field.name) for field in dataclasses.fields(self)]
