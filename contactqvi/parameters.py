"""Named solver/problem parameters and input validation.

Parameters follow the FFCx model: one table ``name: (default, description)`` per
component, merged with what the caller gives. Unknown names and invalid values
raise :class:`ParameterError` naming the parameter, before any expensive work.
"""

from __future__ import annotations

import math
import typing

__all__ = ["ParameterError", "merge_parameters", "require", "require_positive"]

ParameterTable = dict[str, tuple[typing.Any, str]]


class ParameterError(ValueError):
    """Invalid user input; the message starts with the parameter's name."""

    def __init__(self, name: str, message: str):
        super().__init__(f"{name}: {message}")
        self.name = name


def require(condition: bool, name: str, message: str) -> None:
    """Raise :class:`ParameterError` for ``name`` unless ``condition`` holds."""
    if not condition:
        raise ParameterError(name, message)


def require_positive(name: str, value: float, *, allow_zero: bool = False) -> None:
    """Check that ``value`` is a finite number > 0 (>= 0 with ``allow_zero``)."""
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    ok = ok and (value >= 0 if allow_zero else value > 0)
    require(ok, name, f"must be {'>= 0' if allow_zero else '> 0'} and finite, got {value!r}")


def merge_parameters(table: ParameterTable, given: dict[str, typing.Any] | None) -> dict[str, typing.Any]:
    """Defaults of ``table`` overridden by ``given``; unknown names raise."""
    merged = {name: default for name, (default, _) in table.items()}
    for name, value in (given or {}).items():
        require(name in table, name, f"unknown parameter; known: {', '.join(sorted(table))}")
        merged[name] = value
    return merged

