"""Case files: every shipped case parses, every bad input raises a named error."""

from __future__ import annotations

import copy
import pathlib
import re
import typing

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi import meshes, obstacles
from contactqvi.case import (
    Boundary,
    Contact,
    ContactCase,
    Displacement,
    Material,
    MeshSource,
    ObstacleShape,
    Step,
    check_groups,
    check_solver,
    load_case,
    parse_case,
)
from contactqvi.contact.load_path import SOLVER_PARAMETERS
from contactqvi import case as case_module
from contactqvi.laws import LAWS, Coulomb
from contactqvi.parameters import ParameterError
from contactqvi.problems import coulomb as data
from contactqvi.runner import build_problem

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASES = sorted((ROOT / "cases").glob("*.toml"))

#: A small valid case, as read from TOML; each bad input below changes one entry.
BASE = {
    "mesh": {"box": {"lev": 0, "geometry": "d1"}},
    "material": {"young": 70e9, "poisson": 0.334},
    "boundary": {"clamped": ["dirichlet"], "traction": {"top": [0.0, 0.0, -1e9]}},
    "contact": {"surface": "contact", "law": "coulomb", "friction": 0.23},
    "obstacle": {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]},
}


def _geo_groups(path: pathlib.Path) -> list[str]:
    """Names of the 2D physical groups of a .geo file, without meshing it."""
    import gmsh

    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(str(path))
        return [gmsh.model.getPhysicalName(dim, tag) for dim, tag in gmsh.model.getPhysicalGroups(2)]
    finally:
        gmsh.finalize()


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_every_case_is_shipped():
    assert {c.stem for c in CASES} >= {"paper_d3_L2", "arch_block", "hertz", "cattaneo_mindlin", "inclined_plane"}


#: Cases whose meshes the groups test reads on several ranks, one per reader (gmsh's .geo of
#: tetrahedra and of hexahedra, a .msh file); the others take their twin's parallel path.
MESH_READERS = ("patch_test", "hex_patch", "shallow_ironing")


def _cases() -> list:
    twin = pytest.mark.parallel_twin("patch_test", reason="read_gmsh and split_by_body as for patch_test's "
                                     "mesh; another mesh file or none read")
    return [pytest.param(path, id=path.stem, marks=[] if path.stem in MESH_READERS else twin) for path in CASES]


@pytest.mark.parametrize("path", _cases())
def test_shipped_case_parses_and_names_groups_of_its_mesh(path):
    case = load_case(path)
    assert parse_case(case.to_dict()) == case  # the dict form maps back one-to-one
    assert len(case.steps) >= 1
    if case.bodies:  # groups "body.group" exist only on the mesh read
        msh, facet_tags, cell_tags = meshes.read_gmsh(case.mesh.file, MPI.COMM_WORLD)
        assert {b.name for b in case.bodies} <= set(cell_tags.names)
        check_groups(case, meshes.split_by_body(msh, facet_tags, cell_tags).names)
    elif case.mesh.file is not None:
        assert case.mesh.file.is_file()
        check_groups(case, _geo_groups(case.mesh.file))
    else:
        check_groups(case, meshes.BOX_BOUNDARIES)


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_every_law_is_documented_with_its_keys():
    """The case-file documentation names every registered contact law and its keys."""
    for name, law in LAWS.items():
        assert f"``{name}``" in case_module.__doc__
        assert all(f"``{key}``" in case_module.__doc__ for key in law.parameters)


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_paper_case_is_the_demo_problem():
    """cases/paper_d3_L2.toml holds the data of demos/coulomb3d.py --geometry d3 --load L2 --lev 5."""
    case = load_case(ROOT / "cases" / "paper_d3_L2.toml")
    assert case.mesh == MeshSource(box=case.mesh.box) and (case.mesh.box.lev, case.mesh.box.geometry) == (5, "d3")
    assert case.material == Material(data.YOUNG, data.POISSON)
    assert case.contact == Contact("contact", Coulomb(friction=data.FRICTION))
    assert case.boundary.clamped == ("dirichlet",) and case.boundary.body_force is None
    assert case.boundary.traction == data.tractions("L2")
    assert case.obstacle == ObstacleShape("plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0))
    assert case.steps == (Step(1.0, (0.0, 0.0, 0.0)),)
    assert case.solver == {"start": "contact"} and case.petsc == {}  # u0 = 0 shifted, as the demo


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_case_built_in_python_equals_the_file():
    """The dataclasses are the API: the Hertz case written in Python is the file's case."""
    case = ContactCase(
        mesh=MeshSource(file=ROOT / "meshes" / "hertz_medium.geo"),
        material=Material(young=70e9, poisson=0.3),
        boundary=Boundary(
            clamped=["bottom"], displacement={"symmetry_x": Displacement(x=0), "symmetry_y": Displacement(y=0)}
        ),
        contact=Contact("contact", Coulomb(friction=0)),
        obstacle=ObstacleShape("sphere", center=[0, 0, 1], radius=1),
        steps=[Step(translation=(0, 0, -depth)) for depth in (0.25e-3, 0.5e-3, 0.75e-3, 1e-3)],
    )
    assert case == load_case(ROOT / "cases" / "hertz.toml")
    assert case.groups == ["bottom", "symmetry_x", "symmetry_y", "contact"]


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_values_are_normalised():
    case = parse_case(
        _with(BASE, ("obstacle", {"type": "cylinder", "point": [0, 0, -1], "axis": [0, 3, 4], "radius": 1}))
    )
    assert case.obstacle.axis == pytest.approx((0.0, 0.6, 0.8)) and isinstance(case.obstacle.radius, float)
    assert case.steps == (Step(),)
    case = parse_case(_with(BASE, ("obstacle", "normal", [0, 0, 2]), ("steps", [{"load": 2}])))
    assert case.obstacle.normal == (0.0, 0.0, 1.0) and case.steps == (Step(2.0, (0.0, 0.0, 0.0)),)


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_obstacles_and_displacements_for_the_problem_builder():
    case = load_case(ROOT / "cases" / "hertz.toml")
    sphere = case.obstacle.create()
    assert isinstance(sphere, obstacles.Sphere) and sphere.radius == 1.0
    gap, normal = sphere.translated(case.steps[-1].translation).distance(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    assert gap == pytest.approx([-1e-3, np.hypot(0.1, 0.999) - 1.0])
    assert normal[0] == pytest.approx([0.0, 0.0, -1.0])
    assert {name: d.components() for name, d in case.boundary.displacement.items()} == {
        "symmetry_x": {0: 0.0}, "symmetry_y": {1: 0.0}
    }
    plane = load_case(ROOT / "cases" / "inclined_plane.toml").obstacle.create()
    assert isinstance(plane, obstacles.Plane)
    assert plane.normal == pytest.approx([np.sin(np.radians(20)), 0.0, np.cos(np.radians(20))], abs=1e-10)
    cylinder = parse_case(
        _with(BASE, ("obstacle", {"type": "cylinder", "point": [0, 0, -1], "axis": [0, 2, 0], "radius": 0.5}))
    ).obstacle.create()
    assert isinstance(cylinder, obstacles.Cylinder) and cylinder.distance(np.zeros((1, 3)))[0] == pytest.approx(0.5)


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_solver_and_petsc_tables_pass_through():
    case = parse_case(_with(BASE, ("solver", {"pc": "lu", "max_iterations": 30}), ("petsc", {"ksp_monitor": True})))
    assert case.solver == {"pc": "lu", "max_iterations": 30}
    assert case.petsc == {"ksp_monitor": True}


def _with(base: dict, *changes) -> dict:
    """A deep copy of ``base`` with ``(key, ..., value)`` set, or deleted for value ``...``."""
    data = copy.deepcopy(base)
    for *keys, value in changes:
        table = data
        for key in keys[:-1]:
            table = table.setdefault(key, {})
        if value is ...:
            del table[keys[-1]]
        else:
            table[keys[-1]] = value
    return data


BAD = [
    # unknown keys, with the closest valid name
    ((("matrial", {}),), "matrial: unknown key; did you mean 'material'?"),
    ((("obstacle", "nromal", [0, 0, 1]),), "obstacle.nromal: unknown key; did you mean 'normal'?"),
    ((("contact", "mu", 0.2),), "contact.mu: unknown key; valid keys: surface, law, search, friction, slip_bound, friction_limit, pressure_scale"),
    ((("obstacle", "steps", []),),
     "obstacle.steps: unknown key; a key written after the header [obstacle] belongs to that table; move 'steps' above it"),
    ((("mesh", "box", "level", 3),), "mesh.box.level: unknown key; did you mean 'lev'?"),
    ((("boundary", "displacement", {"front": {"w": 0.0}}),),
     "boundary.displacement.front.w: unknown key; valid keys: x, y, z"),
    ((("steps", [{"load": 1}, {"translate": [0, 0, 1]}]),), "steps[1].translate: unknown key; did you mean 'translation'?"),
    # missing tables and keys
    ((("contact", ...),), "contact: required table [contact] missing"),
    ((("material", "young", ...),), "material.young: required key missing"),
    ((("obstacle", "type", ...),), "obstacle.type: required key missing"),
    ((("obstacle", {"type": "sphere", "center": [0, 0, 1]}),), "obstacle.radius: required for a sphere obstacle"),
    ((("obstacle", "radius", 1.0),), "obstacle.radius: not a key of a plane obstacle (keys: type, point, normal)"),
    # wrong types and shapes
    ((("material", "young", "70e9"),), "material.young: must be a finite number, got '70e9'"),
    ((("material", "poisson", True),), "material.poisson: must be a finite number, got True"),
    ((("obstacle", "point", [0, 0]),), "obstacle.point: must be a list of 3 finite numbers [x, y, z], got [0, 0]"),
    ((("boundary", "traction", "top", [0, "a", 1]),),
     "boundary.traction.top: must be a list of 3 finite numbers [x, y, z], got [0, 'a', 1]"),
    ((("boundary", "body_force", 9.81),), "boundary.body_force: must be a list of 3 finite numbers [x, y, z], got 9.81"),
    ((("steps", [{"load": 1}, {"load": 1}, {"translation": [0, 0]}]),),
     "steps[2].translation: must be a list of 3 finite numbers [x, y, z], got [0, 0]"),
    ((("steps", [{"load": "full"}]),), "steps[0].load: must be a finite number, got 'full'"),
    ((("steps", {"load": 1}),), "steps: must be an array of tables [[steps]], got {'load': 1}"),
    ((("obstacle", 3),), "obstacle: must be a table, got 3"),
    ((("boundary", "clamped", "dirichlet"),), "boundary.clamped: must be a list of group names, got 'dirichlet'"),
    ((("boundary", "clamped", ["dirichlet", 4]),), "boundary.clamped[1]: must be a physical group name, got 4"),
    ((("mesh", "box", "lev", 2.5),), "mesh.box.lev: must be an integer >= 0, got 2.5"),
    ((("mesh", "box", "geometry", "d5"),), "mesh.box.geometry: must be one of d1, d2, d3, got 'd5'"),
    ((("petsc", {"ksp_monitor": [1]}),), "petsc.ksp_monitor: must be a string, number or boolean, got [1]"),
    ((("petsc", {"-ksp_monitor": True}),),
     "petsc.-ksp_monitor: write an option name without '-' and without the solver's prefix, e.g. ksp_monitor"),
    # values
    ((("obstacle", "normal", [0, 0, 0]),), "obstacle.normal: must have nonzero length, got [0, 0, 0]"),
    ((("obstacle", {"type": "cylinder", "point": [0, 0, -1], "axis": [0.0, 0.0, 0.0], "radius": 1}),),
     "obstacle.axis: must have nonzero length, got [0.0, 0.0, 0.0]"),
    ((("obstacle", {"type": "sphere", "center": [0, 0, 1], "radius": 0}),), "obstacle.radius: must be > 0 and finite, got 0.0"),
    ((("obstacle", {"type": "cylinder", "point": [0, 0, 1], "axis": [0, 1, 0], "radius": -1}),),
     "obstacle.radius: must be > 0 and finite, got -1.0"),
    ((("obstacle", "type", "sphre"),), "obstacle.type: must be one of plane, sphere, cylinder, got 'sphre' (did you mean 'sphere'?)"),
    ((("contact", "law", "tresca"), ("contact", "friction", ...)),
     "contact.slip_bound: law = 'tresca' needs a slip bound > 0 (Pa)"),
    ((("contact", "law", "tresca"), ("contact", "slip_bound", 1e8)), "contact.friction: only used with law = 'coulomb' or 'pressure_coulomb'"),
    ((("contact", {"surface": "contact", "law": "tresca", "slip_bound": 0}),),
     "contact.slip_bound: must be > 0 and finite, got 0.0"),
    ((("contact", "slip_bound", 1e8),), "contact.slip_bound: only used with law = 'tresca'"),
    ((("contact", "friction", ...),), "contact.friction: law = 'coulomb' needs a friction coefficient >= 0"),
    ((("contact", "friction", -0.1),), "contact.friction: must be >= 0 and finite, got -0.1"),
    ((("contact", "law", "colomb"),), "contact.law: must be one of coulomb, tresca, frictionless, pressure_coulomb, got 'colomb' (did you mean 'coulomb'?)"),
    ((("material", "poisson", 0.5),), "material.poisson: must lie in (-1, 0.5), got 0.5"),
    ((("material", "poisson", -1),), "material.poisson: must lie in (-1, 0.5), got -1"),
    ((("material", "young", 0),), "material.young: must be > 0 and finite, got 0.0"),
    ((("boundary", "clamped", ["dirichlet", "dirichlet"]),), "boundary.clamped[1]: 'dirichlet' listed twice"),
    ((("boundary", "displacement", {"front": {}}),), "boundary.displacement.front: give at least one of x, y, z"),
    ((("boundary", "displacement", {"dirichlet": {"x": 0}}),),
     "boundary.displacement.dirichlet: group 'dirichlet' is already clamped"),
    ((("boundary", "clamped", []),),
     "boundary: needs a clamped group or a prescribed displacement (rigid motions must be fixed)"),
    ((("boundary", "clamped", ["contact"]),),
     "contact.surface: group 'contact' is clamped (u = 0) and cannot come into contact"),
    # mesh
    ((("mesh", "file", "nowhere.geo"),), "mesh: give exactly one of 'file' and 'box'"),
    ((("mesh", {}),), "mesh: give exactly one of 'file' and 'box'"),
    ((("mesh", {"file": "nowhere.msh"}),), "mesh.file: file 'nowhere.msh' not found"),
    ((("mesh", {"file": "body.stl"}),), "mesh.file: must be a gmsh .geo or .msh file, got 'body.stl'"),
    ((("mesh", {"file": 3}),), "mesh.file: must be a file name, got 3"),
]


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
@pytest.mark.parametrize("changes, text", BAD, ids=[text.split(":")[0] for _, text in BAD])
def test_bad_input_raises_a_named_error(changes, text):
    with pytest.raises(ParameterError) as info:
        parse_case(_with(BASE, *changes))
    assert str(info.value) == text
    assert info.value.name == text.split(": ")[0]


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
@pytest.mark.parametrize(
    "solver, text",
    [
        ({"tl": 0.1}, "solver.tl: unknown parameter; did you mean 'tol'?"),
        ({"tol": 2.0}, "solver.tol: must be in (0, 1), got 2.0"),
        ({"pc": "lux"}, "solver.pc: must be one of gamg, paper, hypre, lu, jacobi, pressure_schur, got 'lux' (did you mean 'lu'?)"),
        ({"max_iterations": 0}, "solver.max_iterations: must be >= 1, got 0"),
        ({"geometry_tol": -1e-3}, "solver.geometry_tol: must be in [0, 1], got -0.001"),
        ({"max_searches": 2.5}, "solver.max_searches: must be an integer, got 2.5"),
    ],
)
def test_bad_solver_value_is_named_by_its_key_path(solver, text):
    """Values are checked by the solver's own Parameters table (the SCD solver's and the load
    path's), named under ``solver.`` (by the runner, before the mesh is read: the case layer
    does not import solvers)."""
    with pytest.raises(ParameterError) as info:
        check_solver(parse_case(_with(BASE, ("solver", solver))), SOLVER_PARAMETERS)
    assert str(info.value) == text and info.value.name == text.split(": ")[0]


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_bad_values_in_python_are_named_by_their_key_path():
    sections = parse_case(BASE)
    kwargs = {f: getattr(sections, f) for f in ("mesh", "material", "boundary", "contact", "obstacle")}
    with pytest.raises(ParameterError, match=r"^steps\[1\]\.translation: must be a list of 3"):
        ContactCase(**kwargs, steps=[Step(), Step(translation=(1.0, 2.0))])
    with pytest.raises(ParameterError, match=r"^obstacle\.normal: must have nonzero length"):
        ContactCase(**{**kwargs, "obstacle": ObstacleShape("plane", point=(0, 0, 0), normal=(0, 0, 0))})
    with pytest.raises(ParameterError, match=r"^material: must be Material\(\.\.\.\), got"):
        ContactCase(**{**kwargs, "material": {"young": 1.0, "poisson": 0.3}})


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_case_file_errors(tmp_path):
    """tmp_path differs per rank; each rank reads its own files."""
    with pytest.raises(ParameterError, match=r"^case: case file '.*missing\.toml' not found$"):
        load_case(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[material]\nyoung = \n")
    with pytest.raises(ParameterError, match=r"^case: .*bad\.toml: invalid TOML"):
        load_case(bad)
    body = tmp_path / "body.msh"
    body.write_text("")
    case = tmp_path / "sub" / "case.toml"
    case.parent.mkdir()
    case.write_text('[mesh]\nfile = "../body.msh"\n' + "\n".join(
        f"[{name}]\n" + "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in table.items())
        for name, table in BASE.items() if name in ("material", "contact", "obstacle")
    ) + '\n[boundary]\nclamped = ["dirichlet"]\n')
    assert load_case(case).mesh.file == body  # relative to the case file


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_check_groups_names_the_key_and_lists_the_mesh_groups():
    case = parse_case(_with(BASE, ("boundary", "traction", {"topp": [0, 0, -1]})))
    check_groups(case, ["contact", "dirichlet", "topp"])
    with pytest.raises(ParameterError) as info:
        check_groups(case, {"top": 3, "dirichlet": 1, "contact": 4, "right": 2})
    assert str(info.value) == (
        "boundary.traction.topp: unknown physical group 'topp' (did you mean 'top'?); "
        "the mesh has: contact, dirichlet, right, top"
    )
    with pytest.raises(ParameterError, match=r"^contact\.surface: unknown physical group 'contact'; the mesh has: a, top$"):
        check_groups(parse_case(_with(BASE, ("boundary", "clamped", ["a"]))), ["a", "top"])
    with pytest.raises(ParameterError, match=r"^boundary\.clamped\[0\]: unknown physical group 'dirichlet'"):
        check_groups(case, ["contact", "topp"])


@pytest.mark.parametrize(
    "name, groups",
    [
        ("hertz_coarse", {"contact", "bottom", "symmetry_x", "symmetry_y", "sides"}),
        ("mindlin_coarse", {"contact", "bottom", "symmetry_y", "sides"}),
        ("hertz_full_coarse", {"contact", "bottom", "sides"}),
        ("inclined_block", {"contact", "top", "dirichlet", "right", "front", "back"}),
    ],
)
def test_case_meshes_read_with_named_groups(name, groups):
    """The small meshes of the cases read with read_gmsh; every group has facets; the
    sphere touches the Hertz/Mindlin blocks at a vertex at the origin."""
    msh, tags, _ = meshes.read_gmsh(ROOT / "meshes" / f"{name}.geo", MPI.COMM_WORLD)
    comm = msh.comm
    assert set(tags.names) == groups
    for group in sorted(groups):  # the same order on every rank (a set's order depends on the hash seed)
        assert comm.allreduce(len(meshes.boundary_facets(tags, group)), op=MPI.SUM) > 0
    x = msh.geometry.x
    if name == "inclined_block":
        assert msh.topology.cell_name() == "hexahedron"
        assert msh.topology.index_map(3).size_global == 16 * 8 * 8
    else:
        closest = comm.allreduce(float((x**2).sum(axis=1).min(initial=1.0)), op=MPI.MIN)
        assert closest == pytest.approx(0.0, abs=1e-20)
        assert comm.allreduce(float(x[:, 2].max(initial=-1.0)), op=MPI.MAX) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_solver_start_is_checked():
    assert parse_case(_with(BASE, ("solver", {"start": "contact"}))).solver == {"start": "contact"}
    with pytest.raises(ParameterError, match=r"^solver.start: must be one of rest, contact, got 'zero'"):
        parse_case(_with(BASE, ("solver", {"start": "zero"})))


BODIES = {
    "mesh": {"file": "../meshes/patch_blocks.geo"},
    "bodies": [
        {"name": "lower", "material": {"young": 1e9, "poisson": 0.3},
         "boundary": {"displacement": {"bottom": {"z": 0.0}, "symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}}}},
        {"name": "upper", "material": {"young": 1e9, "poisson": 0.3},
         "boundary": {"displacement": {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}},
                      "traction": {"top": [0.0, 0.0, -1e6]}}},
    ],
    "contacts": [{"slave": "upper.interface", "master": "lower.interface", "law": "frictionless"}],
}


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
@pytest.mark.parametrize("change, name, text", [
    (lambda d: d["contacts"][0].update(master="lower"), "contacts[0].master", "must be 'body.group'"),
    (lambda d: d["contacts"][0].update(obstacle={"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}),
     "contacts[0]", "exactly one of 'master' and 'obstacle'"),
    (lambda d: d["contacts"][0].update(law="coulomb"), "contacts[0].friction", "needs a friction coefficient"),
    (lambda d: d["bodies"][1].update(name="lower"), "bodies[1].name", "listed twice"),
    (lambda d: d.update(material={"young": 1e9, "poisson": 0.3}), "material.young",
     "with [[bodies]], [material] gives only the default model of the bodies; give young in each body's material"),
    (lambda d: d.update(material={"model": "rubber"}), "bodies[0].material.model", "must be one of"),
    (lambda d: [b.pop("boundary") for b in d["bodies"]], "bodies", "at least one must be held"),
])
def test_bad_several_body_case_is_named(change, name, text):
    data = copy.deepcopy(BODIES)
    change(data)
    with pytest.raises(ParameterError, match=re.escape(text)) as info:
        parse_case(data, ROOT / "cases")
    assert info.value.name == name


def test_several_body_case_names_unknown_groups_and_volumes():
    """Against the mesh: a group a body does not have, a body the mesh does not have."""
    case = parse_case(BODIES, ROOT / "cases")
    msh, facet_tags, cell_tags = meshes.read_gmsh(case.mesh.file, MPI.COMM_WORLD)
    names = meshes.split_by_body(msh, facet_tags, cell_tags).names
    check_groups(case, names)
    data = copy.deepcopy(BODIES)
    data["bodies"][0]["boundary"]["displacement"]["top"] = {"z": 0.0}  # "top" bounds the upper body only
    with pytest.raises(ParameterError, match="unknown physical group 'lower.top'") as info:
        check_groups(parse_case(data, ROOT / "cases"), names)
    assert info.value.name == "bodies[0].boundary.displacement.top"
    data = copy.deepcopy(BODIES)
    data["bodies"][1]["name"] = "uper"
    data["contacts"][0]["slave"] = "uper.interface"
    with pytest.raises(ParameterError, match="no physical volume 'uper'") as info:
        build_problem(parse_case(data, ROOT / "cases"), MPI.COMM_WORLD)
    assert info.value.name == "bodies[1].name"


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_material_model_is_the_default_of_every_body():
    """With [[bodies]], ``[material] model`` is the model of every body whose material names
    none; a body naming another one is named by its key."""
    data = copy.deepcopy(BODIES)
    data["material"] = {"model": "neo_hookean"}
    case = parse_case(data, ROOT / "cases")
    assert [b.material.model for b in case.bodies] == ["neo_hookean", "neo_hookean"]
    assert case.material is None and parse_case(case.to_dict()) == case
    data["bodies"][1]["material"]["model"] = "saint_venant_kirchhoff"
    with pytest.raises(ParameterError, match=re.escape("bodies[1].material.model: all bodies take the same model")):
        parse_case(data, ROOT / "cases")


@pytest.mark.one_rank(reason="case-file parsing and checks on dataclasses: no mesh")
def test_a_pair_of_hyperelastic_bodies_is_searched_newton_by_default():
    """A pair of meshed bodies that names no search is searched ``"newton"`` (the geometry of the current
    configuration inside the Newton iteration) where the bodies are hyperelastic and of linear elements on
    a quasi-static path, ``"every_step"`` otherwise (linear elasticity, quadratic elements); a search the
    pair names stays."""
    def search(*changes: typing.Callable[[dict], typing.Any]) -> str:
        data = copy.deepcopy(BODIES)
        for change in changes:
            change(data)
        return parse_case(data, ROOT / "cases").contacts[0].search

    def hyperelastic(data: dict) -> None:
        data["material"] = {"model": "neo_hookean"}

    assert search() == "every_step"
    assert search(hyperelastic) == "newton"
    assert search(hyperelastic, lambda d: d["mesh"].update(order=2)) == "every_step"
    assert search(hyperelastic, lambda d: d["contacts"][0].update(search="once")) == "once"
