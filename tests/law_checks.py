"""Test helper: the discrete contact law at every contact node of a converged solution, for any law."""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.contact.nodal import State

__all__ = ["assert_contact_law_holds"]


def assert_contact_law_holds(problem, u: PETSc.Vec, result, rtol: float = 1e-8) -> np.ndarray:
    """Check the law of ``problem`` (its slip bound b(lambda)) at the owned contact nodes of ``u``.

    The forces come from the equilibrium A u - l + z = 0, z = (g, theta) in Q~(u): the
    obstacle pushes the body with (-g, -theta) = A u - l. Checked to ``rtol`` of the
    largest displacement and force: non-penetration, lambda >= 0, complementarity,
    ||g|| <= b(lambda), no slip at sticking nodes, g = b(lambda) s/||s|| against the slip
    s at sliding nodes, and the solver's own normal forces.

    Returns:
        The normal forces lambda (owned contact nodes, N).
    """
    comm = problem.comm
    r = problem.A.createVecRight()
    problem.A.mult(u, r)
    r.axpy(-1.0, problem.load)
    force = r.array.reshape(-1, 3)[problem.contact_blk].copy()  # (friction force, normal force) on the body
    r.destroy()
    u_c = u.array.reshape(-1, 3)[problem.contact_blk]
    scale_u = comm.allreduce(np.abs(u_c).max(initial=0.0), op=MPI.MAX)
    scale_f = comm.allreduce(np.abs(force).max(initial=0.0), op=MPI.MAX)
    tol_u, tol_f = rtol * scale_u, rtol * scale_f
    lam, friction_force, slip = force[:, 2], force[:, :2], u_c[:, :2]
    bound = np.broadcast_to(problem.law.bound(np.maximum(lam, 0.0)), lam.shape)
    assert np.all(u_c[:, 2] >= -tol_u)  # non-penetration
    assert np.all(lam >= -tol_f)  # non-negative normal reaction
    assert np.all(np.abs(lam * u_c[:, 2]) <= tol_f * scale_u)  # complementarity
    assert np.all(np.linalg.norm(friction_force, axis=1) <= bound + tol_f)  # the law's bound
    stick = np.isin(result.states, (State.STICKING, State.WEAK_STICKING))
    assert np.all(np.linalg.norm(slip[stick], axis=1) <= tol_u)
    slide = result.states == State.SLIDING
    direction = slip[slide] / np.linalg.norm(slip[slide], axis=1)[:, None]
    assert np.allclose(friction_force[slide], -bound[slide, None] * direction, atol=tol_f)
    assert np.allclose(result.normal_force, lam, atol=tol_f)  # the solver's graph point agrees
    return lam
