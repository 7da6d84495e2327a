"""Ownership of PETSc objects: one collective ``destroy()`` and ``with`` support.

PETSc objects on a parallel communicator must be destroyed collectively; left to
Python's garbage collector they end up in PETSc's garbage list (petsc4py's delayed
destruction) or are freed in a rank-dependent order. Every class of
:mod:`contactqvi.vi` and :mod:`contactqvi.qvi` that creates PETSc objects
registers them (and the owners it holds) with :meth:`PETScOwner._own`; the
friction family declares them by :meth:`PETScOwner.petsc_objects`.
"""

from __future__ import annotations

import typing

__all__ = ["PETScOwner"]

T = typing.TypeVar("T")


class PETScOwner:
    """Owns PETSc objects and other owners; :meth:`destroy` frees them, also at the end of a ``with`` block."""

    def _own(self, obj: T) -> T:
        """Register ``obj`` (anything with a collective ``destroy()``) and return it."""
        self.__dict__.setdefault("_owned", []).append(obj)
        return obj

    def petsc_objects(self) -> list[typing.Any]:
        """PETSc objects (or owners) held in attributes, freed after the registered ones."""
        return []

    def destroy(self) -> None:
        """Free everything registered, last registered first, then :meth:`petsc_objects`
        (collective; a second call does nothing)."""
        for obj in [*reversed(self.__dict__.pop("_owned", [])), *self.petsc_objects()]:
            obj.destroy()

    def __enter__(self) -> typing.Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.destroy()
