"""Every shipped case runs with the default solver: converged, in equilibrium, physically right
where that is cheap to check, and with its Newton counts per load step as a regression guard.

Each case file of ``cases/`` runs through :func:`contactqvi.case.load_case` and
:func:`contactqvi.runner.run_case` as shipped, or as its coarse variant where it names a
larger mesh (:data:`shipped_runs.COARSE`), each run once for the session. No case may carry expert solver settings: they must all
converge with the defaults (issue 23). Two edge cases of the stopping test close the module: a first
load step in which nothing touches, and a contact surface far from the obstacle.
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import load_case
from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.contact.nodal import State
from contactqvi.laws import Coulomb
from contactqvi.meshes import create_contact_body
from contactqvi.obstacles import Plane
from contactqvi.problems import coulomb as data
from contactqvi.problems import hertz, press_fit
from output_files import read_vtx
from shipped_runs import group, of_case, shipped_case

ROOT = pathlib.Path(__file__).resolve().parent.parent

#: Regression guard, not a paper number: Newton steps per load step of each case (its
#: variant) with the default solver, measured on 1 and 2 ranks (GAMG depends on the
#: partition). A change of these counts must be measured and explained: searching the body
#: pairs again before every load step (in the configuration of the step before) changed
#: hertz_bodies 1 rank [8, 8, 8, 9] -> [8, 8, 8, 10] and vice [9, 7] -> [9, 8] on 1 and 2 ranks;
#: gamma_rule auto taking nodal_diagonal above a diagonal span of 8 (was 100) changed
#: arch_block [10, 10, 9, 9] / [11, 10, 8, 8], cattaneo_mindlin_bodies [25, 8, 8],
#: hertz_bodies [8, 8, 8, 10] / [7, 8, 9, 9] and vice [9, 8] to [10, 8, 8, 9] / [10, 8, 8, 8],
#: [10, 7, 7], [7, 7, 7, 8] / [7, 7, 7, 6] and [8, 7]; dropping the mortar pairs that do not
#: overlap (zero entries of C and of A, which GAMG aggregated across) changed
#: cattaneo_mindlin_bodies [10, 7, 7] -> [11, 7, 7] on 1 rank, hertz_bodies -> [7, 7, 7, 7]
#: on 1 and 2 ranks and vice [8, 7] -> [8, 8] on 2 ranks; the lean multigrid set-up
#: (multigrid.set_up: products cleared, PETSc's "backend" PtAP on several processes, which
#: sums the coarse operators in another order) moved the 2-rank counts by up to 1 per step;
#: the multigrid levels of several bodies set up once per load path (on A) and kept across
#: the searches changed hertz_bodies [5, 6, 7, 7] / [6, 5, 5, 5] -> [5, 7, 7, 7] / [6, 6, 6, 6],
#: vice [8, 7] -> [8, 8] on 1 rank and cattaneo_mindlin_bodies [9, 7, 6] -> [9, 6, 6] on 2;
#: the preconditioner of a hyperelastic body set up once per solve and lagged within it
#: (scd_newton.SCDNewtonSolver.linearise; before: at every Newton step) changed rubber_pad
#: [11, 15, 15, 14, 15, 15, 20, 22] / [11, 15, 13, 14, 14, 15, 20, 20] to
#: [11, 15, 15, 14, 14, 15, 20, 22] / [11, 15, 15, 14, 14, 15, 20, 21] (Krylov 697 / 702 in
#: all); the ironing cases' first steps are unchanged.
#: The cases of shipped_runs.TWINS run on one rank only (their 2-rank counts were
#: cattaneo_mindlin_bodies [9, 6, 6], cattaneo_mindlin_nu045 [10, 6, 7, 6, 7, 7, 6, 6, 7, 6, 6,
#: 6, 5, 6, 6] and shallow_ironing_frictional [16]).
#: The Mindlin paths run every other step since issue 35 (shipped_runs.COARSE); on all 15 steps
#: they took cattaneo_mindlin [8, 5, 4, 5, 4, 4, 5, 5, 4, 4, 4, 4, 4, 4, 4] / [8, 5, 5, 5, 5, 4, 5,
#: 4, 4, 5, 4, 4, 4, 4, 4] and cattaneo_mindlin_nu045 [9, 6, 7, 6, 6, 7, 6, 5, 5, 6, 5, 6, 6, 6, 6].
#: The stopping floor's share floor gamma max|u| at the contact rows (scd_newton.stopping_target,
#: session 27) ends cattaneo_mindlin_nu045's second step one Newton step earlier, on round-off:
#: [9, 7, 7, 6, 7, 6, 7, 6] became [9, 6, 7, 6, 7, 6, 7, 6]; every other count is unchanged.
#: The first step from rest of a hyperelastic body starting from the tangent's response at rest
#: (load_path._add_elastic_change, session 33) changed shallow_ironing [14] / [14] to [13] / [13]
#: and shallow_ironing_frictional [16] to [17]; the rubber pad, pressed by a moving obstacle
#: alone, starts at rest as before.
#: The rubber pad's roller searched inside the Newton iteration (search = "newton", session 37;
#: docs/finite_strain.md Sect. 18) instead of until each step settles: [11, 15, 15, 14, 14, 15, 20,
#: 22] / [11, 15, 15, 14, 14, 15, 20, 21] became [7, 8, 9, 10, 10, 12, 13, 14] / [7, 8, 10, 10, 11,
#: 12, 13, 14], the forces the same to 4e-6 (until_settled's geometry_tol); with the exact values of
#: the prescribed rows in its Newton steps (scd_newton.SCDNewtonSolver.newton_system) [4, 5, 5, 4, 4,
#: 4, 4, 4] / [4, 5, 5, 4, 4, 4, 4, 4]. The same exact rows in every hyperelastic Newton step
#: changed shallow_ironing [13] / [13] to [12] / [12]. The ironing cases searched "newton" instead of
#: until settled (session 45; docs/finite_strain.md Sect. 21): shallow_ironing [12] / [12] as before,
#: shallow_ironing_frictional [17] to [18]. The slave facets covered in part taking the dual basis of
#: their covered part in the pairs searched "newton" and "until_settled" (session 47; docs/finite_strain.md
#: Sect. 22) changed shallow_ironing [12] / [12] to [12] / [11], shallow_ironing_frictional [18] to [15],
#: sliding_blocks [11, 14, 13, 14, 14, 14, 13, 5] / [11, 14, 13, 13, 14, 12, 13, 5] to
#: [11, 13, 13, 14, 14, 14, 13, 5] / [11, 13, 13, 13, 14, 13, 13, 5] and twisted_fit [16, 14, 10] to
#: [17, 11, 10]. A clipping edge that leaves a segment whole where the master's vertices lie within
#: round-off outside it (segments.CLIP_BAND, session 49; docs/finite_strain.md Sect. 22) changed
#: shallow_ironing_frictional [15] to [14] and sliding_blocks [11, 13, 13, 14, 14, 14, 13, 5] /
#: [11, 13, 13, 13, 14, 13, 13, 5] to [12, 13, 14, 13, 14, 14, 13, 5] / [11, 13, 13, 13, 14, 12, 12, 5].
#: The covered part's basis for every slave facet short of whole cover (not within 1e-9 of it; session
#: 50, covered.covered_basis) changed sliding_blocks to [11, 13, 14, 14, 14, 14, 13, 5] /
#: [11, 13, 13, 13, 12, 12, 13, 5].
NEWTON_STEPS = {
    "arch_block": {1: [10, 8, 8, 9], 2: [10, 8, 7, 7]},
    "cattaneo_mindlin": {1: [8, 5, 5, 5, 5, 5, 4, 4], 2: [8, 6, 5, 5, 5, 5, 5, 4]},
    "cattaneo_mindlin_bodies": {1: [8, 7, 6]},
    "cattaneo_mindlin_nu045": {1: [9, 6, 7, 6, 7, 6, 7, 6]},
    "hertz": {1: [6, 6, 6, 6], 2: [6, 6, 6, 7]},
    "hertz_bodies": {1: [5, 7, 7, 7], 2: [6, 6, 6, 6]},
    "hex_patch": {1: [5], 2: [5]},
    "inclined_plane": {1: [18, 7, 6, 6], 2: [18, 7, 6, 6]},
    "paper_d3_L2": {1: [8], 2: [9]},
    "patch_test": {1: [5], 2: [5]},
    "press_fit": {1: [5], 2: [5]},
    "push_out": {1: [9, 7, 7, 6, 6], 2: [9, 7, 6, 6, 6]},
    "rubber_pad": {1: [4, 5, 5, 4, 4, 4, 4, 4], 2: [4, 5, 5, 4, 4, 4, 4, 4]},
    "shallow_ironing": {1: [12], 2: [11]},
    "shallow_ironing_frictional": {1: [14]},
    "shrink_fit": {1: [5], 2: [4]},
    "sliding_blocks": {1: [11, 13, 14, 14, 14, 14, 13, 5], 2: [11, 13, 13, 13, 12, 12, 13, 5]},
    "twisted_fit": {1: [17, 11, 10]},
    "vice": {1: [8, 8], 2: [8, 7]},
}

#: The same guard for the cases with ``[dynamics]`` (a Newton count per time step is one of
#: dozens): the Newton steps of the implicit steps (3.3) and of the projections (3.2) of
#: docs/dynamics.md summed over the run, with the default solver. Session 27: the stopping
#: floor's gamma max|u| (scd_newton.stopping_target), the projection's prescribed rows given
#: their node's mass and its Newton steps by GMRES + Jacobi (``pc = "jacobi"``) changed
#: bars_impact (198, 168) / (156, 168), drop_test (83, 108) / (83, 106) and sliding_block
#: (261, 0) / (249, 0) to the counts below; session 39 the Krylov tolerance of frictional time steps
#: (dynamics.STEP_TOL) sliding_block's (181, 0) / (182, 0); session 41 y^ without the cancellation of
#: u and d^ and the free block's translation held apart (docs/dynamics.md Sect. 5) bars_impact's
#: (199, 168) / (158, 168), drop_test's (83, 83) / (83, 83) and sliding_block's (114, 0) / (118, 0):
#: the block's steps and projections now resolve what the travel hid. The clipping band
#: (segments.CLIP_BAND, session 49) changed bars_impact's 2-rank count (158, 169) to (156, 169), the
#: covered part's basis for every slave facet short of whole cover (session 50) sliding_block's
#: (122, 19) to (123, 19) on 1 rank.
DYNAMIC_NEWTON_STEPS = {
    "bars_impact": {1: (199, 169), 2: (156, 169)},
    "drop_test": {1: (83, 79), 2: (83, 79)},
    "sliding_block": {1: (123, 19), 2: (126, 21)},
}

#: Newton steps allowed per load step: 15 for the Hertz case (issue 23), 25 for any other (a
#: step searched until it settles counts the Newton steps of all its solves: the rubber pad's
#: three or four solves of 3-8 Newton steps at finite strain).
MAX_NEWTON = {"hertz": 15}

#: Force balance allowed (``equilibrium_error``, and each body's): 1e-7, and for the Hertz case
#: ten times its stopping test's floor, 1e-14 ||l|| = 1e-2 N (the load in the shifted variables
#: holds the gaps of metres of the far nodes), 9.4e-8 of its contact force: a step that stops just
#: below the floor balances to 1.6e-7 (the coarse variant on 3 ranks, step 1: ||y^|| 1.3e-2 N; on 1
#: and 2 ranks 1.7e-8 ... 8.3e-8). The two-body cases balance to 1e-10 since the
#: prescribed values are taken exactly and the contact forces on prescribed master components
#: go to the supports (before: 2e-4 - 1.1e-3).
IMBALANCE = {"hertz": 1e-6}


@pytest.mark.one_rank(reason="case-file contents, no run")
def test_every_shipped_case_is_guarded():
    """A new case file needs its counts in NEWTON_STEPS (and its variant in shipped_runs.COARSE)."""
    assert {path.stem for path in (ROOT / "cases").glob("*.toml")} == set(NEWTON_STEPS) | set(DYNAMIC_NEWTON_STEPS)
    assert all(load_case(ROOT / "cases" / f"{name}.toml").dynamics is not None for name in DYNAMIC_NEWTON_STEPS)


@pytest.mark.one_rank(reason="case-file contents, no run")
@pytest.mark.parametrize("name", sorted(NEWTON_STEPS | DYNAMIC_NEWTON_STEPS))
def test_shipped_case_needs_no_expert_settings(name):
    """Only the initial guess (``start``) and how closely the contact geometry is followed
    (``geometry_tol``, the user's accuracy of a large-sliding path, as Code_Aster's
    RESI_GEOM) may be chosen; no solver parameter, no PETSc option."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    assert set(case.solver) <= {"start", "geometry_tol"} and case.petsc == {}


@pytest.mark.parametrize("name", of_case(*sorted(NEWTON_STEPS)))
def test_shipped_case_converges_in_equilibrium(shipped_runs, name):
    """Every load step of the variant converges within its Newton budget, and the forces
    balance: reactions, applied load and the obstacles' contact forces, and each body's with the
    contact forces between bodies (:data:`IMBALANCE`)."""
    steps = shipped_runs.steps(name)
    assert len(steps) == len(shipped_case(name).steps)
    assert all(step["converged"] for step in steps)
    assert max(step["iterations"] for step in steps) <= MAX_NEWTON.get(name, 25)
    imbalance = IMBALANCE.get(name, 1e-7)
    assert max(step["equilibrium_error"] for step in steps) < imbalance
    assert all(error < imbalance for step in steps for error in step.get("body_equilibrium_errors", {}).values())


@pytest.mark.parametrize("name", of_case(*sorted(NEWTON_STEPS)))
def test_shipped_case_newton_counts_regression_guard(shipped_runs, name):
    """Newton steps per load step as recorded in :data:`NEWTON_STEPS` (ours, not the paper's)."""
    expected = NEWTON_STEPS[name].get(MPI.COMM_WORLD.size)
    if expected is None:
        pytest.skip(f"no counts recorded for {MPI.COMM_WORLD.size} ranks")
    assert [step["iterations"] for step in shipped_runs.steps(name)] == expected


@pytest.mark.parametrize("name", of_case(*sorted(DYNAMIC_NEWTON_STEPS)))
def test_dynamic_case_runs_with_its_energy_balanced(shipped_runs, name):
    """Every time step of a case with ``[dynamics]`` converges, the energy balance (4.1) of
    docs/dynamics.md closes to 1e-7 of the energy at time 0 (measured: 3e-11 bars, 2e-10 drop,
    3e-8 the block, Coulomb's stopping test), and its ``body.bp`` holds every time step and its
    ``energy.png`` is drawn. The Newton counts as in :data:`DYNAMIC_NEWTON_STEPS`."""
    case, run = shipped_case(name), shipped_runs[name]
    steps = shipped_runs.steps(name)
    assert len(steps) == case.dynamics.steps and steps[-1]["time"] == pytest.approx(case.dynamics.end, rel=1e-3)
    initial = run["summary"]["steps"][0]["energy"]["kinetic"] + abs(run["summary"]["steps"][0]["energy"]["external_work"])
    assert max(abs(step["energy"]["balance_error"]) for step in steps) < 1e-7 * initial
    if MPI.COMM_WORLD.rank == 0:
        assert (run["output"] / "energy.png").stat().st_size > 0
        body = read_vtx(run["output"] / "body.bp", -1)
        assert {"displacement [m]", "velocity [m/s]", "acceleration [m/s^2]"} <= set(body.point_data)
    expected = DYNAMIC_NEWTON_STEPS[name].get(MPI.COMM_WORLD.size)
    if expected is not None:
        assert (sum(step["iterations"] for step in steps), sum(step["predictor"]["iterations"] for step in steps)) \
            == expected


@group("drop_test")
def test_drop_test_meets_hertz(shipped_runs):
    """The ball's impact against Hertz's t_c = 522.7 us and F_max = 230.1 kN (cases/drop_test.toml):
    the contact duration to a step (dt = t_c / 20; measured 0.950 t_c), the peak step-mean force
    within 5 % (measured +3.6 %; 2 % on a 1 mm mesh, docs/dynamics.md), and the ball leaves the
    plane at 0.997 of its speed (the energy left in its vibration)."""
    steps = shipped_runs.steps("drop_test")
    t_c, f_max, dt = 522.7e-6, 230.1e3, shipped_case("drop_test").dynamics.dt
    touching = [step["time"] for step in steps if step["contact_force"][2] > 0.0]
    assert abs(touching[-1] - touching[0] + dt - t_c) <= 1.05 * dt
    assert 4 * max(step["contact_force"][2] for step in steps) == pytest.approx(f_max, rel=0.05)
    assert steps[-1]["body_velocity"]["body"][2] == pytest.approx(1.0, rel=0.01)


@group("bars_impact")
def test_bars_exchange_their_velocities(shipped_runs):
    """cases/bars_impact.toml: the contact lasts 2L/c to a step, the velocities are exchanged
    within 6 % (measured -0.948 / +0.948 m/s; docs/dynamics.md Sect. 5 for finer meshes)."""
    steps = shipped_runs.steps("bars_impact")
    dt = shipped_case("bars_impact").dynamics.dt
    touching = [step["time"] for step in steps if step["contact_area"] > 0.0]
    assert abs(touching[-1] - touching[0] + dt - 40 * dt) <= 1.05 * dt
    assert steps[-1]["body_velocity"]["left"][0] == pytest.approx(-1.0, rel=0.06)
    assert steps[-1]["body_velocity"]["right"][0] == pytest.approx(1.0, rel=0.06)


@group("sliding_block")
def test_sliding_block_stops_at_the_coulomb_distance(shipped_runs):
    """cases/sliding_block.toml: the block stops after v^2 / (2 mu g) = 0.16989 m (within 0.1 %),
    having dissipated its kinetic energy, 7.8 J, in friction (within 0.1 %)."""
    steps = shipped_runs.steps("sliding_block")
    mu, g, v = 0.3, 9.81, 1.0
    assert steps[-1]["body_displacement"]["body"][0] == pytest.approx(v**2 / (2 * mu * g), rel=1e-3)
    assert steps[-1]["energy"]["friction_dissipation"] == pytest.approx(7800.0 * 0.002 * v**2 / 2, rel=1e-3)


@group("paper_d3_L2")
def test_paper_case_within_the_paper_count(shipped_runs):
    """Seed 000, Table 2, d3/L2 at lev 3: the paper needs 13 Newton steps from u0 = 0."""
    (step,) = shipped_runs.steps("paper_d3_L2")
    assert step["iterations"] <= data.PAPER_TABLE2[3]["d3/L2"][0]


@group("hertz")
def test_hertz_case_meets_the_closed_form(shipped_runs):
    """Rigid sphere pressed 1 mm into the quarter block (h = a/8): force, contact radius and peak
    pressure against Hertz at the last step, and P ~ delta^(3/2) along the path (within 4 %)."""
    case = load_case(ROOT / "cases" / "hertz.toml")
    E, nu, R = case.material.young, case.material.poisson, case.obstacle.radius
    steps = shipped_runs.steps("hertz")
    depths = np.array([-step.translation[2] for step in case.steps])
    forces = np.array([4 * abs(step["contact_force"][2]) for step in steps])
    delta, a = depths[-1], hertz.contact_radius(R, depths[-1])
    assert forces[-1] == pytest.approx(hertz.contact_force(E, nu, R, delta), rel=0.07)
    assert abs(np.sqrt(4 * steps[-1]["contact_area"] / np.pi) - a) <= 0.5 * a / 8
    assert steps[-1]["max_contact_pressure"] == pytest.approx(hertz.peak_pressure(E, nu, R, delta), rel=0.10)
    assert np.allclose(forces / forces[-1], (depths / delta) ** 1.5, rtol=0.04)


def _fit_force(shipped_runs, name: str) -> tuple[dict, list[float], float]:
    """The one step of the fit ``name`` (the quarter slice of b = 20 mm, c = 40 mm, t = 2 mm), the
    pin's force on the ring (N) and Lamé's p b t."""
    case = load_case(ROOT / "cases" / f"{name}.toml")
    (pin, ring), pair = case.bodies, case.contacts[0]
    materials = [(body.material.young, body.material.poisson) for body in (pin, ring)]
    b, c, t = 0.02, 0.04, 0.002
    (step,) = shipped_runs.steps(name)
    return step, step["pair_forces"][f"{pair.slave}/{pair.master}"], press_fit.contact_pressure(
        pair.interference, b, c, *materials) * b * t


@group("shrink_fit")
def test_shrink_fit_case_meets_lame(shipped_runs):
    """The steel pin 0.1 mm oversize in the aluminium ring: the pin's force on the quarter ring
    is p b t along x and along y, p Lamé's pressure, within 1 % (measured +0.02 %)."""
    _, force, expected = _fit_force(shipped_runs, "shrink_fit")
    assert force[:2] == pytest.approx([expected, expected], rel=0.01)


@group("press_fit")
def test_press_fit_case_on_curved_tetrahedra_meets_lame(shipped_runs):
    """The steel pin 15 um oversize in the steel ring, meshed in unstructured second-order
    tetrahedra: the pin's force on the quarter ring is p b t along x and along y within 1 % of
    Lamé's p (measured +0.19 %; the same mesh in first order: +26 %), no slave node is open and
    no warning says the fit is off (docs/press_fit.md, "Curved contact surfaces")."""
    step, force, expected = _fit_force(shipped_runs, "press_fit")
    assert force[:2] == pytest.approx([expected, expected], rel=0.01)
    assert step["state_counts"]["no contact"] == 0
    assert not shipped_runs["press_fit"]["summary"]["warnings"]


@pytest.mark.parametrize("name", of_case("cattaneo_mindlin", "cattaneo_mindlin_nu045"))
def test_mindlin_case_follows_the_coulomb_bound(shipped_runs, name):
    """Moved tangentially at constant depth, the tangential force grows at every step and stays
    within the Coulomb bound mu P; the sticking area shrinks; at nu = 0.45 (Dundurs beta =
    0.09, nearly the uncoupled problem of the closed forms) Q follows Mindlin's law within
    0.05 mu P on the coarse mesh (0.037 measured; 0.011 on the medium mesh,
    benchmarks/results/cattaneo_mindlin.md)."""
    case = shipped_case(name)
    mu, E, nu = case.contact.law.friction, case.material.young, case.material.poisson
    steps = shipped_runs.steps(name)
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


@group("sliding_blocks")
def test_sliding_case_slides_at_the_coulomb_bound(shipped_runs):
    """The slider of ``sliding_blocks``, searched until settled: in every sliding step the
    friction force is F times the normal force, against the slide (within 0.1 %: the nodes at
    its trailing edge stick), each step searched at least twice; held, the force stays."""
    case = load_case(ROOT / "cases" / "sliding_blocks.toml")
    friction = case.contacts[0].law.friction
    steps = shipped_runs.steps("sliding_blocks")
    forces = np.array([step["pair_forces"]["upper.interface/lower.interface"] for step in steps])
    sliding = [k for k in range(1, len(steps)) if case.steps[k].translation != case.steps[k - 1].translation]
    assert sliding == list(range(1, 7))
    ratio = -forces[sliding, 0] / forces[sliding, 2]
    assert np.all(ratio <= friction * (1 + 1e-9)) and np.all(ratio >= 0.999 * friction), ratio
    assert all(max(entry["search"] for entry in steps[k]["history"]) >= 1 for k in sliding)
    assert np.abs(forces[-1] - forces[-2]).max() <= 1e-4 * forces[-1, 2]


def _touching(comm: MPI.Comm, result) -> int:
    """Number of contact nodes in any state but no contact."""
    return comm.allreduce(int(np.count_nonzero(result.states != State.NO_CONTACT)), op=MPI.SUM)


def _paper_body(comm: MPI.Comm, lev: int, obstacle: Plane | None = None):
    msh, tags = create_contact_body(comm, lev, data.gap_function("d1"))
    return build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions("L1"), Coulomb(data.FRICTION),
                                 obstacle=obstacle)


def test_first_step_in_which_nothing_touches():
    """The foundation moved 5 cm away and nothing loaded: from rest the residual is round-off of
    A d - l (about 0.3 eps ||l||), which meets the floor 1e-14 ||l|| at once; the loaded step that
    follows (foundation back in place) converges as usual."""
    comm = MPI.COMM_WORLD
    problem = _paper_body(comm, 3)
    u = problem.A.createVecRight()
    steps = [LoadStep(0.0, (0.0, 0.0, -0.05)), LoadStep(1.0)]
    results = solve_load_path(problem, steps, u, {}, prefix="shipped_edge_", from_rest=True)
    assert all(r.converged for r in results)
    assert results[0].iterations <= 1 and _touching(comm, results[0]) == 0
    assert results[1].iterations <= data.PAPER_TABLE2[3]["d1/L1"][0]
    u.destroy()
    problem.destroy()


def test_contact_surface_far_from_the_obstacle():
    """The paper's loaded body with the foundation 100 m below: a linear elastic problem whose
    residual from rest (2e8 N) the shifted load ||l|| (gaps of 100 m) dwarfs. Relative to the
    start alone it stalled at the round-off floor (100 Newton steps); with the floor the
    inexact Newton steps (GAMG, tol 0.1, then Eisenstat-Walker) converge in 4."""
    comm = MPI.COMM_WORLD
    problem = _paper_body(comm, 3, Plane((0.0, 0.0, -100.0), (0.0, 0.0, 1.0)))
    u = problem.A.createVecRight()
    (result,) = solve_load_path(problem, [LoadStep()], u, {}, prefix="shipped_far_", from_rest=True)
    assert result.converged and result.iterations <= 4 and _touching(comm, result) == 0
    u.destroy()
    problem.destroy()
