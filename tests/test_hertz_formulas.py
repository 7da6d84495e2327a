"""Closed forms of contactqvi.problems.hertz against numbers checked by hand.

E = 0.91e11 Pa and nu = 0.3 give E* = 1e11 Pa and G = 3.5e10 Pa; with R = 1 m and
delta = 1e-4 m: a = 0.01 m, P = 4/3 1e11 1e-6 = 133333.3 N, p0 = 2e9/pi Pa. With
mu = 0.5 and Q = 7/8 mu P: 1 - Q/(mu P) = 1/8, so c = a/2 and
s = s* (1 - 1/4), s* = 3 mu P 1.7 / (16 G a) = 6.0714e-5 m.
"""

from __future__ import annotations

import numpy as np
import pytest

from contactqvi.problems import hertz

pytestmark = pytest.mark.one_rank(reason="closed forms of contactqvi.problems.hertz on numbers")

E, NU, R, DELTA, MU = 0.91e11, 0.3, 1.0, 1e-4, 0.5
P = 4.0e5 / 3.0


def test_hertz_normal_contact():
    assert hertz.effective_modulus(E, NU) == pytest.approx(1e11)
    assert hertz.contact_radius(R, DELTA) == pytest.approx(0.01)
    assert hertz.contact_force(E, NU, R, DELTA) == pytest.approx(P)
    assert hertz.depth_for_force(E, NU, R, P) == pytest.approx(DELTA)
    p0 = hertz.peak_pressure(E, NU, R, DELTA)
    assert p0 == pytest.approx(2e9 / np.pi)
    assert p0 == pytest.approx(3 * P / (2 * np.pi * 0.01**2))  # the mean pressure is 2/3 p0
    profile = hertz.pressure(np.array([0.0, 0.005, 0.01, 0.02]), E, NU, R, DELTA)
    assert profile == pytest.approx([p0, p0 * np.sqrt(0.75), 0.0, 0.0])


def test_hertz_pressure_integrates_to_the_force():
    r = np.linspace(0.0, 0.01, 200001)
    integrand = 2 * np.pi * r * hertz.pressure(r, E, NU, R, DELTA)
    assert np.trapezoid(integrand, r) == pytest.approx(P, rel=1e-6)


def test_cattaneo_mindlin():
    a, G = 0.01, hertz.shear_modulus(E, NU)
    assert G == pytest.approx(3.5e10)
    s_star = hertz.sliding_displacement(MU, P, G, NU, a)
    assert s_star == pytest.approx(3 * MU * P * 1.7 / (16 * 3.5e10 * 0.01))
    assert s_star == pytest.approx(6.0714285714e-5)
    Q = 7 / 8 * MU * P
    assert hertz.stick_radius(a, Q, MU, P) == pytest.approx(0.005)
    assert hertz.stick_radius(a, [0.0, MU * P, 2 * MU * P], MU, P) == pytest.approx([a, 0.0, 0.0])
    assert hertz.mindlin_displacement(Q, MU, P, G, NU, a) == pytest.approx(0.75 * s_star)
    assert hertz.mindlin_force(0.75 * s_star, MU, P, G, NU, a) == pytest.approx(Q)
    assert hertz.mindlin_force([0.0, s_star, 2 * s_star], MU, P, G, NU, a) == pytest.approx([0.0, MU * P, MU * P])


def test_mindlin_law_is_inverted_and_starts_with_the_no_slip_stiffness():
    a, G = 0.01, hertz.shear_modulus(E, NU)
    Q = np.linspace(0.0, MU * P, 11)
    s = hertz.mindlin_displacement(Q, MU, P, G, NU, a)
    assert hertz.mindlin_force(s, MU, P, G, NU, a) == pytest.approx(Q)
    small = 1e-6 * MU * P
    stiffness = small / hertz.mindlin_displacement(small, MU, P, G, NU, a)
    assert stiffness == pytest.approx(8 * G * a / (2 - NU), rel=1e-5)


@pytest.mark.parametrize("nu, beta", [(0.3, 2 / 7), (0.45, 1 / 11), (0.5, 0.0), (0.0, 0.5)])
def test_dundurs_beta_against_a_rigid_body(nu, beta):
    assert hertz.dundurs_beta(nu) == pytest.approx(beta, abs=1e-15)
