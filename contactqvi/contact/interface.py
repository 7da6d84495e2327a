"""Contact pairs: a slave surface and what it may touch, as nodal data for the GE (6.3).

Contact is a relation between two surfaces whatever lies behind them. A pair is
given by its slave surface and either a rigid analytic obstacle
(:class:`ObstaclePair`, seed 000's setting) or a master surface of a meshed body
(:class:`BodyPair`, seed 000, Remark 6.2). :func:`build_interfaces` turns the pairs
into :class:`Interface` objects that all look the same to the solver: owned slave
nodes, their frames (t1, t2, n), contact areas, gaps and the pair's contact law
(:mod:`contactqvi.laws`). What
differs is the discretisation behind them:

* obstacle: the node's gap to the obstacle and the obstacle's normal; the slave
  node's displacement is the relative one;
* body: the mortar coupling (:mod:`contactqvi.contact.mortar`); the relative
  displacement is w_i = u_i - sum_j C_ij u_j, made a nodal unknown by the change
  of variables u = T w of :mod:`contactqvi.contact.problem` (two-body to one-body,
  the algebraic transformation Remark 6.2 refers to).
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI

import numpy as np
import ufl

from dolfinx import fem, la
from dolfinx import mesh as dmesh

from contactqvi.contact.kinematics import pair_frames
from contactqvi.contact.mortar import MortarCoupling, coupling_on_layout, mortar_coupling, surface_facets
from contactqvi.contact.quadratic import ModifiedBasis
from contactqvi.elasticity import displacement_degree
from contactqvi.exact_surfaces import CoaxialCylinders
from contactqvi.interference import Interference, as_interference
from contactqvi.laws import ContactLaw, Frictionless
from contactqvi.load_steps import SEARCHES, Rotation, placed, rigid_increment
from contactqvi.meshes import boundary_facets
from contactqvi.obstacles import Cylinder, Obstacle, tangent_frames
from contactqvi.parameters import require
from contactqvi.records import warn

__all__ = ["MESHED_INTERFERENCE", "BodyPair", "Interface", "MeshedFit", "ObstaclePair", "assembled_area",
           "build_interfaces", "error_key", "followed", "lumped_area_form", "search_again"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ObstaclePair:
    """A slave surface against a rigid obstacle.

    Attributes:
        surface: facet group of the slave surface.
        obstacle: the obstacle in its initial position (moved by the load steps' translations
            and rotations, :func:`~contactqvi.load_steps.placed`).
        law: the contact law (:mod:`contactqvi.laws`), e.g. ``Coulomb(friction=0.3)``.
        search: ``"once"``: gaps and normals of the reference configuration, the gap
            linearised as g + n . u (exact for a plane; small displacements on a curved
            obstacle); ``"every_step"``, ``"until_settled"``: found again in the deformed
            configuration as a body pair is (:class:`BodyPair`), the gap linearised about it
            (finite displacements on a curved obstacle); ``"newton"``: gaps, normals, frames and the
            objective slip a function of the displacement inside the Newton iteration
            (:mod:`contactqvi.contact.obstacle_geometry`; hyperelastic bodies).
        key: the pair's key in a case file (``contacts[0]``), which errors about it name
            (:func:`error_key`); None: its :attr:`name` (the Python API) and ``obstacle``.
    """

    surface: str
    obstacle: Obstacle
    law: ContactLaw = Frictionless()
    search: str = "once"
    key: str | None = dataclasses.field(default=None, compare=False)

    @property
    def name(self) -> str:
        return f"{self.surface}/obstacle"

    @property
    def slave_surface(self) -> str:
        """The facet group of the slave nodes."""
        return self.surface


#: The searches of a body pair whose solutions are those of the contact in the current configuration:
#: their slave facets covered in part take the dual basis of their covered part
#: (:class:`~contactqvi.contact.covered.CoveredBasis`; docs/finite_strain.md Sect. 22), the others
#: that of the whole facet.
CURRENT_CONFIGURATION = ("until_settled", "newton")


@dataclasses.dataclass(frozen=True)
class BodyPair:
    """A slave surface against a master surface of another (or the same) meshed body.

    Attributes:
        slave, master: facet groups (``"body.group"`` for meshes with several bodies).
        law: as for :class:`ObstaclePair`.
        search_distance: master facets farther than this from a slave facet are not
            paired with it (m); None: the slave facet's longest edge. Nodes whose gap
            can close within a load step must lie within it.
        search: ``"every_step"``: the pair is searched again before every load step
            after the first, in the configuration the step before ended in, so a sliding
            contact follows the bodies (:func:`search_again`); ``"until_settled"``: as
            ``"every_step"``, and each step is solved again after a search in the
            configuration it reached, until that configuration settles (no lag of one
            step: :func:`~contactqvi.contact.load_path.solve_load_path`); ``"newton"``: the
            contact geometry (D, M, normals, frames, gaps and the objective slip) a function of
            the displacement inside the Newton iteration, linearised in its steps
            (:mod:`contactqvi.contact.current_geometry`; hyperelastic bodies); ``"once"``: only
            in the reference configuration (small sliding over the whole load path). With
            ``"until_settled"`` and ``"newton"`` a slave facet that the master covers in part
            takes the dual basis of its covered part (:data:`CURRENT_CONFIGURATION`).
        interference: the declared overlap of the two surfaces as meshed (m, >= 0; a press or
            shrink fit), a number or an :class:`~contactqvi.interference.Interference` linear in
            position (a taper), read at each slave node's reference position: slave nodes may
            start up to this deep inside the master body (and :data:`FACETING` of their size
            deeper), and some node must. The contact conditions are those of the measured gaps
            once the fit is resolved: in the first load step, or over the steps' ``fit``
            fractions (:meth:`Interface.gap`; docs/press_fit.md).
        key: as for :class:`ObstaclePair`.
        cylinder: both surfaces are coaxial cylinders about this axis: the weighted gap is taken
            between the exact cylinders (:mod:`contactqvi.exact_surfaces`); None: between the facets.
    """

    slave: str
    master: str
    law: ContactLaw = Frictionless()
    search_distance: float | None = None
    search: str = "every_step"
    interference: float | Interference = 0.0
    key: str | None = dataclasses.field(default=None, compare=False)
    cylinder: CoaxialCylinders | None = None

    @property
    def name(self) -> str:
        return f"{self.slave}/{self.master}"

    @property
    def slave_surface(self) -> str:
        """The facet group of the slave nodes."""
        return self.slave


Pair = ObstaclePair | BodyPair


def error_key(pair: Pair, sub: str | None = None) -> str:
    """The name of an error about ``pair``, or about its key ``sub``: the key path in the case
    file of a pair read from one (``contacts[0]``, ``contacts[0].interference``), else the pair's
    name (``top/obstacle``, ``top/obstacle: search``); an obstacle without a key is ``obstacle``."""
    if pair.key is not None:
        return pair.key if sub is None else f"{pair.key}.{sub}"
    if sub == "obstacle":
        return "obstacle"
    return pair.name if sub is None else f"{pair.name}: {sub}"


@dataclasses.dataclass(frozen=True)
class Interface:
    """The owned slave nodes of one pair and their nodal contact data.

    Attributes:
        pair: what the interface was built from.
        blk: (m,) owned local node indices of the slave nodes that may touch.
        frames: (m, 3, 3) rows t1, t2, n (n from the master side into the slave body).
        area: (m,) contact area of each node (m^2): the lumped area (obstacle) or
            D_ii of the mortar segments (body).
        coupling: the mortar rows C of a body pair; None for an obstacle.
        initial_gap: (m,) gap of the reference positions (m): to an obstacle before
            any translation of it; for a body pair weighted with the C of the last search.
        position: (m, 3) reference positions of the slave nodes (m): the nodes', or on the
            surface of quadratic elements those of the modified basis
            (:mod:`contactqvi.contact.quadratic`), whose gaps are the weighted ones.
        searched_at: (m, 3) displacement of the slave nodes in the configuration an obstacle
            pair was searched in (its gap is linearised about it), or None: the reference.
        meshed_fit: a body pair that declares an interference: its mean overlap as meshed
            and mean declared interference (:class:`MeshedFit`, from the reference search;
            a search again keeps it); None otherwise.
    """

    pair: Pair
    blk: np.ndarray
    frames: np.ndarray
    area: np.ndarray
    coupling: MortarCoupling | None
    initial_gap: np.ndarray
    position: np.ndarray
    searched_at: np.ndarray | None = None
    meshed_fit: MeshedFit | None = None

    @property
    def obstacle(self) -> Obstacle | None:
        return self.pair.obstacle if isinstance(self.pair, ObstaclePair) else None

    @property
    def searched_each_step(self) -> bool:
        """Whether the pair is searched again before every load step (its ``search``)."""
        return self.pair.search in ("every_step", "until_settled", "newton")

    @property
    def follows(self) -> bool:
        """Whether the geometry follows the Newton iterate (``search = "newton"``)."""
        return self.pair.search == "newton"

    @property
    def settles(self) -> bool:
        """Whether a step is solved again until its configuration settles (its ``search``)."""
        return self.pair.search == "until_settled"

    @property
    def slave_surface(self) -> str:
        """The facet group of the slave nodes."""
        return self.pair.slave_surface

    def gap(self, x: np.ndarray, translation: np.ndarray, rotation: Rotation | None = None,
            fit: float = 1.0) -> np.ndarray:
        """Gap of each slave node (m) at reference positions ``x`` with the obstacle at a step's
        position, ``rotation`` about its centre then ``translation``
        (:func:`~contactqvi.load_steps.placed`). An obstacle pair searched in a deformed
        configuration u_s gives g(x + u_s) - n . u_s, so that g + n . u is the gap linearised
        about that configuration. A body pair's weighted gap does not depend on the obstacles'
        position; with a declared interference δ(x) resolved by the fraction ``fit`` of it, it
        is g_i + (1 - fit) δ(x_i): the overlap not yet taken up is admitted
        (docs/press_fit.md, "A fit over several steps")."""
        if self.obstacle is None:
            if fit == 1.0:
                return self.initial_gap
            return self.initial_gap + (1.0 - fit) * as_interference(self.pair.interference).at_points(x)
        obstacle = placed(self.obstacle, translation, rotation)
        if self.searched_at is None:
            return obstacle.distance(x)[0]
        gap = obstacle.distance(x + self.searched_at)[0]
        return gap - np.einsum("ij,ij->i", self.frames[:, 2], self.searched_at)

    def obstacle_increment(self, x: np.ndarray, translation: np.ndarray, rotation: Rotation | None,
                           previous_translation: np.ndarray, previous_rotation: Rotation | None) -> np.ndarray:
        """Displacement (m, 3; m) of the obstacle's surface at each slave node since the step before,
        the slip reference of friction: the displacement between the two step ends of the
        obstacle's material point at the node's closest point p = y - g(y) n(y) on the obstacle
        at this step, y = x + u_s the node where the gap is linearised (``x`` reference
        positions, u_s :attr:`searched_at`, zero if not searched), by
        :func:`~contactqvi.load_steps.rigid_increment`: the rigid velocity field of rotation and
        translation integrated over the step, t_1 - t_0 at every node without rotations.
        Zero for a body pair (its master moves with the solution: the slip is in w itself)."""
        if self.obstacle is None:
            return np.zeros((len(x), 3))
        y = x if self.searched_at is None else x + self.searched_at
        if rotation is not None or previous_rotation is not None:
            gap, normal = placed(self.obstacle, translation, rotation).distance(y)
            y = y - gap[:, None] * normal
        return rigid_increment(y, translation, rotation, previous_translation, previous_rotation)


def build_interfaces(
    V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, pairs: typing.Sequence[Pair], constrained: np.ndarray,
    modified: ModifiedBasis | None = None,
) -> list[Interface]:
    """The interfaces of ``pairs`` (collective).

    Args:
        V: vector P1 (or P2) space of all bodies.
        facet_tags: named facet groups.
        pairs: the contact pairs.
        constrained: (local nodes, 3) mask of prescribed components; nodes with all
            three prescribed cannot be slave nodes.
        modified: the slave surfaces' modified basis of a P2 space (obstacle pairs; a body pair's
            mortar integrals take it themselves).

    Raises:
        ParameterError: a bad contact law, a node on two slave surfaces or on a
            slave and a master surface, a pair that finds no master facet, or
            bodies/obstacles that overlap initially.
    """
    require(len(pairs) > 0, "contacts", "give at least one contact pair")
    interfaces = []
    for pair in pairs:
        require(isinstance(pair.law, ContactLaw), f"{pair.name}.law",
                f"must be a contact law of contactqvi.laws, got {pair.law!r}")
        pair.law.checked(pair.name)
        if isinstance(pair, ObstaclePair):
            interfaces.append(_obstacle_interface(V, facet_tags, pair, constrained, modified=modified))
        else:
            interfaces.append(_body_interface(V, facet_tags, pair, constrained))
    _check_disjoint(V, facet_tags, pairs, interfaces)
    return interfaces


def search_again(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, interfaces: typing.Sequence[Interface],
                 constrained: np.ndarray, displacement: fem.Function, translation: np.ndarray,
                 finite_strain: bool = False, rotation: Rotation | None = None,
                 linearised: bool = True, modified: ModifiedBasis | None = None) -> list[Interface]:
    """The interfaces with the pairs searched each step found again in the configuration
    x + ``displacement``, the obstacles rotated by ``rotation`` (None: not) and translated by
    ``translation`` (m; :func:`~contactqvi.load_steps.placed`; the others as they are;
    collective).

    Its slave nodes, mortar rows, normals and areas are those of that configuration (an
    obstacle's nodal areas: the deformed ones with ``finite_strain``, the reference ones of
    small-strain theory otherwise); a pair may find fewer nodes or none (the bodies moved
    apart), and a small overlap left by the last step's discrete conditions is no error. The
    couplings of pairs searched ``"newton"`` carry their derivatives if ``linearised``. ``modified``:
    as for :func:`build_interfaces`.
    """
    x = displacement.x.array.reshape(-1, 3)

    def again(interface: Interface) -> Interface:
        if isinstance(interface.pair, ObstaclePair):
            return _obstacle_interface(V, facet_tags, interface.pair, constrained, x,
                                       displacement if finite_strain else None, translation, rotation, modified)
        kept = interface.coupling.slave_blk if interface.follows else None
        return dataclasses.replace(_body_interface(V, facet_tags, interface.pair, constrained, x,
                                                   interface.follows and linearised, kept),
                                   meshed_fit=interface.meshed_fit)

    return [again(i) if i.searched_each_step else i for i in interfaces]


def followed(V: fem.FunctionSpace, interfaces: typing.Sequence[Interface], constrained: np.ndarray,
             displacement: fem.Function, translation: np.ndarray, rotation: Rotation | None,
             areas: typing.Callable[[str], np.ndarray], linearised: bool = False) -> list[Interface]:
    """The interfaces with the pairs searched ``"newton"`` taken again at x + ``displacement``: a body
    pair integrated on the facet pairs and slave nodes of its last search
    (:func:`~contactqvi.contact.mortar.coupling_on_layout`), with its derivatives if ``linearised``;
    an obstacle pair's normals, frames and nodal areas at its nodes there (``areas(surface)``: the
    local nodes' areas of that surface deformed by ``displacement``), the obstacle placed by
    ``translation`` and ``rotation`` (its gap linearised about that configuration,
    :meth:`Interface.gap`); the others as they are (collective)."""
    x = displacement.x.array.reshape(-1, 3)

    def again(interface: Interface) -> Interface:
        if interface.coupling is None:
            at = x[interface.blk]
            normal = placed(interface.obstacle, translation, rotation).distance(interface.position + at)[1]
            area = areas(interface.pair.surface)[interface.blk]
            return dataclasses.replace(interface, frames=tangent_frames(normal), area=area, searched_at=at)
        coupling = coupling_on_layout(V, interface.coupling.layout, x, linearised=linearised)
        normal, frames = pair_frames(coupling.normal, constrained[coupling.slave_blk])
        return dataclasses.replace(interface, frames=frames, area=coupling.weight, coupling=coupling,
                                   initial_gap=np.einsum("ij,ij->i", normal, coupling.separation))

    return [again(i) if i.follows else i for i in interfaces]


def _obstacle_interface(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, pair: ObstaclePair,
                        constrained: np.ndarray, displacement: np.ndarray | None = None,
                        deformed: fem.Function | None = None,
                        translation: typing.Sequence[float] = (0.0, 0.0, 0.0),
                        rotation: Rotation | None = None, modified: ModifiedBasis | None = None) -> Interface:
    """An obstacle pair's interface in the reference configuration, the obstacle at rest
    (checked: no node inside it), or in x + ``displacement`` (local nodes, 3), the obstacle
    rotated by ``rotation`` and translated by ``translation``: its normals there; :meth:`Interface.gap` measures the gap
    to the obstacle of each step. The nodal areas are those of the surface deformed by
    ``deformed`` if given, else of the reference one. On quadratic elements the positions,
    displacements and areas are those of the ``modified`` basis (:mod:`contactqvi.contact.quadratic`)."""
    require(pair.search in SEARCHES, error_key(pair, "search"),
            f"must be one of {', '.join(SEARCHES)}, got {pair.search!r}")
    n_owned = V.dofmap.index_map.size_local
    excluded_blk = np.flatnonzero(constrained.all(axis=1))
    blk = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, boundary_facets(facet_tags, pair.surface))
    blk = np.setdiff1d(blk[blk < n_owned], excluded_blk).astype(np.int32)
    positions = V.tabulate_dof_coordinates()
    if modified is not None:
        positions = modified.positions(positions)
        displacement = None if displacement is None else modified.positions(displacement)
    searched_at = None if displacement is None else displacement[blk]
    x = positions[blk]
    if searched_at is None:
        gap, normal = pair.obstacle.distance(x)
    else:
        gap, normal = placed(pair.obstacle, translation, rotation).distance(x + searched_at)
    comm = V.mesh.comm
    undefined = comm.allreduce(int(np.count_nonzero(~np.isfinite(normal).all(axis=1))), op=MPI.SUM)
    require(undefined == 0, error_key(pair, "obstacle"), f"{undefined} contact nodes of {pair.surface!r} lie where "
            "the obstacle has no normal (a sphere's centre or a cylinder's axis)")
    if searched_at is None:
        _check_overlap(comm, V, gap, error_key(pair, "obstacle"), f"contact nodes of {pair.surface!r} lie inside "
                       "the obstacle", hint="; the body must start outside it (check its position and, for a plane, "
                       "that the normal points into the body's side)")
    area = _lumped_area(V, facet_tags, pair.surface, deformed)
    area = (area if modified is None else modified.areas(area))[blk]
    return Interface(pair, blk, tangent_frames(normal), area, None, gap, x, searched_at)


#: Initial penetrations of a slave node into a master body up to this fraction of the node's
#: size sqrt(D_ii) are accepted: a master surface meshed from a curved one is a set of chords,
#: and a chord of length h on radius R lies h^2 / (8 R) inside it, i.e. 0.02 h for h = R / 6.
#: The first load step pushes such nodes out (the Hertz meshes with the block as slave: 1.4e-6 m
#: at h = 5.3 mm on the coarse mesh). Overlaps of meshed bodies by mistake are larger.
FACETING = 0.02


def _body_interface(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, pair: BodyPair,
                    constrained: np.ndarray, displacement: np.ndarray | None = None,
                    linearised: bool = False, kept_blk: np.ndarray | None = None) -> Interface:
    """A body pair's interface searched in the reference configuration (checked: it finds
    nodes, and they do not overlap) or in x + ``displacement`` (local nodes, 3); its coupling
    with its derivatives if ``linearised``, the nodes ``kept_blk`` of the last search kept as
    long as they are covered at all (:func:`~contactqvi.contact.mortar.mortar_coupling`)."""
    slave, master = boundary_facets(facet_tags, pair.slave), boundary_facets(facet_tags, pair.master)
    distance = pair.search_distance
    require(distance is None or distance > 0.0, error_key(pair, "search_distance"), f"must be > 0, got {distance!r}")
    require(pair.search in SEARCHES, error_key(pair, "search"),
            f"must be one of {', '.join(SEARCHES)}, got {pair.search!r}")
    comm = V.mesh.comm
    exact = None if pair.cylinder is None else _exact_cylinders(V, slave, master, pair)
    coupling = mortar_coupling(V, slave, master, distance, np.flatnonzero(constrained.all(axis=1)), displacement,
                               linearised, kept_blk, exact, projecting=pair.search in CURRENT_CONFIGURATION)
    if displacement is None:
        found = comm.allreduce(len(coupling.slave_blk), op=MPI.SUM)
        reach = "one facet size" if distance is None else f"{distance:.3g} m"
        require(found > 0, error_key(pair), f"no node of {pair.slave!r} has a facet of {pair.master!r} within "
                f"{reach} facing it: the surfaces are nowhere near each other (raise search_distance?)")
    # on a symmetry plane through the interface (prescribed components) the normal lies in the plane
    normal, frames = pair_frames(coupling.normal, constrained[coupling.slave_blk])
    gap = np.einsum("ij,ij->i", normal, coupling.separation)
    fit = None
    if displacement is None:
        fit = _check_interference(comm, V, gap, pair, coupling.weight,
                                  V.tabulate_dof_coordinates()[coupling.slave_blk])
    return Interface(pair, coupling.slave_blk, frames, coupling.weight, coupling, gap,
                     V.tabulate_dof_coordinates()[coupling.slave_blk], meshed_fit=fit)


def _exact_cylinders(V: fem.FunctionSpace, slave: np.ndarray, master: np.ndarray,
                     pair: BodyPair) -> tuple[Cylinder, Cylinder]:
    """The exact cylinders of the slave and master facets ``slave``, ``master`` of ``pair``
    (:meth:`~contactqvi.exact_surfaces.CoaxialCylinders.surfaces`, from their vertices). Collective."""
    surfaces = [surface_facets(V, facets) for facets in (slave, master)]
    require(all(s.x.shape[1] == 3 for s in surfaces), error_key(pair, "cylinder"),
            "exact cylinders take tetrahedral meshes (triangular facets)")
    return pair.cylinder.surfaces(V.mesh.comm, *(s.x for s in surfaces), (pair.slave, pair.master),
                                  error_key(pair, "cylinder"))


#: A declared interference is reported (a warning) when the surfaces as meshed overlap by more
#: than this fraction more or less on average, and when the solved fit pushes them apart by more
#: than it more or less: the chords of curved surfaces lie inside them by h^2 / (8 R), which
#: changes a small fit (docs/press_fit.md).
MESHED_INTERFERENCE = 0.01


class MeshedFit(typing.NamedTuple):
    """A declared interference as the mesh has it (m): ``overlap``, the mean overlap as meshed
    -sum_i D_ii g_i / sum_i D_ii over the slave nodes; ``declared``, the mean declared one
    sum_i D_ii delta(x_i) / sum_i D_ii."""

    overlap: float
    declared: float


def _check_interference(comm: MPI.Comm, V: fem.FunctionSpace, gap: np.ndarray, pair: BodyPair,
                        weight: np.ndarray, x: np.ndarray) -> MeshedFit | None:
    """Raise if the declared interference δ(x_i) of a body pair is negative at a slave node (x its
    slave nodes' reference positions), if a slave node overlaps the master body by more than
    δ(x_i) plus the faceting allowance :data:`FACETING` sqrt(D_ii) (m), or if a declared
    interference is not in the mesh: no node overlaps by at least its δ(x_i) less its allowance.
    Warn if the mean overlap as meshed, -sum_i D_ii g_i / sum_i D_ii, differs from the mean declared
    one, sum_i D_ii δ(x_i) / sum_i D_ii, by more than :data:`MESHED_INTERFERENCE` of it."""
    interference = as_interference(pair.interference)
    declared, faceting = interference.at_points(x), FACETING * np.sqrt(weight)
    _check_sign(comm, declared, pair)
    largest = comm.allreduce(float(faceting.max(initial=0.0)), op=MPI.MAX)
    faceting_text = f"the faceting allowance {FACETING:g} x sqrt(D_ii) (up to {largest:.3e} m here)"
    text = _declared_text(comm, interference, declared)
    fit = comm.allreduce(float(declared.max(initial=0.0)), op=MPI.MAX) > 0.0
    allowance = f"the declared interference {text} plus {faceting_text}" if fit else faceting_text
    declare = "[[contacts]] interference" if pair.key is None else error_key(pair, "interference")
    hint = "" if fit else f"; for a press or shrink fit, declare the overlap as {declare} (m)"
    _check_overlap(comm, V, gap, error_key(pair, "interference") if fit else error_key(pair),
                   f"nodes of {pair.slave!r} lie inside the body of {pair.master!r} by more than {allowance}",
                   declared + faceting, hint)
    if not fit:
        return None
    reached = comm.allreduce(float(np.max(faceting - gap - declared, initial=-np.inf)), op=MPI.MAX)
    overlap = comm.allreduce(float(np.max(-gap, initial=0.0)), op=MPI.MAX)
    require(reached >= 0.0, error_key(pair, "interference"), f"declared {text}, but the surfaces "
            f"overlap by at most {overlap:.3e} m as meshed, less than it by more than {faceting_text}: "
            "mesh the bodies overlapping by the interference, e.g. a pin of radius b + interference in a "
            "hole of radius b")
    area = comm.allreduce(float(weight.sum()), op=MPI.SUM)
    mean = -comm.allreduce(float(weight @ gap), op=MPI.SUM) / area
    expected = interference.value if interference.uniform else comm.allreduce(float(weight @ declared),
                                                                              op=MPI.SUM) / area
    if abs(mean / expected - 1.0) > MESHED_INTERFERENCE:
        warn(comm, logger, "meshed_interference",
             f"{pair.name}: the surfaces overlap by {mean:.4e} m on average as meshed, "
             f"{100.0 * (mean / expected - 1.0):+.1f} % of the declared interference {expected:.4e} m"
             f"{'' if interference.uniform else ' (its mean over the surface)'}; the fit solved is the meshed one "
             "(chords lie inside a curved surface by h^2 / (8 R)): mesh in second-order tetrahedra "
             "(Mesh.ElementOrder = 2: curved surfaces) or both surfaces in equal segments (docs/press_fit.md)",
             mean_overlap=mean, declared=expected, relative_difference=mean / expected - 1.0)
    return MeshedFit(mean, expected)


def _check_sign(comm: MPI.Comm, declared: np.ndarray, pair: BodyPair) -> None:
    """Raise unless the declared interference δ(x_i) (m) is >= 0 at every slave node x_i."""
    count = comm.allreduce(int(np.count_nonzero(declared < 0.0)), op=MPI.SUM)
    lowest = comm.allreduce(float(declared.min(initial=np.inf)), op=MPI.MIN)
    require(count == 0, error_key(pair, "interference"), f"delta(x) = value + slope . (x - at) is negative at {count} "
            f"nodes of {pair.slave!r}, down to {lowest:.3e} m; it must be >= 0 on the contact surface")


def _declared_text(comm: MPI.Comm, interference: Interference, declared: np.ndarray) -> str:
    """The declared interference in a message: ``1.000e-04 m``, or its range over the slave nodes."""
    if interference.uniform:
        return f"{interference.value:.3e} m"
    low = comm.allreduce(float(declared.min(initial=np.inf)), op=MPI.MIN)
    high = comm.allreduce(float(declared.max(initial=-np.inf)), op=MPI.MAX)
    return f"delta(x) from {low:.3e} to {high:.3e} m"


def _check_overlap(comm: MPI.Comm, V: fem.FunctionSpace, gap: np.ndarray, name: str, what: str,
                   allowance: float | np.ndarray = 0.0, hint: str = "") -> None:
    """Raise if a gap is negative beyond round-off of the mesh size and ``allowance`` (m)."""
    x = V.mesh.geometry.x
    extent = comm.allreduce(float(np.ptp(x, axis=0).max()) if len(x) else 0.0, op=MPI.MAX)
    count = comm.allreduce(int(np.count_nonzero(gap < -1e-10 * extent - allowance)), op=MPI.SUM)
    worst = comm.allreduce(float(gap.min(initial=np.inf)), op=MPI.MIN)
    require(count == 0, name, f"initial penetration: {count} {what}, the deepest by {-worst:.3e} m{hint}")


def _check_disjoint(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, pairs: typing.Sequence[Pair],
                    interfaces: list[Interface]) -> None:
    """No node on two slave surfaces, nor on a slave and a master surface."""
    comm = V.mesh.comm
    n_owned = V.dofmap.index_map.size_local
    slave_count = np.zeros(n_owned, dtype=np.int32)
    for interface in interfaces:
        slave_count[interface.blk] += 1
    twice = comm.allreduce(int(np.count_nonzero(slave_count > 1)), op=MPI.SUM)
    require(twice == 0, "contacts", f"{twice} nodes lie on two slave surfaces; a node can be a slave of one pair only")
    for pair in pairs:
        if isinstance(pair, BodyPair):
            master = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, boundary_facets(facet_tags, pair.master))
            master = master[master < n_owned]
            both = comm.allreduce(int(np.count_nonzero(slave_count[master])), op=MPI.SUM)
            require(both == 0, error_key(pair, "master"), f"{both} nodes of the master surface {pair.master!r} are "
                    "slave nodes of a pair; a node cannot be both")


def lumped_area_form(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, surface: str,
                     deformed: fem.Function | None = None) -> fem.Form:
    """The form of the lumped area int N_i of ``surface`` at each node of V, of the surface deformed
    by the displacement ``deformed`` if given (da = J |F^-T N| dA, Nanson), else of the reference one
    (:func:`assembled_area`)."""
    msh = V.mesh
    Q = fem.functionspace(msh, ("Lagrange", displacement_degree(V)))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=facet_tags)
    stretch = 1.0
    if deformed is not None:
        F = ufl.Identity(3) + ufl.grad(deformed)
        pulled = ufl.inv(F).T * ufl.FacetNormal(msh)
        stretch = ufl.det(F) * ufl.sqrt(ufl.dot(pulled, pulled))
    return fem.form(stretch * ufl.TestFunction(Q) * ds(facet_tags.names[surface]))


def assembled_area(form: fem.Form) -> np.ndarray:
    """The nodal areas of a :func:`lumped_area_form` (m^2; local nodes, ghosts included, owned
    entries complete)."""
    area = la.vector(form.function_spaces[0].dofmap.index_map)
    fem.assemble_vector(area.array, form)
    area.scatter_reverse(la.InsertMode.add)
    return area.array


def _lumped_area(V: fem.FunctionSpace, facet_tags: dmesh.MeshTags, surface: str,
                 deformed: fem.Function | None = None) -> np.ndarray:
    """Lumped area int N_i of ``surface`` at each node of V (local, ghosts included; m^2; owned
    entries complete), of the surface deformed by the displacement ``deformed`` if given."""
    return assembled_area(lumped_area_form(V, facet_tags, surface, deformed))
