"""What a contact law is: its case-file form (:class:`ContactLaw`) and its nodal form (:class:`NodalLaw`).

The nodal law of seed 000, Sect. 6, generalised from Coulomb's F lambda to a slip
bound b(lambda) >= 0 of the normal force lambda = -theta >= 0 (N):

    Q~(v) = {(-b(-theta) dd||v12||, theta) : theta in N_{R+}(v3)}.

Everything the SCD semismooth* Newton method does with the law
(:mod:`contactqvi.contact.nodal`) asks only for b and its slope db/dlambda at the
contact nodes:

* the resolvent (6.6)-(6.8): theta = min(w3, 0) does not depend on b, and v12 is the
  block soft thresholding of w12 at b(-theta);
* the states of Table 1: ||g|| against b, and b = 0 (no sticking branch);
* the SCD bases of Cor. 6.7/6.8 at a sliding node in contact: with t = v12/||v12||,
  the graph near it is {(v12, 0, b(-theta) t, theta)}, whose tangents are
      (h12, 0, b/||v12|| (I - t t^T) h12 - b'(-theta) omega t, omega),
  so (6.12)-(6.15) hold with F lambda replaced by b(lambda) and the F of the coupling
  row F t^T by the slope b'(lambda) (the paper's b is F lambda, whose slope is F);
* the Lipschitz modulus of the resolvent: the proof of Prop. 6.4 uses only
  |b(lambda1) - b(lambda2)| <= L |lambda1 - lambda2| and b >= 0, so it is
  sqrt(2 (1 + L^2)) / gamma with L = sup |b'| (:attr:`NodalLaw.slope_bound`).

A law as a user gives it (:class:`ContactLaw`: a name for ``law = "..."`` in a case
file, parameters with units) becomes a nodal law by :meth:`ContactLaw.lumped`, which
turns tractions into nodal forces with each slave node's contact area. A new law is
a subclass of :class:`ContactLaw` with a ``name``, its ``parameters`` and ``lumped``,
plus the :class:`NodalLaw` that ``lumped`` returns (b, b' and sup |b'|), in one module
of this package imported by its ``__init__``; defining the class registers it in
:data:`LAWS`, from which the case reader, the demo and the docs take the names.
"""

from __future__ import annotations

import abc
import collections.abc
import dataclasses
import typing

import numpy as np

from contactqvi.parameters import require, require_choice, require_number, require_positive

__all__ = [
    "DEFAULT_LAW",
    "LAWS",
    "ContactLaw",
    "LawParameter",
    "LinearSlipBound",
    "NodalLaw",
    "StackedLaw",
    "create_law",
    "parameter_names",
]

#: Every contact law by its case-file name (``law = "..."``), in the order the classes were defined.
LAWS: dict[str, type[ContactLaw]] = {}

#: The law of a case-file contact table without a ``law`` key.
DEFAULT_LAW = "coulomb"


class NodalLaw(abc.ABC):
    """The slip bound b_i(lambda) >= 0 (N) of each contact node after lumping.

    Arrays of normal forces lambda >= 0 (N) hold one value per contact node, in the
    order of the nodes the law was lumped to; the results broadcast to that shape.
    """

    @abc.abstractmethod
    def bound(self, normal_force: np.ndarray) -> np.ndarray:
        """b(lambda) (N): the largest friction force at normal force lambda."""

    @abc.abstractmethod
    def slope(self, normal_force: np.ndarray) -> np.ndarray:
        """db/dlambda (dimensionless), what the coupling row of the SCD bases needs (Cor. 6.7)."""

    @property
    @abc.abstractmethod
    def slope_bound(self) -> float:
        """sup |db/dlambda| over lambda >= 0: the Lipschitz constant of b (Prop. 6.4) on this rank's nodes."""

    @property
    @abc.abstractmethod
    def frictional(self) -> bool:
        """Whether b is nonzero for some lambda at some node of this rank (friction acts)."""


@dataclasses.dataclass(frozen=True, eq=False)
class LinearSlipBound(NodalLaw):
    """b = s + F lambda: Coulomb (s = 0), Tresca (F = 0) and frictionless (s = F = 0) after lumping.

    Attributes:
        given: s >= 0 (N), a number or one per node (a Tresca bound times the node's
            area, or the bound of the current iterate in the fixed-point method).
        friction: F >= 0, a number or one per node.
    """

    given: float | np.ndarray = 0.0
    friction: float | np.ndarray = 0.0

    def bound(self, normal_force: np.ndarray) -> np.ndarray:
        return self.given + self.friction * normal_force

    def slope(self, normal_force: np.ndarray) -> np.ndarray:
        return np.broadcast_to(self.friction, np.shape(normal_force))

    @property
    def slope_bound(self) -> float:
        return float(np.max(self.friction, initial=0.0))

    @property
    def frictional(self) -> bool:
        return bool(np.any(self.friction) or np.any(self.given))


@dataclasses.dataclass(frozen=True, eq=False)
class StackedLaw(NodalLaw):
    """The nodal laws of several contact pairs as one: node i follows ``laws[law_of_node[i]]``.

    Attributes:
        laws: each pair's nodal law, lumped to that pair's nodes (in their order).
        law_of_node: (m,) index into ``laws`` of each contact node.
    """

    laws: tuple[NodalLaw, ...]
    law_of_node: np.ndarray

    def _per_node(self, normal_force: np.ndarray,
                  value: typing.Callable[[NodalLaw, np.ndarray], np.ndarray]) -> np.ndarray:
        """``value(law, lambda)`` of each pair's law at its nodes, as one (m,) array."""
        normal_force = np.asarray(normal_force, dtype=float)
        out = np.zeros(normal_force.shape)
        for k, law in enumerate(self.laws):
            nodes = np.flatnonzero(self.law_of_node == k)
            out[nodes] = value(law, normal_force[nodes])
        return out

    def bound(self, normal_force: np.ndarray) -> np.ndarray:
        return self._per_node(normal_force, lambda law, lam: law.bound(lam))

    def slope(self, normal_force: np.ndarray) -> np.ndarray:
        return self._per_node(normal_force, lambda law, lam: law.slope(lam))

    @property
    def slope_bound(self) -> float:
        return max(law.slope_bound for law in self.laws)

    @property
    def frictional(self) -> bool:
        return any(law.frictional for law in self.laws)


@dataclasses.dataclass(frozen=True)
class LawParameter:
    """One parameter of a contact law, as a case file gives it.

    Attributes:
        help: what it is, as a noun phrase (``"a friction coefficient"``).
        unit: its unit (``"Pa"``), empty if dimensionless.
        allow_zero: 0 is a valid value (else it must be > 0); negative values never are.
    """

    help: str
    unit: str = ""
    allow_zero: bool = True

    @property
    def range_text(self) -> str:
        """``a friction coefficient >= 0``, ``a slip bound > 0 (Pa)``."""
        unit = f" ({self.unit})" if self.unit else ""
        return f"{self.help} {'>=' if self.allow_zero else '>'} 0{unit}"

    def check(self, name: str, value: typing.Any, law: str) -> float:
        """``value`` as a float; :class:`~contactqvi.parameters.ParameterError` named ``name``."""
        require(value is not None, name, f"law = {law!r} needs {self.range_text}")
        value = require_number(name, value)
        require_positive(name, value, allow_zero=self.allow_zero)
        return value


class ContactLaw(abc.ABC):
    """A contact law as the user gives it: ``law = NAME`` and its parameters in a case file.

    Subclasses are frozen dataclasses whose fields are the :attr:`parameters` (in
    their units), with a class attribute :attr:`name`; defining one registers it in
    :data:`LAWS`.
    """

    #: Case-file name (``law = "..."``).
    name: typing.ClassVar[str]
    #: Parameters by case-file key, in the order of the dataclass fields.
    parameters: typing.ClassVar[dict[str, LawParameter]] = {}

    def __init_subclass__(cls, **kwargs: typing.Any) -> None:
        super().__init_subclass__(**kwargs)
        if "name" in cls.__dict__:
            assert cls.name not in LAWS, f"two contact laws named {cls.name!r}"
            LAWS[cls.name] = cls

    @abc.abstractmethod
    def lumped(self, area: float | np.ndarray) -> NodalLaw:
        """The nodal law of slave nodes with contact areas ``area`` (m^2, one per node).

        Tractions (Pa) become nodal forces (N) by the node's area: a Tresca bound
        tau becomes s_i = tau area_i, a pressure lambda_i / area_i.
        """

    @property
    def frictional(self) -> bool:
        """Whether the law resists tangential motion at some normal force (checks that a body is held)."""
        return self.lumped(np.ones(1)).frictional

    def to_dict(self) -> dict[str, typing.Any]:
        """The law as the keys of a case-file contact table: ``{"law": name, **parameters}``."""
        values = {key: getattr(self, key) for key in self.parameters}
        return {"law": self.name, **{key: value for key, value in values.items() if value is not None}}

    def checked(self, path: str = "") -> ContactLaw:
        """The law with its parameters checked and made floats; errors named ``{path}.{key}``."""
        return create_law(self.to_dict(), path)


def parameter_names() -> list[str]:
    """The case-file keys of all laws' parameters, each once, in the order of :data:`LAWS`."""
    return list(dict.fromkeys(key for cls in LAWS.values() for key in cls.parameters))


def create_law(table: collections.abc.Mapping[str, typing.Any], path: str = "") -> ContactLaw:
    """The contact law of a case-file table: ``law`` (default :data:`DEFAULT_LAW`) and its parameters.

    Keys other than ``law`` and the laws' parameter names are the caller's (e.g. a
    pair's ``slave``) and are ignored here; a parameter of another law is an error.

    Raises:
        ParameterError: named ``{path}.law`` or ``{path}.{key}``: an unknown law, a
            parameter the law does not take, a missing or invalid one.
    """
    name = table.get("law", DEFAULT_LAW)
    require_choice(_join(path, "law"), name, LAWS)
    cls = LAWS[name]
    for key in parameter_names():
        if table.get(key) is not None and key not in cls.parameters:
            users = " or ".join(repr(law) for law, other in LAWS.items() if key in other.parameters)
            require(False, _join(path, key), f"only used with law = {users}")
    return cls(**{key: p.check(_join(path, key), table.get(key), name) for key, p in cls.parameters.items()})


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key
