"""The nodal law of seed 000 for any slip bound: resolvent, contact states and SCD subspace bases.

All functions act on arrays of shape (m, 3) holding one 3-vector per contact node
(components: two tangential, then normal, in the node's frame), vectorised over
the nodes; gamma is one number or one per node (a diagonal Gamma in (6.17)).

Notation (seed 000, Sect. 6): the nodal multifunction of Coulomb friction is
    Q~(v) = {(-F theta dd||v12||, theta) : theta in N_{R+}(v3)},
and a point of its graph is written (v, z) with z = (g, theta), theta <= 0 the
negative normal force and g the friction force. The functions here hold for any
slip bound b(lambda) >= 0 of the normal force lambda = -theta in place of F lambda
(:class:`~contactqvi.laws.NodalLaw`): they ask the law only for b and its slope
db/dlambda (:mod:`contactqvi.laws.base` derives why that is all (6.6)-(6.15) need).
Coulomb (b = F lambda), Tresca (b = s, the VI of the second kind of the seed's
refs. [15, 16]), frictionless contact (b = 0) and Coulomb with a pressure-dependent
coefficient are such laws (:mod:`contactqvi.laws`).

A node is classified by a normal and a tangential kind (:class:`Normal`,
:class:`Tangential`); the pair selects the SCD subspace and maps to the contact
states of Table 1 (:class:`State`).
"""

from __future__ import annotations

import enum

import numpy as np

from contactqvi.laws import NodalLaw

__all__ = [
    "Normal",
    "State",
    "TOUCHING",
    "Tangential",
    "classify",
    "contact_states",
    "lipschitz_constant",
    "resolvent",
    "scd_adjoint_blocks",
    "stick_reversed_slip",
]


class State(enum.IntEnum):
    """Contact states of seed 000, Table 1 (values are written to the output)."""

    NO_CONTACT = 0  # L:   v3 > 0, theta = 0
    SLIDING = 1  # M1:  v3 = 0, theta < 0, v12 != 0
    STICKING = 2  # M3+: v3 = 0, theta < 0, v12 = 0, ||g|| < b
    WEAK_CONTACT_SLIDING = 3  # M2: v3 = 0, theta = 0, v12 != 0
    WEAK_STICKING = 4  # M3-: v3 = 0, theta < 0, v12 = 0, ||g|| = b
    WEAK_CONTACT_STICKING = 5  # M4: v = 0, z = 0
    SEPARATED_STICKING = 6  # Tresca only: theta = 0, v12 = 0, 0 < ||g|| <= s


#: The states of a contact node that touches its master surface (theta < 0: a contact force).
TOUCHING = (State.SLIDING, State.STICKING, State.WEAK_STICKING)


class Normal(enum.IntEnum):
    """Normal kind of a graph point: which of v3, theta vanishes."""

    OPEN = 0  # v3 > 0, theta = 0: rge(I, 0) in the normal component
    WEAK = 1  # v3 = 0, theta = 0: rge(I, 0) chosen
    CONTACT = 2  # v3 = 0, theta < 0: rge(0, I)


class Tangential(enum.IntEnum):
    """Tangential kind of a graph point."""

    SLIDING = 0  # v12 != 0, g = -b v12/||v12||: the sliding basis (Cor. 6.7; rge(I, 0) when b = 0)
    STICKING = 1  # v12 = 0, ||g|| < b: rge(0, I)
    WEAK_STICKING = 2  # v12 = 0, ||g|| = b > 0: rge(0, I) chosen
    WEAK_FREE = 3  # v12 = 0, g = 0, b = 0: rge(I, 0) (the graph of 0 * dd||.|| is R^2 x {0})


def _per_node(gamma: float | np.ndarray, m: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(gamma, dtype=float), (m,))


def resolvent(w: np.ndarray, gamma: float | np.ndarray, law: NodalLaw) -> tuple[np.ndarray, np.ndarray]:
    """(gamma I + Q~)^{-1}(w) in closed form (Prop. 6.4, (6.6)-(6.8)).

    Args:
        w: (m, 3) arguments.
        gamma: gamma > 0, one or per node.
        law: the slip bound b of each node.

    Returns:
        ``(v, z)``: v = (gamma I + Q~)^{-1}(w) and z = w - gamma v in Q~(v), so
        (v, z) lies on the graph of Q~. z is computed as the projection itself (z_12 = w_12 of a
        sticking node, b w_12 / ||w_12|| of a sliding one; theta = min(w_3, 0)), not as the
        difference w - gamma v, whose terms are gamma |v| where the forces are far smaller.
    """
    v = np.empty_like(w)
    gamma = _per_node(gamma, len(w))
    theta = np.minimum(w[:, 2], 0.0)  # (6.8)
    v[:, 2] = np.maximum(w[:, 2], 0.0) / gamma
    w12 = w[:, :2]
    norm_w12 = np.linalg.norm(w12, axis=1)
    bound = np.broadcast_to(law.bound(-theta), norm_w12.shape)
    slides = norm_w12 > bound
    shrink = np.zeros_like(norm_w12)
    shrink[slides] = (1.0 - bound[slides] / norm_w12[slides]) / gamma[slides]
    v[:, :2] = shrink[:, None] * w12  # (6.7): block soft thresholding
    z = w.copy()
    z[slides, :2] *= (bound[slides] / norm_w12[slides])[:, None]
    z[:, 2] = theta
    return v, z


def lipschitz_constant(gamma: float, law: NodalLaw) -> float:
    """Lipschitz modulus sqrt(2 (1 + L^2)) / gamma of the resolvent (proof of Prop. 6.4).

    L = sup |db/dlambda| is the Lipschitz constant of the slip bound (F for Coulomb;
    a given part of b does not change it), the largest over the nodes.
    """
    return float(np.sqrt(2.0 * (1.0 + law.slope_bound**2)) / gamma)


def classify(
    v: np.ndarray, z: np.ndarray, gamma: float | np.ndarray, law: NodalLaw, tol: float
) -> tuple[np.ndarray, np.ndarray]:
    """Normal and tangential kind of each graph point (v, z) of Q~.

    A quantity counts as zero when its magnitude is <= ``tol``. ``tol`` is a force:
    it is compared with z = (g, theta), with the slip bound b and with gamma v
    (gamma v and z both have the units of force, see (6.6)-(6.7)); the solver sets
    it relative to the size of the current resolvent arguments. Weak kinds are the
    boundary cases of the strong ones within that tolerance.

    Returns:
        ``(normal, tangential)``: (m,) int8 arrays of :class:`Normal` and
        :class:`Tangential` values.
    """
    theta = z[:, 2]
    normal = np.full(len(v), Normal.WEAK, dtype=np.int8)
    normal[gamma * v[:, 2] > tol] = Normal.OPEN
    normal[theta < -tol] = Normal.CONTACT
    bound = np.broadcast_to(law.bound(-theta), theta.shape)
    slip = gamma * np.linalg.norm(v[:, :2], axis=1) > tol
    inside = bound - np.linalg.norm(z[:, :2], axis=1) > tol  # ||g|| < b
    tangential = np.full(len(v), Tangential.WEAK_FREE, dtype=np.int8)
    tangential[bound > tol] = Tangential.WEAK_STICKING
    tangential[inside] = Tangential.STICKING
    tangential[slip] = Tangential.SLIDING
    return normal, tangential


def stick_reversed_slip(
    v: np.ndarray, z: np.ndarray, tangential: np.ndarray, v_previous: np.ndarray, law: NodalLaw, tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move sliding nodes whose slip reversed onto the sticking branch of gph Q~.

    A node counts as reversed when it is SLIDING with slip bound b > ``tol`` and its
    slip points against the previous iterate's, v12 . v12_prev < 0: the slip went
    through zero, where the node most likely sticks. Such a node gets the graph
    point (v', z) with v'12 = 0 and v'3 = v3, z unchanged. z12 = g of a sliding
    point has ||g|| = b, so (v', z) lies on gph Q~ (state M3-, Table 1) and its
    tangential kind becomes WEAK_STICKING (subspace rge(0, I)).

    Used by the approximation step of :class:`~contactqvi.contact.scd_newton.SCDNewtonSolver`
    (Algorithm 1 admits any point of the graph close to the iterate, (4.2)): the
    point moves by ||v12||, which is O(||u - u_bar||) at nodes that stick in the
    solution, and nodes that slide in the solution do not reverse near it.

    Returns:
        ``(v', tangential', reversed)``: copies with the reversed nodes changed and
        the (m,) boolean mask of those nodes.
    """
    bound = np.broadcast_to(law.bound(-z[:, 2]), (len(v),))
    reversed_ = (
        (tangential == Tangential.SLIDING) & (bound > tol) & (np.einsum("ij,ij->i", v[:, :2], v_previous[:, :2]) < 0.0)
    )
    v, tangential = v.copy(), tangential.copy()
    v[reversed_, :2] = 0.0
    tangential[reversed_] = Tangential.WEAK_STICKING
    return v, tangential, reversed_


def contact_states(normal: np.ndarray, tangential: np.ndarray) -> np.ndarray:
    """Table 1 state of each node from its kinds (frictionless contact counts as sliding)."""
    stick = np.isin(tangential, (Tangential.STICKING, Tangential.WEAK_STICKING))
    states = np.full(len(normal), State.NO_CONTACT, dtype=np.int8)
    states[(normal == Normal.WEAK) & ~stick] = State.WEAK_CONTACT_STICKING
    states[(normal == Normal.WEAK) & (tangential == Tangential.SLIDING)] = State.WEAK_CONTACT_SLIDING
    states[(normal != Normal.CONTACT) & stick] = State.SEPARATED_STICKING
    contact = normal == Normal.CONTACT
    states[contact] = State.SLIDING
    states[contact & (tangential == Tangential.STICKING)] = State.STICKING
    states[contact & (tangential == Tangential.WEAK_STICKING)] = State.WEAK_STICKING
    return states


def scd_adjoint_blocks(
    v: np.ndarray, z: np.ndarray, normal: np.ndarray, tangential: np.ndarray, gamma: float | np.ndarray,
    law: NodalLaw,
) -> tuple[np.ndarray, np.ndarray]:
    """Transposed bases (W*^T, U*^T) of an element rge(W*, U*) of S*Q~(v, z).

    The Newton matrix rows of a contact node are W*^T A + U*^T and its right-hand
    side -(W*^T y1 + U*^T y2) ((5.4) with Cor. 6.8). The subspace is the product of
    a normal and a tangential part ((6.10), (6.11), (6.16)), coupled only at
    sliding nodes in contact through the slip bound b(lambda) (Cor. 6.7):
      * normal OPEN, WEAK: rge(I, 0); CONTACT: rge(0, I);
      * tangential STICKING, WEAK_STICKING: rge(0, I); WEAK_FREE: rge(I, 0);
        SLIDING: the well-conditioned basis of Cor. 6.7.

    Difference from the paper, documented: the bases are scaled so that every
    Newton row has the units of A (force/length). The subspaces, hence the exact
    Newton step, are unchanged; only the balance of rows seen by an inexact
    Krylov solver changes. Concretely rge(0, I) is represented as rge(0, gamma I),
    and the sliding basis uses the scaling matrix C of Cor. 6.7 with the unit
    (dimensionless) identity replaced by gamma:
        C = diag(gamma (gamma I2 + b/||v12|| (I2 - P))^{-1}, gamma),  P = t t^T,
    t = v12/||v12||, which gives with beta = b / (gamma ||v12|| + b) in [0, 1)
        W* = [[(1 - beta) I2 + beta P, 0], [b' t^T, 0]],
        U* = [[gamma beta (I2 - P), 0], [0, gamma]]
    with b = b(lambda) and its slope b' = db/dlambda (the row b' t^T only in contact;
    with b = 0, beta = 0 and the tangential part is rge(I, 0)). With gamma = 1 and
    Coulomb's b = F lambda, b' = F, this is (6.15) derived from (6.13) and C: the
    seed's printed second matrix of (6.15) lacks the factor 1/(||v12|| - F theta);
    see the tests. For any other b the tangent space of the graph near a sliding
    point in contact, {(v12, 0, b(-theta) v12/||v12||, theta)}, is that of (6.12)
    with -F theta -> b and F -> b' (:mod:`contactqvi.laws.base`), hence these bases.

    Returns:
        ``(Wt, Ut)``, each (m, 3, 3): the blocks W*^T and U*^T.
    """
    m = len(v)
    gamma = _per_node(gamma, m)
    Wt = np.zeros((m, 3, 3))
    Ut = np.zeros((m, 3, 3))
    contact = normal == Normal.CONTACT
    Wt[~contact, 2, 2] = 1.0
    Ut[contact, 2, 2] = gamma[contact]
    Wt[tangential == Tangential.WEAK_FREE, :2, :2] = np.eye(2)
    stick = np.isin(tangential, (Tangential.STICKING, Tangential.WEAK_STICKING))
    Ut[stick, :2, :2] = gamma[stick, None, None] * np.eye(2)
    slide = tangential == Tangential.SLIDING
    v12 = v[slide, :2]
    norm_v12 = np.linalg.norm(v12, axis=1)
    t = v12 / norm_v12[:, None]
    P = t[:, :, None] * t[:, None, :]
    lam = -z[:, 2]
    bound = np.broadcast_to(law.bound(lam), (m,))[slide]
    beta = bound / (gamma[slide] * norm_v12 + bound)
    I2 = np.eye(2)
    Wt[slide, :2, :2] = (1.0 - beta)[:, None, None] * I2 + beta[:, None, None] * P
    Ut[slide, :2, :2] = (gamma[slide] * beta)[:, None, None] * (I2 - P)
    slope = np.broadcast_to(law.slope(lam), (m,))[slide & contact]
    Wt[slide & contact, :2, 2] = slope[:, None] * t[contact[slide]]  # (W*^T)_{12,3} = b' t
    return Wt, Ut
