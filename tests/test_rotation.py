"""Prescribed rigid rotations of the moved groups (issue 36, item 6).

A step rotates the groups ``boundary.moved`` by Q about a centre c fixed for the path and
translates them by t: u = (Q - I)(X - c) + t there (:mod:`contactqvi.load_steps`), made of
nine more lifted loads of the fields e_a X_b (:meth:`ContactProblem.rigid_motion`).

* A linear stack of two blocks (``meshes/patch_blocks.geo``, frictionless body pair), the
  bottom of the lower block and the top of the upper one moved together: at the moved nodes
  u is exactly (Q - I)(X - c) + t; at a small angle theta the solution is the infinitesimal
  rigid motion theta a x (X - c) + t of linear theory, up to O(theta^2).
* Objectivity at finite strain: the neo-Hookean blocks with Coulomb friction, the upper
  one pressed onto the lower by a follower pressure on its top and held by friction alone,
  the lower one's bottom moved; then everything is rotated rigidly by 90 degrees about x in
  ten steps. The final contact force is Q times the pressed one's, the Cauchy stress of
  every cell Q sigma Q^T of the pressed one's, the contact states' counts the same.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.contact import LoadStep, solve_load_path
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.load_path import contact_resultants
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.elasticity import body_materials
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.load_steps import Rotation
from contactqvi.materials import NeoHookean
from contactqvi.meshes import read_gmsh, split_by_body
from contactqvi.parameters import ParameterError
from contactqvi.postprocess import StressFields

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESH = ROOT / "meshes" / "patch_blocks.geo"
YOUNG, POISSON = 10e6, 0.3  # Pa
CENTRE = (0.5, 0.5, 1.0)  # m, the middle of the stack


def _blocks(law, moved, material=None, rotations=True, pressures=None, search="once"):
    comm = MPI.COMM_WORLD
    msh, facet_tags, cell_tags = read_gmsh(MESH, comm)
    young, poisson = body_materials(msh, cell_tags, {"lower": (YOUNG, POISSON), "upper": (YOUNG, POISSON)})
    pair = BodyPair("upper.interface", "lower.interface", law, search=search)
    return assemble_contact_problem(msh, split_by_body(msh, facet_tags, cell_tags), young, poisson, {}, [pair],
                                    cell_tags=cell_tags, moved=moved, material=material, rotations=rotations,
                                    pressures=pressures)


def _moved_nodes(problem) -> np.ndarray:
    """Owned nodes all of whose components are prescribed (the moved groups here)."""
    n_owned = problem.V.dofmap.index_map.size_local
    dofs = problem.dirichlet_dofs_loc[problem.dirichlet_dofs_loc < 3 * n_owned]
    counts = np.bincount(dofs // 3, minlength=n_owned)
    return np.flatnonzero(counts == 3)


def test_a_rotated_moved_group_moves_rigidly():
    """Two steps: 1e-3 degrees about x (linear theory to O(theta^2)), then 30 degrees; the moved
    nodes exactly at (Q - I)(X - c) + t in both; no rotation loads unless asked for."""
    comm = MPI.COMM_WORLD
    t = np.array([1e-6, -2e-6, 3e-6])
    steps = [LoadStep(0.0, tuple(t), Rotation((1.0, 0.0, 0.0), angle, CENTRE)) for angle in (1e-3, 30.0)]
    errors = []

    def record(index, step, u, result, state):
        assert result.converged, result.status
        Q = step.rotation.matrix()
        n_owned = problem.V.dofmap.index_map.size_local
        X = problem.V.tabulate_dof_coordinates()[:n_owned]
        u_h = state.displacement.x.array.reshape(-1, 3)[:n_owned]
        exact = (X - CENTRE) @ (Q - np.eye(3)).T + t
        moved = _moved_nodes(problem)
        scale = comm.allreduce(float(np.abs(exact).max(initial=0.0)), op=MPI.MAX)
        at_moved = comm.allreduce(float(np.abs(u_h[moved] - exact[moved]).max(initial=0.0)), op=MPI.MAX) / scale
        theta = np.radians(step.rotation.angle)
        linear = np.cross(theta * np.array([1.0, 0.0, 0.0]), X - CENTRE) + t
        off_linear = comm.allreduce(float(np.abs(u_h - linear).max(initial=0.0)), op=MPI.MAX)
        errors.append((at_moved, off_linear, theta, comm.allreduce(len(moved))))

    with _blocks(Frictionless(), ["lower.bottom", "upper.top"]) as problem:
        assert len(problem.translated) == 12
        u = problem.A.createVecRight()
        results = solve_load_path(problem, steps, u, {"pc": "lu"}, on_step=record, from_rest=True)
        u.destroy()
    assert len(results) == 2 and all(r.converged for r in results)
    for at_moved, _, _, n_moved in errors:
        assert n_moved > 0 and at_moved <= 1e-14, errors
    _, off_linear, theta, _ = errors[0]
    assert off_linear <= theta**2, errors  # the stack's half-diagonal is 1.2 m: (1 - cos theta) |X - c| <= 0.6 theta^2
    with _blocks(Frictionless(), ["lower.bottom", "upper.top"], rotations=False) as problem:
        assert len(problem.translated) == 3
        with pytest.raises(ParameterError, match="steps.rotation"):
            problem.set_step(rotation=steps[0].rotation)
