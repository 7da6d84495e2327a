"""Nodal Coulomb law of seed 000: resolvent, contact states and SCD subspace bases.

All functions act on arrays of shape (m, 3) holding one 3-vector per contact node
(components: two tangential, then normal = e3), vectorised over the nodes.

Notation (seed 000, Sect. 6): the nodal multifunction is
    Q~(v) = {(-F theta dd||v12||, theta) : theta in N_{R+}(v3)},
and a point of its graph is written (v, z) with z = (g, theta), theta <= 0 the
negative normal force and g the friction force. The contact states are those
of Table 1.
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["State", "resolvent", "classify", "scd_adjoint_blocks", "lipschitz_constant"]


class State(enum.IntEnum):
    """Contact states of seed 000, Table 1 (values are written to the output)."""

    NO_CONTACT = 0  # L:   v3 > 0, theta = 0
    SLIDING = 1  # M1:  v3 = 0, theta < 0, v12 != 0
    STICKING = 2  # M3+: v3 = 0, theta < 0, v12 = 0, ||g|| < -F theta
    WEAK_CONTACT_SLIDING = 3  # M2: v3 = 0, theta = 0, v12 != 0
    WEAK_STICKING = 4  # M3-: v3 = 0, theta < 0, v12 = 0, ||g|| = -F theta
    WEAK_CONTACT_STICKING = 5  # M4: v = 0, z = 0


def resolvent(w: np.ndarray, gamma: float, friction: float) -> tuple[np.ndarray, np.ndarray]:
    """(gamma I + Q~)^{-1}(w) in closed form (Prop. 6.4, (6.6)-(6.8)).

    Args:
        w: (m, 3) arguments.
        gamma: gamma > 0.
        friction: friction coefficient F >= 0.

    Returns:
        ``(v, z)``: v = (gamma I + Q~)^{-1}(w) and z = w - gamma v in Q~(v), so
        (v, z) lies on the graph of Q~.
    """
    v = np.empty_like(w)
    theta = np.minimum(w[:, 2], 0.0)  # (6.8)
    v[:, 2] = np.maximum(w[:, 2], 0.0) / gamma
    w12 = w[:, :2]
    norm_w12 = np.linalg.norm(w12, axis=1)
    bound = -friction * theta  # slip bound F lambda, lambda = -theta
    slides = norm_w12 > bound
    shrink = np.zeros_like(norm_w12)
    shrink[slides] = (1.0 - bound[slides] / norm_w12[slides]) / gamma
    v[:, :2] = shrink[:, None] * w12  # (6.7): block soft thresholding
    z = w - gamma * v
    z[:, 2] = theta
    return v, z


def lipschitz_constant(gamma: float, friction: float) -> float:
    """Lipschitz modulus sqrt(2 (1 + F^2)) / gamma of the resolvent (proof of Prop. 6.4)."""
    return float(np.sqrt(2.0 * (1.0 + friction**2)) / gamma)


def classify(v: np.ndarray, z: np.ndarray, gamma: float, friction: float, tol: float) -> np.ndarray:
    """Contact state (Table 1) of each graph point (v, z) of Q~.

    A quantity counts as zero when its magnitude is <= ``tol``. ``tol`` is a force:
    it is compared with z = (g, theta) and with gamma v (gamma v and z both have
    the units of force, see (6.6)-(6.7)); the solver sets it relative to the size
    of the current resolvent arguments. The weak states are the boundary cases
    of the strong ones within that tolerance.

    Returns:
        (m,) int8 array of :class:`State` values.
    """
    theta = z[:, 2]
    contact = theta < -tol  # strong contact: lambda = -theta > 0
    gap_open = gamma * v[:, 2] > tol
    slip = gamma * np.linalg.norm(v[:, :2], axis=1) > tol
    inside_cone = -friction * theta - np.linalg.norm(z[:, :2], axis=1) > tol  # ||g|| < F lambda
    states = np.empty(len(v), dtype=np.int8)
    states[~contact] = np.where(slip[~contact], State.WEAK_CONTACT_SLIDING, State.WEAK_CONTACT_STICKING)
    states[gap_open & ~contact] = State.NO_CONTACT
    states[contact & slip] = State.SLIDING
    states[contact & ~slip] = np.where(inside_cone[contact & ~slip], State.STICKING, State.WEAK_STICKING)
    return states


def scd_adjoint_blocks(
    v: np.ndarray, z: np.ndarray, states: np.ndarray, gamma: float, friction: float
) -> tuple[np.ndarray, np.ndarray]:
    """Transposed bases (W*^T, U*^T) of an element rge(W*, U*) of S*Q~(v, z).

    The Newton matrix rows of a contact node are W*^T A + U*^T and its right-hand
    side -(W*^T y1 + U*^T y2) ((5.4) with Cor. 6.8). Subspaces per state:
      * L, M2, M4: rge(I, 0) ((6.10), (6.16));
      * M3+, M3-: rge(0, I) ((6.11), (6.16));
      * M1: the well-conditioned basis of Cor. 6.7.

    Difference from the paper, documented: the bases are scaled so that every
    Newton row has the units of A (force/length). The subspaces, hence the exact
    Newton step, are unchanged; only the balance of rows seen by an inexact
    Krylov solver changes. Concretely rge(0, I) is represented as rge(0, gamma I),
    and the M1 basis uses the scaling matrix C of Cor. 6.7 with the unit
    (dimensionless) identity replaced by gamma:
        C = diag(gamma (gamma I2 - F theta/||v12|| (I2 - P))^{-1}, gamma),  P = t t^T,
    t = v12/||v12||, which gives with beta = -F theta / (gamma ||v12|| - F theta) in (0, 1)
        W* = [[(1 - beta) I2 + beta P, 0], [F t^T, 0]],
        U* = [[gamma beta (I2 - P), 0], [0, gamma]].
    (With gamma = 1 this is (6.15) derived from (6.13) and C: the seed's printed
    second matrix of (6.15) lacks the factor 1/(||v12|| - F theta); see the tests.)

    Returns:
        ``(Wt, Ut)``, each (m, 3, 3): the blocks W*^T and U*^T.
    """
    m = len(v)
    Wt = np.zeros((m, 3, 3))
    Ut = np.zeros((m, 3, 3))
    free = np.isin(states, (State.NO_CONTACT, State.WEAK_CONTACT_SLIDING, State.WEAK_CONTACT_STICKING))
    Wt[free] = np.eye(3)
    stick = np.isin(states, (State.STICKING, State.WEAK_STICKING))
    Ut[stick] = gamma * np.eye(3)
    slide = states == State.SLIDING
    v12 = v[slide, :2]
    norm_v12 = np.linalg.norm(v12, axis=1)
    t = v12 / norm_v12[:, None]
    P = t[:, :, None] * t[:, None, :]
    bound = -friction * z[slide, 2]
    beta = bound / (gamma * norm_v12 + bound)
    I2 = np.eye(2)
    Wt[slide, :2, :2] = (1.0 - beta)[:, None, None] * I2 + beta[:, None, None] * P
    Wt[slide, :2, 2] = friction * t  # (W*^T)_{12,3} = F t
    Ut[slide, :2, :2] = (gamma * beta)[:, None, None] * (I2 - P)
    Ut[slide, 2, 2] = gamma
    return Wt, Ut
