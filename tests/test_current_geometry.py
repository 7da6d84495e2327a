"""The Newton step of pairs searched ``"newton"`` (issue 45, items 3-4; docs/finite_strain.md, Sects. 13-14).

* The two Jacobians of (13.3), del_w f = A + Gamma T and del_w v = (dv/du~) T, assembled by
  :func:`~contactqvi.contact.current_geometry.geometric_rows` at a deformed, slipped
  configuration of the bulging block (two neo-Hookean blocks on non-matching tetrahedra, rollers
  on symmetry planes through the interface), against central differences of f and of the law's
  variables v taken with the geometry followed (:meth:`ContactProblem.follow`) along random
  directions, on 1-3 ranks.
* ``search = "newton"`` between linear bodies is named as the pair's error.

The closed-form compression searched ``"newton"`` is in tests/test_homogeneous_compression.py.
"""

from __future__ import annotations

import pathlib
import tomllib

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx import fem

from contactqvi.case import parse_case
from contactqvi.runner import build_problem

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "benchmarks" / "data" / "homogeneous_compression"
#: Largest difference between the assembled Jacobians' action and central differences, relative to the action.
BOUND = 1e-6


def _case(name: str, friction: float = 0.0, **solver):
    data = tomllib.loads((DATA / name).read_text())
    for pair in data["contacts"]:
        pair["search"] = "newton"
        if friction:
            pair.update(law="coulomb", friction=friction)
    data.setdefault("solver", {}).update(solver)
    return parse_case(data, DATA)


def _deformed(x: np.ndarray, body: np.ndarray, amplitude: float) -> np.ndarray:
    """A compression with a lateral bulge and a shear, and a node-wise wobble of 1e-3 m, a function
    of the position and of the node's ``body`` (the same on any number of ranks): the meshes of the
    two blocks share vertex positions on the interface, where D and M have kinks
    (docs/finite_strain.md, Sect. 14), and the wobble moves them apart. Nodes on the symmetry
    planes stay on them."""
    z = x[:, 2]
    smooth = amplitude * np.column_stack([0.3 * x[:, 0] * z + 0.05 * np.sin(3 * z), 0.25 * x[:, 1] * z
                                          + 0.04 * np.cos(2 * z), -0.6 * z + 0.02 * x[:, 0] * x[:, 1]])
    wobble = 1e-3 * np.sin(x @ np.array([[17.0, 5.0, 3.0], [7.0, 13.0, 2.0], [11.0, 3.0, 19.0]]) + body[:, None])
    return (smooth + wobble) * (x > 1e-12)


def test_newton_matrix_against_differences():
    """(13.3)'s del_w f and del_w v at a slipped configuration against central differences
    (measured: 5e-11 and 1.2e-8 on 1 rank, 4e-10 and 1.2e-7 on 2, 8e-11 and 3e-8 on 3)."""
    problem = build_problem(_case("bulging_block.toml"), MPI.COMM_WORLD)
    V = problem.V
    x = V.tabulate_dof_coordinates()
    start, here = fem.Function(V), fem.Function(V)
    start.x.array[:] = _deformed(x, problem.node_body, 0.05).ravel()
    here.x.array[:] = _deformed(x, problem.node_body, 0.1).ravel()
    problem.set_step(0.2)  # the top moved by 0.12 m, as the deformation of here
    problem.search(start)  # the step's start: the slip's reference
    problem.search(here, start=False)  # the facet pairs of here
    problem.set_step(0.2)  # the top moved by 0.12 m, as the deformation of here
    _check_jacobians(problem, here)


def test_obstacle_newton_matrix_against_differences():
    """(13.3) for a rigid obstacle searched ``"newton"`` ((18.1)-(18.2), docs/finite_strain.md
    Sect. 18): the rubber pad under its roller (a cylinder, curvature terms), frictional, the
    roller moved between the step's start and the iterate (the slip's reference carried with
    it), rollers on the symmetry planes through the contact surface; del_w f and
    del_w v against central differences (measured: 1.2e-10 and 3.7e-10 on 1 rank, 6.9e-11 and 3.4e-10 on
    2, 1.4e-10 and 5.4e-10 on 3; without the curvature terms H, 1.6e-2 and 0.2)."""
    data = tomllib.loads((ROOT / "cases" / "rubber_pad.toml").read_text())
    data["mesh"]["file"] = str(ROOT / "meshes" / "rubber_pad_coarse.geo")
    data["contact"]["search"] = "newton"
    data["steps"] = [{"translation": [0.0, 0.0, -1e-3]}, {"translation": [0.0, 0.0, -2e-3]}]
    case = parse_case(data, ROOT / "cases")
    problem = build_problem(case, MPI.COMM_WORLD)
    V = problem.V
    x = V.tabulate_dof_coordinates()

    height = x[:, 2] + 0.01  # above the clamped bottom z = -10 mm

    def pressed(amplitude: float) -> np.ndarray:  # zero on the clamped bottom and the symmetry planes
        wobble = 2e-5 * np.sin(x @ np.array([[1700.0, 500.0, 300.0], [0.0] * 3, [1100.0, 300.0, 1900.0]]).T)
        smooth = amplitude * np.column_stack([8.0 * x[:, 0] * height, np.zeros(len(x)),
                                              -20.0 * height**2 + 3.0 * x[:, 0] * height])
        mask = np.column_stack([x[:, 0] > 1e-12, np.zeros(len(x)), np.ones(len(x))]) * (height[:, None] > 1e-12)
        return (smooth + wobble) * mask

    start, here = fem.Function(V), fem.Function(V)
    start.x.array[:] = pressed(0.5).ravel()
    here.x.array[:] = pressed(1.0).ravel()
    steps = case.steps
    problem.set_step(1.0, steps[0].translation)
    problem.search(start)  # the step's start: the slip's reference, the roller where step 1 has it
    problem.set_step(1.0, steps[1].translation)
    problem.search(here, start=False)
    problem.set_step(1.0, steps[1].translation)
    _check_jacobians(problem, here)


def _check_jacobians(problem, here: fem.Function) -> None:
    """del_w f = A + Gamma T and del_w v = (dv/du~) T of ``problem`` (set at a step, its geometry
    searched at ``here``) against central differences of f and of the contact nodes' variables
    along three random directions, the geometry followed (:meth:`ContactProblem.follow`): the
    largest difference within :data:`BOUND` of the largest action. Destroys ``problem``."""
    comm, V = problem.comm, problem.V
    u = problem.A.createVecRight()
    problem.solver_variables(here, u)
    u.axpy(1.0, problem.shift)
    problem.tangent(u)
    forces, variables = problem.geometric_rows(u)
    gradient_f = problem.A.copy()
    gradient_f.axpy(1.0, forces, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    contact = (3 * problem.contact_blk[:, None] + np.arange(3)).ravel()
    free = np.ones(u.getLocalSize(), dtype=bool)
    free[problem.hyperelastic.prescribed] = False
    rng = np.random.default_rng(7 + comm.rank)
    scale = comm.allreduce(float(np.abs(here.x.array).max()), op=MPI.MAX)
    h = 1e-6 * scale

    def at(w: PETSc.Vec) -> tuple[np.ndarray, np.ndarray]:
        """f and the contact nodes' variables at u~ + T w, the geometry followed there."""
        moved = fem.Function(V)
        problem.to_global.mult(w, moved.x.petsc_vec)
        moved.x.scatter_forward()
        moved.x.array[:] += here.x.array
        problem_state = problem.current.displacement.x.array.copy()
        problem.follow(moved)
        trial = u.duplicate()
        problem.solver_variables(moved, trial)
        trial.axpy(1.0, problem.shift)
        f = u.duplicate()
        problem.residual(trial, f)
        values = f.array.copy(), trial.array[contact].copy()
        back = fem.Function(V)
        back.x.array[:] = problem_state
        problem.follow(back)
        for vec in (trial, f):
            vec.destroy()
        return values

    errors, sizes = np.zeros(2), np.zeros(2)
    for _ in range(3):
        direction = u.duplicate()
        direction.array[:] = rng.standard_normal(u.getLocalSize()) * free * scale
        plus, minus = direction.copy(), direction.copy()
        plus.scale(h / scale)
        minus.scale(-h / scale)
        f_plus, v_plus = at(plus)
        f_minus, v_minus = at(minus)
        predicted_f, predicted_v = u.duplicate(), u.duplicate()
        gradient_f.mult(direction, predicted_f)
        variables.mult(direction, predicted_v)
        difference_f = (f_plus - f_minus) / (2 * h / scale)
        difference_v = (v_plus - v_minus) / (2 * h / scale)
        for k, (predicted, difference) in enumerate(((predicted_f.array[free], difference_f[free]),
                                                     (predicted_v.array[contact], difference_v))):
            errors[k] = max(errors[k], np.abs(predicted - difference).max(initial=0.0))
            sizes[k] = max(sizes[k], np.abs(predicted).max(initial=0.0))
        for vec in (direction, plus, minus, predicted_f, predicted_v):
            vec.destroy()
    comm.Allreduce(MPI.IN_PLACE, errors, op=MPI.MAX)
    comm.Allreduce(MPI.IN_PLACE, sizes, op=MPI.MAX)
    for M in (forces, variables, gradient_f):
        M.destroy()
    u.destroy()
    problem.destroy()
    assert (sizes > 0).all()
    assert (errors <= BOUND * sizes).all(), errors / sizes


def test_newton_on_linear_bodies_is_named():
    """``search = "newton"`` between bodies of linear elasticity is an error naming the pair's key,
    raised while the problem is built, before any solve."""
    from contactqvi.parameters import ParameterError

    data = tomllib.loads((DATA / "stacked_30.toml").read_text())
    data["contacts"][0]["search"] = "newton"
    for body in data["bodies"]:
        del body["material"]["model"]
    with pytest.raises(ParameterError, match=r"^contacts\[0\]\.search: 'newton' takes the "
                       r"geometry of finite deformations into the Newton iteration and needs hyperelastic bodies"):
        build_problem(parse_case(data, DATA), MPI.COMM_WORLD)


def test_a_restarted_path_is_the_uninterrupted_one(mpi_tmp_path):
    """The 30 % compression searched ``"newton"``, its first five steps (to 25 %), stopped after
    step 3 and restarted: the pair forces and displacements of the uninterrupted run to 1e-12 on 1
    rank (measured 1e-14: the slip's reference and the predictor's increment come back from the
    checkpoint) and to 1e-11 on more, where two runs of the same steps differ by up to 1.3e-12 of
    the force already in step 1, before any restart (MUMPS schedules its parallel factorisation
    dynamically; one run in five, on the code before session 41 too). The Newton steps to one
    (equal in every run on 1 rank; on 2 ranks, under `make test` beside another job, the run
    stopped after step 3 once took 4 Newton steps in step 2 against 3: a second run of the same
    steps with MUMPS). Exact Newton steps (LU): a multigrid set up again at the restart, where the
    uninterrupted run carries its levels, changes the inexact directions at round-off; and the last
    step to 30 %, where the blocks' rims meet and the layout changes with round-off
    (docs/finite_strain.md Sect. 14), took 7 Newton steps against 5 in the restarted run even with
    LU."""
    from contactqvi.paraview import read_vtx
    from contactqvi.runner import run_case

    comm = MPI.COMM_WORLD
    data = tomllib.loads((DATA / "stacked_30.toml").read_text())
    data["contacts"][0]["search"] = "newton"
    data.setdefault("solver", {})["pc"] = "lu"
    data["steps"] = data["steps"][:5]
    case = parse_case(data, DATA)
    whole, parts = mpi_tmp_path / "whole", mpi_tmp_path / "parts"
    full, code = run_case(case, whole, comm, plot=False)
    assert code == 0
    run_case(case, parts, comm, plot=False, stop_after=3)
    continued, code = run_case(case, parts, comm, plot=False, restart=True)
    assert code == 0
    bound = 1e-12 if comm.size == 1 else 1e-11
    counts = np.array([[a["iterations"], b["iterations"]] for a, b in zip(full["steps"], continued["steps"])])
    assert np.abs(np.diff(counts, axis=1)).max() <= 1, counts  # on 2 ranks once 4 against 3 (step 2)
    for a, b in zip(full["steps"], continued["steps"]):
        (fa,), (fb,) = a["pair_forces"].values(), b["pair_forces"].values()
        assert np.abs(np.subtract(fa, fb)).max() <= bound * np.abs(fa).max(), (a["step"], fa, fb)
    difference = None
    if comm.rank == 0:
        last = len(full["steps"]) - 1
        difference = float(np.abs(read_vtx(whole / "body.bp", last).point_data["displacement [m]"]
                                  - read_vtx(parts / "body.bp", last).point_data["displacement [m]"]).max())
    assert comm.bcast(difference, root=0) <= bound
