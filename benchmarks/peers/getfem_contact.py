"""GetFEM 5.4 on a peer-benchmark case: nodal rigid-obstacle contact with Coulomb friction.

    /usr/bin/python3 benchmarks/peers/getfem_contact.py CASE.toml --output DIR \\
        [--lsolver mumps|superlu|gmres/ilu] [--max-res 1e-10] [--r 1.0] [--option 1]

(``.venv/bin/python`` works too: it sees Debian's ``python3-getfem``.) Reads the case file
and its ``.msh`` (:mod:`common`), builds the model and solves each load step with
``Model.solve`` (GetFEM's generalized Newton on the Alart-Curnier system, line search
'default'), then writes the result files of :mod:`common`.

The discretisation is ours: Q1 hexahedra / P1 tetrahedra, the stiffness integrated with the
quadrature DOLFINx uses (hexahedra: 3 Gauss points per direction, faces 4; tetrahedra: exact),
and ``add_nodal_contact_with_rigid_obstacle_brick`` (``--option 1``: non-symmetric
Alart-Curnier), whose conditions are nodal: u_n <= gap at each contact node and the nodal
friction force within F times the nodal normal force, for the obstacle's signed distance
and normal at the node in the reference configuration. That is the discrete problem (6.3) of
seed 000 that contactqvi solves, so the solutions must agree to round-off (checked by
``peers_real.py``).

Pitfalls, and how this driver handles them:

* Units. In SI units GetFEM's Newton stops after one iteration at a wrong answer: its
  residual test adds force residuals (N, ~1e9) and contact-equation residuals; stresses are
  scaled to GPa here (``STRESS_UNIT``): E, tractions in GPa, forces in GN; lengths in m.
* Clamped contact nodes. A node both clamped and on the contact surface makes the nodal brick
  singular (its contact rows act on eliminated dofs). The brick's region is the contact faces
  that touch no clamped node; the driver checks that its nodes are exactly the contact nodes
  minus the clamped ones (contactqvi's contact nodes) and stops otherwise.
* Regions. GetFEM 5.4 numbers the regions of an imported gmsh file by elementary entity tags,
  not physical group tags; the regions are built here from the physical groups' nodes
  (:func:`common.read_msh`) with ``Mesh.faces_from_pid`` on the outer faces.
* Load steps. The obstacle of the nodal brick is a fixed expression: each step replaces the
  brick (same multipliers, warm start). The rigid brick's friction acts on the total tangential
  displacement; ours on the slip since the step before, relative to the obstacle (seed 000,
  (6.3) with d_t of the previous step). The basic brick has that form: its tangential
  condition is on B_T (u + gamma w_t) (the sign as GetFEM 5.4 assembles it,
  ``getfem_contact_and_friction_nodal.cc``), and with gamma = -1 and w_t = u of the step
  before plus the obstacle's translation since it, it is our incremental condition (checked:
  three steps of Cattaneo-Mindlin agree with ours to 6e-9). So a frictional case with several
  steps gets the basic brick (``--brick auto``); the rigid brick refuses it.

Contact force and reactions are K u - f summed over the contact and clamped nodes (K, f
assembled by GetFEM, ``asm_generic``); ``contact_force_multipliers`` is the sum of the brick's
own multipliers along the obstacle normal, as a check.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time
import typing

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402

import getfem as gf  # noqa: E402

#: Stresses in GPa (see the module docstring): E, tractions / STRESS_UNIT; forces * STRESS_UNIT.
STRESS_UNIT = 1e9

#: Quadrature that DOLFINx 0.9 picks for our forms (estimated degrees 5 and 7 on hexahedra).
INTEGRATION = {
    "hexahedron": ("IM_GAUSS_PARALLELEPIPED(3,5)", "IM_GAUSS_PARALLELEPIPED(3,7)"),
    "tetrahedron": ("IM_TETRAHEDRON(1)", "IM_TETRAHEDRON(2)"),
}


def obstacle_expression(case: common.Case, translation: np.ndarray) -> str:
    """Signed distance to the obstacle (positive on the body's side) in GetFEM's syntax."""
    kind = case.obstacle["type"]
    if kind == "plane":
        n = np.asarray(case.obstacle["normal"], float)
        n = n / np.linalg.norm(n)
        p = np.asarray(case.obstacle["point"], float) + translation
        return "+".join(f"({c}-({float(pc)!r}))*({float(nc)!r})" for c, pc, nc in zip("xyz", p, n))
    if kind == "sphere":
        c = np.asarray(case.obstacle["center"], float) + translation
        squares = "+".join(f"sqr({v}-({float(cv)!r}))" for v, cv in zip("xyz", c))
        return f"sqrt({squares})-({float(case.obstacle['radius'])!r})"
    raise NotImplementedError(kind)


def _tangents(normal: np.ndarray) -> np.ndarray:
    """(m, 2, 3) orthonormal tangent pairs of the unit normals (m, 3)."""
    helper = np.where(np.abs(normal[:, [0]]) < 0.9, np.eye(3)[0], np.eye(3)[1])
    t1 = np.cross(normal, helper)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return np.stack([t1, np.cross(normal, t1)], axis=1)


def command_line(description: str) -> argparse.ArgumentParser:
    """The command line the GetFEM drivers share: case, output and GetFEM's Newton settings."""
    parser = argparse.ArgumentParser(description=description, formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("case")
    parser.add_argument("--output", required=True)
    parser.add_argument("--lsolver", default="mumps", help="GetFEM linear solver: mumps, gmres/ilu, ...")
    parser.add_argument("--lsearch", default="default", help="GetFEM line search: default, simplest, basic, ...")
    parser.add_argument("--max-res", type=float, default=1e-10, help="Newton stops at this residual (GPa units)")
    parser.add_argument("--max-iter", type=int, default=100)
    parser.add_argument("--option", type=int, default=1, help="augmented_version of the brick (1: non-symmetric AC)")
    parser.add_argument("--noisy", action="store_true")
    parser.add_argument("--threads", type=int, default=1, help="GetFEM threads (gf.util_set_num_threads)")
    return parser


def set_up(args: argparse.Namespace) -> list:
    """Threads and messages of GetFEM as ``args`` ask; the options of ``Model.solve``."""
    gf.util_set_num_threads(args.threads)
    gf.util_trace_level(2 if args.noisy else 0)
    gf.util_warning_level(2 if args.noisy else 0)
    options = ["max_res", args.max_res, "max_iter", args.max_iter, "lsolver", args.lsolver, "lsearch", args.lsearch]
    return options + (["noisy"] if args.noisy else [])


def newton(md: gf.Model, options: list, max_iter: int) -> tuple[int, bool]:
    """``Model.solve``: its Newton iterations and whether it converged."""
    iterations = md.solve(*options)
    its = int(np.ravel(iterations)[0])
    return its, bool(np.ravel(iterations)[1]) if np.size(iterations) > 1 else its < max_iter


def outer_face_regions(m: gf.Mesh, pid: np.ndarray) -> typing.Callable[[int, np.ndarray], None]:
    """``region(rnum, nodes)``: make GetFEM region ``rnum`` of the outer faces of ``m`` whose
    vertices are all in ``nodes`` (our node indices; our node i is GetFEM point ``pid[i]``)."""
    outer = m.outer_faces()
    outer_keys = set(zip(outer[0].tolist(), outer[1].tolist()))

    def region(rnum: int, nodes: np.ndarray) -> None:
        faces = np.asarray(m.faces_from_pid(pid[nodes]))
        keep = [i for i, key in enumerate(zip(faces[0].tolist(), faces[1].tolist())) if key in outer_keys]
        m.set_region(rnum, faces[:, keep])

    return region


def main() -> int:
    parser = command_line(__doc__.split("\n")[0])
    parser.add_argument("--r", type=float, default=None,
                        help="Alart-Curnier augmentation r (GPa); default E (GetFEM's advice)")
    parser.add_argument("--brick", default="auto", choices=["auto", "rigid", "basic"],
                        help="rigid: add_nodal_contact_with_rigid_obstacle_brick; basic: add_basic_contact_brick "
                             "with BN, BT from the exact obstacle normal; auto: rigid for a plane, basic otherwise")
    args = parser.parse_args()
    options = set_up(args)
    case = common.load_case(args.case)
    mesh = common.read_msh(case.mesh)
    m = gf.Mesh("import", "gmsh", str(case.mesh))
    # Our node i is GetFEM point pid[i] (the import keeps gmsh's numbering; checked, not assumed).
    pts = m.pts().T
    pid = np.arange(len(pts)) if np.array_equal(pts, mesh.points) else np.asarray(
        m.pid_from_coords(mesh.points.T, 1e-12 * np.abs(mesh.points).max()), dtype=np.int64)
    region = outer_face_regions(m, pid)

    fixed = mesh.clamped_nodes(case)
    regions = {}
    for number, name in enumerate(dict.fromkeys([*case.clamped, *case.traction, *case.displacement]), start=101):
        region(number, mesh.group_nodes(name))
        regions[name] = number
    # The contact region: contact faces that touch no clamped node (pitfall 2).
    contact_faces = mesh.faces[case.contact]
    free_faces = contact_faces[~np.isin(contact_faces, fixed).any(axis=1)]
    contact_nodes = np.setdiff1d(mesh.group_nodes(case.contact), fixed)
    if not np.array_equal(np.unique(free_faces), contact_nodes):
        raise RuntimeError("a contact node lies only on faces that touch a clamped node: "
                           "the nodal brick's region cannot exclude the clamped nodes alone")
    contact_region = 200
    region(contact_region, np.unique(free_faces))

    mf_u = gf.MeshFem(m, 3)
    mf_u.set_classical_fem(1)
    volume, boundary = INTEGRATION[mesh.cell_type]
    mim = gf.MeshIm(m, gf.Integ(volume))
    mim_b = gf.MeshIm(m, gf.Integ(boundary))
    young = case.young / STRESS_UNIT
    nu = case.poisson
    md = gf.Model("real")
    md.add_fem_variable("u", mf_u)
    md.add_initialized_data("lambda", [young * nu / ((1 + nu) * (1 - 2 * nu))])
    md.add_initialized_data("mu", [young / (2 * (1 + nu))])
    md.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
    load_bricks = {}
    for name, traction in case.traction.items():
        md.add_initialized_data(f"t_{name}", traction / STRESS_UNIT)
        load_bricks[name] = md.add_source_term_brick(mim_b, "u", f"t_{name}", regions[name])
    if case.body_force is not None:
        md.add_initialized_data("body_force", case.body_force / STRESS_UNIT)
        md.add_source_term_brick(mim, "u", "body_force")
    for name in case.clamped:
        md.add_Dirichlet_condition_with_simplification("u", regions[name])
    for name, components in case.displacement.items():  # rollers: nodal u . e_c = value
        nodes = mesh.roller_nodes(case, name)
        for c, value in components.items():
            md.add_initialized_data(f"pt_{name}_{c}", mesh.points[nodes].ravel())
            md.add_initialized_data(f"dir_{name}_{c}", np.tile(np.eye(3)[c], len(nodes)))
            md.add_initialized_data(f"val_{name}_{c}", np.full(len(nodes), value))
            md.add_pointwise_constraints_with_multipliers("u", f"pt_{name}_{c}", f"dir_{name}_{c}", f"val_{name}_{c}")

    n_contact = len(mf_u.basic_dof_on_region(contact_region)) // 3
    assert n_contact == len(contact_nodes), (n_contact, len(contact_nodes))
    md.add_variable("lambda_n", n_contact)
    frictional = case.friction > 0
    if frictional:
        md.add_variable("lambda_t", 2 * n_contact)
        md.add_initialized_data("friction", [case.friction])
    r = args.r if args.r is not None else young
    md.add_initialized_data("r", [r])
    # The rigid brick takes the normal by finite differences (step 1e-3 x cell radius) of the moved
    # obstacle's distance: exact for a plane only; a sphere gets the basic brick with our normals.
    path_dependent = frictional and len(case.steps) > 1
    brick = args.brick if args.brick != "auto" else (
        "rigid" if case.obstacle["type"] == "plane" and not path_dependent else "basic")
    if brick == "rigid" and path_dependent:
        raise ValueError("--brick rigid: its friction acts on the total tangential displacement, not on the "
                         "slip of each load step; use --brick basic for a frictional load path")
    # GetFEM's vector dofs: node k of the fem has dofs 3 k, 3 k + 1, 3 k + 2 (checked: basic_dof_nodes).
    dof_nodes = mf_u.basic_dof_nodes()[:, ::3].T
    dof_pid = np.asarray(m.pid_from_coords(dof_nodes.T, 1e-12 * np.abs(mesh.points).max()), dtype=np.int64)
    order = np.empty(len(pts), dtype=np.int64)
    order[dof_pid] = np.arange(len(dof_pid))
    fem_node = order[pid]  # our node -> GetFEM's fem node
    if brick == "basic":
        # The rigid brick's matrices, with the exact normal: BN u <= gap, BN = -n^T (n into the body),
        # BT an orthonormal tangent basis, alpha = (mass matrix diagonal on the region) / (mesh size l).
        contact_fem = np.sort(fem_node[contact_nodes])  # the rigid brick's order: increasing dof
        contact_ours = contact_nodes[np.argsort(fem_node[contact_nodes])]
        mass = gf.asm_mass_matrix(mim_b, mf_u, mf_u, contact_region)
        extent = float(np.ptp(mesh.points, axis=0).max())
        alpha = np.array([mass[3 * k, 3 * k] for k in contact_fem]) / extent
        md.add_initialized_data("alpha", alpha)
        md.add_initialized_data("gap", np.zeros(n_contact))
        if frictional:  # the slip of a step: B_T (u + gamma w_t), gamma = -1, w_t = u before + translation since
            md.add_initialized_data("gamma", [-1.0])
            md.add_initialized_data("wt", np.zeros(mf_u.nbdof()))

    def add_contact(translation: np.ndarray) -> int:
        if brick == "rigid":
            obstacle = obstacle_expression(case, translation)
            if frictional:
                return md.add_nodal_contact_with_rigid_obstacle_brick(
                    mim_b, "u", "lambda_n", "lambda_t", "r", "friction", contact_region, obstacle, args.option)
            return md.add_nodal_contact_with_rigid_obstacle_brick(mim_b, "u", "lambda_n", "r", contact_region,
                                                                   obstacle, args.option)
        # As contactqvi: the gap to the moved obstacle, the normal of the obstacle at rest
        # (frames fixed in the reference configuration, contactqvi.obstacles).
        gap = case.obstacle_distance(mesh.points[contact_ours], translation)[0]
        normal = case.obstacle_distance(mesh.points[contact_ours], np.zeros(3))[1]
        md.set_variable("gap", gap)
        BN = gf.Spmat("empty", n_contact, mf_u.nbdof())
        BT = gf.Spmat("empty", 2 * n_contact, mf_u.nbdof())
        tangents = _tangents(normal)
        for j, k in enumerate(contact_fem):
            dofs = np.arange(3 * k, 3 * k + 3)
            BN.add([j], dofs, -normal[j][None, :])
            BT.add([2 * j, 2 * j + 1], dofs, tangents[j])
        if frictional:
            return md.add_basic_contact_brick("u", "lambda_n", "lambda_t", "r", BN, BT, "friction", "gap", "alpha",
                                              args.option, "gamma", "wt")
        return md.add_basic_contact_brick("u", "lambda_n", "r", BN, "gap", "alpha", args.option)

    per_step, status = [], "converged"
    contact_brick, previous, solutions = None, np.zeros(3), []
    t0, c0 = time.perf_counter(), time.process_time()
    for load, translation in case.steps:
        for name, brick_data in case.traction.items():
            md.set_variable(f"t_{name}", load * brick_data / STRESS_UNIT)
        if brick == "basic" and frictional:
            md.set_variable("wt", md.variable("u") + np.tile(translation - previous, mf_u.nbdof() // 3))
        previous = translation
        if contact_brick is not None:
            md.delete_brick(contact_brick)
        contact_brick = add_contact(translation)
        its, converged = newton(md, options, args.max_iter)
        per_step.append(its)
        solutions.append(md.variable("u").copy())
        if not converged:
            status = f"not converged in {args.max_iter} Newton iterations"
            break
    solve_time, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    wall_time = common.clock()
    peak = common.peak_memory_mib()

    def resultants(u: np.ndarray, load: float) -> tuple[list[float], dict[str, list[float]]]:
        """Contact force and reactions (N) from the nodal forces K u - f at load factor ``load``."""
        stress = "(lambda*Trace(Grad_u)*Id(3)+mu*(Grad_u+Grad_u'))"
        internal = gf.asm_generic(mim, 1, f"{stress}:Grad_Test_u", -1, "u", 1, mf_u, u,
                                  "lambda", 0, md.variable("lambda"), "mu", 0, md.variable("mu"))
        external = np.zeros_like(internal)
        for name, traction in case.traction.items():
            external += gf.asm_generic(mim_b, 1, "t.Test_u", regions[name], "u", 1, mf_u, u,
                                       "t", 0, load * traction / STRESS_UNIT)
        nodal = ((internal - external).reshape(-1, 3)[fem_node]) * STRESS_UNIT
        return common.nodal_resultants(case, mesh, nodal, contact_nodes)

    step_forces = [resultants(u, load)[0] for u, (load, _) in zip(solutions, case.steps)]
    contact_force, reactions = resultants(solutions[-1], case.steps[len(solutions) - 1][0])
    u_nodes = solutions[-1].reshape(-1, 3)[fem_node]  # displacement at our nodes
    lambda_n = md.variable("lambda_n")
    record = {
        "code": f"GetFEM 5.4.4 ({brick} nodal contact brick, Alart-Curnier option {args.option})",
        "case": str(case.path), "status": status,
        "dofs": 3 * len(mesh.points), "free_dofs": 3 * (len(mesh.points) - len(fixed)),
        "contact_nodes": int(n_contact), "unknowns": int(md.nbdof()),
        "newton_iterations": int(sum(per_step)), "newton_per_step": per_step,
        "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
        "contact_force": contact_force, "contact_force_per_step": step_forces,
        "contact_force_multipliers_normal": float(-np.sum(lambda_n)) * STRESS_UNIT,
        "reactions": reactions,
        "settings": {"lsolver": args.lsolver, "lsearch": args.lsearch, "max_res": args.max_res, "r": r,
                     "option": args.option, "brick": brick, "stress_unit": STRESS_UNIT,
                     "integration": [volume, boundary]},
        "threads": args.threads,
    }
    common.write_result(args.output, record, mesh.points, u_nodes)
    print(f"getfem: {status}, {record['newton_iterations']} Newton {per_step}, {solve_time:.2f} s, "
          f"contact force {np.array2string(np.asarray(record['contact_force']), precision=6)}")
    return 0 if status == "converged" else 1


if __name__ == "__main__":
    sys.exit(main())
