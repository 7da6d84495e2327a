"""Named parameters: one declaration feeds validation, ``--help`` and ``summary.json``.

Each solver declares its parameters once in a :class:`Parameters` table of
:class:`Parameter` entries (name, default, type, range or choices, one-line help;
FFCx's options table is the model). :meth:`Parameters.check` merges the caller's
values with the defaults and validates them before any expensive work; every
violation raises :class:`ParameterError` with the same text shape,
``name: must ..., got ...``; :meth:`Parameters.add_arguments` puts the same
table on an argparse parser.
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import math
import typing

__all__ = [
    "Parameter",
    "ParameterError",
    "Parameters",
    "require",
    "require_choice",
    "require_number",
    "require_positive",
]


class ParameterError(ValueError):
    """Invalid user input; the message starts with the parameter's name."""

    def __init__(self, name: str, message: str):
        super().__init__(f"{name}: {message}")
        self.name = name


def require(condition: bool, name: str, message: str) -> None:
    """Raise :class:`ParameterError` for ``name`` unless ``condition`` holds."""
    if not condition:
        raise ParameterError(name, message)


def require_number(name: str, value: typing.Any) -> float:
    """``value`` as a float; it must be a finite number (not a bool)."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    require(ok and math.isfinite(value), name, f"must be a finite number, got {value!r}")
    return float(value)


def require_positive(name: str, value: typing.Any, *, allow_zero: bool = False) -> None:
    """Check that ``value`` is a finite number > 0 (>= 0 with ``allow_zero``)."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    ok = ok and (value >= 0 if allow_zero else value > 0)
    require(ok, name, f"must be {'>= 0' if allow_zero else '> 0'} and finite, got {value!r}")


def require_choice(name: str, value: typing.Any, choices: typing.Iterable[typing.Any]) -> None:
    """Check that ``value`` is one of ``choices``; the error names the closest one."""
    choices = list(choices)
    if value in choices:
        return
    close = difflib.get_close_matches(str(value), [str(c) for c in choices], n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise ParameterError(name, f"must be one of {', '.join(map(str, choices))}, got {value!r}{hint}")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One solver parameter.

    Attributes:
        default: value when the caller gives none (``None`` allowed if ``optional``).
        help: one line for ``--help`` and the docs.
        type: ``int``, ``float``, ``bool`` or ``str``.
        choices: allowed values (strings), or empty.
        minimum, maximum: bounds of a number, or None.
        exclusive: bounds are strict (``minimum < value < maximum``).
        optional: ``None`` is a valid value (meaning "chosen by a rule").
    """

    default: typing.Any
    help: str
    type: type = float
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    exclusive: bool = False
    optional: bool = False

    def check(self, name: str, value: typing.Any) -> typing.Any:
        """``value`` converted to the parameter's type; raises :class:`ParameterError`."""
        if value is None and self.optional:
            return None
        if self.choices:
            require_choice(name, value, self.choices)
            return value
        if self.type is bool:
            require(isinstance(value, (bool, int)) and value in (0, 1), name, f"must be true or false, got {value!r}")
            return bool(value)
        if self.type is str:
            require(isinstance(value, str), name, f"must be a string, got {value!r}")
            return value
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if self.type is int:
            require(number and float(value).is_integer(), name, f"must be an integer, got {value!r}")
            value = int(value)
        else:
            require(number and math.isfinite(value), name, f"must be a finite number, got {value!r}")
            value = float(value)
        low, high = self.minimum, self.maximum
        if self.exclusive:
            ok = (low is None or value > low) and (high is None or value < high)
        else:
            ok = (low is None or value >= low) and (high is None or value <= high)
        require(ok, name, f"must be {self.range_text()}, got {value!r}")
        return value

    def range_text(self) -> str:
        """The admissible values in words (``in (0, 1)``, ``>= 1``, ``one of a, b``)."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        low, high = self.minimum, self.maximum
        if low is not None and high is not None:
            brackets = "()" if self.exclusive else "[]"
            return f"in {brackets[0]}{low:g}, {high:g}{brackets[1]}"
        if low is not None:
            return f"{'>' if self.exclusive else '>='} {low:g}"
        if high is not None:
            return f"{'<' if self.exclusive else '<='} {high:g}"
        return f"a {self.type.__name__}"


class Parameters(dict[str, Parameter]):
    """A table ``name -> Parameter`` of one solver."""

    def defaults(self) -> dict[str, typing.Any]:
        return {name: p.default for name, p in self.items()}

    def check(self, given: typing.Mapping[str, typing.Any] | None = None) -> dict[str, typing.Any]:
        """Defaults overridden by ``given``, each value checked.

        Unknown names raise :class:`ParameterError` naming the closest known one.
        """
        merged = self.defaults()
        for name, value in (given or {}).items():
            if name not in self:
                close = difflib.get_close_matches(name, list(self), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else f"; known: {', '.join(sorted(self))}"
                raise ParameterError(name, f"unknown parameter{hint}")
            merged[name] = value
        return {name: self[name].check(name, value) for name, value in merged.items()}

    def add_arguments(self, parser: argparse.ArgumentParser, names: typing.Iterable[str] | None = None) -> None:
        """Add ``--name`` (underscores as dashes) for each parameter to ``parser``.

        Values are parsed by type only; :meth:`check` validates them. Booleans
        take ``--name`` / ``--no-name``.
        """
        for name in self if names is None else names:
            p = self[name]
            flag = "--" + name.replace("_", "-")
            text = f"{p.help} [{p.range_text()}]"
            if p.type is bool:
                parser.add_argument(flag, dest=name, default=p.default, action=argparse.BooleanOptionalAction, help=text)
            elif p.choices:
                parser.add_argument(flag, dest=name, default=p.default, choices=p.choices, help=p.help)
            else:
                parser.add_argument(flag, dest=name, default=p.default, type=_none_or(p.type), help=text)

    def from_namespace(self, args: argparse.Namespace) -> dict[str, typing.Any]:
        """Checked values of the parameters that ``args`` (from :meth:`add_arguments`) holds."""
        return self.check({name: getattr(args, name) for name in self if hasattr(args, name)})


def _none_or(kind: type) -> typing.Callable[[str], typing.Any]:
    def convert(text: str) -> typing.Any:
        return None if text.lower() == "none" else kind(text)

    convert.__name__ = kind.__name__
    return convert

