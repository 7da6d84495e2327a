"""The dual basis of the covered part of a slave facet that the master covers in part.

The dual basis psi = A phi of a whole slave facet is biorthogonal over the facet: on a linear
triangle psi_i = 4 phi_i - 1, negative where phi_i < 1/4, so over a part of the facet
D_ii = int psi_i falls through zero while most of the facet is covered, and C = D^-1 M is
unbounded (a slave surface that reaches past the master's edge: docs/finite_strain.md Sect. 22).
Biorthogonal over the covered part S instead (the consistent boundary treatment of Cichosz and
Bischoff, CMAME 2011; for partially projecting slave elements in 3D, Popp, Seitz, Gee and Wall,
CMAME 2013),

    F = int_S phi,   H = int_S phi phi^T,   G_p = int_{S_p} phi (phi^m)^T,   A = diag(F) H^-1,   (22.1)
    D_p = A F_p,   M_p = A G_p   (per facet pair p of the facet, S the union of its segments S_p),

so that int_S psi_i phi_k = delta_ik F_k: D_ii = int_S phi_i, the covered share of the node's area,
the rows of M sum to D, and a linear field is reproduced over S. A facet whose segments add up to
its whole area keeps the whole facet's basis; one short of it by any amount, round-off included,
takes (22.1), which tends to the whole facet's basis as the cover closes: no switch of basis at a
sliver (one counted whole below 1e-9 of its area left the 50 % compression's last step a linear
tail, docs/finite_strain.md Sect. 22). F, G, H are :func:`~contactqvi.contact.segments.basis_integrals`.

A depends on every pair of its facet; its derivative is a sum of one term per pair, of that pair's
own vertices,

    dA = sum_p (diag(dF_p) - A dH_p) H^-1,                                                   (L.5)

and with H 1 = F (sum_b phi_b = 1) D = F, so dD = sum_p dF_p, and the geometric derivative of
sum_j M_ij x_j = A sum_p G_p x_p^m is, per pair,

    A dG_p x^m + diag(dF_p) Y - A dH_p Y,   Y = H^-1 sum_p G_p x_p^m                          (L.6)

(:mod:`contactqvi.contact.linearisation`); the master shares (L.4) take the term of (L.5) between
every two pairs of one facet (:func:`~contactqvi.contact.kinematics.master_shares`).
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from contactqvi.contact.facets import facet_areas

__all__ = ["NO_COVER", "CoveredBasis", "CoveredDerivatives", "covered_basis", "covered_entries"]

#: A slave facet covered by less than this fraction of its area couples nothing (its covered part's
#: mass matrix is singular to round-off).
NO_COVER = 1e-6


@dataclasses.dataclass(frozen=True)
class CoveredBasis:
    """(22.1) of the partly covered slave facets of a set of facet pairs, per pair of such a facet.

    Attributes:
        pairs: (Q,) the pairs' indices among the set's.
        facet: (Q,) their facet's index among the partly covered facets (the pairs of one facet
            share A, H^-1 and Y).
        A, Hinv: (Q, n, n) A and H^-1 of the pair's facet (zero for a facet covered by less than
            :data:`NO_COVER`).
        Y: (Q, n, 3) H^-1 sum_p G_p x_p^m over the facet's pairs (the master vertices' positions).
        G: (Q, n, n_m) the pair's int phi_a phi_j^m.
    """

    pairs: np.ndarray
    facet: np.ndarray
    A: np.ndarray
    Hinv: np.ndarray
    Y: np.ndarray
    G: np.ndarray


@dataclasses.dataclass(frozen=True)
class CoveredDerivatives:
    """What (L.5) adds to dM of the pairs of partly covered facets, for the master shares.

    Attributes:
        pairs: (Q,) the pairs' indices among the rank's pairs; facet: (Q,) their facet's index.
        dF: (Q, n_s, N, 3), dH: (Q, n_s, n_s, N, 3) derivatives of the pairs' F and H with respect
            to their N vertices (slave first).
        A, Hinv: (Q, n_s, n_s) A and H^-1 of each pair's facet; G: (Q, n_s, n_m) the pair's G.
    """

    pairs: np.ndarray
    facet: np.ndarray
    dF: np.ndarray
    dH: np.ndarray
    A: np.ndarray
    Hinv: np.ndarray
    G: np.ndarray


def covered_basis(slave_x: np.ndarray, master_x: np.ndarray, pairs_s: np.ndarray, D: np.ndarray, M: np.ndarray,
                  integrals: typing.Callable) -> tuple[np.ndarray, np.ndarray, CoveredBasis | None]:
    """The segment integrals ``D``, ``M`` of facet pairs (of the whole facets' dual basis) with the
    pairs of partly covered slave facets integrated in (22.1) instead, and that basis (None where
    every facet is covered whole).

    Args:
        slave_x: (f, n, 3) the slave facets; master_x: (P, n_m, 3) each pair's master facet; pairs_s:
            (P,) each pair's slave facet; integrals: the pairs' F, G, H from (slave facets, master
            facets) (:func:`~contactqvi.contact.segments.basis_integrals` along the projection).
    """
    area = facet_areas(slave_x)
    covered = np.zeros(len(area))
    np.add.at(covered, pairs_s, D.sum(axis=1))  # sum_i psi_i = 1: the segments' area
    partly = np.flatnonzero(covered[pairs_s] < area[pairs_s])
    if len(partly) == 0:
        return D, M, None
    F, G, H = integrals(pairs_s[partly], master_x[partly])
    facets, facet = np.unique(pairs_s[partly], return_inverse=True)
    n = F.shape[1]
    Fe, He, GX = np.zeros((len(facets), n)), np.zeros((len(facets), n, n)), np.zeros((len(facets), n, 3))
    np.add.at(Fe, facet, F)
    np.add.at(He, facet, H)
    np.add.at(GX, facet, np.einsum("paj,pjk->pak", G, master_x[partly]))
    some = Fe.sum(axis=1) > NO_COVER * area[facets]
    Hinv = np.zeros_like(He)
    Hinv[some] = np.linalg.inv(He[some])
    A = Fe[:, :, None] * Hinv
    Y = np.einsum("fab,fbk->fak", Hinv, GX)
    D, M = D.copy(), M.copy()
    D[partly] = np.einsum("pab,pb->pa", A[facet], F)
    M[partly] = np.einsum("pab,pbj->paj", A[facet], G)
    return D, M, CoveredBasis(partly, facet, A[facet], Hinv[facet], Y[facet], G)


def covered_entries(covered: CoveredBasis, k: np.ndarray, master_x: np.ndarray, derivatives: tuple) -> tuple:
    """The derivative entries of the pairs ``k`` of ``covered`` (their master facets ``master_x``,
    (q, n_m, 3), and the derivatives (dF, dG, dH) of their F, G, H): ``(dD, dM, dMx)`` of the shapes of
    :func:`~contactqvi.contact.linearisation.coupling_derivatives`' entries, dD = dF (zero on a facet
    that couples nothing), dM = A dG at fixed A, and dM x of (L.6)."""
    dF, dG, dH = derivatives
    A, Y = covered.A[k], covered.Y[k]
    dD = dF * A.any(axis=(1, 2))[:, None, None, None]
    dM = np.einsum("pab,pbjvc->pajvc", A, dG)
    dGx = np.einsum("pbjvc,pjk->pbvck", dG, master_x)
    dMx = (np.einsum("pab,pbvck->pavck", A, dGx) + dF[..., None] * Y[:, :, None, None, :]
           - np.einsum("pab,pbdvc,pdk->pavck", A, dH, Y))
    return dD, dM, dMx
