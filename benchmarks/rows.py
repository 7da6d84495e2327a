"""Rows of a benchmark table, a failed run among them, written and read back without a crash.

A benchmark that runs many cases records every run as a row, also one that failed (a solver
that did not converge, a process that timed out or crashed): :func:`failed_row` gives it the
row's key, its ``status`` and the ``seconds`` it used, and nothing else, so whatever writes
or reads the table must take a row without a measured field. :func:`read_table` reads an
earlier run's file back (a missing or unreadable file is an empty table, said on stderr),
:func:`merge_rows` keeps the rows of it that a new run does not replace, :func:`order` sorts
rows whose fields may be missing, :func:`cell` formats a field that may be missing,
:func:`write_text` writes a file whole or not at all (a run stopped while writing leaves the
earlier file).

No MPI here: the scripts that start solver processes (``peers_real.py``) import it without
initialising MPI themselves; :mod:`benchlib` re-exports it for the scripts that run in-process.
"""

from __future__ import annotations

import json
import os
import pathlib
import sys
import typing

__all__ = ["cell", "failed", "failed_row", "merge_rows", "order", "percent", "read_table", "write_text"]


def failed_row(status: str, seconds: float, **key: typing.Any) -> dict[str, typing.Any]:
    """The row of a run that failed: its ``key`` fields, ``status`` (why: ``"failed: timeout after
    900 s"``, ``"diverged_max_it"``), the wall ``seconds`` it used, and ``failed`` = True."""
    return {**key, "status": status, "seconds": float(seconds), "failed": True}


def failed(row: dict[str, typing.Any]) -> bool:
    """Whether ``row`` is the row of a failed run (:func:`failed_row`)."""
    return bool(row.get("failed", False))


def read_table(path: pathlib.Path) -> dict[str, typing.Any]:
    """The JSON object ``path`` as an earlier run wrote it (a table of ``rows``, a run's summary or
    result); ``{}`` if there is none or it cannot be read (a truncated or hand-edited file: said on
    stderr, and the new run writes a new one)."""
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        print(f"{path}: not read ({exc}); its rows are dropped", file=sys.stderr)
        return {}
    if not isinstance(data, dict) or not isinstance(data.get("rows", []), list):
        print(f"{path}: not a table of rows; its rows are dropped", file=sys.stderr)
        return {}
    return data


def merge_rows(path: pathlib.Path, rows: list[dict], key: tuple[str, ...]) -> list[dict]:
    """``rows`` plus the rows already in the JSON file ``path`` (:func:`read_table`) that they do not
    replace (same ``key``; a field missing from a row counts as None)."""
    new = {tuple(r.get(k) for k in key) for r in rows}
    old = [r for r in read_table(path).get("rows", []) if tuple(r.get(k) for k in key) not in new]
    return old + rows


def order(*names: str) -> typing.Callable[[dict[str, typing.Any]], tuple]:
    """A sort key of rows by the fields ``names``, a missing (or None) field after every value."""
    def key(row: dict[str, typing.Any]) -> tuple:
        return tuple((row.get(name) is None, row.get(name) if row.get(name) is not None else 0) for name in names)
    return key


def percent(row: dict[str, typing.Any], name: str, missing: str = "\u2013") -> str:
    """``row[name]``, a relative difference, as a signed percentage for a markdown table; ``missing``
    (an en dash) where there is none."""
    return f"{100.0 * row[name]:+.2f} %" if row.get(name) is not None else missing


def cell(row: dict[str, typing.Any], name: str, spec: str = ".3g") -> str:
    """``row[name]`` for a markdown table: a float by ``spec``, an en dash where it is missing or None."""
    value = row.get(name)
    if value is None:
        return "\u2013"
    if isinstance(value, float):
        return format(value, spec)
    return str(value)


def write_text(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically: a temporary sibling renamed into place (serial
    scripts; MPI programs use :func:`contactqvi.tables.atomic_path`)."""
    tmp = path.with_name(f".{path.name}.partial")
    tmp.write_text(text)
    os.replace(tmp, path)
