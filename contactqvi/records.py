"""Warnings as records: each logged once, from rank 0, and kept for ``summary.json``.

A warning of a run (a fit changed by the faceting, a cut load step, a restart without a
checkpoint) is something the user must be able to read afterwards, not only on the console.
:func:`warn` logs it on rank 0 only (not once per rank) and appends it, as
``{"key", "message", "numbers"}``, to every :class:`Recorder` active at that moment; the
case runner keeps one active for the whole run and writes its list as ``warnings`` of
``summary.json``. ``key`` names the kind of warning (a test or a script matches on it),
``numbers`` holds the values the message quotes, in SI units.

:func:`warn` is called with the same arguments on every rank of ``comm`` where the warning
follows from collective (reduced) values, so every rank's recorder holds the same list; rank 0's
is the one written.
"""

from __future__ import annotations

import logging
import typing

from mpi4py import MPI

__all__ = ["Recorder", "warn"]

#: The recorders active now, innermost last (:class:`Recorder` as a context manager).
_ACTIVE: list[Recorder] = []


class Recorder:
    """The warnings issued while it is active (a ``with`` block), as dicts for ``summary.json``.

    Args:
        records: the list to append to (e.g. the warnings of an earlier run that a restart
            continues); a new one if None.
    """

    def __init__(self, records: list[dict[str, typing.Any]] | None = None):
        self.records = [] if records is None else records

    def __enter__(self) -> Recorder:
        _ACTIVE.append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        _ACTIVE.remove(self)


def warn(comm: MPI.Comm, log: logging.Logger, key: str, message: str, **numbers: float) -> dict[str, typing.Any]:
    """Log ``message`` as a warning on rank 0 of ``comm`` and record it in the active recorders.

    Returns:
        The record ``{"key": key, "message": message, "numbers": numbers}``.
    """
    record = {"key": key, "message": message, "numbers": {name: float(value) for name, value in numbers.items()}}
    if comm.rank == 0:
        log.warning("%s", message)
    for recorder in _ACTIVE:
        recorder.records.append(record)
    return record
