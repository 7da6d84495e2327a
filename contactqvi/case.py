"""Contact cases: a user's contact problem as a TOML file or as Python dataclasses.

A case file is data, not code (stdlib :mod:`tomllib`); it maps one-to-one onto
:class:`ContactCase`, whose sections tests and notebooks may also build directly.
SI units throughout (m, Pa, N/m^3). Example::

    [mesh]
    file = "../meshes/arch_block.geo"   # gmsh .geo/.msh, relative to this file
    # box = {lev = 5, geometry = "d3"}  # ... or the body Omega(d) of seed 000, Sect. 7

    [material]
    young = 70e9                        # Young's modulus E (Pa)
    poisson = 0.334                     # Poisson's ratio nu, in (-1, 0.5)

    [boundary]
    clamped = ["dirichlet"]             # physical groups with u = 0
    body_force = [0.0, 0.0, -26500.0]   # optional (N/m^3)
    [boundary.displacement.symmetry_y]  # optional: prescribed components (m) of u
    y = 0.0
    [boundary.traction]                 # surface tractions (Pa) per physical group
    top = [0.0, 0.0, -1e9]

    [contact]
    surface = "contact"                 # physical group that may touch the obstacle
    law = "coulomb"                     # the contact law and its parameters (below)
    friction = 0.23                     # Coulomb coefficient F >= 0

    [obstacle]                          # rigid; the body lies on the side of `normal`,
    type = "plane"                      # outside a sphere or cylinder
    point = [0.0, 0.0, 0.0]             # plane: point, normal (normalised here)
    normal = [0.0, 0.0, 1.0]            # sphere: center, radius; cylinder: point, axis, radius

    [[steps]]                           # load path; none = one step, load 1, no translation
    load = 0.5                          # factor on tractions, body force, prescribed displacements
    translation = [0.0, 0.0, 0.0]       # translation (m) of the obstacle and of boundary.moved groups
    # fit = 0.5                         # fraction of the [[contacts]] interferences resolved (default 1)
    # rotation = {axis = [0, 0, 1], angle = 30.0, centre = [0, 0, 0]}  # of the obstacle and the
    #                                   # boundary.moved groups: x = Q (X - centre) + centre + translation;
    #                                   # degrees, total; one centre for the whole path; a rotated
    #                                   # obstacle needs [contact] search = "every_step", "until_settled"
    #                                   # or "newton"
    [[steps]]
    load = 1.0

    [solver]                            # SCD Newton parameters, names as in demos/coulomb3d.py
    pc = "gamg"
    tol = 0.1

    [petsc]                             # PETSc options under the solver's prefix
    ksp_monitor = true                  # true: a flag without value

Several bodies: one gmsh file whose physical volumes are the bodies (sharing no
nodes); each ``[[bodies]]`` entry names its volume, its material and its own
boundary conditions on facet groups of that body, and ``[[contacts]]`` pairs a
slave surface with a master surface (``"body.group"``) or with a rigid obstacle
(then ``[material]``, ``[boundary]``, ``[contact]`` and ``[obstacle]`` are not used)::

    [mesh]
    file = "../meshes/patch_blocks.geo"

    # [material]
    # model = "neo_hookean"             # optional: every body's model unless its material names one

    [[bodies]]
    name = "lower"                      # physical volume group
    material = {young = 1e9, poisson = 0.3}
    [bodies.boundary.displacement]
    bottom = {z = 0.0}                  # the group "bottom" where it bounds "lower"

    [[bodies]]
    name = "upper"
    material = {young = 3e9, poisson = 0.3}
    [bodies.boundary.traction]
    top = [0.0, 0.0, -1e6]

    [[contacts]]
    slave = "upper.interface"           # "body.group"
    master = "lower.interface"          # ... or obstacle = {type = "plane", ...}
    law = "coulomb"                     # as in [contact]
    friction = 0.3
    # search_distance = 0.01            # m; default: each slave facet's longest edge
    # search = "newton"                 # the geometry inside the Newton iteration (default for
    #                                   # hyperelastic bodies of linear elements, quasi-static);
    #                                   # "every_step" (default otherwise): before each step;
    #                                   # "until_settled": also after each step, solved again
    #                                   # until it settles; "once": the reference configuration
    # interference = 1e-4               # m: the surfaces overlap by this as meshed (a press fit), or
    #                                   # linear in x (a taper): {value = 1e-4, at = [0, 0, 0],
    #                                   # slope = [0, 0, 2e-3]}, delta(x) = value + slope . (x - at)
    # cylinder = {axis = [0, 0, 1], point = [0, 0, 0]}  # both surfaces coaxial cylinders: the gap
    #                                   # between the exact ones, not the facets (linear elasticity)

Time (implicit dynamics, docs/dynamics.md): a ``[dynamics]`` table makes the case a
time integration instead of a quasi-static load path; every body needs its density, and
the ``[[steps]]``, if any, are time points (the load factor and translation linear in time
between them, :func:`~contactqvi.load_steps.at_time`; none: constant loads)::

    [dynamics]
    scheme = "newmark"                  # or "hht" (alpha = 0.05), "generalized_alpha" (rho_infinity = 0.8);
                                        # all contact-stabilised; newmark: beta = 1/4, gamma = 1/2
    dt = 1e-5                           # time step (s) > 0
    end = 1e-3                          # end time (s)
    initial_velocity = [0.0, 0.0, -1.0] # m/s; with [[bodies]]: each body's own key
    [material]
    density = 7800.0                    # kg/m^3 (each body's material with [[bodies]])
    [[steps]]
    time = 5e-4                         # s; from load 0 at t = 0 to load 1 at 0.5 ms, then held
    load = 1.0
    translation = [0.0, 0.0, -1e-4]     # the obstacles and moved groups, m

Contact laws (:data:`contactqvi.laws.LAWS`; ``law`` may be left out for ``coulomb``),
with the keys each takes beside ``law`` (checked by the law's class, errors named by
the key path, ``contacts[0].friction``):

* ``coulomb``: ``friction`` = F >= 0, the friction force is at most F times the
  normal force (seed 000; F = 0 is frictionless);
* ``tresca``: ``slip_bound`` > 0 (Pa), a bound on the friction traction whatever
  the normal force;
* ``frictionless``: no keys;
* ``pressure_coulomb``: ``friction`` = F0 >= 0, ``friction_limit`` = F_inf >= 0 and
  ``pressure_scale`` = p0 > 0 (Pa): Coulomb friction with the coefficient
  F(p) = F0 + (F_inf - F0) p / (p + p0) at contact pressure p.

The same case in Python (sections left out take their defaults)::

    ContactCase(
        mesh=MeshSource(file="meshes/arch_block.geo"),
        material=Material(young=70e9, poisson=0.334),
        boundary=Boundary(clamped=["dirichlet"], traction={"top": (0, 0, -1e9)}),
        contact=Contact("contact", Coulomb(friction=0.23)),   # the law: contactqvi.laws
        obstacle=ObstacleShape("plane", point=(0, 0, 0), normal=(0, 0, 1)),
        steps=[Step(load=0.5), Step(load=1.0)],
    )

``case.obstacle.create()`` is the :mod:`contactqvi.obstacles` object, and
``case.to_dict()`` the tables again (for ``summary.json``).

:func:`load_case` validates everything that needs no mesh and no solver before any
expensive work; errors are :class:`~contactqvi.parameters.ParameterError` named by
the key path (``obstacle.normal``, ``steps[2].translation``), unknown keys name the
closest valid one. The case layer imports no solver: :func:`check_solver` checks
``[solver]`` against the table the program passes (the runner: the SCD solver's),
before the mesh is read. Checks that need the mesh belong to the problem builder;
:func:`check_groups` does the physical-group part of them.
"""

from __future__ import annotations

import collections.abc
import dataclasses
import difflib
import math
import os
import pathlib
import tomllib
import typing

from contactqvi import obstacles
from contactqvi.exact_surfaces import CoaxialCylinders, check_cylinders
from contactqvi.interference import Interference, check_interference
from contactqvi.laws import LAWS, ContactLaw, create_law, parameter_names
from contactqvi.load_steps import SEARCHES, Rotation, check_fit, check_rotation, check_steps, rotates
from contactqvi.materials import FORMULATIONS, MATERIALS
from contactqvi.load_steps import LoadStep as Step
from contactqvi.parameters import (
    ParameterError,
    Parameters,
    require,
    require_choice,
    require_number,
    require_positive,
)
from contactqvi.time_scheme import SCHEMES, TimeScheme

__all__ = [
    "OBSTACLE_KEYS",
    "Body",
    "Boundary",
    "Contact",
    "ContactCase",
    "DEFAULT_HHT_ALPHA",
    "DEFAULT_RHO_INFINITY",
    "DYNAMICS_SCHEMES",
    "Dynamics",
    "ContactPair",
    "Displacement",
    "Interference",
    "Material",
    "MeshSource",
    "ObstacleShape",
    "PaperBody",
    "Rotation",
    "Step",
    "check_bodies",
    "check_groups",
    "check_solver",
    "load_case",
    "parse_case",
]

#: Keys of ``[obstacle]`` besides ``type``, per obstacle type.
OBSTACLE_KEYS: dict[str, tuple[str, ...]] = {
    "plane": ("point", "normal"),
    "sphere": ("center", "radius"),
    "cylinder": ("point", "axis", "radius"),
}

Vector = tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class PaperBody:
    """``mesh.box``: the body Omega(d) of seed 000, Sect. 7 (hexahedra, named facets
    ``dirichlet``, ``right``, ``top``, ``contact``, ``front``, ``back``).

    Attributes:
        lev: discretisation level (Table 2), an integer >= 0.
        geometry: bottom surface d, one of ``d1``, ``d2``, ``d3``
            (:data:`contactqvi.problems.coulomb.GEOMETRIES`).
    """

    lev: int = 5
    geometry: str = "d1"


@dataclasses.dataclass(frozen=True)
class MeshSource:
    """``[mesh]``: where the body comes from; exactly one of ``file`` and ``box``.

    Attributes:
        file: a gmsh ``.geo`` or ``.msh`` file whose physical groups name the
            boundaries (in a case file: relative to the case file).
        box: the paper's body instead of a file.
        order: of the elements' displacements: 1 (linear) or 2 (quadratic: P2 on 10-node
            tetrahedra, Q2 on 27-node hexahedra, curved where the mesh file is of second order;
            docs/quadratic.md).
    """

    file: pathlib.Path | None = None
    box: PaperBody | None = None
    order: int = 1


@dataclasses.dataclass(frozen=True)
class Material:
    """``[material]``: isotropic elasticity, small strain (linear) or hyperelastic.

    Attributes:
        young: Young's modulus E (Pa), > 0 (of the linearisation at rest).
        poisson: Poisson's ratio nu, in (-1, 0.5).
        model: None (linear elasticity, small strain) or a hyperelastic material of
            :data:`contactqvi.materials.MATERIALS` (finite strain: ``"neo_hookean"``,
            ``"saint_venant_kirchhoff"``). With ``[[bodies]]`` every body takes the same model;
            a case file's ``[material]`` may then hold ``model`` alone, the default of the bodies.
        density: mass density rho (kg/m^3) > 0, required with ``[dynamics]`` (unused without).
        formulation: how the volume change is discretised, one of
            :data:`contactqvi.materials.FORMULATIONS`: ``"displacement"`` (plain P1) or
            ``"nodal_pressure"`` (averaged at the nodes: for nearly incompressible bodies,
            docs/nearly_incompressible.md); with ``[[bodies]]`` each body its own.
    """

    young: float
    poisson: float
    model: str | None = None
    density: float | None = None
    formulation: str = "displacement"


@dataclasses.dataclass(frozen=True)
class Displacement:
    """``[boundary.displacement.NAME]``: prescribed components of u (m) on a group;
    ``None`` leaves a component free (e.g. ``Displacement(y=0.0)``: a roller on y = const).
    """

    x: float | None = None
    y: float | None = None
    z: float | None = None

    def components(self) -> dict[int, float]:
        """The prescribed components by index (0, 1, 2), e.g. ``{1: 0.0}``."""
        return {i: value for i, value in enumerate((self.x, self.y, self.z)) if value is not None}


@dataclasses.dataclass(frozen=True)
class Boundary:
    """``[boundary]``: conditions on physical groups of the mesh.

    Attributes:
        clamped: groups with u = 0.
        displacement: group -> prescribed components of u (m).
        traction: group -> surface traction [tx, ty, tz] (Pa), scaled by the step's load.
        body_force: [fx, fy, fz] (N/m^3), scaled by the step's load; ``None``: none.
        moved: groups whose displacement is the step's ``translation`` (all three
            components, moved rigidly with the obstacles; not scaled by ``load``).
        pressure: group -> pressure p (Pa, > 0 pushes into the body), scaled by the step's
            load: the traction -p n, on the deformed surface for a hyperelastic material.
    """

    clamped: tuple[str, ...] = ()
    displacement: dict[str, Displacement] = dataclasses.field(default_factory=dict)
    traction: dict[str, Vector] = dataclasses.field(default_factory=dict)
    body_force: Vector | None = None
    moved: tuple[str, ...] = ()
    pressure: dict[str, float] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class Contact:
    """``[contact]``: the surface that may touch the obstacle, and its contact law.

    In a case file the law is ``law = NAME`` and its parameters, keys of the same
    table (``law = "coulomb"``, ``friction = 0.23``); here it is one object.

    Attributes:
        surface: physical group of the contact surface.
        law: the contact law (:mod:`contactqvi.laws`), e.g. ``Coulomb(friction=0.23)``,
            ``Tresca(slip_bound=1e8)``, ``Frictionless()``.
        search: ``"once"`` (gaps and normals of the reference configuration; None means
            it), or ``"every_step"`` / ``"until_settled"``: found again in the deformed
            configuration (finite displacements on a curved obstacle; :class:`ContactPair`), or
            ``"newton"``: the geometry a function of the iterate inside the Newton iteration
            (hyperelastic bodies; docs/finite_strain.md, Sect. 18).
    """

    surface: str
    law: ContactLaw | None = None
    search: str | None = None


@dataclasses.dataclass(frozen=True)
class ObstacleShape:
    """``[obstacle]``: a rigid obstacle in its initial position.

    ``type = "plane"``: ``point``, unit ``normal`` pointing into the body's side;
    ``"sphere"``: ``center``, ``radius``; ``"cylinder"``: ``point`` on the axis,
    ``axis``, ``radius``. The body lies outside a sphere or cylinder. Directions
    are normalised when the case is checked; lengths in m.
    """

    type: str
    point: Vector | None = None
    normal: Vector | None = None
    center: Vector | None = None
    axis: Vector | None = None
    radius: float | None = None

    def create(self) -> obstacles.Obstacle:
        """The analytic obstacle (:mod:`contactqvi.obstacles`) in its initial position."""
        kinds = {"plane": obstacles.Plane, "sphere": obstacles.Sphere, "cylinder": obstacles.Cylinder}
        return kinds[self.type](**{key: getattr(self, key) for key in OBSTACLE_KEYS[self.type]})


@dataclasses.dataclass(frozen=True)
class Body:
    """``[[bodies]]``: one body of a mesh with several.

    Attributes:
        name: its physical volume group in the mesh.
        material: its material.
        boundary: conditions on facet groups where they bound this body (group names
            without the body's name; at least one body needs a support, the others
            may be held by contact alone).
        initial_velocity: the body's velocity at time 0 (m/s) with ``[dynamics]``; None: at rest.
    """

    name: str
    material: Material
    boundary: Boundary = Boundary()
    initial_velocity: Vector | None = None


#: Time-stepping schemes of ``[dynamics] scheme`` (docs/dynamics.md, :mod:`contactqvi.time_scheme`),
#: each with the contact-stabilised predictor of Deuflhard, Krause and Ertel (2008).
DYNAMICS_SCHEMES = SCHEMES
#: The defaults of HHT's ``alpha`` (Abaqus/Standard's "moderate dissipation", -0.05 in its sign)
#: and of generalized-α's ``rho_infinity``.
DEFAULT_HHT_ALPHA = 0.05
DEFAULT_RHO_INFINITY = 0.8


@dataclasses.dataclass(frozen=True)
class Dynamics:
    """``[dynamics]``: an implicit time integration instead of a quasi-static load path.

    Attributes:
        dt: the time step (s) > 0.
        end: the end time (s) >= dt; the steps are t_k = k dt, k = 1, ..., ceil(end / dt)
            (all of length dt: the last one ends at ``end`` or just after it).
        scheme: one of :data:`DYNAMICS_SCHEMES`.
        initial_velocity: the body's velocity at time 0 (m/s), one body; with ``[[bodies]]``
            each body's ``initial_velocity``. None: at rest.
        alpha: HHT's alpha in [0, 1/3] (``scheme = "hht"`` only; None: :data:`DEFAULT_HHT_ALPHA`).
        rho_infinity: generalized-α's spectral radius at infinite frequency in [0, 1]
            (``scheme = "generalized_alpha"`` only; None: :data:`DEFAULT_RHO_INFINITY`).
    """

    dt: float
    end: float
    scheme: str = "newmark"
    initial_velocity: Vector | None = None
    alpha: float | None = None
    rho_infinity: float | None = None

    def time_scheme(self) -> TimeScheme:
        """The (alpha_m, alpha_f, beta, gamma) of ``scheme`` and its parameter."""
        if self.scheme == "hht":
            return TimeScheme.hht(DEFAULT_HHT_ALPHA if self.alpha is None else self.alpha)
        if self.scheme == "generalized_alpha":
            rho_infinity = DEFAULT_RHO_INFINITY if self.rho_infinity is None else self.rho_infinity
            return TimeScheme.generalized_alpha(rho_infinity)
        return TimeScheme.newmark()

    @property
    def steps(self) -> int:
        """The number of time steps, ceil(end / dt) (an end within 1e-9 dt of a step is that step)."""
        return math.ceil(self.end / self.dt - 1e-9)


@dataclasses.dataclass(frozen=True)
class ContactPair:
    """``[[contacts]]``: a slave surface and what it may touch.

    Attributes:
        slave: ``"body.group"``, the surface whose nodes carry the contact conditions.
        master: ``"body.group"`` of another body's surface (mortar coupling), or
        obstacle: a rigid obstacle (exactly one of ``master`` and ``obstacle``).
        law: the contact law, as in :class:`Contact`.
        search_distance: reach of the contact search (m) > 0; None: each slave
            facet's longest edge.
        search: when the pair is searched: ``"every_step"`` (before every load step
            after the first, in the configuration the step before ended in),
            ``"until_settled"`` (also after each step, which is solved again until its
            configuration settles), ``"newton"`` (the geometry a function of the iterate
            inside the Newton iteration, hyperelastic bodies; docs/finite_strain.md, Sects. 14
            and 18) or ``"once"`` (in the reference configuration
            only); None: ``"once"`` for an obstacle, and for a ``master`` ``"newton"`` where the bodies are
            hyperelastic, of linear elements and on a quasi-static path, ``"every_step"`` otherwise.
        interference: the overlap of the slave and master surfaces as meshed (m, >= 0;
            a press or shrink fit), or an :class:`~contactqvi.interference.Interference`
            linear in position (a taper); resolved in the first load step, or over the
            steps' ``fit`` fractions; body pairs only
            (:class:`~contactqvi.contact.interface.BodyPair`, docs/press_fit.md). None: 0.
        cylinder: the slave and master surfaces are coaxial cylinders about this axis
            (:class:`~contactqvi.exact_surfaces.CoaxialCylinders`): the weighted gap is taken between
            the exact cylinders, not the facets (a press fit; linear elasticity, body pairs only).
    """

    slave: str
    master: str | None = None
    obstacle: ObstacleShape | None = None
    law: ContactLaw | None = None
    search_distance: float | None = None
    search: str | None = None
    interference: float | Interference | None = None
    cylinder: CoaxialCylinders | None = None


@dataclasses.dataclass(frozen=True)
class ContactCase:
    """A contact problem: body, material, boundary conditions, obstacle, load path, solver.

    Every value is checked and normalised on construction (vectors become tuples of
    floats, the plane normal and cylinder axis unit vectors; no steps become one
    step with load 1 and no translation); :class:`ParameterError` names the key path.

    Attributes:
        mesh, material, boundary, contact, obstacle: the sections of the same names.
        steps: the load path, at least one step.
        dynamics: the time integration (:class:`Dynamics`), or None: a quasi-static path.
        solver: SCD Newton parameters (names of ``contactqvi.contact.scd_newton.PARAMETERS``).
        petsc: PETSc options (without ``-`` and prefix) set under the solver's prefix;
            ``True`` is a flag without value.
    """

    mesh: MeshSource
    material: Material | None = None
    boundary: Boundary | None = None
    contact: Contact | None = None
    obstacle: ObstacleShape | None = None
    steps: tuple[Step, ...] = ()
    solver: dict[str, typing.Any] = dataclasses.field(default_factory=dict)
    petsc: dict[str, typing.Any] = dataclasses.field(default_factory=dict)
    bodies: tuple[Body, ...] = ()
    contacts: tuple[ContactPair, ...] = ()
    dynamics: Dynamics | None = None

    def __post_init__(self):
        checked = {"mesh": _check_mesh(self.mesh), "steps": _check_steps(self.steps),
                   "solver": _check_solver(self.solver), "petsc": _check_petsc(self.petsc)}
        if self.bodies or self.contacts:
            for name in ("material", "boundary", "contact", "obstacle"):
                require(getattr(self, name) is None, name, "not used with [[bodies]]: give each body its "
                        "material (Body(material=Material(young, poisson, model))) and boundary, and each contact "
                        "pair its obstacle")
            require(self.mesh.file is not None, "mesh.file", "several bodies need a gmsh file with one "
                    "physical volume per body")
            checked["bodies"] = _check_bodies(self.bodies, held=self.dynamics is None)
            checked["contacts"] = _check_contacts(self.contacts, _body_pair_search(checked["bodies"], checked["mesh"],
                                                                                   self.dynamics))
        else:
            for name in ("material", "boundary", "contact", "obstacle"):
                require(getattr(self, name) is not None, name, f"required table [{name}] missing")
            checked.update(material=_check_material(self.material, "material"),
                           boundary=_check_boundary(self.boundary, "boundary", supported=self.dynamics is None),
                           contact=_check_contact(self.contact), obstacle=_check_obstacle(self.obstacle, "obstacle"))
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        if not self.bodies:
            _check_consistency(self)
        _check_rotations(self)
        _check_fits(self)
        _check_limit_points(self)
        if self.dynamics is not None:
            object.__setattr__(self, "dynamics", _check_dynamics(self))
        else:
            timed = next((i for i, step in enumerate(self.steps) if step.time is not None), None)
            require(timed is None, f"steps[{timed}].time", "a time point belongs to a time integration: add "
                    "[dynamics] (a quasi-static path's steps have no time)")

    @property
    def groups(self) -> list[str]:
        """The facet groups the case names, each once, in file order (``"body.group"``
        with several bodies)."""
        return list(dict.fromkeys(name for _, name in _group_uses(self)))

    @property
    def pair_keys(self) -> list[tuple[str, str | None]]:
        """Each contact pair's key in the case file and its obstacle's (None for a body pair), in
        the order of the problem's interfaces: ``("contact", "obstacle")`` for [contact] and
        [obstacle], ``("contacts[i]", "contacts[i].obstacle")`` for [[contacts]]."""
        if self.contact is not None:
            return [("contact", "obstacle")]
        return [(f"contacts[{i}]", f"contacts[{i}].obstacle" if pair.obstacle is not None else None)
                for i, pair in enumerate(self.contacts)]

    def to_dict(self) -> dict[str, typing.Any]:
        """The case as the tables of a case file (JSON-ready: lists, strings; unset keys left out)."""
        return _plain(self)


# -- reading -----------------------------------------------------------------------


def load_case(path: str | pathlib.Path) -> ContactCase:
    """Read and check the case file ``path`` (``mesh.file`` is relative to it)."""
    path = pathlib.Path(path)
    require(path.is_file(), "case", f"case file {str(path)!r} not found")
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("case", f"{path}: invalid TOML: {exc}") from None
    return parse_case(data, path.parent)


def parse_case(data: collections.abc.Mapping, base_dir: str | pathlib.Path = ".") -> ContactCase:
    """The :class:`ContactCase` of the tables ``data`` of a case file.

    Args:
        data: the parsed TOML document.
        base_dir: directory a relative ``mesh.file`` is taken from.
    """
    top = _table(data, "", ContactCase, required=False)
    mesh = _section(top, "mesh", MeshSource)
    if mesh.get("box") is not None:
        mesh["box"] = PaperBody(**_table(mesh["box"], "mesh.box", PaperBody))
    if mesh.get("file") is not None:
        require(isinstance(mesh["file"], str), "mesh.file", f"must be a file name, got {mesh['file']!r}")
        mesh["file"] = pathlib.Path(os.path.normpath(pathlib.Path(base_dir) / mesh["file"]))
    common = {
        "mesh": MeshSource(**mesh),
        "steps": tuple(_parse_step(step, f"steps[{i}]") for i, step in enumerate(_array(top, "steps"))),
        "solver": _table(top.get("solver", {}), "solver"),
        "petsc": _table(top.get("petsc", {}), "petsc"),
        "dynamics": Dynamics(**_table(top["dynamics"], "dynamics", Dynamics)) if "dynamics" in top else None,
    }
    if top.get("bodies") or top.get("contacts"):
        model = _default_model(top)
        return ContactCase(**common, **{name: top[name] for name in _ONE_BODY if name in top and name != "material"},
                           bodies=tuple(_parse_body(b, f"bodies[{i}]", model)
                                        for i, b in enumerate(_array(top, "bodies"))),
                           contacts=tuple(_parse_pair(c, f"contacts[{i}]")
                                          for i, c in enumerate(_array(top, "contacts"))))
    return ContactCase(
        **common,
        material=Material(**_section(top, "material", Material)),
        boundary=_parse_boundary(_section(top, "boundary", Boundary), "boundary"),
        contact=Contact(**_with_law(_section(top, "contact", Contact, parameter_names()), "contact")),
        obstacle=ObstacleShape(**_section(top, "obstacle", ObstacleShape)),
    )


_ONE_BODY = ("material", "boundary", "contact", "obstacle")


def _array(top: dict[str, typing.Any], name: str) -> list[typing.Any]:
    value = top.get(name, [])
    require(_is_list(value), name, f"must be an array of tables [[{name}]], got {value!r}")
    return list(value)


def _parse_step(value: typing.Any, path: str) -> Step:
    step = _table(value, path, Step)
    if "rotation" in step:
        step["rotation"] = Rotation(**_table(step["rotation"], f"{path}.rotation", Rotation))
    return Step(**step)


def _parse_boundary(boundary: dict[str, typing.Any], path: str) -> Boundary:
    if "displacement" in boundary:
        groups = _table(boundary["displacement"], f"{path}.displacement")
        boundary["displacement"] = {
            name: Displacement(**_table(value, f"{path}.displacement.{name}", Displacement))
            for name, value in groups.items()
        }
    for key in ("traction", "pressure"):
        if key in boundary:
            boundary[key] = _table(boundary[key], f"{path}.{key}")
    return Boundary(**boundary)


def _default_model(top: dict[str, typing.Any]) -> str | None:
    """``[material] model`` of a case with ``[[bodies]]``: the model of every body that names none."""
    if "material" not in top:
        return None
    material = _table(top["material"], "material", Material, required=False)
    for key in material:
        require(key == "model", f"material.{key}", "with [[bodies]], [material] gives only the default model of "
                f"the bodies; give {key} in each body's material (bodies[i].material = {{young = ..., poisson = "
                "...}})")
    return material.get("model")


def _parse_body(value: typing.Any, path: str, model: str | None = None) -> Body:
    """A ``[[bodies]]`` entry; ``model``: the default of its material's model (``[material] model``)."""
    body = _table(value, path, Body)
    material = _table(body["material"], f"{path}.material", Material)
    body["material"] = Material(**{"model": model, **material})
    if "boundary" in body:
        body["boundary"] = _parse_boundary(_table(body["boundary"], f"{path}.boundary", Boundary), f"{path}.boundary")
    return Body(**body)


def _parse_pair(value: typing.Any, path: str) -> ContactPair:
    pair = _with_law(_table(value, path, ContactPair, extra=parameter_names()), path)
    if "obstacle" in pair:
        pair["obstacle"] = ObstacleShape(**_table(pair["obstacle"], f"{path}.obstacle", ObstacleShape))
    if isinstance(pair.get("interference"), collections.abc.Mapping):
        pair["interference"] = Interference(**_table(pair["interference"], f"{path}.interference", Interference))
    if "cylinder" in pair:
        pair["cylinder"] = CoaxialCylinders(**_table(pair["cylinder"], f"{path}.cylinder", CoaxialCylinders))
    return ContactPair(**pair)


def _with_law(table: dict[str, typing.Any], path: str) -> dict[str, typing.Any]:
    """A contact table with ``law`` and the law's parameter keys replaced by the law object."""
    keys = ("law", *parameter_names())
    table["law"] = create_law({key: table.pop(key) for key in keys if key in table}, path)
    return table


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _table(value: typing.Any, path: str, cls: type | None = None, required: bool = True,
           extra: typing.Sequence[str] = ()) -> dict[str, typing.Any]:
    """``value`` as a dict; with ``cls``, its keys checked against the fields of ``cls`` and
    ``extra`` (and, if ``required``, the fields without default present)."""
    require(isinstance(value, collections.abc.Mapping), path or "case", f"must be a table, got {value!r}")
    value = dict(value)
    if cls is None:
        return value
    fields = [f.name for f in dataclasses.fields(cls)] + list(extra)
    for key in value:
        if key not in fields:
            close = difflib.get_close_matches(key, fields, n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"valid keys: {', '.join(fields)}"
            if path and key in _SECTIONS:
                hint = f"a key written after the header [{path}] belongs to that table; move '{key}' above it"
            raise ParameterError(_join(path, key), f"unknown key; {hint}")
    for f in dataclasses.fields(cls) if required else ():
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            require(f.name in value, _join(path, f.name), "required key missing")
    return value


_SECTIONS = tuple(f.name for f in dataclasses.fields(ContactCase))


def _section(top: dict[str, typing.Any], name: str, cls: type,
             extra: typing.Sequence[str] = ()) -> dict[str, typing.Any]:
    require(name in top, name, f"required table [{name}] missing")
    return _table(top[name], name, cls, extra=extra)


# -- checks (shared by files and Python-built cases) -------------------------------


def _is_list(value: typing.Any) -> bool:
    return isinstance(value, collections.abc.Sequence) and not isinstance(value, str)


def _vector(value: typing.Any, name: str) -> Vector:
    ok = _is_list(value) and len(value) == 3
    ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    require(ok, name, f"must be a list of 3 finite numbers [x, y, z], got {value!r}")
    return tuple(float(v) for v in value)


def _direction(value: typing.Any, name: str) -> Vector:
    vector = _vector(value, name)
    length = math.sqrt(sum(v * v for v in vector))
    require(length > 0.0, name, f"must have nonzero length, got {list(value)!r}")
    if math.isclose(length, 1.0, rel_tol=1e-15):  # keep a unit vector as given: checking is idempotent
        return vector
    return tuple(v / length for v in vector)


def _name(value: typing.Any, name: str) -> str:
    require(isinstance(value, str) and value != "", name, f"must be a physical group name, got {value!r}")
    return value


def _instance(value: typing.Any, cls: type, name: str) -> None:
    require(isinstance(value, cls), name, f"must be {cls.__name__}(...), got {value!r}")


def _check_mesh(mesh: MeshSource) -> MeshSource:
    _instance(mesh, MeshSource, "mesh")
    require((mesh.file is None) != (mesh.box is None), "mesh", "give exactly one of 'file' and 'box'")
    require(mesh.order in (1, 2) and not isinstance(mesh.order, bool), "mesh.order",
            f"must be 1 (linear elements) or 2 (quadratic), got {mesh.order!r}")
    if mesh.box is not None:
        _instance(mesh.box, PaperBody, "mesh.box")
        lev = mesh.box.lev
        ok = isinstance(lev, int) and not isinstance(lev, bool) and lev >= 0
        require(ok, "mesh.box.lev", f"must be an integer >= 0, got {lev!r}")
        from contactqvi.problems.coulomb import GEOMETRIES  # imports dolfinx: only for the paper's body

        require_choice("mesh.box.geometry", mesh.box.geometry, GEOMETRIES)
        return mesh
    require(isinstance(mesh.file, (str, pathlib.Path)), "mesh.file", f"must be a file name, got {mesh.file!r}")
    path = pathlib.Path(mesh.file)
    require(path.suffix in (".geo", ".msh"), "mesh.file", f"must be a gmsh .geo or .msh file, got {str(path)!r}")
    require(path.is_file(), "mesh.file", f"file {str(path)!r} not found")
    return dataclasses.replace(mesh, file=path)


def _check_material(material: Material, path: str) -> Material:
    _instance(material, Material, path)
    young = require_number(f"{path}.young", material.young)
    require_positive(f"{path}.young", young)
    poisson = require_number(f"{path}.poisson", material.poisson)
    require(-1.0 < poisson < 0.5, f"{path}.poisson", f"must lie in (-1, 0.5), got {material.poisson!r}")
    if material.model is not None:
        require_choice(f"{path}.model", material.model, ["linear", *MATERIALS])
    density = material.density
    if density is not None:
        require_positive(f"{path}.density", density)
        density = float(density)
    require_choice(f"{path}.formulation", material.formulation, FORMULATIONS)
    return Material(young, poisson, None if material.model == "linear" else material.model, density,
                    material.formulation)


def _check_boundary(boundary: Boundary, path: str, supported: bool = True) -> Boundary:
    """``boundary`` checked; ``supported``: it must hold the body (a clamped group or a
    prescribed displacement)."""
    _instance(boundary, Boundary, path)
    clamped = boundary.clamped
    require(_is_list(clamped), f"{path}.clamped", f"must be a list of group names, got {clamped!r}")
    clamped = tuple(_name(name, f"{path}.clamped[{i}]") for i, name in enumerate(clamped))
    for i, name in enumerate(clamped):
        require(name not in clamped[:i], f"{path}.clamped[{i}]", f"{name!r} listed twice")
    _instance(boundary.displacement, dict, f"{path}.displacement")
    displacement = {}
    for name, given in boundary.displacement.items():
        key = f"{path}.displacement.{name}"
        _instance(given, Displacement, key)
        components = {
            axis: None if value is None else require_number(f"{key}.{axis}", value)
            for axis, value in dataclasses.asdict(given).items()
        }
        require(any(v is not None for v in components.values()), key, "give at least one of x, y, z")
        require(name not in clamped, key, f"group {name!r} is already clamped")
        displacement[_name(name, key)] = Displacement(**components)
    _instance(boundary.traction, dict, f"{path}.traction")
    traction = {_name(name, f"{path}.traction.{name}"): _vector(value, f"{path}.traction.{name}")
                for name, value in boundary.traction.items()}
    body_force = None if boundary.body_force is None else _vector(boundary.body_force, f"{path}.body_force")
    moved = boundary.moved
    require(_is_list(moved), f"{path}.moved", f"must be a list of group names, got {moved!r}")
    moved = tuple(_name(name, f"{path}.moved[{i}]") for i, name in enumerate(moved))
    for i, name in enumerate(moved):
        require(name not in (*clamped, *displacement, *moved[:i]), f"{path}.moved[{i}]",
                f"group {name!r} already has a prescribed displacement")
    require(clamped or displacement or moved or not supported, path,
            "needs a clamped group or a prescribed displacement (rigid motions must be fixed)")
    _instance(boundary.pressure, dict, f"{path}.pressure")
    pressure = {_name(name, f"{path}.pressure.{name}"): require_number(f"{path}.pressure.{name}", value)
                for name, value in boundary.pressure.items()}
    return Boundary(clamped, displacement, traction, body_force, moved, pressure)


def _check_contact(contact: Contact) -> Contact:
    _instance(contact, Contact, "contact")
    surface = _name(contact.surface, "contact.surface")
    if contact.search is not None:
        require_choice("contact.search", contact.search, SEARCHES)
    return Contact(surface, _check_law(contact.law, "contact"), contact.search)


def _check_law(law: ContactLaw | None, path: str) -> ContactLaw:
    """``law`` checked by its own class (:meth:`~contactqvi.laws.ContactLaw.checked`)."""
    require(isinstance(law, ContactLaw), f"{path}.law", f"must be a contact law ({', '.join(LAWS)}), e.g. "
            f"Coulomb(friction=0.3) from contactqvi.laws, got {law!r}")
    return law.checked(path)


def _check_bodies(bodies: typing.Sequence[Body], held: bool = True) -> tuple[Body, ...]:
    """The ``[[bodies]]`` checked; ``held``: some body must have a support (not with ``[dynamics]``,
    where the mass holds them)."""
    require(_is_list(bodies) and len(bodies) > 0, "bodies", "give at least one [[bodies]] entry")
    checked = []
    for i, body in enumerate(bodies):
        path = f"bodies[{i}]"
        _instance(body, Body, path)
        name = _name(body.name, f"{path}.name")
        require("." not in name, f"{path}.name", f"must not contain '.', got {name!r}")
        require(name not in [b.name for b in checked], f"{path}.name", f"body {name!r} listed twice")
        material = _check_material(body.material, f"{path}.material")
        first = checked[0].material.model if checked else material.model
        require(material.model == first, f"{path}.material.model",
                f"all bodies take the same model (each its own young and poisson), got {material.model!r} here "
                f"and {first!r} in bodies[0]: a stiff part beside a hyperelastic one can be "
                "'saint_venant_kirchhoff' (linear elasticity at small strain, exact under large rotations)")
        velocity = None if body.initial_velocity is None else _vector(body.initial_velocity, f"{path}.initial_velocity")
        checked.append(Body(name, material, _check_boundary(body.boundary, f"{path}.boundary", supported=False),
                            velocity))
    supported = any(b.boundary.clamped or b.boundary.displacement or b.boundary.moved for b in checked)
    require(supported or not held, "bodies", "no body has a clamped group or a prescribed displacement; at least one "
            "must be held (the others may be held by contact)")
    return tuple(checked)


def _body_pair_search(bodies: tuple[Body, ...], mesh: MeshSource, dynamics: Dynamics | None) -> str:
    """The search of a pair of meshed bodies that does not name one: ``"newton"`` (the contact geometry
    of the current configuration inside the Newton iteration, docs/finite_strain.md Sects. 14 and 22)
    for hyperelastic bodies of linear elements on a quasi-static path, ``"every_step"`` otherwise
    (linear elasticity, quadratic elements, a time integration)."""
    hyperelastic = bool(bodies) and bodies[0].material.model is not None
    return "newton" if hyperelastic and mesh.order == 1 and dynamics is None else "every_step"


def _check_contacts(contacts: typing.Sequence[ContactPair], body_search: str) -> tuple[ContactPair, ...]:
    """The ``[[contacts]]`` pairs checked; their bodies are checked with the mesh (:func:`check_bodies`)."""
    require(_is_list(contacts) and len(contacts) > 0, "contacts", "give at least one [[contacts]] pair")
    checked = []
    for i, pair in enumerate(contacts):
        path = f"contacts[{i}]"
        _instance(pair, ContactPair, path)
        for key in ("slave", "master") if pair.master is not None else ("slave",):
            value = _name(getattr(pair, key), f"{path}.{key}")
            body, _, group = value.partition(".")
            require(body != "" and group != "", f"{path}.{key}", f"must be 'body.group', got {value!r}")
        require((pair.master is None) != (pair.obstacle is None), path, "give exactly one of 'master' and 'obstacle'")
        obstacle = None if pair.obstacle is None else _check_obstacle(pair.obstacle, f"{path}.obstacle")
        require(pair.master != pair.slave, f"{path}.master", "must differ from the slave surface")
        law = _check_law(pair.law, path)
        distance = pair.search_distance
        if distance is not None:
            distance = require_number(f"{path}.search_distance", distance)
            require_positive(f"{path}.search_distance", distance)
        search = pair.search
        if search is None:  # an obstacle's default; a body pair's (exact cylinders: of the reference configuration)
            search = "once" if obstacle is not None else body_search if pair.cylinder is None else "every_step"
        require_choice(f"{path}.search", search, SEARCHES)
        checked.append(ContactPair(pair.slave, pair.master, obstacle, law, distance, search,
                                   _check_interference(pair, path), _check_cylinder(pair, search, path)))
    return tuple(checked)


def _check_cylinder(pair: ContactPair, search: str, path: str) -> CoaxialCylinders | None:
    """A pair's ``cylinder``: between meshed bodies, searched once or before each step (its gap is
    the reference configuration's)."""
    if pair.cylinder is None:
        return None
    _instance(pair.cylinder, CoaxialCylinders, f"{path}.cylinder")
    require(pair.obstacle is None, f"{path}.cylinder", "declares the surfaces of two meshed bodies exact cylinders; "
            "a rigid obstacle is exact already")
    require(search != "newton", f"{path}.cylinder", "takes the gap of the reference configuration (linear "
            "elasticity): search the pair 'once', 'every_step' or 'until_settled', not 'newton'")
    return check_cylinders(pair.cylinder, f"{path}.cylinder")


def _check_interference(pair: ContactPair, path: str) -> float | Interference | None:
    """A pair's ``interference``: a number >= 0 (m) or an :class:`Interference` (a taper; its
    sign on the surface is checked with the mesh), between meshed bodies only."""
    if pair.interference is None:
        return None
    interference = check_interference(pair.interference, f"{path}.interference")
    require(pair.obstacle is None, f"{path}.interference", "an overlap is declared between meshed bodies only (a "
            "'master' surface); a rigid obstacle's position is exact: move it or the body")
    return interference


def _check_obstacle(obstacle: ObstacleShape, path: str) -> ObstacleShape:
    _instance(obstacle, ObstacleShape, path)
    require_choice(f"{path}.type", obstacle.type, OBSTACLE_KEYS)
    keys = OBSTACLE_KEYS[obstacle.type]
    given = {k: v for k, v in dataclasses.asdict(obstacle).items() if k != "type" and v is not None}
    for key in given:
        require(key in keys, f"{path}.{key}",
                f"not a key of a {obstacle.type} obstacle (keys: type, {', '.join(keys)})")
    for key in keys:
        require(key in given, f"{path}.{key}", f"required for a {obstacle.type} obstacle")
    checked = {}
    for key, value in given.items():
        name = f"{path}.{key}"
        if key in ("normal", "axis"):
            checked[key] = _direction(value, name)
        elif key == "radius":
            checked[key] = require_number(name, value)
            require_positive(name, checked[key])
        else:
            checked[key] = _vector(value, name)
    return ObstacleShape(obstacle.type, **checked)


def _check_steps(steps: typing.Sequence[Step]) -> tuple[Step, ...]:
    require(_is_list(steps), "steps", f"must be a list of steps, got {steps!r}")
    checked = []
    for i, step in enumerate(steps):
        _instance(step, Step, f"steps[{i}]")
        load = require_number(f"steps[{i}].load", step.load)
        require(load >= 0.0, f"steps[{i}].load", f"must be >= 0, got {load!r}")
        rotation = None if step.rotation is None else check_rotation(step.rotation, f"steps[{i}].rotation")
        time = None if step.time is None else require_number(f"steps[{i}].time", step.time)
        checked.append(Step(load, _vector(step.translation, f"steps[{i}].translation"), rotation,
                            check_fit(step.fit, f"steps[{i}].fit"), time))
    return tuple(checked) or (Step(),)


def _check_rotations(case: ContactCase) -> None:
    """Rotations of a path: one centre, something to rotate (moved groups or a rigid obstacle),
    and every rigid obstacle's pair searched each step (a rotation turns its normals)."""
    check_steps(case.steps)
    first = rotates(case.steps)
    if first is None:
        return
    moved = case.boundary.moved if case.boundary is not None else [m for b in case.bodies for m in b.boundary.moved]
    searches = {"contact.search": case.contact.search} if case.obstacle is not None else {
        f"contacts[{i}].search": p.search for i, p in enumerate(case.contacts) if p.obstacle is not None}
    require(bool(moved) or bool(searches), f"steps[{first}].rotation", "rotates the groups boundary.moved and the "
            "rigid obstacles, and the case has neither")
    for key, search in searches.items():
        require(search in ("every_step", "until_settled", "newton"), key, f"steps[{first}] rotates the obstacle, "
                "whose normals then turn: search it each step ('every_step', 'until_settled' or 'newton'), got "
                f"{search or 'once'!r}")


def _check_fits(case: ContactCase) -> None:
    """A step's ``fit`` takes up declared interferences: some pair must declare one; exact cylinders
    (``cylinder``) take linear-elastic bodies."""
    declared = any(pair.interference is not None for pair in case.contacts)
    for i, step in enumerate(case.steps):
        require(step.fit is None or declared, f"steps[{i}].fit", "resolves the declared interferences of "
                "[[contacts]], and no pair declares one")
    models = {body.material.model for body in case.bodies}
    for i, pair in enumerate(case.contacts):
        require(pair.cylinder is None or models == {None}, f"contacts[{i}].cylinder", "takes the gap between the "
                "cylinders of the reference configuration, which is linear elasticity's; the bodies are of "
                f"{', '.join(sorted(str(m) for m in models))}")


#: Initial guesses of the first step (``solver.start``): the body at rest (u~ = 0), or
#: u = 0 in the shifted variables, every contact node on the obstacle (seed 000, Sect. 7).
STARTS = ("rest", "contact")


def _check_solver(solver: dict[str, typing.Any]) -> dict[str, typing.Any]:
    """``[solver]`` as a table with ``start`` checked (:data:`STARTS`); the solver's own
    parameters are checked against its table by :func:`check_solver`."""
    _instance(solver, dict, "solver")
    if "start" in solver:
        require_choice("solver.start", solver["start"], STARTS)
    return dict(solver)


def _check_limit_points(case: ContactCase) -> None:
    """``solver.limit_points = "relax"`` (the load path's relaxation past a limit point,
    docs/finite_strain.md Sect. 15) takes a hyperelastic body whose pairs are not searched
    ``until_settled``; the value itself is checked with the solver's table (:func:`check_solver`)."""
    if case.solver.get("limit_points") != "relax":
        return
    model = case.bodies[0].material.model if case.bodies else case.material.model
    searches = [case.contact.search] if case.contact is not None else [p.search for p in case.contacts]
    require(model is not None and "until_settled" not in searches, "solver.limit_points",
            "'relax' takes a hyperelastic body (material.model) whose pairs are searched once, every step or inside "
            f"the Newton iteration ('newton'), got model {model or 'linear'!r} and search "
            f"{', '.join(str(s) for s in searches)}")


def check_solver(case: ContactCase, table: Parameters) -> dict[str, typing.Any]:
    """The case's ``[solver]`` parameters checked by the solver's ``table`` (errors named
    ``solver.NAME``), without ``start`` and without the defaults added."""
    given = {name: value for name, value in case.solver.items() if name != "start"}
    try:
        merged = table.check(given)
    except ParameterError as exc:
        raise ParameterError(f"solver.{exc.name}", str(exc).removeprefix(f"{exc.name}: ")) from None
    return {name: merged[name] for name in given}


def _check_petsc(petsc: dict[str, typing.Any]) -> dict[str, typing.Any]:
    _instance(petsc, dict, "petsc")
    for name, value in petsc.items():
        require(isinstance(name, str) and name and not name.startswith("-") and " " not in name, f"petsc.{name}",
                "write an option name without '-' and without the solver's prefix, e.g. ksp_monitor")
        ok = isinstance(value, (bool, int, float, str))
        require(ok, f"petsc.{name}", f"must be a string, number or boolean, got {value!r}")
    return dict(petsc)


def _check_consistency(case: ContactCase) -> None:
    surface = case.contact.surface
    require(surface not in case.boundary.clamped, "contact.surface",
            f"group {surface!r} is clamped (u = 0) and cannot come into contact")


def _check_dynamics(case: ContactCase) -> Dynamics:
    """``[dynamics]`` checked against the case: a known scheme, dt > 0, end >= dt, a density
    for every body (none for some and one for others is named as such), the time points of
    ``[[steps]]`` (:func:`_check_time_points`), a hyperelastic body in the displacement
    formulation, contact searched once or before every time step (docs/dynamics.md)."""
    dynamics = case.dynamics
    _instance(dynamics, Dynamics, "dynamics")
    require_choice("dynamics.scheme", dynamics.scheme, DYNAMICS_SCHEMES)
    alpha = _scheme_parameter(dynamics, "alpha", "hht", (0.0, 1.0 / 3.0))
    rho_infinity = _scheme_parameter(dynamics, "rho_infinity", "generalized_alpha", (0.0, 1.0))
    dt = require_number("dynamics.dt", dynamics.dt)
    require(dt > 0.0, "dynamics.dt", f"the time step must be > 0 (s), got {dynamics.dt!r}")
    end = require_number("dynamics.end", dynamics.end)
    require(end >= dt, "dynamics.end", f"must be >= dt = {dt:g} s, got {dynamics.end!r}")
    bodies = case.bodies or (Body("body", case.material, case.boundary, dynamics.initial_velocity),)
    prefix = [f"bodies[{i}]" for i in range(len(case.bodies))] or [""]
    velocity = None if dynamics.initial_velocity is None else _vector(dynamics.initial_velocity,
                                                                       "dynamics.initial_velocity")
    require(velocity is None or not case.bodies, "dynamics.initial_velocity",
            "with [[bodies]] each body gives its own initial_velocity")
    _check_masses(bodies, prefix)
    for body, path in zip(bodies, prefix):
        where = f"{path}." if path else ""
        require(body.material.model is None or body.material.formulation == "displacement",
                f"{where}material.formulation", "[dynamics] takes a hyperelastic body in the displacement "
                f"formulation, got {body.material.formulation!r}")
    _check_time_points(case, bodies, prefix)
    searches = [case.contact.search] if case.contact is not None else [p.search for p in case.contacts]
    for i, search in enumerate(searches):
        key = "contact.search" if case.contact is not None else f"contacts[{i}].search"
        require(search in (None, "once", "every_step"), key, "[dynamics] searches the contact once or before "
                f"every time step (\"once\", \"every_step\"), got {search!r}")
    return Dynamics(dt, end, dynamics.scheme, velocity, alpha, rho_infinity)


def _scheme_parameter(dynamics: Dynamics, key: str, scheme: str, bounds: tuple[float, float]) -> float | None:
    """``dynamics.<key>``, the parameter of ``scheme`` alone, checked within ``bounds`` (None: not given)."""
    value = getattr(dynamics, key)
    if value is None:
        return None
    require(dynamics.scheme == scheme, f"dynamics.{key}", f"a parameter of scheme = {scheme!r}, not of "
            f"{dynamics.scheme!r}")
    value = require_number(f"dynamics.{key}", value)
    require(bounds[0] <= value <= bounds[1], f"dynamics.{key}", f"must be in [{bounds[0]:g}, {bounds[1]:.4g}] "
            f"(unconditional stability), got {value!r}")
    return value


def _check_time_points(case: ContactCase, bodies: typing.Sequence[Body], paths: typing.Sequence[str]) -> None:
    """The ``[[steps]]`` of a time integration are time points (docs/dynamics.md, Sect. 1): each
    with its ``time``, increasing, and no ``fit``; the body starts at rest
    where meshed, so at t = 0 nothing is translated or rotated and a prescribed displacement is
    zero (load factor 0 there, or no nonzero prescribed component). Without steps the loads are
    constant (load factor 1 from t = 0)."""
    steps = case.steps
    prescribed = next((f"{path + '.' if path else ''}boundary.displacement.{name}"
                       for body, path in zip(bodies, paths) for name, given in body.boundary.displacement.items()
                       if any(v != 0.0 for v in given.components().values())), None)
    if steps == (Step(),):
        require(prescribed is None, prescribed, "a nonzero prescribed displacement needs [[steps]] with times: the "
                "body starts at rest where meshed (load factor 0 at t = 0)")
        return
    before = -math.inf
    for i, step in enumerate(steps):
        require(step.time is not None, f"steps[{i}].time", "required with [dynamics]: each step is a time point "
                "(s); the loads are linear in time between them")
        require(step.time >= 0.0 and step.time > before, f"steps[{i}].time", f"must be >= 0 and increase from "
                f"step to step, got {step.time!r} after {before!r}")
        require(step.fit is None, f"steps[{i}].fit", "not used with [dynamics] (interferences are resolved at t = 0)")
        before = step.time
    if steps[0].time == 0.0:
        require(steps[0].translation == (0.0, 0.0, 0.0), "steps[0].translation", "the obstacles and moved groups "
                "start where meshed: the translation at time 0 must be zero")
        require(steps[0].rotation is None or steps[0].rotation.angle == 0.0, "steps[0].rotation.angle",
                "the obstacles and moved groups start where meshed: the angle at time 0 must be zero")
        require(prescribed is None or steps[0].load == 0.0, "steps[0].load", f"must be 0 at time 0: {prescribed} "
                "is nonzero and the body starts at rest where meshed")


def _check_masses(bodies: typing.Sequence[Body], paths: typing.Sequence[str]) -> None:
    """Every body has a density with ``[dynamics]``; a body without one next to a body with
    one is its own error (a massless body beside a massive one is not a time integration
    this scheme makes: its rows of M vanish)."""
    given = [(body, path) for body, path in zip(bodies, paths) if body.material.density is not None]
    for body, path in zip(bodies, paths):
        key = f"{path}.material.density" if path else "material.density"
        if body.material.density is not None:
            continue
        if given:
            other, other_path = given[0]
            raise ParameterError(key, f"a body with no mass next to one with mass ({other_path}, "
                                 f"{other.material.density:g} kg/m^3): give every body its density")
        raise ParameterError(key, "required with [dynamics] (kg/m^3)")


def check_groups(case: ContactCase, names_in_mesh: typing.Iterable[str]) -> None:
    """Check that every physical group the case names exists in the mesh.

    Call it right after reading the mesh (e.g. with ``facet_tags.names``).

    Raises:
        ParameterError: named by the key path (``boundary.traction.topp``), naming the
            closest group and listing the groups the mesh has.
    """
    known = sorted(names_in_mesh)
    for path, name in _group_uses(case):
        if name not in known:
            close = difflib.get_close_matches(name, known, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(path, f"unknown physical group {name!r}{hint}; the mesh has: {', '.join(known)}")


def check_bodies(case: ContactCase, volumes: typing.Iterable[str]) -> None:
    """Check the bodies of a case with ``[[bodies]]`` against the mesh's physical volumes, then
    the bodies its ``[[contacts]]`` name against its bodies.

    Call it right after reading the mesh (``cell_tags.names``): which of two names that differ
    is misspelt, a body's or a pair's, only the mesh tells.

    Raises:
        ParameterError: ``bodies[i].name`` naming the closest volume (and the pairs that name
            it), or ``contacts[i].slave`` / ``.master`` naming the closest body.
    """
    known = sorted(volumes)
    names = [body.name for body in case.bodies]
    uses = [(f"contacts[{i}].{key}", getattr(pair, key).partition(".")[0]) for i, pair in enumerate(case.contacts)
            for key in ("slave", "master") if getattr(pair, key) is not None]
    for i, name in enumerate(names):
        if name not in known:
            close = difflib.get_close_matches(name, known, n=1)
            hint = ""
            if close:
                named = [path for path, body in uses if body == close[0]]
                also = f", which {' and '.join(named)} name{'s' if len(named) == 1 else ''}" if named else ""
                hint = f" (did you mean {close[0]!r}{also}?)"
            raise ParameterError(f"bodies[{i}].name", f"no physical volume {name!r} in the mesh{hint}; it has: "
                                 f"{', '.join(known)}")
    for path, body in uses:
        if body not in names:
            close = difflib.get_close_matches(body, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(path, f"unknown body {body!r}{hint}; the [[bodies]] are: {', '.join(names)}")


def _group_uses(case: ContactCase) -> list[tuple[str, str]]:
    """(key path, facet group) of every group the case names (``"body.group"`` for bodies)."""
    if not case.bodies:
        return _boundary_uses(case.boundary, "boundary") + [("contact.surface", case.contact.surface)]
    uses = []
    for i, body in enumerate(case.bodies):
        uses += [(path, f"{body.name}.{name}") for path, name in _boundary_uses(body.boundary, f"bodies[{i}].boundary")]
    for i, pair in enumerate(case.contacts):
        uses += [(f"contacts[{i}].slave", pair.slave)]
        uses += [(f"contacts[{i}].master", pair.master)] if pair.master is not None else []
    return uses


def _boundary_uses(boundary: Boundary, path: str) -> list[tuple[str, str]]:
    uses = [(f"{path}.clamped[{i}]", name) for i, name in enumerate(boundary.clamped)]
    uses += [(f"{path}.displacement.{name}", name) for name in boundary.displacement]
    uses += [(f"{path}.moved[{i}]", name) for i, name in enumerate(boundary.moved)]
    uses += [(f"{path}.pressure.{name}", name) for name in boundary.pressure]
    return uses + [(f"{path}.traction.{name}", name) for name in boundary.traction]


def _plain(value: typing.Any) -> typing.Any:
    if dataclasses.is_dataclass(value):
        plain = {}
        for f in dataclasses.fields(value):
            field = getattr(value, f.name)
            if isinstance(field, ContactLaw):  # as in the file: law = NAME and its keys
                plain.update(field.to_dict())
            elif field is not None:
                plain[f.name] = _plain(field)
        return plain
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, pathlib.Path):
        return str(value)
    return value
