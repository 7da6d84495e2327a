"""A user's mistakes end in an error that names the cause, before any solve (issue 46).

The cases are a new user's (``tests/data/mistakes/``): a plane obstacle whose normal points
away from the body (``m08_normal_flipped.toml``: before, it "converged" with zero contact
force and exit 0), a facet in two physical groups (``facet_in_two_groups.toml``: "0 of its
316 facets arrived after distributing the mesh"), and a body name misspelt in ``[[bodies]]``
(``m20_wrong_body_name.toml``: "unknown body 'middle' (did you mean 'midle'?)", the
suggestion backwards; following it, ``m20b_...``, gave the opposite error).
"""

from __future__ import annotations

import dataclasses
import pathlib
import re
import tomllib

from mpi4py import MPI

import pytest

from contactqvi.case import ContactCase, Displacement, check_bodies, load_case, parse_case
from contactqvi.contact.reach import body_travel, check_reach
from contactqvi.parameters import ParameterError
from contactqvi.runner import EXIT_CODES, build_problem, run_case
from program_runs import run_program

DATA = pathlib.Path(__file__).resolve().parent / "data" / "mistakes"

#: The obstacle of m08 starts on the block's top face (z = 10 mm) with its normal +z, pointing
#: out of the block, and moves down 0.3 mm per step: the top face's nodes are 0.3 mm from it at
#: step 1 and farther after, and of the block's 237 nodes all but the 44 of the top lie behind it.
NEVER = ("contact: the pair top/obstacle can never touch: no node of 'top' comes nearer than 0.0003 m to the obstacle "
         "in the 10 load steps (the smallest gap, at step 1; the obstacle travels up to 0.003 m), and nothing "
         "moves the bodies more than 0 m (prescribed displacements, moved groups, the other pairs; no force "
         "acts). Likely cause: the obstacle faces away from the body: 193 of its 237 nodes lie behind the "
         "obstacle's surface (signed distance down to -0.0097 m, at load factor 1, translation of the obstacles "
         "and moved groups (0, 0, -0.0003) m); a plane's normal must point into the body's side (flip "
         "obstacle.normal)")
#: The group "contact" holds the surfaces of "side_x" and "top" too.
TWO_GROUPS = ("mesh: the physical groups 'contact' and 'side_x' share 26 facets (gmsh surface 2); 'contact' and "
              "'top' share 38 facets (gmsh surface 6): a facet may be in one physical group only")
#: The body "middle" of the mesh is called "midle" in [[bodies]], "middle" in [[contacts]]: the
#: body is misspelt, and both cases point at the mesh's name.
MISSPELT = ("bodies[1].name: no physical volume 'midle' in the mesh (did you mean 'middle', which contacts[0].slave "
            "and contacts[1].master name?); it has: base, middle, topblk")
FOLLOWED = ("bodies[1].name: no physical volume 'midle' in the mesh (did you mean 'middle'?); it has: base, middle, "
            "topblk")
MISTAKES = {"m08_normal_flipped": NEVER, "facet_in_two_groups": TWO_GROUPS, "m20_wrong_body_name": MISSPELT,
            "m20b_wrong_body_name_followed_hint": FOLLOWED}


@pytest.mark.parametrize("name", MISTAKES)
def test_a_mistake_is_named_before_any_solve(name, mpi_tmp_path):
    """Each mistake raises its named error from run_case, on every rank, before a summary is written."""
    with pytest.raises(ParameterError) as error:
        run_case(load_case(DATA / f"{name}.toml"), mpi_tmp_path / "out", plot=False)
    assert str(error.value).startswith(MISTAKES[name]), str(error.value)
    assert not (mpi_tmp_path / "out" / "summary.json").exists()


@pytest.mark.serial
@pytest.mark.parametrize("ranks", [1, 3])
@pytest.mark.parametrize("name", MISTAKES)
def test_a_mistake_exits_2_with_its_message_on_1_and_3_ranks(tmp_path, name, ranks):
    """``python -m contactqvi run`` on each mistake: exit 2 and the named error, printed once, on 1 and 3 ranks."""
    done = run_program(DATA / f"{name}.toml", tmp_path / "out", ranks)
    assert done.returncode == EXIT_CODES["bad input"], done.stderr[-3000:]
    assert done.stderr.count(f"error: {MISTAKES[name]}") == 1, done.stderr[-3000:]  # rank 0's only
    assert "Traceback" not in done.stderr and "MPI_ABORT" not in done.stderr


def _flipped() -> ContactCase:
    """The case of m08: a plate on the block's top face, its normal pointing out of the block."""
    return load_case(DATA / "m08_normal_flipped.toml")


def test_a_pair_that_can_touch_passes():
    """The normal the right way round (-z, into the block's side): the plate presses the block,
    nothing is refused; a body force could carry the block to the flipped plate: not checked."""
    case = _flipped()
    right = dataclasses.replace(case, obstacle=dataclasses.replace(case.obstacle, normal=(0.0, 0.0, -1.0)))
    with build_problem(right, MPI.COMM_WORLD) as problem:
        check_reach(problem, right.steps)
    loaded = dataclasses.replace(case, boundary=dataclasses.replace(case.boundary, body_force=(0.0, 0.0, 1e3)))
    with build_problem(loaded, MPI.COMM_WORLD) as problem:
        assert body_travel(problem, loaded.steps) is None
        check_reach(problem, loaded.steps)


def test_a_prescribed_motion_that_may_close_the_gap_passes(mpi_tmp_path):
    """The plate 1 mm above the block, whose bottom a prescribed displacement lifts: by 0.6 mm the
    gap exceeds the travel but not twice it (a node may move farther than its support), so the
    pair may touch; by 0.4 mm it cannot, and the runner's error names the travel and the gap."""
    case = _flipped()
    above = dataclasses.replace(case.obstacle, point=(0.0, 0.0, 0.011), normal=(0.0, 0.0, -1.0))
    steps = tuple(dataclasses.replace(step, translation=(0.0, 0.0, 0.0)) for step in case.steps)
    with build_problem(dataclasses.replace(case, obstacle=above, steps=steps), MPI.COMM_WORLD) as problem:
        assert body_travel(problem, steps, 6e-4) == pytest.approx(6e-4, rel=1e-15)
        check_reach(problem, steps, 6e-4)
    lifted = dataclasses.replace(case.boundary, displacement={**case.boundary.displacement,
                                                              "bottom": Displacement(z=4e-4)})
    with pytest.raises(ParameterError, match=re.escape(
            "contact: the pair top/obstacle can never touch: no node of 'top' comes nearer than 0.001 m to the "
            "obstacle in the 10 load steps (the smallest gap, at step 1; the obstacle travels up to 0 m), and "
            "nothing moves the bodies more than 0.0004 m") + ".* Likely cause: the obstacle is placed"):
        run_case(dataclasses.replace(case, obstacle=above, steps=steps, boundary=lifted), mpi_tmp_path / "out",
                 plot=False)


def test_a_pair_that_can_never_touch_is_named_by_its_key(mpi_tmp_path):
    """The case-file key names the pair that can never touch, and the normal to flip: ``contact`` and
    ``obstacle.normal`` above (m08), ``contacts[0]`` and ``contacts[0].obstacle.normal`` for the same
    block and plate as one of [[bodies]] with its [[contacts]]; without keys (the Python API) the pair's
    groups name it."""
    bodies = _as_bodies()
    assert bodies.pair_keys == [("contacts[0]", "contacts[0].obstacle")] and _flipped().pair_keys == [
        ("contact", "obstacle")]
    with pytest.raises(ParameterError) as error:
        run_case(bodies, mpi_tmp_path / "out", plot=False)
    assert error.value.name == "contacts[0]"
    assert str(error.value).startswith("contacts[0]: the pair block.top/obstacle can never touch: no node of "
                                       "'block.top' comes nearer than 0.0003 m")
    assert str(error.value).endswith("(flip contacts[0].obstacle.normal)")
    case = _flipped()
    with build_problem(case, MPI.COMM_WORLD) as problem, pytest.raises(ParameterError) as error:
        check_reach(problem, case.steps)
    assert str(error.value) == NEVER.replace("contact: the pair top/obstacle", "top/obstacle: the pair")


def _as_bodies(slave: str = "top", obstacle: dict | None = None, steps: bool = True) -> ContactCase:
    """m08's block and plate as the body "block" of [[bodies]] with one [[contacts]] pair: its
    group ``slave`` against the plate (or ``obstacle``), along m08's steps (or one step at rest)."""
    data = tomllib.loads((DATA / "m08_normal_flipped.toml").read_text())
    contact = {"slave": f"block.{slave}", "law": "frictionless", "obstacle": obstacle or data["obstacle"]}
    return parse_case({"mesh": data["mesh"], "steps": data["steps"] if steps else [{}],
                       "bodies": [{"name": "block", "material": data["material"], "boundary": data["boundary"]}],
                       "contacts": [contact]}, DATA)


def test_an_initial_penetration_is_named_by_the_obstacle_key():
    """The plate 1 mm below the block's top face, the block on its -z side: the top face starts
    inside it; the error names the pair's obstacle by its key, ``contacts[0].obstacle``, with the
    group and the hint."""
    inside = {"type": "plane", "point": [0.0, 0.0, 0.009], "normal": [0.0, 0.0, -1.0]}
    with pytest.raises(ParameterError) as error:
        build_problem(_as_bodies(obstacle=inside), MPI.COMM_WORLD)
    assert error.value.name == "contacts[0].obstacle"
    assert re.fullmatch(r"contacts\[0\]\.obstacle: initial penetration: \d+ contact nodes of 'block\.top' lie inside "
                        r"the obstacle, the deepest by 1\.000e-03 m; the body must start outside it \(check its "
                        r"position and, for a plane, that the normal points into the body's side\)", str(error.value))


def test_a_wrong_contact_group_is_named_by_the_key_that_selects_it(mpi_tmp_path):
    """A plate 1 mm off the block's face x = 0 (its normal +x), the contact group the opposite face
    ``side_x`` (11 mm away), nothing moving: the likely cause names the key that selects the group,
    ``contacts[0].slave`` with [[bodies]], ``contact.surface`` with [contact]."""
    plate = {"type": "plane", "point": [-0.001, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]}
    with pytest.raises(ParameterError) as error:
        run_case(_as_bodies("side_x", plate, steps=False), mpi_tmp_path / "out", plot=False)
    assert error.value.name == "contacts[0]"
    assert str(error.value).endswith("Likely cause: a wrong contact group: nodes of the body off 'block.side_x' come "
                                     "within 0.001 m of the obstacle, nearer than the group; name the face that "
                                     "meets it in contacts[0].slave")
    case = _flipped()
    single = dataclasses.replace(case, contact=dataclasses.replace(case.contact, surface="side_x"),
                                 obstacle=dataclasses.replace(case.obstacle, point=(-0.001, 0.0, 0.0),
                                                              normal=(1.0, 0.0, 0.0)), steps=())
    with build_problem(single, MPI.COMM_WORLD) as problem, pytest.raises(ParameterError) as error:
        check_reach(problem, single.steps, keys=single.pair_keys)
    assert str(error.value).endswith("name the face that meets it in contact.surface")


@pytest.mark.one_rank(reason="case-file checks on dataclasses against a list of names: no mesh")
def test_a_pair_that_misspells_a_body_is_named_with_the_body():
    """The body named as in the mesh, the pair misspelt: the pair's key is named, with the body."""
    case = load_case(DATA / "m20b_wrong_body_name_followed_hint.toml")
    bodies = tuple(dataclasses.replace(b, name="middle") if b.name == "midle" else b for b in case.bodies)
    right = dataclasses.replace(case, bodies=bodies)
    with pytest.raises(ParameterError, match=re.escape("contacts[0].slave: unknown body 'midle' (did you mean "
                                                       "'middle'?); the [[bodies]] are: base, middle, topblk")):
        check_bodies(right, ["base", "middle", "topblk"])
    check_bodies(case, ["base", "midle", "topblk"])  # a mesh whose volume is called so
