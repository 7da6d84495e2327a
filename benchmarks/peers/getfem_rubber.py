"""GetFEM 5.4 on the rubber pad: finite-strain neo-Hookean body, large-sliding contact with a rigid roller.

    /usr/bin/python3 benchmarks/peers/getfem_rubber.py CASE.toml --output DIR \\
        [--r 6.0] [--release 2.5] [--frictionless] [--substeps 1] [--max-res 1e-8]

(``.venv/bin/python`` works too.) Reads a case file in the format of ``cases/rubber_pad.toml``
(one body, ``material.model = "neo_hookean"``, a rigid ``cylinder`` obstacle moved by the
steps' translations, rollers and a clamped group) and its ``.msh`` (:mod:`common`), and
solves each load step with ``Model.solve``. Writes the result files of :mod:`common`.

The model, and how it relates to ours (``docs/rubber_getfem.md``):

* Body: P1 tetrahedra on the nodes of the ``.msh``; ``add_finite_strain_elasticity_brick``
  with the law ``Compressible_Neo_Hookean_Bonet``, parameters ``[lambda; mu]``, whose
  energy in GetFEM 5.4 (``Neo_Hookean_hyperelastic_law::strain_energy``, bonet = true) is
  mu/2 (i1(C) - 3 - ln i3(C)) + lambda/8 (ln i3(C))^2 = mu/2 (tr C - 3) - mu ln J +
  lambda/2 (ln J)^2, ours (:class:`contactqvi.materials.NeoHookean`); the driver checks the
  two energies on the mesh for a random displacement (``law_check`` in ``result.json``).
  Volume integrals with ``IM_TETRAHEDRON(2)`` (4 points: our quadrature degree 2).
* Contact: ``add_integral_large_sliding_contact_brick_raytracing`` with one slave boundary
  (the case's contact surface, a P1 multiplier filtered on it: the contact stress per
  reference area) and the roller as a rigid obstacle of the brick, the level-set
  ``sqrt(sqr(x - a) + sqr(z - c)) - R`` of the current point (raytracing from the deformed
  surface, an integral Alart-Curnier formulation; Coulomb friction from the case,
  ``alpha`` = 1 and ``w`` = u of the step before: the slip of each step).
* Moving obstacle. The brick's obstacle is a fixed expression, and its friction term takes
  the obstacle at rest. So the problem is solved in the roller's frame: the obstacle stays
  where the case puts it at rest and the clamped group is moved by minus the step's
  translation (with the rollers, which prescribe components normal to the translation:
  the driver checks that); the solution differs from the case's by that rigid translation,
  which is removed before the results are written, and the forces are the same.
* Units: lengths in mm, stresses in MPa, forces in N (in SI units GetFEM's Newton stops
  early, ``/work/shared/DOLFINX-0.9-NOTES.md``); results are written in SI.

Forces: the contact force is the nodal internal force (the Bonet PK1 assembled with
``asm_generic``) summed over the contact surface's nodes, less the components prescribed
there (:func:`common.nodal_resultants`); ``contact_force_multipliers_per_step`` integrates the
brick's multiplier over the reference contact surface, as a check.
"""

from __future__ import annotations

import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402
import getfem_contact  # noqa: E402

import getfem as gf  # noqa: E402

#: Case units (m, Pa) -> driver units (mm, MPa): lengths * LENGTH, stresses / STRESS; forces in N.
LENGTH, STRESS = 1e3, 1e6
LAW = "Compressible_Neo_Hookean_Bonet"
#: First Piola-Kirchhoff stress of the law in GetFEM's language (F S with the law's PK2).
PK1 = f"((Id(3)+Grad_u)*{LAW}_PK2(Grad_u,[lambda;mu]))"
#: Our energy (docs/finite_strain.md) written out in GetFEM's language.
OUR_ENERGY = ("(mu/2*(Trace(Right_Cauchy_Green(Id(3)+Grad_u))-3)-mu*log(Det(Id(3)+Grad_u))"
              "+lambda/2*sqr(log(Det(Id(3)+Grad_u))))")


def cylinder_expression(case: common.Case) -> str:
    """Signed distance to the case's cylinder at rest (mm, positive outside) in GetFEM's language."""
    obstacle = case.obstacle
    if obstacle["type"] != "cylinder":
        raise NotImplementedError(f"obstacle type {obstacle['type']!r}: this driver takes a cylinder")
    axis = np.asarray(obstacle["axis"], float)
    axis /= np.linalg.norm(axis)
    if not np.allclose(np.abs(axis), [0.0, 1.0, 0.0]):
        raise NotImplementedError("this driver takes a cylinder whose axis is along y")
    a, _, c = (float(v) * LENGTH for v in obstacle["point"])
    return f"sqrt(sqr(x-({a!r}))+sqr(z-({c!r})))-({float(obstacle['radius']) * LENGTH!r})"


def main() -> int:
    parser = getfem_contact.command_line(__doc__.split("\n")[0])
    parser.set_defaults(max_res=1e-8)
    parser.add_argument("--r", type=float, default=None,
                        help="augmentation parameter of the brick (MPa/mm); default E/(1 mm)")
    parser.add_argument("--release", type=float, default=2.5,
                        help="release distance of the raytracing (mm); 5 mm (half the pad) stalls Newton at "
                             "step 4 of the coarse mesh")
    parser.add_argument("--contact-integration", default="IM_TETRAHEDRON(5)",
                        help="integration on the contact faces (the faces of this volume method)")
    parser.add_argument("--frictionless", action="store_true", help="ignore the case's friction")
    parser.add_argument("--substeps", type=int, default=1,
                        help="equal increments of the obstacle's translation per load step (forces at the step's end)")
    args = parser.parse_args()
    options = getfem_contact.set_up(args)
    case = common.load_case(args.case)
    mesh = common.read_msh(case.mesh)
    if mesh.cell_type != "tetrahedron":
        raise NotImplementedError("this driver takes tetrahedra")
    if case.traction or case.body_force is not None:
        raise NotImplementedError("this driver takes no tractions or body force")
    for name, components in case.displacement.items():
        for _, translation in case.steps:
            if any(abs(translation[c]) > 0 for c in components):
                raise ValueError(f"roller {name!r} prescribes a component of the obstacle's translation: "
                                 "the roller's frame would move it")
    friction = 0.0 if args.frictionless else case.friction

    points = mesh.points * LENGTH
    m = gf.Mesh("empty", 3)
    m.add_convex(gf.GeoTrans("GT_PK(3,1)"), np.transpose(points[mesh.cells], (2, 1, 0)))
    pid = np.asarray(m.pid_from_coords(points.T, 1e-9 * np.abs(points).max()), dtype=np.int64)
    if (pid < 0).any() or len(np.unique(pid)) != len(pid):
        raise RuntimeError("GetFEM merged or lost nodes of the mesh")
    region = getfem_contact.outer_face_regions(m, pid)

    regions = {}
    for number, name in enumerate(dict.fromkeys([*case.clamped, case.contact]), start=101):
        region(number, mesh.group_nodes(name))
        regions[name] = number
    contact_nodes = mesh.group_nodes(case.contact)

    mf_u = gf.MeshFem(m, 3)
    mf_u.set_classical_fem(1)
    mf_lambda = gf.MeshFem(m, 3)
    mf_lambda.set_classical_fem(1)
    mim = gf.MeshIm(m, gf.Integ("IM_TETRAHEDRON(2)"))
    mim_c = gf.MeshIm(m, gf.Integ(args.contact_integration))
    young, nu = case.young / STRESS, case.poisson
    lame_mu, lame_lambda = young / (2 * (1 + nu)), young * nu / ((1 + nu) * (1 - 2 * nu))

    # Our node i is GetFEM's fem node fem_node[i] (vector dofs 3 k, 3 k + 1, 3 k + 2).
    dof_nodes = mf_u.basic_dof_nodes()[:, ::3]
    dof_pid = np.asarray(m.pid_from_coords(dof_nodes, 1e-9 * np.abs(points).max()), dtype=np.int64)
    order = np.empty(len(points), dtype=np.int64)
    order[dof_pid] = np.arange(len(dof_pid))
    fem_node = order[pid]

    md = gf.Model("real")
    md.add_fem_variable("u", mf_u)
    md.add_initialized_data("lambda", [lame_lambda])
    md.add_initialized_data("mu", [lame_mu])
    law_check = _check_law(mim, mf_u, lame_lambda, lame_mu)
    md.add_finite_strain_elasticity_brick(mim, LAW, "u", "[lambda;mu]")
    fixed = mesh.clamped_nodes(case)
    md.add_initialized_data("clamped_motion", np.zeros(3))
    for name in case.clamped:
        md.add_Dirichlet_condition_with_simplification("u", regions[name], "clamped_motion")
    for name, components in case.displacement.items():  # rollers: nodal u . e_c = value
        nodes = mesh.roller_nodes(case, name)
        for c, value in components.items():
            md.add_initialized_data(f"pt_{name}_{c}", points[nodes].ravel())
            md.add_initialized_data(f"dir_{name}_{c}", np.tile(np.eye(3)[c], len(nodes)))
            md.add_initialized_data(f"val_{name}_{c}", np.full(len(nodes), value * LENGTH))
            md.add_pointwise_constraints_with_multipliers("u", f"pt_{name}_{c}", f"dir_{name}_{c}", f"val_{name}_{c}")

    md.add_filtered_fem_variable("lambda_c", mf_lambda, regions[case.contact])
    r = args.r if args.r is not None else young
    md.add_initialized_data("r", [r])
    md.add_initialized_data("friction", [friction])
    md.add_initialized_data("alpha", [1.0])
    w_name = ""
    if friction > 0:
        md.add_fem_data("w", mf_u)
        w_name = "w"
    brick = md.add_integral_large_sliding_contact_brick_raytracing("r", args.release, "friction", "alpha", 0)
    md.add_slave_contact_boundary_to_large_sliding_contact_brick(brick, mim_c, regions[case.contact], "u",
                                                                 "lambda_c", w_name)
    obstacle = cylinder_expression(case)
    md.add_rigid_obstacle_to_large_sliding_contact_brick(brick, obstacle, 3)

    def resultants(u: np.ndarray) -> tuple[list[float], dict[str, list[float]]]:
        """Contact force and reactions (N) from the nodal internal forces at ``u`` (mm)."""
        internal = gf.asm_generic(mim, 1, f"{PK1}:Grad_Test_u", -1, "u", 1, mf_u, u,
                                  "lambda", 0, [lame_lambda], "mu", 0, [lame_mu])
        return common.nodal_resultants(case, mesh, internal.reshape(-1, 3)[fem_node], contact_nodes)

    def multiplier_force() -> list[float]:
        """The brick's multiplier integrated over the reference contact surface (N)."""
        return [float(gf.asm_generic(mim_c, 0, f"lambda_c({i + 1})", regions[case.contact], md)) for i in range(3)]

    per_step, status, forces, multiplier_forces, history = [], "converged", [], [], []
    previous = previous_step = np.zeros(3)
    t0, c0 = time.perf_counter(), time.process_time()
    for load, translation in case.steps:
        ts, its = time.perf_counter(), 0
        for fraction in np.arange(1, args.substeps + 1) / args.substeps:
            target = previous_step + fraction * (translation - previous_step)
            shift = -(target - previous) * LENGTH  # the clamped group's motion in the roller's frame
            previous = target
            if w_name:
                md.set_variable("w", md.variable("u"))
            md.set_variable("clamped_motion", -target * LENGTH)
            md.set_variable("u", md.variable("u") + np.tile(shift, mf_u.nbdof() // 3))  # rigid predictor
            sub_its, converged = getfem_contact.newton(md, options, args.max_iter)
            its += sub_its
            if not converged:
                break
        previous_step = translation
        u = md.variable("u")
        per_step.append(its)
        force, reactions = resultants(u)
        forces.append(force)
        multiplier_forces.append(multiplier_force())
        history.append({"translation": translation.tolist(), "newton": its, "time": time.perf_counter() - ts,
                        "contact_force": force, "reactions": reactions,
                        "contact_force_multipliers": multiplier_forces[-1]})
        print(f"step {len(per_step)}: {its} Newton, F {np.array2string(np.asarray(force), precision=5)} N, "
              f"multipliers {np.array2string(np.asarray(multiplier_forces[-1]), precision=5)} N, "
              f"{history[-1]['time']:.2f} s", flush=True)
        if not converged:
            status = f"not converged in {args.max_iter} Newton iterations (step {len(per_step)})"
            break
    solve_time, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    wall_time = common.clock()
    peak = common.peak_memory_mib()
    u = md.variable("u").reshape(-1, 3)[fem_node] / LENGTH + previous  # back to the case's frame, m
    record = {
        "code": f"GetFEM 5.4.4 (large-sliding integral contact brick, raytracing, {LAW})",
        "case": str(case.path), "status": status,
        "dofs": 3 * len(points), "free_dofs": 3 * (len(points) - len(fixed)),
        "contact_nodes": len(contact_nodes), "unknowns": int(md.nbdof()),
        "newton_iterations": int(sum(per_step)), "newton_per_step": per_step,
        "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
        "contact_force": forces[-1], "contact_force_per_step": forces,
        "contact_force_multipliers_per_step": multiplier_forces,
        "reactions": history[-1]["reactions"], "steps": history, "law_check": law_check,
        "settings": {"lsolver": args.lsolver, "lsearch": args.lsearch, "max_res": args.max_res,
                     "max_iter": args.max_iter, "substeps": args.substeps, "r": r, "release_distance": args.release,
                     "friction": friction,
                     "units": "mm, MPa, N", "obstacle": obstacle, "law": LAW, "lambda": lame_lambda,
                     "mu": lame_mu, "integration": ["IM_TETRAHEDRON(2)", args.contact_integration]},
        "threads": args.threads,
    }
    common.write_result(args.output, record, mesh.points, u)
    print(f"getfem: {status}, {record['newton_iterations']} Newton {per_step}, {solve_time:.2f} s")
    return 0 if status == "converged" else 1


def _check_law(mim: gf.MeshIm, mf_u: gf.MeshFem, lame_lambda: float, lame_mu: float) -> dict[str, float]:
    """GetFEM's Bonet potential against our energy written out, both integrated over the mesh
    for a random displacement (gradients of order 0.1): their relative difference."""
    rng = np.random.default_rng(0)
    points = mf_u.basic_dof_nodes()
    size = float(np.ptp(points, axis=1).max())
    u = 0.01 * size * rng.uniform(-1.0, 1.0, mf_u.nbdof())
    data = ["u", 0, mf_u, u, "lambda", 0, [lame_lambda], "mu", 0, [lame_mu]]
    theirs = float(gf.asm_generic(mim, 0, f"{LAW}_potential(Grad_u,[lambda;mu])", -1, *data))
    ours = float(gf.asm_generic(mim, 0, OUR_ENERGY, -1, *data))
    return {"getfem_energy": theirs, "our_energy": ours, "relative_difference": abs(theirs - ours) / abs(ours)}


if __name__ == "__main__":
    sys.exit(main())
