"""The SCD semismooth* Newton method for a nonlinear f (issue 36, the core): 0 in f(u) + Q(u)
with f the residual of a hyperelastic body (:mod:`contactqvi.contact.hyperelastic`).

A block on a frictionless rigid plane, rollers on two lateral faces, its top face pushed
down by 30 % of its height in ten load steps, the other faces free: the deformation is
homogeneous uniaxial stress, F = diag(a, a, s) with s = 0.7 and the lateral stretch a
from zero lateral stress, which trilinear hexahedra represent exactly. Closed forms
(docs/finite_strain.md):

* neo-Hookean, P = mu (F - F^-T) + lambda ln J F^-T: mu (a^2 - 1) + lambda ln(a^2 s) = 0,
  P33 = mu (s - 1/s) + lambda ln(a^2 s) / s;
* Saint Venant-Kirchhoff, S = lambda tr E I + 2 mu E: E11 = -lambda E33 / (2 (lambda + mu)),
  P33 = s (lambda (2 E11 + E33) + 2 mu E33).

The displacement must equal u = ((a - 1) x, (a - 1) y, (s - 1) z) to 1e-8 of its size and
the contact pressure must be uniform and equal to -P33 to 1e-8, in every step.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
import scipy.optimize


from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.elasticity import lame_parameters
from contactqvi.laws import Frictionless
from contactqvi.materials import NeoHookean, SaintVenantKirchhoff
from contactqvi.meshes import create_contact_body
from contactqvi.problems.uniaxial import uniaxial_stress

YOUNG, POISSON = 10e6, 0.3  # Pa, a compressible rubber-like solid
COMPRESSION = 0.3  # of the height 1 m
STEPS = 10
MU, LMBDA = lame_parameters(YOUNG, POISSON)


def neo_hookean(s: float) -> tuple[float, float]:
    """Lateral stretch a and axial nominal stress P33 (Pa) of uniaxial stress at axial stretch s."""
    return uniaxial_stress(s, YOUNG, POISSON)


def saint_venant_kirchhoff(s: float) -> tuple[float, float]:
    e3 = (s * s - 1.0) / 2.0
    e1 = -LMBDA * e3 / (2.0 * (LMBDA + MU))
    return np.sqrt(1.0 + 2.0 * e1), s * (LMBDA * (2.0 * e1 + e3) + 2.0 * MU * e3)


CLOSED_FORMS = {"neo_hookean": (NeoHookean(), neo_hookean), "saint_venant_kirchhoff": (SaintVenantKirchhoff(),
                                                                                       saint_venant_kirchhoff)}


def _compressed_block(material, compression: float, steps: int, lev: int = 1,
                      parameters: dict | None = None, search: str = "once",
                      loads: list[float] | None = None) -> list[dict]:
    """Solve the compression in ``steps`` equal load steps (or to the load factors ``loads``); per
    step the displacement, the contact nodes' coordinates, pressures, the Newton count and the
    result (failed steps too)."""
    comm = MPI.COMM_WORLD
    msh, tags = create_contact_body(comm, lev, lambda x, y: np.zeros_like(x), length=1.0, width=1.0, height=1.0)
    problem = build_contact_problem(msh, tags, YOUNG, POISSON, {}, Frictionless(), clamped=(), contact="contact",
                                    displacements={"dirichlet": {0: 0.0}, "front": {1: 0.0},
                                                   "top": {2: -compression}}, material=material, search=search)
    rows = []

    def record(index, step, u, result, state):
        x = problem.V.tabulate_dof_coordinates()[: problem.V.dofmap.index_map.size_local]
        rows.append({"load": step.load, "x": x, "u": state.displacement.x.array.reshape(-1, 3)[: len(x)].copy(),
                     "pressure": result.normal_force / problem.contact_area, "iterations": result.iterations,
                     "result": result})

    with problem:
        u = problem.A.createVecRight()
        loads = loads or [(k + 1) / steps for k in range(steps)]
        solve_load_path(problem, [LoadStep(load) for load in loads], u,
                        {"pc": "lu", **(parameters or {})}, on_step=record, from_rest=True)
        u.destroy()
    return rows


@pytest.mark.parametrize("name", CLOSED_FORMS)
def test_uniaxial_compression_on_a_rigid_plane_is_the_closed_form(name):
    material, closed_form = CLOSED_FORMS[name]
    comm = MPI.COMM_WORLD
    for row in _compressed_block(material, COMPRESSION, STEPS):
        assert row["result"].converged, row["result"].status
        s = 1.0 - COMPRESSION * row["load"]
        a, P33 = closed_form(s)
        exact = row["x"] * np.array([a - 1.0, a - 1.0, s - 1.0])
        error = comm.allreduce(float(np.abs(row["u"] - exact).max(initial=0.0)), op=MPI.MAX)
        assert error <= 1e-8 * (1.0 - s), (row["load"], error)
        p = row["pressure"]
        spread = comm.allreduce(float(np.abs(p + P33).max(initial=0.0)), op=MPI.MAX)
        assert spread <= 1e-8 * abs(P33), (row["load"], spread, P33)
        assert row["iterations"] <= 8, row


def test_a_searched_obstacle_gives_the_cauchy_pressure():
    """Searched until settled, the obstacle's nodal areas are those of the deformed surface
    (Nanson), so the contact pressure is the Cauchy traction -P33 / a^2 (uniform to 1e-8);
    searched once it is the nominal -P33 (the test above)."""
    comm = MPI.COMM_WORLD
    rows = _compressed_block(NeoHookean(), COMPRESSION, 3, search="until_settled")
    for row in rows:
        a, P33 = neo_hookean(1.0 - COMPRESSION * row["load"])
        spread = comm.allreduce(float(np.abs(row["pressure"] + P33 / a**2).max(initial=0.0)), op=MPI.MAX)
        assert spread <= 1e-8 * abs(P33), (row["load"], spread)


def test_a_hyperelastic_body_at_small_strain_is_the_linear_one():
    """At 1e-4 compression the neo-Hookean and the linear solution agree to O(strain)."""
    comm = MPI.COMM_WORLD
    (neo,), (linear,) = (_compressed_block(m, 1e-4, 1) for m in (NeoHookean(), None))
    size = comm.allreduce(float(np.abs(linear["u"]).max(initial=0.0)), op=MPI.MAX)
    difference = comm.allreduce(float(np.abs(neo["u"] - linear["u"]).max(initial=0.0)), op=MPI.MAX)
    assert difference <= 1e-3 * size, difference / size


def test_a_case_file_with_a_hyperelastic_material(mpi_tmp_path):
    """``[material] model = "neo_hookean"``: the paper's box (2 x 1 x 0.99 m above a gap of
    1 cm) pushed down 0.3 m onto the foundation: at the end uniaxial stress with s = 0.7/0.99;
    the top's reaction is P33 times its area, the largest von Mises stress the Cauchy
    stress |P33| / a^2, and the summary's equilibrium holds."""
    from contactqvi.case import parse_case
    from contactqvi.runner import run_case

    case = parse_case({
        "mesh": {"box": {"lev": 1, "geometry": "d1"}},
        "material": {"young": YOUNG, "poisson": POISSON, "model": "neo_hookean"},
        "boundary": {"displacement": {"dirichlet": {"x": 0.0}, "front": {"y": 0.0}, "top": {"z": -COMPRESSION}}},
        "contact": {"surface": "contact", "law": "frictionless"},
        "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]},
        "steps": [{"load": (k + 1) / STEPS} for k in range(STEPS)],
        "solver": {"pc": "lu"},
    })
    summary, code = run_case(case, mpi_tmp_path / "out", plot=False)
    assert code == 0, summary["status"]
    a, P33 = neo_hookean((1.0 - COMPRESSION) / 0.99)
    last = summary["steps"][-1]
    assert abs(last["reaction_forces"]["top"][2] - 2.0 * P33) <= 1e-8 * abs(2.0 * P33)
    assert abs(last["contact_force"][2] + 2.0 * P33) <= 1e-8 * abs(2.0 * P33)
    assert abs(last["max_von_mises"] - abs(P33) / a**2) <= 1e-8 * abs(P33)
    assert last["equilibrium_error"] <= 1e-10


def test_bad_material_models_are_named_errors():
    from contactqvi.case import parse_case
    from contactqvi.parameters import ParameterError

    base = {"mesh": {"box": {"lev": 1, "geometry": "d1"}}, "boundary": {"clamped": ["dirichlet"]},
            "contact": {"surface": "contact", "law": "frictionless"}, "steps": [{"load": 1.0}],
            "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}}
    with pytest.raises(ParameterError, match=r"material\.model: .*neo_hookean"):
        parse_case({**base, "material": {"young": YOUNG, "poisson": POISSON, "model": "neo_hooke"}})


def test_a_frictional_finite_strain_path_is_in_balance_and_restarts_exactly(mpi_tmp_path):
    """A neo-Hookean box clamped at one end, pressed and sheared onto the foundation with
    Coulomb friction (not homogeneous): every step in balance (reactions from the nonlinear
    residual, integrated as the solver's), and stopped after step 3 and restarted, the
    uninterrupted run's counts and solution (the path state carries a finite-strain run too)."""
    import json

    from contactqvi.case import parse_case
    from contactqvi.runner import run_case

    case = parse_case({
        "mesh": {"box": {"lev": 1, "geometry": "d3"}},
        "material": {"young": YOUNG, "poisson": POISSON, "model": "neo_hookean"},
        "boundary": {"clamped": ["dirichlet"], "traction": {"top": [2e5, 0.0, -1e6]}},
        "contact": {"surface": "contact", "law": "coulomb", "friction": 0.3},
        "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]},
        "steps": [{"load": (k + 1) / 6} for k in range(6)], "solver": {"pc": "lu"},
    })
    whole, code = run_case(case, mpi_tmp_path / "whole", plot=False)
    assert code == 0 and max(step["equilibrium_error"] for step in whole["steps"]) <= 1e-10
    force = np.array(whole["steps"][-1]["contact_force"])
    assert 0.05 * force[2] < np.hypot(*force[:2]) <= 0.3 * force[2]  # sheared, within the friction cone
    run_case(case, mpi_tmp_path / "restarted", plot=False, stop_after=3)
    restarted, code = run_case(case, mpi_tmp_path / "restarted", plot=False, restart=True)
    assert code == 0
    counts = [[(s["iterations"], s["inner_iterations"]) for s in r["steps"]] for r in (whole, restarted)]
    assert counts[0] == counts[1]
    if MPI.COMM_WORLD.rank == 0:
        ua, ub = (np.load(mpi_tmp_path / d / "solution.npz")["u"] for d in ("whole", "restarted"))
        assert np.abs(ua - ub).max() <= 1e-12 * np.abs(ua).max()
    assert json.loads((mpi_tmp_path / "restarted" / "summary.json").read_text())["restarts"][0]["after_step"] == 3


def _closed_form_error(row: dict, compression: float) -> float:
    """Largest distance of a compressed block's displacement from the neo-Hookean closed form."""
    a, _ = neo_hookean(1.0 - compression)
    exact = row["x"] * np.array([a - 1.0, a - 1.0, -compression])
    return MPI.COMM_WORLD.allreduce(float(np.abs(row["u"] - exact).max()), op=MPI.MAX)


def test_a_step_whose_predictor_inverts_elements_starts_from_the_elastic_response():
    """From 1 % to half the height (and to 70 %) in one step: the predictor (the prescribed top moved
    at once) inverts the top cells, so the step starts from the small-strain stiffness's response to
    its change instead (load_path._add_elastic_change) and converges uncut to the closed form
    (measured: 4 and 5 Newton steps; before, the step was cut)."""
    for compression in (0.5, 0.7):
        _, row = _compressed_block(NeoHookean(), compression, 2, loads=[0.02, 1.0])
        result = row["result"]
        assert result.converged and all("substep" not in entry for entry in result.history), result.status
        assert row["iterations"] <= 8, row["iterations"]
        assert _closed_form_error(row, compression) <= 1e-8 * compression


def test_a_step_that_fails_is_cut_until_it_converges():
    """From 1 % to 95 % of the height in one step with at most 4 Newton steps per solve: the step
    fails, is halved and grows back until it ends at the closed form. With no halving allowed (and
    no relaxation) the path stops, reported as not converged. (From the tangent's response at the
    last step, load_path._tangent_change, 1 % to 80 % converges in 4 Newton steps uncut.)"""
    parameters = {"max_iterations": 4, "limit_points": "stop"}
    _, row = _compressed_block(NeoHookean(), 0.95, 2, parameters=parameters, loads=[0.01 / 0.95, 1.0])
    result = row["result"]
    assert result.converged, result.status
    attempts = {(entry["substep"], entry["substep_load"], entry["substep_status"]) for entry in result.history}
    assert (0, 1.0, "diverged_max_it") in attempts and len(attempts) > 2
    assert _closed_form_error(row, 0.95) <= 1e-8 * 0.95
    *_, row = _compressed_block(NeoHookean(), 0.95, 2, parameters={**parameters, "max_cuts": 0},
                                loads=[0.01 / 0.95, 1.0])
    assert not row["result"].converged


def test_half_the_height_from_rest_in_one_step():
    """The first step from rest starts from the tangent's response at rest (load_path._add_elastic_change),
    not from the prescribed top moved alone: half the height in one step converges uncut to the
    closed form (with the top moved alone it inverted the top cells and was cut three times).
    Measured: 4 Newton steps on 1, 2, 3 and 4 ranks (6, 6, 9 and 7 while the bottom nodes that touch
    the plane were told by the sign of their round-off gaps, load_path.GAP_ROUNDOFF)."""
    (row,) = _compressed_block(NeoHookean(), 0.5, 1, parameters={"max_iterations": 20, "max_cuts": 0})
    assert row["result"].converged, row["result"].status
    assert _closed_form_error(row, 0.5) <= 1e-8 * 0.5
    assert row["iterations"] <= 8, row["iterations"]


def _indented_by_a_sphere(search: str, parameters: dict) -> list[tuple[float, float]]:
    """A neo-Hookean unit cube, top clamped, indented from below by a rigid sphere (R = 1 m)
    in four steps of 5 cm: per step the largest distance of a touching node of the deformed
    surface from the sphere, the contact force, the largest difference of a touching node's
    normal from the sphere's and the Newton steps."""
    from contactqvi.obstacles import Sphere

    comm = MPI.COMM_WORLD
    msh, tags = create_contact_body(comm, 2, lambda x, y: np.zeros_like(x), length=1.0, width=1.0, height=1.0)
    sphere = Sphere((0.5, 0.5, -1.0), 1.0)
    problem = build_contact_problem(msh, tags, YOUNG, POISSON, {}, Frictionless(), clamped=("top",),
                                    contact="contact", obstacle=sphere, material=NeoHookean(), search=search)
    rows = []

    def record(index, step, u, result, state):
        assert result.converged, result.status
        blk = problem.contact_blk
        x = problem.V.tabulate_dof_coordinates()[blk] + state.displacement.x.array.reshape(-1, 3)[blk]
        distance, normal = sphere.translated(np.asarray(step.translation)).distance(x)
        touching = result.normal_force > 0
        off = float(np.abs(distance[touching]).max(initial=0.0))
        tilt = float(np.abs(problem.frames[touching, 2] - normal[touching]).max(initial=0.0))
        rows.append((comm.allreduce(off, op=MPI.MAX), comm.allreduce(float(result.normal_force.sum()), op=MPI.SUM),
                     comm.allreduce(tilt, op=MPI.MAX), result.iterations))

    with problem:
        u = problem.A.createVecRight()
        steps = [LoadStep(1.0, (0.0, 0.0, 0.05 * (k + 1))) for k in range(4)]
        solve_load_path(problem, steps, u, {"pc": "lu", **parameters}, on_step=record, from_rest=True)
        u.destroy()
    return rows


def test_contact_with_a_curved_obstacle_in_the_current_configuration():
    """Searched until settled (the sphere's gaps and normals found again at x + u, the step
    solved again until it settles), the touching nodes of the deformed body lie on the
    sphere to 1e-9 m at 20 % indentation, and their normals are those of the sphere where it
    has moved to, to 1e-6 (they were the sphere's at rest, up to 0.2 off, which tilted a
    rubber pad's frictionless roller force by 4.7 %); with the reference configuration's gap
    g + n . u (``once``) the nodes are millimetres off (2.7 mm measured), and the force
    differs by 1 %."""
    settled = _indented_by_a_sphere("until_settled", {"geometry_tol": 1e-7})
    once = _indented_by_a_sphere("once", {})
    assert max(row[0] for row in settled) <= 1e-9, settled
    assert max(row[2] for row in settled) <= 1e-6, settled
    assert once[-1][0] >= 1e-3, once
    assert 0.005 <= settled[-1][1] / once[-1][1] - 1.0 <= 0.02, (settled[-1], once[-1])


def test_a_curved_obstacle_searched_inside_the_newton_iteration():
    """``search = "newton"`` (docs/finite_strain.md Sect. 18): the same indentation with the
    sphere's gaps, normals and frames taken at every iterate, their curvature in the Newton
    matrix. The touching nodes lie on the sphere to 1e-12 m and their normals are the sphere's
    to 1e-12 (measured 2.2e-16 m and 1.7e-16; until settled to geometry_tol 1e-7: 2.2e-16 m and
    4.5e-9), the force that of the settled run to 1e-6 (measured 3.2e-10), and exact Newton steps
    converge quadratically: at most 6 a step (measured 4, 4, 4, 5; until settled 9, 12, 12, 15)."""
    settled = _indented_by_a_sphere("until_settled", {"geometry_tol": 1e-7})
    newton = _indented_by_a_sphere("newton", {})
    assert max(row[0] for row in newton) <= 1e-12, newton
    assert max(row[2] for row in newton) <= 1e-12, newton
    assert all(abs(a[1] / b[1] - 1.0) <= 1e-6 for a, b in zip(newton, settled)), (newton, settled)
    assert max(row[3] for row in newton) <= 6, newton


@pytest.mark.parametrize("model", [None, "neo_hookean"])
def test_a_pressure_on_a_block_on_the_foundation(model, mpi_tmp_path):
    """``[boundary.pressure] top = p``: a block on the frictionless foundation (rollers on two
    sides) under a pressure on its top. Linear: the dead traction -p N, a force p A on the
    foundation. Neo-Hookean: the pressure follows the deformed top, whose area grows by a^2
    (Nanson), so P33 = -p a^2 at the axial stretch s where the closed form's P33(s) equals
    it; the top sinks by (1 - s) H and the foundation carries p a^2 A, balanced to 1e-10."""
    from contactqvi.case import parse_case
    from contactqvi.runner import run_case

    p = 2e6  # Pa, about 20 % compression of the neo-Hookean block
    material = {"young": YOUNG, "poisson": POISSON, **({} if model is None else {"model": model})}
    case = parse_case({
        "mesh": {"box": {"lev": 1, "geometry": "d1"}},
        "material": material,
        "boundary": {"displacement": {"dirichlet": {"x": 0.0}, "front": {"y": 0.0}}, "pressure": {"top": p}},
        "contact": {"surface": "contact", "law": "frictionless"},
        "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.01], "normal": [0.0, 0.0, 1.0]},
        "steps": [{"load": (k + 1) / 4} for k in range(4)],
        "solver": {"pc": "lu"},
    })
    summary, code = run_case(case, mpi_tmp_path / "out", plot=False)
    assert code == 0, summary["status"]
    last = summary["steps"][-1]
    area = 2.0  # the box's top: 2 m x 1 m
    if model is None:
        expected = p * area
    else:
        s = scipy.optimize.brentq(lambda s: neo_hookean(s)[1] + p * neo_hookean(s)[0] ** 2, 0.3, 1.0, xtol=1e-15)
        expected = p * neo_hookean(s)[0] ** 2 * area
    assert abs(last["contact_force"][2] - expected) <= 1e-8 * expected, (last["contact_force"], expected)
    assert last["equilibrium_error"] <= 1e-10
