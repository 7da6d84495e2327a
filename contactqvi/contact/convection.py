"""The predictor of a slide step: the last solution carried along with what slides (issue 45).

A step that moves a die along the surface it presses (an ironing's slide, a moving load) starts, by
the tangent's response (:func:`~contactqvi.contact.load_path._elastic_change`), from the last
solution with the die moved and the trough it pressed left behind: the die's front ploughs into the
unindented surface, most of its contact opens, and the first Newton steps are damped to 1/128 while
they find the contact again (docs/finite_strain.md Sects. 19-20: 15-28 Newton steps a slide step on
the shipped ironing). In steady sliding the state is at rest in the frame that moves with the die,
so the predictor of such a step is the last solution convected with it:

    u~_pred(X) = u~_n(X) + t           on the bodies that hold a group ``boundary.moved``,
    u~_pred(X) = u~_n(X - t)           on the others (the trough carried along),

t the step's change of translation (:func:`sliding_translation`), the obstacles moved by t as every
step moves them. A node whose point X - t lies outside its own body keeps u~_n. It assumes that the
contact zone travels with what slides, as under a die or a slider on a longer body; a step that
moves obstacles alone keeps the tangent's predictor (a plane slid along itself, a plate dragged
over a seal, moves no contact zone), and so does a path that turns. The values
u~_n(X - t) are found on the ranks whose cells of the node's body hold the point
(:func:`_convected_values`); nothing is gathered. The load path puts the prescribed values of the
step into the predictor and searches the pairs there (:func:`~contactqvi.contact.load_path._predict`).
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

from dolfinx import fem, geometry
from dolfinx import mesh as dmesh

from contactqvi.contact.nodal import TOUCHING
from contactqvi.contact.path_state import PathState
from contactqvi.contact.problem import ContactProblem
from contactqvi.load_steps import LoadStep

__all__ = ["SLIDING_COSINE", "convected", "sliding_translation"]

#: A step slides when its translation's mean |cos| with the normals of the touching contact nodes is
#: below this: it moves along the contact (the ironing's steps along x) rather than into it (its press).
SLIDING_COSINE = 0.5
#: Bounding-box padding (m) of the point location.
PADDING = 1e-10


def sliding_translation(problem: ContactProblem, state: PathState, step: LoadStep) -> np.ndarray | None:
    """The change t of translation from ``state`` (a converged solve) to ``step`` if the step slides
    (module docstring), else None: a path that turns, a step that does not translate, one that moves
    obstacles only (no body holds a group ``boundary.moved``), or one whose translation is not along
    the contact of the nodes that touched (:data:`SLIDING_COSINE`). Collective."""
    change = np.asarray(step.translation, dtype=float) - state.translation
    length = float(np.linalg.norm(change))
    if state.solved == 0 or length == 0.0 or step.rotation is not None or state.rotation is not None:
        return None
    if len(_carried_bodies(problem, _node_body(problem))) == 0:
        return None  # obstacles alone slide: a plane slid along itself moves no contact zone
    touching = np.isin(state.contact_states(problem), TOUCHING)
    cosines = np.abs(problem.frames[touching, 2, :] @ (change / length))
    total, count = problem.comm.allreduce(np.array([cosines.sum(), float(len(cosines))]), op=MPI.SUM)
    return change if count > 0 and total / count < SLIDING_COSINE else None


def convected(problem: ContactProblem, last: fem.Function, change: np.ndarray) -> fem.Function:
    """The predictor u~_pred of the module docstring (a new function, ghosts updated) from the last
    solution ``last`` (u~_n, global components) for the step's change of translation ``change``.
    Collective."""
    V = problem.V
    n_owned = V.dofmap.index_map.size_local
    body = _node_body(problem)
    carried = _carried_bodies(problem, body)
    values = last.x.array.reshape(-1, 3)[:n_owned].copy()
    moving = np.isin(body[:n_owned], carried)
    values[moving] += change
    points = V.tabulate_dof_coordinates()[:n_owned] - change
    still = np.flatnonzero(~moving)
    cell_body = body[V.dofmap.list[:, 0]]  # a cell's body: that of its nodes
    shifted, found = _convected_values(last, points[still], body[still], cell_body)
    values[still[found]] = shifted[found]
    out = fem.Function(V)
    out.x.array[:3 * n_owned] = values.ravel()
    out.x.scatter_forward()
    return out


def _node_body(problem: ContactProblem) -> np.ndarray:
    """Each local node's body index (0 for a problem of one body)."""
    if problem.node_body is not None:
        return problem.node_body
    index_map = problem.V.dofmap.index_map
    return np.zeros(index_map.size_local + index_map.num_ghosts, dtype=np.int32)


def _carried_bodies(problem: ContactProblem, body: np.ndarray) -> np.ndarray:
    """The bodies that hold a moved dof (a group ``boundary.moved``): where a unit translation's
    load :attr:`~contactqvi.contact.problem.ContactProblem.translated` prescribes 1. Collective."""
    n_owned = problem.V.dofmap.index_map.size_local
    moved = np.zeros(n_owned, dtype=bool)
    prescribed = problem.dirichlet_dofs_loc[problem.dirichlet_dofs_loc < 3 * n_owned]
    for component, load in enumerate(problem.translated[:3]):
        dofs = prescribed[prescribed % 3 == component]
        moved[dofs // 3] |= load.array_r[dofs] != 0.0
    held = np.unique(body[:n_owned][moved])
    return np.unique(np.concatenate(problem.comm.allgather(held))).astype(np.int32)


def _convected_values(u: fem.Function, points: np.ndarray, body: np.ndarray,
                      cell_body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u at ``points`` (m, 3), each found in a cell of its own ``body`` (``cell_body``: each local
    cell's), and whether it was found (points outside their body: False). Each point goes to the ranks
    whose cells of its body have a bounding box around it, and takes the value of the lowest that finds
    it: a point on the face that two bodies share (a press fit, stacked blocks) belongs to the body of
    its node, whichever rank holds the other's cell. Collective."""
    comm = u.function_space.mesh.comm
    low, high = _body_boxes(u.function_space.mesh, cell_body, int(body.max(initial=-1)) + 1)
    near = [np.flatnonzero(np.all((points >= low[r, body]) & (points <= high[r, body]), axis=1))
            for r in range(comm.size)]  # the ranks, not the points
    requests = comm.alltoall([np.column_stack([points[p], body[p]]) for p in near])
    asked = np.concatenate(requests)
    values, found = _evaluate(u, asked[:, :3], asked[:, 3].astype(np.int32), cell_body)
    bounds = np.cumsum([len(r) for r in requests])[:-1]
    replies = comm.alltoall(np.split(np.column_stack([values, found]), bounds))
    out, located = np.zeros((len(points), 3)), np.zeros(len(points), dtype=bool)
    for p, reply in zip(near, replies):  # by rank: the lowest that found a point gives its value
        new = (reply[:, 3] > 0.5) & ~located[p]
        out[p[new]] = reply[new, :3]
        located[p[new]] = True
    return out, located


def _body_boxes(msh: dmesh.Mesh, cell_body: np.ndarray, bodies: int) -> tuple[np.ndarray, np.ndarray]:
    """The bounding box of each body's local cells on every rank, padded by :data:`PADDING`: the
    lower and upper corners, (ranks, bodies, 3) each (empty boxes where a rank has none of a body).
    Collective."""
    bodies = msh.comm.allreduce(bodies, op=MPI.MAX)
    x, cells = msh.geometry.x, msh.geometry.dofmap
    low, high = np.full((bodies, 3), np.inf), np.full((bodies, 3), -np.inf)
    for k in range(bodies):  # the bodies, not the nodes
        corners = x[cells[cell_body[:len(cells)] == k]].reshape(-1, 3)
        if len(corners):
            low[k], high[k] = corners.min(axis=0) - PADDING, corners.max(axis=0) + PADDING
    return np.array(msh.comm.allgather(low)), np.array(msh.comm.allgather(high))


def _evaluate(u: fem.Function, points: np.ndarray, body: np.ndarray,
              cell_body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u at the local ``points`` in a local cell of each point's ``body``: the values (m, 3) and
    whether such a cell was found (1.0 or 0.0)."""
    values, found = np.zeros((len(points), 3)), np.zeros(len(points))
    if len(points) == 0:
        return values, found
    msh = u.function_space.mesh
    tree = geometry.bb_tree(msh, msh.topology.dim, padding=PADDING)
    colliding = geometry.compute_colliding_cells(msh, geometry.compute_collisions_points(tree, points), points)
    links, offsets = colliding.array, colliding.offsets
    point = np.repeat(np.arange(len(points)), np.diff(offsets))
    own = cell_body[links] == body[point]
    inside, first = np.unique(point[own], return_index=True)  # each point's first cell of its body
    if len(inside):
        values[inside] = u.eval(points[inside], links[own][first])
        found[inside] = 1.0
    return values, found
