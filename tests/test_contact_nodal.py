"""Nodal contact laws (seed 000, Prop. 6.4, Table 1, Prop. 6.6, Cor. 6.7) for every law of contactqvi.laws.

The nodal algebra of :mod:`contactqvi.contact.nodal` asks a law for its slip bound
b(lambda) and slope only; each test here runs for every registered law (lumped to
nodes of unit area), for a law with both a given part and a Coulomb part, and for a
pressure-dependent coefficient that falls with the pressure.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from contactqvi.contact.nodal import (
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
from contactqvi.laws import (
    LAWS,
    Coulomb,
    Frictionless,
    LinearSlipBound,
    NodalLaw,
    PressureDependentCoulomb,
    StackedLaw,
    Tresca,
    create_law,
)
from contactqvi.parameters import ParameterError

pytestmark = pytest.mark.one_rank(reason="nodal algebra of the laws on numpy arrays: no mesh, no communicator")

GAMMA, FRICTION = 3.0, 0.4
COULOMB = Coulomb(FRICTION).lumped(1.0)
#: One instance of every registered law (keyed by name), lumped to nodes of unit area; the resolvent
#: arguments below have normal components of order 1 (N), so the pressure scale 0.5 Pa puts the
#: pressure-dependent coefficient mid-way.
EXAMPLES = {"coulomb": Coulomb(FRICTION), "tresca": Tresca(0.7), "frictionless": Frictionless(),
            "pressure_coulomb": PressureDependentCoulomb(0.2, 0.6, 0.5)}
LAWS_AT_NODES: dict[str, NodalLaw] = {
    **{name: law.lumped(1.0) for name, law in EXAMPLES.items()},
    "mixed": LinearSlipBound(given=0.3, friction=FRICTION),
    "pressure_falling": PressureDependentCoulomb(0.6, 0.1, 0.5).lumped(1.0),
}
FRICTIONAL = {name: law for name, law in LAWS_AT_NODES.items() if law.frictional}
rng = np.random.default_rng(20221107)


def test_every_registered_law_has_an_example():
    assert set(EXAMPLES) == set(LAWS)


def _points(kind: str, m: int = 40, law: NodalLaw = COULOMB) -> np.ndarray:
    """Resolvent arguments w landing in a given region (contact, slip bound b of ``law``)."""
    w = rng.normal(size=(m, 3))
    if kind == "no_contact":
        w[:, 2] = np.abs(w[:, 2]) + 0.1
    elif kind in ("sliding", "sticking"):
        w[:, 2] = -np.abs(w[:, 2]) - 0.1
        bound = law.bound(-w[:, 2])
        target = bound + 0.5 if kind == "sliding" else 0.5 * bound
        w[:, :2] *= (target / np.linalg.norm(w[:, :2], axis=1))[:, None]
    elif kind == "wide":  # several orders of magnitude, both signs
        w *= 10.0 ** rng.uniform(-3, 3, size=(m, 1))
    return w


@pytest.mark.parametrize("law", FRICTIONAL.values(), ids=FRICTIONAL.keys())
def test_resolvent_force_is_not_a_difference_of_large_terms(law):
    """A sliding node whose trial force w12 is 1e8 times its slip bound (a steel block slipping
    1.7 cm per time step: gamma |u| = 4e8 N against nodal forces of a few newtons) gets ||g|| = b to
    a few eps of b: z is the projection itself. As w - gamma v it was resolved to eps ||w12||, 1e-8
    of b, which the step's final iterate carried (docs/dynamics.md Sect. 5)."""
    w = np.array([[1e8, 3e7, -1.0], [-4e8, 1e8, -2.0], [2e8, -5e8, -0.5]])
    v, z = resolvent(w, GAMMA, law)
    bound = np.broadcast_to(law.bound(-z[:, 2]), (len(w),))
    assert np.all(bound > 0.0) and np.all(np.linalg.norm(v[:, :2], axis=1) > 0.0)
    assert np.all(np.abs(np.linalg.norm(z[:, :2], axis=1) - bound) <= 4 * np.finfo(float).eps * bound)
    assert np.all(np.abs(z[:, :2] * np.linalg.norm(w[:, :2], axis=1)[:, None] - bound[:, None] * w[:, :2])
                  <= 4 * np.finfo(float).eps * (bound * np.linalg.norm(w[:, :2], axis=1))[:, None])


@pytest.mark.parametrize("law", LAWS_AT_NODES.values(), ids=LAWS_AT_NODES.keys())
@pytest.mark.parametrize("kind", ["no_contact", "sliding", "sticking", "mixed", "wide"])
def test_resolvent_is_the_projection_onto_the_graph(kind, law):
    """v = (gamma I + Q~)^{-1}(w) pointwise: z = w - gamma v lies in Q~(v), i.e. theta in N_R+(v3),
    ||g|| <= b(-theta), g = b v12/||v12|| where v12 != 0; and v12 minimises
    gamma/2 |v12|^2 - w12.v12 + b |v12| (b fixed by theta = min(w3, 0), (6.8))."""
    w = _points(kind, law=law)
    v, z = resolvent(w, GAMMA, law)
    tol = 1e-12 * np.abs(w).max(axis=1)  # round-off of w - gamma v
    assert np.all(np.abs(z - (w - GAMMA * v)).max(axis=1) <= 1e-2 * tol)
    lam = -z[:, 2]
    bound = np.broadcast_to(law.bound(lam), lam.shape)
    assert np.all(v[:, 2] >= 0) and np.all(lam >= 0) and np.all(v[:, 2] * lam == 0)
    g, slip = z[:, :2], np.linalg.norm(v[:, :2], axis=1)
    assert np.all(np.linalg.norm(g, axis=1) <= bound + tol)
    sliding = slip > 0
    expected = (bound[sliding] / slip[sliding])[:, None] * v[sliding, :2]
    assert np.all(np.linalg.norm(g[sliding] - expected, axis=1) <= tol[sliding])
    if kind == "wide":
        return
    for wi, vi, bi in zip(w, v, bound):
        energy = lambda x: 0.5 * GAMMA * x @ x - wi[:2] @ x + bi * np.linalg.norm(x)
        best = scipy.optimize.minimize(energy, x0=wi[:2] / GAMMA, method="Nelder-Mead",
                                       options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 4000}).x
        assert energy(vi[:2]) <= energy(best) + 1e-10
        assert np.linalg.norm(vi[:2] - best) < 1e-5


@pytest.mark.parametrize("law", LAWS_AT_NODES.values(), ids=LAWS_AT_NODES.keys())
def test_slope_is_the_derivative_of_the_bound(law):
    """b' by central differences of b, b >= 0, and |b'| <= slope_bound (the L of Prop. 6.4) up to large forces."""
    lam = np.concatenate([np.linspace(0.0, 5.0, 101), 10.0 ** np.linspace(1, 6, 20)])
    h = 1e-6 * np.maximum(lam, 1.0)
    difference = (law.bound(lam + h) - law.bound(np.maximum(lam - h, 0.0))) / (lam + h - np.maximum(lam - h, 0.0))
    slope = np.broadcast_to(law.slope(lam), lam.shape)
    np.testing.assert_allclose(difference, slope, rtol=1e-5, atol=1e-8)  # one-sided at lambda = 0
    assert np.all(law.bound(lam) >= 0.0)
    assert np.all(np.abs(slope) <= law.slope_bound * (1 + 1e-12))


def test_resolvent_lipschitz_bound():
    """|v1 - v2| <= sqrt(2 (1 + L^2)) / gamma |w1 - w2|, L = sup |b'| (proof of Prop. 6.4), for every law."""
    w1, w2 = _points("mixed", 2000), _points("mixed", 2000)
    w2[:1000] = w1[:1000] + 1e-3 * rng.normal(size=(1000, 3))  # include nearby pairs
    for law in LAWS_AT_NODES.values():
        v1, _ = resolvent(w1, GAMMA, law)
        v2, _ = resolvent(w2, GAMMA, law)
        ratio = np.linalg.norm(v1 - v2, axis=1) / np.linalg.norm(w1 - w2, axis=1)
        assert ratio.max() <= lipschitz_constant(GAMMA, law) * (1 + 1e-12)
        assert ratio.max() > 0.5 / GAMMA  # not vacuous


def _states(w: np.ndarray, law: NodalLaw = COULOMB) -> np.ndarray:
    v, z = resolvent(w, GAMMA, law)
    return contact_states(*classify(v, z, GAMMA, law, 1e-12))


@pytest.mark.parametrize("law", FRICTIONAL.values(), ids=FRICTIONAL.keys())
def test_classify_regions(law):
    """Table 1 states of the strong regions, for every law with friction."""
    expected = {"no_contact": State.NO_CONTACT, "sliding": State.SLIDING, "sticking": State.STICKING}
    for kind, state in expected.items():
        w = _points(kind, law=law)
        if kind == "no_contact" and np.any(law.bound(np.zeros(1)) > 0):  # friction without contact
            w[:, :2] *= 10.0
        assert np.all(_states(w, law) == state)


def test_classify_weak_points():
    """Table 1 states of the weak (kink) points, Coulomb and Tresca; frictionless contact is free tangentially."""
    weak = np.array([[0.3, 0.0, 0.0], [0.0, 0.0, 0.0], [FRICTION * 2.0, 0.0, -2.0]])
    assert list(_states(weak)) == [State.WEAK_CONTACT_SLIDING, State.WEAK_CONTACT_STICKING, State.WEAK_STICKING]
    # Tresca: friction acts without contact.
    tresca = LAWS_AT_NODES["tresca"]
    w = np.array([[0.1, 0.2, 1.0], [1.0, 0.0, 1.0], [0.1, 0.0, -1.0]])
    assert list(_states(w, tresca)) == [State.SEPARATED_STICKING, State.NO_CONTACT, State.STICKING]
    frictionless = LAWS_AT_NODES["frictionless"]
    v, z = resolvent(np.array([[0.0, 0.0, -1.0]]), GAMMA, frictionless)
    normal, tangential = classify(v, z, GAMMA, frictionless, 1e-12)
    assert normal[0] == Normal.CONTACT and tangential[0] == Tangential.WEAK_FREE


def _graph_tangents(w0: np.ndarray, law: NodalLaw, h: float = 1e-7) -> np.ndarray:
    """Columns (dv, dz) spanning T gph Q~ at (v(w0), z(w0)), by central differences of the resolvent."""
    cols = []
    for e in np.eye(3):
        vp, zp = resolvent((w0 + h * e)[None], GAMMA, law)
        vm, zm = resolvent((w0 - h * e)[None], GAMMA, law)
        cols.append(np.concatenate([(vp - vm)[0], (zp - zm)[0]]) / (2 * h))
    return np.array(cols).T  # (6, 3)


@pytest.mark.parametrize("law", LAWS_AT_NODES.values(), ids=LAWS_AT_NODES.keys())
@pytest.mark.parametrize("kind", ["no_contact", "sliding", "sticking"])
def test_adjoint_basis_spans_scd_subspace(kind, law):
    """rge(W*, U*) is the adjoint L* of L = T gph Q~ (Prop. 6.6): <U* c, dv> = <W* c, dz>, with the
    tangents from finite differences of the resolvent where it is differentiable (the strong regions);
    for a pressure-dependent coefficient this checks the coupling row b'(lambda) t^T of the sliding basis."""
    for w0 in _points(kind, 10, law):
        v, z = resolvent(w0[None], GAMMA, law)
        Wt, Ut = scd_adjoint_blocks(v, z, *classify(v, z, GAMMA, law, 1e-12), GAMMA, law)
        W, U = Wt[0].T, Ut[0].T
        tangents = _graph_tangents(w0, law)
        assert np.linalg.matrix_rank(tangents, tol=1e-6) == 3
        pairing = U.T @ tangents[:3] - W.T @ tangents[3:]
        assert np.abs(pairing).max() < 1e-6 * (1 + np.abs(tangents).max())
        assert np.linalg.matrix_rank(np.vstack([W, U]), tol=1e-10) == 3


def test_sliding_basis_needs_the_slope_not_the_secant():
    """With a pressure-dependent coefficient the coupling row is b'(lambda) t^T: the secant b/lambda = F(p)
    in its place violates the adjoint relation of the finite-difference tangents."""
    law = LAWS_AT_NODES["pressure_coulomb"]
    w0 = _points("sliding", 1, law)[0]
    v, z = resolvent(w0[None], GAMMA, law)
    Wt, Ut = scd_adjoint_blocks(v, z, *classify(v, z, GAMMA, law, 1e-12), GAMMA, law)
    lam = -z[0, 2]
    assert abs(law.slope(lam) - law.bound(lam) / lam) > 0.05
    secant = Wt[0].copy()
    secant[:2, 2] *= law.bound(lam) / lam / law.slope(lam)
    tangents = _graph_tangents(w0, law)

    def pairing(Wt0: np.ndarray) -> float:
        return float(np.abs(Ut[0] @ tangents[:3] - Wt0 @ tangents[3:]).max())

    assert pairing(Wt[0]) < 1e-6 and pairing(secant) > 1e-3


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


@pytest.mark.parametrize("law", FRICTIONAL.values(), ids=FRICTIONAL.keys())
def test_stick_reversed_slip_moves_reversed_nodes_onto_the_sticking_branch(law):
    """Sliding nodes whose slip turned against the previous one get (v12 = 0, same z), a point
    of gph Q~ in state M3- (||g|| = b); every other node is left as it is."""
    w = np.concatenate([_points("sliding", 30, law), _points("sticking", 10, law), _points("no_contact", 10, law)])
    v, z = resolvent(w, GAMMA, law)
    normal, tangential = classify(v, z, GAMMA, law, 1e-12)
    v_previous = rng.normal(size=v.shape)
    v_new, tangential_new, reversed_ = stick_reversed_slip(v, z, tangential, v_previous, law, 1e-12)
    bound = np.broadcast_to(law.bound(-z[:, 2]), (len(v),))
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
    law = LAWS_AT_NODES["frictionless"]
    v, z = resolvent(_points("sliding", 20, law), GAMMA, law)
    _, tangential = classify(v, z, GAMMA, law, 1e-12)
    _, _, reversed_ = stick_reversed_slip(v, z, tangential, -v, law, 1e-12)
    assert not reversed_.any()


def test_stacked_law_follows_each_pair():
    """Nodes of several pairs: each node's bound, slope and resolvent are those of its pair's law."""
    m = 60
    law_of_node = rng.integers(0, 3, size=m)
    area = rng.uniform(0.5, 2.0, size=m)
    pair_laws = [EXAMPLES["coulomb"], EXAMPLES["tresca"], EXAMPLES["pressure_coulomb"]]
    nodal = [law.lumped(area[law_of_node == k]) for k, law in enumerate(pair_laws)]
    stacked = StackedLaw(tuple(nodal), law_of_node)
    w = _points("mixed", m)
    v, z = resolvent(w, GAMMA, stacked)
    kinds = classify(v, z, GAMMA, stacked, 1e-12)
    blocks = scd_adjoint_blocks(v, z, *kinds, GAMMA, stacked)
    for k, law in enumerate(nodal):
        nodes = law_of_node == k
        np.testing.assert_array_equal(stacked.bound(-z[:, 2])[nodes], law.bound(-z[nodes, 2]))
        np.testing.assert_array_equal(stacked.slope(-z[:, 2])[nodes], law.slope(-z[nodes, 2]))
        v_k, z_k = resolvent(w[nodes], GAMMA, law)
        np.testing.assert_array_equal(v[nodes], v_k)
        kinds_k = classify(v_k, z_k, GAMMA, law, 1e-12)
        for a, b in zip(blocks, scd_adjoint_blocks(v_k, z_k, *kinds_k, GAMMA, law)):
            np.testing.assert_array_equal(a[nodes], b)
    assert stacked.slope_bound == max(law.slope_bound for law in nodal) and stacked.frictional


def test_lumping_turns_tractions_into_nodal_forces():
    """A Tresca bound (Pa) times the node's area; the pressure of the pressure-dependent law is lambda / area."""
    area = np.array([0.5, 2.0])
    np.testing.assert_allclose(Tresca(1e6).lumped(area).bound(np.array([3.0, 0.0])), [5e5, 2e6])
    law = PressureDependentCoulomb(0.2, 0.6, 1e6)
    lam = np.array([1e6, 1e6])
    np.testing.assert_allclose(law.lumped(area).bound(lam), lam * law.coefficient(lam / area), rtol=1e-14)
    assert law.coefficient(0.0) == 0.2 and law.coefficient(1e6) == pytest.approx(0.4)
    assert law.coefficient(1e12) == pytest.approx(0.6, rel=1e-5)
    assert Coulomb(0.3).lumped(area).bound(lam).tolist() == [3e5, 3e5]


@pytest.mark.parametrize("name", sorted(LAWS))
def test_every_law_reads_back_from_its_case_table(name):
    """to_dict() is the law's case-file table; create_law reads it back; its parameters are named on error."""
    law = EXAMPLES[name]
    assert create_law(law.to_dict(), "contacts[0]") == law and law.checked("x") == law
    for key in LAWS[name].parameters:
        with pytest.raises(ParameterError, match="needs") as info:
            create_law({k: v for k, v in law.to_dict().items() if k != key}, "contacts[0]")
        assert info.value.name == f"contacts[0].{key}"
        with pytest.raises(ParameterError, match="must be") as info:
            create_law({**law.to_dict(), key: -1.0}, "contact")
        assert info.value.name == f"contact.{key}"
    for key in {k for other in LAWS.values() for k in other.parameters} - set(LAWS[name].parameters):
        with pytest.raises(ParameterError, match="only used with law") as info:
            create_law({**law.to_dict(), key: 1.0}, "contact")
        assert info.value.name == f"contact.{key}"
