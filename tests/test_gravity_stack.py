"""Body forces with several bodies: a stack of three blocks under their own weight.

``tests/data/gravity_stack.geo``: three blocks of 1 x 1 x 0.5 m stacked along z, meshed
independently (non-matching tetrahedra at both interfaces), of steel (bottom),
copper (middle) and aluminium (top), each with its own weight as
``[bodies.boundary] body_force = [0, 0, -rho g]`` (N/m^3). Rollers on the planes x = 0
and y = 0 hold every block sideways and against rotation; vertically the blocks are
held by frictionless contact alone: the middle block on the bottom one, the top block
on the middle one, and the bottom block on a rigid floor (a plane obstacle at z = 0).

Equilibrium is then exact for any discretisation: each interface carries the weight of
the blocks above it (straight down: the rollers take no vertical force, frictionless
contact on the flat interfaces searched in the reference configuration no lateral
one), the floor carries all three, and each block's weight, contact forces and roller
reactions balance. Checked at load factor 0.5 and 1 (the body forces scale with it).
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import parse_case
from contactqvi.elasticity import body_forces
from contactqvi.meshes import read_gmsh
from contactqvi.parameters import ParameterError
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESH = ROOT / "tests" / "data" / "gravity_stack.geo"
G = 9.81  # m/s^2
VOLUME = 0.5  # m^3, each block
#: body: (E (Pa), nu, density (kg/m^3)), bottom to top
BLOCKS = {"bottom": (200e9, 0.3, 7850.0), "middle": (120e9, 0.34, 8960.0), "top": (70e9, 0.33, 2700.0)}
ROLLERS = {"symmetry_x": {"x": 0.0}, "symmetry_y": {"y": 0.0}}
LOADS = (0.5, 1.0)


def _stack_case() -> dict:
    """The case file of the stack, as the dict ``tomllib`` would read."""
    bodies = [{"name": name, "material": {"young": young, "poisson": poisson},
               "boundary": {"displacement": ROLLERS, "body_force": [0.0, 0.0, -density * G]}}
              for name, (young, poisson, density) in BLOCKS.items()]
    frictionless = {"law": "frictionless", "search": "once"}
    contacts = [
        {"slave": "bottom.floor", "law": "frictionless",
         "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}},
        {"slave": "middle.joint_1", "master": "bottom.joint_1", **frictionless},  # each on the stiffer one below
        {"slave": "top.joint_2", "master": "middle.joint_2", **frictionless},
    ]
    return {"mesh": {"file": str(MESH)}, "bodies": bodies, "contacts": contacts,
            "steps": [{"load": load} for load in LOADS]}


def _weight(name: str) -> float:
    """Weight (N) of one block."""
    return BLOCKS[name][2] * G * VOLUME


def test_each_interface_carries_the_weight_above_it(mpi_tmp_path):
    """At each step (load factor 0.5 and 1): the floor carries the three weights, the lower
    joint the middle and top blocks', the upper joint the top block's, as force vectors to
    1e-8 relative; the applied force is the total weight; every block and the whole are in
    balance to 1e-10."""
    summary, code = run_case(parse_case(_stack_case()), mpi_tmp_path / "stack", plot=False)
    assert code == 0
    assert len(summary["steps"]) == len(LOADS)
    for load, step in zip(LOADS, summary["steps"]):
        above = {
            "bottom.floor/obstacle": _weight("bottom") + _weight("middle") + _weight("top"),
            "middle.joint_1/bottom.joint_1": _weight("middle") + _weight("top"),
            "top.joint_2/middle.joint_2": _weight("top"),
        }
        for pair, weight in above.items():
            force = np.asarray(step["pair_forces"][pair])
            expected = np.array([0.0, 0.0, load * weight])
            assert np.linalg.norm(force - expected) < 1e-8 * abs(load * weight), (pair, force, expected)
        total = sum(_weight(name) for name in BLOCKS)
        assert step["applied_force"] == pytest.approx([0.0, 0.0, -load * total], rel=1e-12, abs=1e-9 * total)
        assert set(step["body_equilibrium_errors"]) == set(BLOCKS)
        assert max(step["body_equilibrium_errors"].values()) < 1e-10
        assert step["equilibrium_error"] < 1e-10


def test_a_force_for_an_unknown_body_is_named():
    """``body_forces`` names the body it cannot find and lists the mesh's bodies."""
    msh, _, cell_tags = read_gmsh(MESH, MPI.COMM_WORLD)
    with pytest.raises(ParameterError, match=r"body_force\[toop\].*no cell group 'toop'.*bottom, middle, top"):
        body_forces(msh, cell_tags, {"top": (0.0, 0.0, -1.0), "toop": (0.0, 0.0, -1.0)})
    f = body_forces(msh, cell_tags, {"middle": (0.0, 0.0, -2.0)})
    n_cells = msh.topology.index_map(3).size_local
    values = f.x.array.reshape(-1, 3)[:n_cells]
    middle = cell_tags.find(cell_tags.names["middle"])
    middle = middle[middle < n_cells]
    assert np.all(values[middle] == [0.0, 0.0, -2.0])
    assert MPI.COMM_WORLD.allreduce(int(np.count_nonzero(values)), op=MPI.SUM) == \
        MPI.COMM_WORLD.allreduce(len(middle), op=MPI.SUM)
