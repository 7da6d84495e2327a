"""The dual numbers of forward-mode differentiation (:mod:`contactqvi.contact.dual`): every
operation the segment integrals use, its values bitwise those of the plain arrays and its
tangents against central differences; an operation it does not know is an error."""

from __future__ import annotations

import numpy as np
import pytest

from contactqvi.contact.dual import Dual, primal

pytestmark = pytest.mark.one_rank(reason="numpy arithmetic, no mesh")

#: Functions of x (4, 3, 2) built from the operations that :class:`Dual` defines.
FUNCTIONS = {
    "arithmetic": lambda x: (1.0 - x * x[:, ::-1]) / (2.0 + x[..., 0, None] * x[..., 0, None]) - x[:, None, 1],
    "sqrt, sum": lambda x: np.sqrt(np.sum(x * x, axis=2)).sum(axis=1, keepdims=True),
    "einsum": lambda x: np.einsum("pij,pkj,i->pk", x, x + 1.0, np.arange(3.0)),
    "stack, concatenate": lambda x: np.concatenate([np.stack([x[..., 0], 2.0 * x[..., 1]], axis=-1), x], axis=-2),
    "where, roll, swapaxes": lambda x: np.swapaxes(np.where(x > 0.3, x, -x) * np.roll(x, -1, axis=1), 1, 2),
    "cross": lambda x: np.cross(x[:, :, 0], x[:, :, 1]),
    "solve": lambda x: np.linalg.solve(x[:, :2] + 3.0 * np.eye(2), x[:, 1:]),
    "indexing, setitem": lambda x: _assembled(x),
}


def _assembled(x):
    out = np.zeros((4, 5, 2), like=x)
    out[:, [0, 2, 4]] = x * 2.0
    out[np.arange(4), np.array([1, 3, 1, 3])] += x[:, 0]
    return out


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_values_and_tangents(name):
    """Values as on plain arrays (bitwise) and tangents within 1e-8 of central differences."""
    function = FUNCTIONS[name]
    x = np.random.default_rng(1).uniform(-1.0, 1.0, (4, 3, 2))
    out = function(Dual.seed(x))
    assert np.array_equal(out.value, function(x))
    h = 1e-6
    for k in range(6):
        step = np.zeros((3, 2))
        step.flat[k] = h
        difference = (function(x + step) - function(x - step)) / (2 * h)
        assert np.abs(out.tangent[..., k] - difference).max() <= 1e-8 * max(1.0, np.abs(difference).max())


def test_unknown_operation_is_an_error():
    with pytest.raises(TypeError):
        np.exp(Dual.seed(np.ones((2, 3))))
    with pytest.raises(TypeError):
        np.linalg.norm(Dual.seed(np.ones((2, 3))))
    assert primal(2.0) == 2.0
