"""A block slid along a longer one by several element sizes: the contact search is done
again before every load step, so the contact follows the sliding body.

The upper block's top is moved by (s_k, 0, -delta) with s_k up to 0.6 m, 2.4 element
sizes of the lower block, with Coulomb friction F = 0.2 (:mod:`meshes/sliding_blocks.geo`).
What the search must give, checked at every step:

* the force on the master (lower) block acts where the slave block is: the centroid of
  the normal nodal forces on the master nodes equals that on the slave nodes, both in
  the deformed configuration (moment balance across the interface; C reproduces linear
  fields in the configuration it was searched in, which is the step before's, so they
  agree within the increment 0.1 m, and within 1e-3 m in the last step, which repeats
  the last position);
* the friction force opposes the sliding, at the Coulomb bound F times the normal force
  at every sliding node;
* the master and slave forces balance (Newton's third law through C^T).

Searched only once, in the reference configuration, the force on the master stays where
the block started: the same check fails by the whole slide.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
from petsc_audit import assert_frees_petsc_objects

from dolfinx import fem

from contactqvi.contact import LoadStep, solve_load_path
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.nodal import State
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.elasticity import body_materials
from contactqvi.laws import Coulomb
from contactqvi.meshes import boundary_facets, read_gmsh, split_by_body
from contactqvi.result import Status

MESH = pathlib.Path(__file__).resolve().parent.parent / "meshes" / "sliding_blocks.geo"
FRICTION = 0.2
DELTA = 1e-3  # m, the indentation
SLIDES = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.6)  # m, the last step repeats the last position


@pytest.fixture(scope="module")
def blocks():
    msh, facet_tags, cell_tags = read_gmsh(MESH, MPI.COMM_WORLD)
    return msh, split_by_body(msh, facet_tags, cell_tags), cell_tags


def _centroid(comm: MPI.Comm, x: np.ndarray, forces: np.ndarray) -> float:
    """x-coordinate of the centroid of the normal (z) forces at the points ``x``."""
    moment, total = (comm.allreduce(float(v), op=MPI.SUM) for v in ((x[:, 0] * forces[:, 2]).sum(), forces[:, 2].sum()))
    return moment / total


def _slide(blocks, search: str, parameters: dict | None = None, slides: tuple[float, ...] = SLIDES) -> list[dict]:
    """Per step: the centroids of the normal forces on the slave and on the master nodes,
    the contact forces on both sides, the Coulomb bound's excess at the sliding nodes and
    the solver status."""
    msh, tags, cell_tags = blocks
    comm = msh.comm
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, 0.3), "upper": (1e9, 0.3)})
    pair = BodyPair("upper.interface", "lower.interface", Coulomb(FRICTION), search=search)
    steps = [LoadStep(1.0, (s, 0.0, -DELTA)) for s in slides]
    rows = []
    with assemble_contact_problem(msh, tags, young, poisson, {}, [pair], clamped=["lower.bottom"],
                                  cell_tags=cell_tags, moved=["upper.top"]) as problem:
        V = problem.V
        n_owned = V.dofmap.index_map.size_local
        master = fem.locate_dofs_topological(V, 2, boundary_facets(tags, "lower.interface"))
        master = master[master < n_owned]
        reference = V.tabulate_dof_coordinates()[:n_owned]
        displacement = fem.Function(V)

        def record(index, step, u, result, state):
            x = reference + problem.physical_displacement(u, displacement).x.array.reshape(-1, 3)[:n_owned]
            forces = problem.nodal_contact_forces(result.normal_force, result.friction_force)
            slave = problem.contact_blk
            sliding = result.states == State.SLIDING
            excess = np.linalg.norm(result.friction_force, axis=1) - FRICTION * result.normal_force
            rows.append({
                "converged": result.converged,
                "status": result.status,
                "on_master": comm.allreduce(forces[master].sum(axis=0), op=MPI.SUM),
                "on_slave": np.array(contact_resultants(problem, result)["pair_forces"][pair.name]),
                "master_centroid": _centroid(comm, x[master], forces[master]),
                "slave_centroid": _centroid(comm, x[slave], forces[slave]),
                "sliding": comm.allreduce(int(sliding.sum()), op=MPI.SUM),
                "touching": comm.allreduce(int((result.normal_force > 0).sum()), op=MPI.SUM),
                "bound_excess": comm.allreduce(float(np.abs(excess[sliding]).max(initial=0.0)), op=MPI.MAX),
                "searches": 1 + max((entry.get("search", 0) for entry in result.history), default=0),
                "iterations": result.iterations,
            })

        u = problem.A.createVecRight()
        try:
            solve_load_path(problem, steps, u, {"pc": "lu", **(parameters or {})}, on_step=record, from_rest=True)
        finally:
            u.destroy()
    return rows


def test_contact_search_follows_a_sliding_block(blocks):
    rows = _slide(blocks, "every_step")
    assert [r["converged"] for r in rows] == [True] * len(SLIDES)
    for k, row in enumerate(rows):
        increment = SLIDES[k] - SLIDES[k - 1] if k else 0.0
        assert abs(row["master_centroid"] - row["slave_centroid"]) <= increment + 1e-3, (k, row)
        slave, master = row["on_slave"], row["on_master"]
        assert np.abs(slave + master).max() <= 1e-9 * slave[2]  # third law through C^T
        assert slave[2] > 0.0  # the lower block pushes the upper one up
        if increment > 0.0:  # sliding along +x: friction along -x, at the bound at every sliding node
            assert row["sliding"] >= 0.9 * row["touching"], (k, row)
            assert row["bound_excess"] <= 1e-8 * slave[2], (k, row)
            assert -slave[0] >= 0.99 * FRICTION * slave[2], (k, row)


def test_a_pair_searched_until_settled_has_no_lag(blocks):
    """Searched again after each step in the configuration it reached and solved again until
    that settles, the force on the master acts under the slave block in every step, not one
    increment behind; each sliding step needs a second search, and friction still acts at
    the Coulomb bound against the slide."""
    rows = _slide(blocks, "until_settled")
    assert [r["converged"] for r in rows] == [True] * len(SLIDES)
    lagged = _slide(blocks, "every_step")
    for k, (row, before) in enumerate(zip(rows, lagged)):
        assert abs(row["master_centroid"] - row["slave_centroid"]) <= 1e-3, (k, row)
        slave = row["on_slave"]
        assert np.abs(slave + row["on_master"]).max() <= 1e-9 * slave[2]
        if SLIDES[k] != SLIDES[k - 1] and k:
            assert row["searches"] >= 2, (k, row)
            assert row["bound_excess"] <= 1e-8 * slave[2], (k, row)
            assert -slave[0] >= 0.99 * FRICTION * slave[2], (k, row)
            assert abs(before["master_centroid"] - before["slave_centroid"]) >= 0.05  # the lag it removes


def test_a_step_that_does_not_move_is_settled_without_a_search(blocks):
    """Held at the same position, a step's displacement changes by round-off only once the
    step before has settled (the second step still settles the first one's remainder,
    1e-3 of its increment): it keeps that configuration instead of chasing round-off (which
    fails any relative test) until ``max_searches``."""
    rows = _slide(blocks, "until_settled", slides=(0.0, 0.0, 0.0))
    assert [r["converged"] for r in rows] == [True] * 3
    assert rows[2]["searches"] == 1


def test_a_configuration_that_does_not_settle_fails_its_step(blocks):
    """When the searches allowed do not settle the configuration, the step is reported as not
    converged (``diverged_max_it``) and the load path stops there."""
    rows = _slide(blocks, "until_settled", {"geometry_tol": 0.0, "max_searches": 1})  # no change is small enough
    assert len(rows) == 1
    assert rows[0]["status"] == Status.DIVERGED_MAX_IT and rows[0]["searches"] == 2


def test_searches_until_settled_free_their_petsc_objects(blocks, mpi_tmp_path):
    """Three steps searched until settled with the multigrid levels kept across the searches:
    after ``destroy()`` nothing is alive."""
    msh, tags, cell_tags = blocks

    def run():
        young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, 0.3), "upper": (1e9, 0.3)})
        pair = BodyPair("upper.interface", "lower.interface", Coulomb(FRICTION), search="until_settled")
        problem = assemble_contact_problem(msh, tags, young, poisson, {}, [pair], clamped=["lower.bottom"],
                                           cell_tags=cell_tags, moved=["upper.top"])
        u = problem.A.createVecRight()
        steps = [LoadStep(1.0, (s, 0.0, -DELTA)) for s in SLIDES[:3]]
        results = solve_load_path(problem, steps, u, {"pc": "gamg"}, prefix="settle_", from_rest=True)
        assert all(r.converged for r in results) and max(e["search"] for e in results[1].history) >= 1
        return [u, problem]

    assert_frees_petsc_objects(run, mpi_tmp_path)


def test_a_pair_searched_once_keeps_the_reference_coupling(blocks):
    """The control: without a new search the force on the master stays where the block started."""
    last = _slide(blocks, "once")[-1]
    assert last["converged"]
    assert abs(last["master_centroid"] - last["slave_centroid"]) > 0.5


def test_a_search_changes_A_in_place_near_the_interface(blocks):
    """After a search, A is the same object and holds T^T A_K T of the new T, and the change
    returned is the new A minus the old one (what the kept multigrid levels are updated by)."""
    msh, tags, cell_tags = blocks
    young, poisson = body_materials(msh, cell_tags, {"lower": (1e9, 0.3), "upper": (1e9, 0.3)})
    pair = BodyPair("upper.interface", "lower.interface", Coulomb(FRICTION))
    with assemble_contact_problem(msh, tags, young, poisson, {}, [pair], clamped=["lower.bottom"],
                                  cell_tags=cell_tags, moved=["upper.top"]) as problem:
        A, before = problem.A, problem.A.copy()
        displacement = fem.Function(problem.V)  # the upper block slid by 0.3 m: new couplings
        upper = problem.node_body == list(cell_tags.names).index("upper")
        displacement.x.array.reshape(-1, 3)[upper, 0] = 0.3
        change = problem.search(displacement, change=True)
        assert problem.A.handle == A.handle
        expected = problem.elastic.stiffness.PtAP(problem.transform)
        scale = expected.norm()
        different = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN
        expected.axpy(-1.0, problem.A, different)  # T^T A_K T - A
        before.axpy(1.0, change, different)
        before.axpy(-1.0, problem.A, different)  # old A + change - A
        assert expected.norm() <= 1e-13 * scale
        assert before.norm() <= 1e-13 * scale
        assert change.norm() >= 1e-3 * scale  # the coupling moved
        for M in (before, change, expected):
            M.destroy()
