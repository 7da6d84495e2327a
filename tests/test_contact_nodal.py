"""Nodal friction laws (seed 000, Prop. 6.4, Table 1, Prop. 6.6, Cor. 6.7) for Coulomb and Tresca."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from contactqvi.contact.nodal import (
    FrictionLaw,
    Normal,
    State,
    Tangential,
    classify,
    contact_states,
    lipschitz_constant,
    resolvent,
    scd_adjoint_blocks,
    stick_reversed_slip,
)
from contactqvi.contact.scd_newton import line_search_steps

GAMMA, FRICTION = 3.0, 0.4
COULOMB = FrictionLaw(friction=FRICTION)
LAWS = {"coulomb": COULOMB, "tresca": FrictionLaw(slip_bound=0.7), "mixed": FrictionLaw(FRICTION, 0.3)}
rng = np.random.default_rng(20221107)


def _points(kind: str, m: int = 40, law: FrictionLaw = COULOMB) -> np.ndarray:
    """Resolvent arguments w landing in a given region (contact, slip bound b of ``law``)."""
    w = rng.normal(size=(m, 3))
    if kind == "no_contact":
        w[:, 2] = np.abs(w[:, 2]) + 0.1
    elif kind in ("sliding", "sticking"):
        w[:, 2] = -np.abs(w[:, 2]) - 0.1
        bound = law.bound(w[:, 2])
        target = bound + 0.5 if kind == "sliding" else 0.5 * bound
        w[:, :2] *= (target / np.linalg.norm(w[:, :2], axis=1))[:, None]
    return w


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
@pytest.mark.parametrize("kind", ["no_contact", "sliding", "sticking", "mixed"])
def test_resolvent_solves_inclusion_and_matches_minimisation(kind, law):
    """w - gamma v in Q~(v), and v12 minimises gamma/2 |v12|^2 - w12.v12 + b |v12| (b = s + F lambda fixed)."""
    w = _points(kind, law=law)
    v, z = resolvent(w, GAMMA, law)
    np.testing.assert_allclose(z, w - GAMMA * v, atol=1e-14)
    lam = -z[:, 2]
    bound = law.bound(z[:, 2])
    assert np.all(v[:, 2] >= 0) and np.all(lam >= 0) and np.allclose(v[:, 2] * lam, 0)
    g, slip = z[:, :2], np.linalg.norm(v[:, :2], axis=1)
    assert np.all(np.linalg.norm(g, axis=1) <= bound + 1e-12)
    sliding = slip > 0
    expected = (bound[sliding] / slip[sliding])[:, None] * v[sliding, :2]
    np.testing.assert_allclose(g[sliding], expected, atol=1e-12)
    for wi, vi, bi in zip(w, v, bound):
        energy = lambda x: 0.5 * GAMMA * x @ x - wi[:2] @ x + bi * np.linalg.norm(x)
        best = scipy.optimize.minimize(energy, x0=wi[:2] / GAMMA, method="Nelder-Mead",
                                       options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 4000}).x
        assert energy(vi[:2]) <= energy(best) + 1e-10
        assert np.linalg.norm(vi[:2] - best) < 1e-5


def test_resolvent_lipschitz_bound():
    """|v1 - v2| <= sqrt(2 (1 + F^2)) / gamma |w1 - w2| (proof of Prop. 6.4)."""
    w1, w2 = _points("mixed", 2000), _points("mixed", 2000)
    w2[:1000] = w1[:1000] + 1e-3 * rng.normal(size=(1000, 3))  # include nearby pairs
    for law in LAWS.values():
        v1, _ = resolvent(w1, GAMMA, law)
        v2, _ = resolvent(w2, GAMMA, law)
        ratio = np.linalg.norm(v1 - v2, axis=1) / np.linalg.norm(w1 - w2, axis=1)
        assert ratio.max() <= lipschitz_constant(GAMMA, law) * (1 + 1e-12)
        assert ratio.max() > 0.5 / GAMMA  # not vacuous


def _states(w: np.ndarray, law: FrictionLaw = COULOMB) -> np.ndarray:
    v, z = resolvent(w, GAMMA, law)
    return contact_states(*classify(v, z, GAMMA, law, 1e-12))


def test_classify_regions():
    """Table 1 states of the strong regions and of the weak (kink) points, Coulomb and Tresca."""
    expected = {"no_contact": State.NO_CONTACT, "sliding": State.SLIDING, "sticking": State.STICKING}
    for kind, state in expected.items():
        assert np.all(_states(_points(kind)) == state)
    weak = np.array([[0.3, 0.0, 0.0], [0.0, 0.0, 0.0], [FRICTION * 2.0, 0.0, -2.0]])
    assert list(_states(weak)) == [State.WEAK_CONTACT_SLIDING, State.WEAK_CONTACT_STICKING, State.WEAK_STICKING]
    # Tresca: friction acts without contact; frictionless contact is free tangentially.
    tresca = FrictionLaw(slip_bound=0.7)
    w = np.array([[0.1, 0.2, 1.0], [1.0, 0.0, 1.0], [0.1, 0.0, -1.0]])
    assert list(_states(w, tresca)) == [State.SEPARATED_STICKING, State.NO_CONTACT, State.STICKING]
    v, z = resolvent(np.array([[0.0, 0.0, -1.0]]), GAMMA, FrictionLaw())
    normal, tangential = classify(v, z, GAMMA, FrictionLaw(), 1e-12)
    assert normal[0] == Normal.CONTACT and tangential[0] == Tangential.WEAK_FREE


def _graph_tangents(w0: np.ndarray, law: FrictionLaw, h: float = 1e-7) -> np.ndarray:
    """Columns (dv, dz) spanning T gph Q~ at (v(w0), z(w0)), by central differences of the resolvent."""
    cols = []
    for e in np.eye(3):
        vp, zp = resolvent((w0 + h * e)[None], GAMMA, law)
        vm, zm = resolvent((w0 - h * e)[None], GAMMA, law)
        cols.append(np.concatenate([(vp - vm)[0], (zp - zm)[0]]) / (2 * h))
    return np.array(cols).T  # (6, 3)


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
@pytest.mark.parametrize("kind", ["no_contact", "sliding", "sticking"])
def test_adjoint_basis_spans_scd_subspace(kind, law):
    """rge(W*, U*) is the adjoint L* of L = T gph Q~ (Prop. 6.6): <U* c, dv> = <W* c, dz>."""
    for w0 in _points(kind, 10, law):
        v, z = resolvent(w0[None], GAMMA, law)
        Wt, Ut = scd_adjoint_blocks(v, z, *classify(v, z, GAMMA, law, 1e-12), GAMMA, law)
        W, U = Wt[0].T, Ut[0].T
        tangents = _graph_tangents(w0, law)
        assert np.linalg.matrix_rank(tangents, tol=1e-6) == 3
        pairing = U.T @ tangents[:3] - W.T @ tangents[3:]
        assert np.abs(pairing).max() < 1e-6 * (1 + np.abs(tangents).max())
        assert np.linalg.matrix_rank(np.vstack([W, U]), tol=1e-10) == 3


def test_sliding_basis_is_paper_basis_rescaled():
    """(6.15), derived from (6.13) times C, spans the same subspace as our gamma-scaled basis.

    The seed's printed second matrix of (6.15) (-F theta (I - P)) does not: the
    factor 1/(||v12|| - F theta) is missing there.
    """
    v, z = resolvent(_points("sliding", 20), GAMMA, COULOMB)
    Wt, Ut = scd_adjoint_blocks(v, z, *classify(v, z, GAMMA, COULOMB, 1e-12), GAMMA, COULOMB)
    for i in range(len(v)):
        v12, theta = v[i, :2], z[i, 2]
        s = np.linalg.norm(v12)
        t, P = v12 / s, np.outer(v12, v12) / s**2
        W0 = np.zeros((3, 3)); U0 = np.zeros((3, 3))  # (6.13)
        W0[:2, :2] = np.eye(2); W0[2, :2] = FRICTION * t
        U0[:2, :2] = -FRICTION * theta / s * (np.eye(2) - P); U0[2, 2] = 1.0
        C = np.eye(3)
        C[:2, :2] = np.linalg.inv(np.eye(2) - FRICTION * theta / s * (np.eye(2) - P))
        paper = np.vstack([W0 @ C, U0 @ C])
        ours = np.vstack([Wt[i].T, Ut[i].T])
        coeffs = np.linalg.lstsq(paper, ours, rcond=None)[0]
        assert np.abs(paper @ coeffs - ours).max() < 1e-10 * np.abs(ours).max()
        printed = paper.copy()
        printed[3:5, :2] = -FRICTION * theta * (np.eye(2) - P)
        coeffs = np.linalg.lstsq(printed, ours, rcond=None)[0]
        assert np.abs(printed @ coeffs - ours).max() > 1e-6 * np.abs(ours).max()


def test_line_search_steps_of_section_7():
    expected = [1, 1 / 2, 1 / 4, 1 / 8, 1 / 32, 1 / 128, 0.1 / 128, 0.01 / 128, 0.001 / 128]
    np.testing.assert_allclose(line_search_steps(9), expected, rtol=1e-15)
    assert len(line_search_steps(3)) == 3


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
def test_stick_reversed_slip_moves_reversed_nodes_onto_the_sticking_branch(law):
    """Sliding nodes whose slip turned against the previous one get (v12 = 0, same z), a point
    of gph Q~ in state M3- (||g|| = b); every other node is left as it is."""
    w = np.concatenate([_points("sliding", 30, law), _points("sticking", 10, law), _points("no_contact", 10, law)])
    v, z = resolvent(w, GAMMA, law)
    normal, tangential = classify(v, z, GAMMA, law, 1e-12)
    v_previous = rng.normal(size=v.shape)
    v_new, tangential_new, reversed_ = stick_reversed_slip(v, z, tangential, v_previous, law, 1e-12)
    bound = np.broadcast_to(law.bound(z[:, 2]), (len(v),))
    expected = (tangential == Tangential.SLIDING) & (bound > 0) & (np.sum(v[:, :2] * v_previous[:, :2], axis=1) < 0)
    assert np.array_equal(reversed_, expected) and 0 < expected.sum() < 30
    np.testing.assert_array_equal(v_new[reversed_, :2], 0.0)
    np.testing.assert_array_equal(v_new[~reversed_], v[~reversed_])
    np.testing.assert_array_equal(v_new[:, 2], v[:, 2])
    # On the graph: ||g|| = b at the moved nodes, so classify finds them weakly sticking.
    np.testing.assert_allclose(np.linalg.norm(z[reversed_, :2], axis=1), bound[reversed_], rtol=1e-12)
    assert np.array_equal(classify(v_new, z, GAMMA, law, 1e-9)[1], tangential_new)
    assert np.all(tangential_new[reversed_] == Tangential.WEAK_STICKING)
    assert np.array_equal(tangential_new[~reversed_], tangential[~reversed_])


def test_stick_reversed_slip_leaves_frictionless_nodes_free():
    """Without a slip bound there is no sticking branch: no node is moved."""
    law = FrictionLaw()
    v, z = resolvent(_points("sliding", 20, law), GAMMA, law)
    _, tangential = classify(v, z, GAMMA, law, 1e-12)
    _, _, reversed_ = stick_reversed_slip(v, z, tangential, -v, law, 1e-12)
    assert not reversed_.any()
