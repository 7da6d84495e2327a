"""Every shipped case runs with the default solver: converged, in equilibrium, physically right
where that is cheap to check, and with its Newton counts per load step as a regression guard.

Each case file of ``cases/`` runs through :func:`contactqvi.case.load_case` and
:func:`contactqvi.runner.run_case` exactly as shipped, on its coarse mesh where it names a
larger one (:data:`COARSE`). No case may carry expert solver settings: they must all converge
with the defaults (issue 23). Two edge cases of the stopping test close the module: a first
load step in which nothing touches, and a contact surface far from the obstacle.
"""

from __future__ import annotations

import dataclasses
import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import ContactCase, PaperBody, load_case
from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.meshes import create_contact_body
from contactqvi.obstacles import Plane
from contactqvi.problems import coulomb as data
from contactqvi.problems import hertz
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent

#: The coarse variant of each case whose file names a larger mesh.
COARSE = {
    "hertz": "hertz_coarse.geo",
    "hertz_bodies": "hertz_bodies_coarse.geo",
    "cattaneo_mindlin": "mindlin_coarse.geo",
    "cattaneo_mindlin_nu045": "mindlin_coarse.geo",
    "paper_d3_L2": PaperBody(lev=3, geometry="d3"),
}

#: Regression guard, not a paper number: Newton steps per load step of each case (its coarse
#: variant) with the default solver, measured on 1 and 2 ranks (GAMG depends on the partition).
#: A change of these counts must be measured and explained.
NEWTON_STEPS = {
    "arch_block": {1: [10, 10, 9, 9], 2: None},
    "hertz_bodies": {1: [8, 11, 13, 10], 2: None},
    "patch_test": {1: [5], 2: None},
    "vice": {1: [9, 7], 2: None},
    "inclined_plane": {1: [18, 7, 6, 6], 2: None},
    "paper_d3_L2": {1: [8], 2: None},
    "hertz": {1: [6, 6, 6, 6], 2: None},
    "cattaneo_mindlin": {1: [8, 5, 4, 5, 4, 4, 5, 5, 4, 4, 4, 4, 4, 4, 4], 2: None},
    "cattaneo_mindlin_nu045": {1: [9, 6, 7, 6, 6, 7, 6, 5, 5, 6, 5, 6, 6, 6, 6], 2: None},
}


def _coarse(case: ContactCase, name: str) -> ContactCase:
    variant = COARSE.get(name)
    if isinstance(variant, PaperBody):
        return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, box=variant))
    if variant is not None:
        return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / variant))
    return case


@pytest.fixture(scope="module")
def summaries(tmp_path_factory) -> dict[str, dict]:
    """Summaries of every shipped case (coarse variant), each run once for the whole module."""
    comm = MPI.COMM_WORLD
    base = pathlib.Path(comm.bcast(str(tmp_path_factory.mktemp("shipped")) if comm.rank == 0 else None, root=0))
    runs = {}
    for path in sorted((ROOT / "cases").glob("*.toml")):
        summary, code = run_case(_coarse(load_case(path), path.stem), base / path.stem, comm, plot=False)
        runs[path.stem] = {"summary": summary, "code": code}
    comm.Barrier()
    return runs


def test_every_shipped_case_is_guarded():
    """A new case file needs its counts in NEWTON_STEPS (and its coarse mesh in COARSE)."""
    assert {path.stem for path in (ROOT / "cases").glob("*.toml")} == set(NEWTON_STEPS)


@pytest.mark.parametrize("name", sorted(NEWTON_STEPS))
def test_shipped_case_needs_no_expert_settings(name):
    """Only the initial guess (``start``) may be chosen; no solver parameter, no PETSc option."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    assert set(case.solver) <= {"start"} and case.petsc == {}


@pytest.mark.parametrize("name", sorted(NEWTON_STEPS))
def test_shipped_case_converges_in_equilibrium(summaries, name):
    """Every load step converges within 15 Newton steps but for the first step of the inclined
    plane (18), and the forces balance to 1e-7 of the largest: on one body reactions, applied
    load and contact force (the stopping test's floor, 1e-14 ||l||, is about 1e-8 of the Hertz
    contact force: its load in the shifted variables holds the gaps of metres of the far nodes);
    between bodies, whose contact forces are internal, reactions and applied load."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    steps = summaries[name]["summary"]["steps"]
    assert summaries[name]["code"] == 0 and len(steps) == len(case.steps)
    assert all(step["converged"] for step in steps)
    newton = [step["iterations"] for step in steps]
    assert max(newton[1:] + newton[:1] * (name != "inclined_plane"), default=0) <= 15, newton
    assert max(_imbalance(step, several_bodies=bool(case.bodies)) for step in steps) < IMBALANCE.get(name, 1e-7)


#: Force balance allowed where the reactions, not the solve, limit it: hertz_bodies lists a
#: reaction per support group, and the nodes on two groups (a symmetry plane and the ball's
#: loaded face) give the rollers z-components; their sum misses the load by 1.4e-4 (measured).
IMBALANCE = {"hertz_bodies": 1e-3}


def _imbalance(step: dict, several_bodies: bool) -> float:
    if not several_bodies:
        return step["equilibrium_error"]
    forces = np.array([step["applied_force"], *step["reaction_forces"].values()])
    return float(np.linalg.norm(forces.sum(axis=0)) / np.linalg.norm(forces, axis=1).max())


@pytest.mark.parametrize("name", sorted(NEWTON_STEPS))
def test_shipped_case_newton_counts_regression_guard(summaries, name):
    expected = NEWTON_STEPS[name].get(MPI.COMM_WORLD.size)
    if expected is None:
        pytest.skip(f"no counts recorded for {MPI.COMM_WORLD.size} ranks")
    assert [step["iterations"] for step in summaries[name]["summary"]["steps"]] == expected


def test_paper_case_within_the_paper_count(summaries):
    """Seed 000, Table 2, d3/L2 at lev 3: the paper needs 13 Newton steps from u0 = 0."""
    (step,) = summaries["paper_d3_L2"]["summary"]["steps"]
    assert step["iterations"] <= data.PAPER_TABLE2[3]["d3/L2"][0]


def test_hertz_case_meets_the_closed_form(summaries):
    """Rigid sphere pressed 1 mm into the quarter block (h = a/8): force, contact radius and peak
    pressure against Hertz at the last step, and P ~ delta^(3/2) along the path (within 4 %)."""
    case = load_case(ROOT / "cases" / "hertz.toml")
    E, nu, R = case.material.young, case.material.poisson, case.obstacle.radius
    steps = summaries["hertz"]["summary"]["steps"]
    depths = np.array([-step.translation[2] for step in case.steps])
    forces = np.array([4 * abs(step["contact_force"][2]) for step in steps])
    delta, a = depths[-1], hertz.contact_radius(R, depths[-1])
    assert forces[-1] == pytest.approx(hertz.contact_force(E, nu, R, delta), rel=0.07)
    assert abs(np.sqrt(4 * steps[-1]["contact_area"] / np.pi) - a) <= 0.5 * a / 8
    assert steps[-1]["max_contact_pressure"] == pytest.approx(hertz.peak_pressure(E, nu, R, delta), rel=0.10)
    assert np.allclose(forces / forces[-1], (depths / delta) ** 1.5, rtol=0.04)


@pytest.mark.parametrize("name", ["cattaneo_mindlin", "cattaneo_mindlin_nu045"])
def test_mindlin_case_follows_the_coulomb_bound(summaries, name):
    """Moved tangentially at constant depth, the tangential force grows at every step and stays
    within the Coulomb bound mu P; the sticking area shrinks; at nu = 0.45 (Dundurs beta =
    0.09, nearly the uncoupled problem of the closed forms) Q follows Mindlin's law within
    0.05 mu P on the coarse mesh (0.037 measured; 0.011 on the medium mesh,
    benchmarks/results/cattaneo_mindlin.md)."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    mu, E, nu = case.contact.friction, case.material.young, case.material.poisson
    steps = summaries[name]["summary"]["steps"]
    P = 2 * abs(steps[0]["contact_force"][2])
    a = np.sqrt(2 * steps[0]["contact_area"] / np.pi)
    s = np.array([step.translation[0] for step in case.steps[1:]])
    Q = np.array([2 * abs(step["contact_force"][0]) for step in steps[1:]])
    normal = np.array([2 * abs(step["contact_force"][2]) for step in steps[1:]])
    sticking = np.array([step["sticking_area"] for step in steps[1:]])
    assert np.all(np.diff(Q) > 0) and np.all(Q <= mu * normal * (1 + 1e-9))
    assert np.all(np.diff(sticking) <= 0) and sticking[0] > 0
    if nu == 0.45:
        mindlin = hertz.mindlin_force(s, mu, P, hertz.shear_modulus(E, nu), nu, a)
        assert np.abs(Q - mindlin).max() <= 0.05 * mu * P


def _paper_body(comm: MPI.Comm, lev: int, obstacle: Plane | None = None):
    msh, tags = create_contact_body(comm, lev, data.gap_function("d1"))
    return build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L1"), data.FRICTION,
                                 obstacle=obstacle)


def test_first_step_in_which_nothing_touches():
    """The foundation moved 5 cm away and nothing loaded: from rest the residual is round-off of
    A d - l (about 0.3 eps ||l||), which meets the floor 1e-14 ||l|| at once; the loaded step that
    follows (foundation back in place) converges as usual."""
    problem = _paper_body(MPI.COMM_WORLD, 3)
    u = problem.A.createVecRight()
    steps = [LoadStep(0.0, (0.0, 0.0, -0.05)), LoadStep(1.0)]
    results = solve_load_path(problem, steps, u, {}, prefix="shipped_edge_", from_rest=True)
    assert all(r.converged for r in results)
    assert results[0].iterations <= 1 and results[0].states.max(initial=0) == 0  # no contact node touches
    assert results[1].iterations <= data.PAPER_TABLE2[3]["d1/L1"][0]
    u.destroy()
    problem.destroy()


def test_contact_surface_far_from_the_obstacle():
    """The paper's loaded body with the foundation 100 m below: a linear elastic problem whose
    residual from rest (2e8 N) the shifted load ||l|| (gaps of 100 m) dwarfs. Relative to the
    start alone it stalled at the round-off floor (100 Newton steps); with the floor the
    inexact Newton steps (GAMG, tol 0.1, then Eisenstat-Walker) converge in 4."""
    problem = _paper_body(MPI.COMM_WORLD, 3, Plane((0.0, 0.0, -100.0), (0.0, 0.0, 1.0)))
    u = problem.A.createVecRight()
    (result,) = solve_load_path(problem, [LoadStep()], u, {}, prefix="shipped_far_", from_rest=True)
    assert result.converged and result.iterations <= 4
    assert result.states.max(initial=0) == 0
    u.destroy()
    problem.destroy()
