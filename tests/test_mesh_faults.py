"""Meshes DOLFINx cannot take, or that are not separate bodies (issue 35, part 3): a named
error before any solve, on every rank, instead of an MPI abort.

The meshes are small gmsh scripts in ``tests/data/mesh_faults/``. Before these checks,
bodies whose coincident nodes gmsh merged (``touching.geo``: a structured extrusion) and a
facet group on a volume in no physical volume (``unphysical.geo``) ended in
``MPI_ERR_RANK: invalid rank`` and ``MPI_ABORT`` (exit 6), a volume in two physical
volumes (``twice.geo``) in a heap corruption (SIGABRT), and bodies joined by
BooleanFragments ran on into errors about the contact search that did not name the cause;
a hexahedral body on a tetrahedral one (``mixed_cells.geo``) ended in ``MPI_ERR_RANK``.
"""

from __future__ import annotations

import pathlib
import re
import tomllib

from mpi4py import MPI

import pytest

from contactqvi.case import parse_case
from contactqvi.meshes import read_gmsh, split_by_body
from contactqvi.parameters import ParameterError
from contactqvi.runner import EXIT_CODES, run_case
from program_runs import run_program

DATA = pathlib.Path(__file__).resolve().parent / "data" / "mesh_faults"
#: What the error says of touching.geo: the bodies, the shared nodes (count and where), the
#: facets left on no cell, and the fix.
MERGED = ("mesh: physical volumes 'block' and 'cyl' share 3 nodes (x = 0, y in [0, 0.2], z = 0), and 12 facets "
          "of the physical groups 'curved' (8 of 32), 'ends' (4 of 190) have nodes in no cell (3 nodes, x = 0, "
          "y in [0, 0.2], z = 0): each body must be a mesh of its own")


def _case(mesh: str, cyl_boundary: str = "{displacement = {load = {x = 0.0, y = 0.0, z = -1e-3}}}") -> str:
    """A case file of the two bodies of ``mesh`` (a cylinder on a block) in contact."""
    return f"""[mesh]
file = "{DATA / mesh}"
[[bodies]]
name = "block"
material = {{young = 70e9, poisson = 0.33}}
boundary = {{clamped = ["bottom"]}}
[[bodies]]
name = "cyl"
material = {{young = 210e9, poisson = 0.3}}
boundary = {cyl_boundary}
[[contacts]]
slave = "block.top"
master = "cyl.curved"
law = "frictionless"
"""


def test_merged_nodes_of_touching_bodies_are_named_before_the_mesh_is_distributed():
    """gmsh's structured extrusion merged the nodes of two bodies where they touch: the error
    names both bodies, how many nodes they share and where, and says how to mesh them."""
    with pytest.raises(ParameterError) as error:
        read_gmsh(DATA / "touching.geo", MPI.COMM_WORLD)
    message = str(error.value)
    assert message.startswith(MERGED), message
    assert "Layers{}" in message and "BooleanFragments" in message and "gap" in message


@pytest.mark.serial
@pytest.mark.parametrize("ranks", [1, 3])
def test_merged_nodes_give_exit_code_2_with_the_message_on_any_number_of_ranks(tmp_path, ranks):
    """``python -m contactqvi run`` on the merged mesh: exit 2 and the named error, on 1 and 3
    ranks (an MPI abort with exit 6 before)."""
    case = tmp_path / "touching.toml"
    case.write_text(_case("touching.geo"))
    done = run_program(case, tmp_path / "out", ranks)
    assert done.returncode == EXIT_CODES["bad input"], done.stderr[-3000:]
    assert f"error: {MERGED}" in done.stderr and "MPI_ABORT" not in done.stderr, done.stderr[-3000:]
    assert not (tmp_path / "out" / "summary.json").exists()


@pytest.mark.parametrize("mesh, shared", [
    ("touching_fragments.geo", "physical volumes 'block' and 'cyl' share 2 nodes (x = 0, y in [0, 0.2], z = 0)"),
    ("stacked_fragments.geo", "physical volumes 'lower' and 'upper' share 45 nodes (x in [0, 1], y in [0, 1], z = 1)"),
], ids=["line", "face"])
def test_bodies_joined_by_fragments_are_named_when_split_into_bodies(mesh, shared):
    """Volumes joined by BooleanFragments share nodes but DOLFINx takes the mesh (one body of
    two volumes is legal); as bodies they are a named error, before the contact search."""
    msh, facet_tags, cell_tags = read_gmsh(DATA / mesh, MPI.COMM_WORLD)
    assert [str(s) for s in cell_tags.shared_nodes] == [shared]
    with pytest.raises(ParameterError, match="^" + re.escape(f"mesh: {shared}: each body must be a mesh of its own")):
        split_by_body(msh, facet_tags, cell_tags)


def test_a_facet_group_on_a_volume_in_no_physical_volume_is_named():
    """The group "top" lies on a volume that is in no physical volume: its facets are faces of
    no cell (an MPI abort before); the error names the group, the counts and where."""
    with pytest.raises(ParameterError, match=r"^mesh: 44 facets of the physical groups 'top' \(44 of 44\) have "
                       r"nodes in no cell \(31 nodes, x in \[0, 1\], y in \[0, 1\], z = 2.5\): each facet of a "
                       r"physical group must be a face of a cell of a physical volume"):
        read_gmsh(DATA / "unphysical.geo", MPI.COMM_WORLD)


def test_a_volume_in_two_physical_volumes_is_named():
    """Volume 1 in the physical volumes "lower" and "both": DOLFINx would get its cells twice
    (a heap corruption before)."""
    with pytest.raises(ParameterError, match="^mesh: gmsh volume 1 is in the physical volumes 'lower' and 'both': "
                       "each cell must be in one physical volume"):
        read_gmsh(DATA / "twice.geo", MPI.COMM_WORLD)


def test_bodies_with_cells_of_two_kinds_are_named():
    """A hexahedral body on a tetrahedral one (DOLFINx 0.9 builds a mesh of one cell type; an
    MPI abort before): the error names each volume's kind of cell and the fix."""
    with pytest.raises(ParameterError, match="^" + re.escape(
            "mesh: the physical volumes hold cells of several kinds ('lower': Hexahedron 8; 'upper': "
            "Tetrahedron 4): the bodies of a case share one mesh, and DOLFINx 0.9 takes one kind of cell per mesh")):
        read_gmsh(DATA / "mixed_cells.geo", MPI.COMM_WORLD)


@pytest.mark.parametrize("mesh, groups", [
    ("touching_gap.geo", {"block.top", "block.bottom", "block.ends", "cyl.ends", "cyl.load", "cyl.curved"}),
    ("free_point.geo", {"block.bottom"}),
], ids=["gap", "free_point"])
def test_separate_bodies_and_a_free_node_are_accepted(mesh, groups):
    """The fix the error advises (the cylinder 1e-6 above the block, still extruded in layers)
    gives separate bodies; a node in no cell and no facet (a free point) is harmless."""
    msh, facet_tags, cell_tags = read_gmsh(DATA / mesh, MPI.COMM_WORLD)
    assert cell_tags.shared_nodes == []
    assert set(split_by_body(msh, facet_tags, cell_tags).names) == groups


def test_a_group_with_no_facets_on_the_body_that_names_it_is_named(mpi_tmp_path):
    """``cyl`` clamped on "bottom", which bounds the block only: named by its key path."""
    case = parse_case(tomllib.loads(_case("touching_gap.geo", cyl_boundary='{clamped = ["bottom"]}')))
    with pytest.raises(ParameterError, match=r"^bodies\[1\]\.boundary\.clamped\[0\]: unknown physical group "
                       r"'cyl.bottom' \(did you mean 'block.bottom'\?\)"):
        run_case(case, mpi_tmp_path / "out", plot=False)
