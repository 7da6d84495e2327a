"""Forward-mode automatic differentiation of vectorised numpy code: arrays of dual numbers.

A :class:`Dual` is a value array of shape S and a tangent array of shape S + (k,): the
derivatives of every entry along k directions. numpy's operations on it (arithmetic,
``sqrt``, ``einsum``, ``stack``, ``where``, indexing, ...) compute the value with the same
numpy call as on a plain array, so values are bitwise those of the plain evaluation, and
carry the tangents by the chain rule alongside (forward mode: Griewank and Walther,
"Evaluating Derivatives", 2nd ed., SIAM 2008, Ch. 3; vector mode, Sect. 3.2). One
evaluation then gives the value and its derivatives in all k directions, with every
branch (a comparison, ``np.where``'s condition, an index) taken on the values: the
derivative of the branch the value took.

The geometry of the mortar segments (:mod:`contactqvi.contact.segments`,
:mod:`contactqvi.contact.facets`) is written for plain arrays and runs unchanged on
duals; :mod:`contactqvi.contact.linearisation` seeds its coordinates. Only the operations
that code uses are defined; any other numpy function raises ``TypeError`` rather than
drop the tangents.
"""

from __future__ import annotations

import string
import typing

import numpy as np

__all__ = ["Dual", "primal"]


def primal(a: typing.Any) -> typing.Any:
    """The value of a :class:`Dual`; anything else as it is."""
    return a.value if isinstance(a, Dual) else a


def _tangent(a: typing.Any) -> typing.Any:
    """The tangent of a :class:`Dual`; 0.0 (a constant) for anything else."""
    return a.tangent if isinstance(a, Dual) else 0.0


def _axis(axis: int, ndim: int) -> int:
    """A value axis as a non-negative index (the tangent's axes are the value's, then k)."""
    return axis + ndim if axis < 0 else axis


def _tangent_index(index: typing.Any) -> typing.Any:
    """The index of a tangent for an ``index`` of the value: the trailing axis k kept whole."""
    index = index if isinstance(index, tuple) else (index,)
    return (*index, slice(None)) if any(i is Ellipsis for i in index) else index


class Dual(np.lib.mixins.NDArrayOperatorsMixin):
    """Values (shape S) and their derivatives along k directions (shape S + (k,)).

    Attributes:
        value: the values, a float array.
        tangent: d value / d(direction), the directions last.
    """

    __slots__ = ("tangent", "value")

    def __init__(self, value: np.ndarray, tangent: np.ndarray):
        self.value, self.tangent = np.asarray(value), np.asarray(tangent)

    @classmethod
    def seed(cls, x: np.ndarray) -> Dual:
        """The independent variables x (P, ...): the derivatives of each row with respect to its
        own entries, k = x[0].size directions in C order (row p's entry i along direction i)."""
        k = int(np.prod(x.shape[1:]))
        return cls(x, np.broadcast_to(np.eye(k).reshape(*x.shape[1:], k), (*x.shape, k)))

    @property
    def directions(self) -> int:
        return self.tangent.shape[-1]

    @property
    def shape(self) -> tuple[int, ...]:
        return self.value.shape

    @property
    def ndim(self) -> int:
        return self.value.ndim

    def __len__(self) -> int:
        return len(self.value)

    def __repr__(self) -> str:
        return f"Dual(shape={self.shape}, directions={self.directions})"

    def __getitem__(self, index: typing.Any) -> Dual:
        return Dual(self.value[index], self.tangent[_tangent_index(index)])

    def __setitem__(self, index: typing.Any, other: typing.Any) -> None:
        if not self.tangent.flags.writeable:
            self.tangent = self.tangent.copy()
        self.value[index] = primal(other)
        self.tangent[_tangent_index(index)] = _tangent(other)

    # in-place operators make a new dual (a tangent may be a broadcast view)
    def __iadd__(self, other: typing.Any) -> Dual:
        return self + other

    def __isub__(self, other: typing.Any) -> Dual:
        return self - other

    def __imul__(self, other: typing.Any) -> Dual:
        return self * other

    def __itruediv__(self, other: typing.Any) -> Dual:
        return self / other

    def reshape(self, *shape: int) -> Dual:
        """The values reshaped to ``shape`` (no -1), the directions kept last."""
        return Dual(self.value.reshape(shape), self.tangent.reshape(*shape, self.directions))

    def sum(self, axis: int, keepdims: bool = False) -> Dual:
        """np.sum along a value axis."""
        return np.sum(self, axis=axis, keepdims=keepdims)

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if method != "__call__" or "out" in kwargs or ufunc not in _UFUNCS:
            return NotImplemented
        return _UFUNCS[ufunc](*inputs)

    def __array_function__(self, func, types, args, kwargs):
        if func not in _FUNCTIONS:
            return NotImplemented
        if func is np.zeros:  # np.zeros(shape, like=dual): a constant with this dual's directions
            value = np.zeros(*args, **kwargs)
            return Dual(value, np.zeros((*value.shape, self.directions)))
        return _FUNCTIONS[func](*args, **kwargs)


def _add(a, b) -> Dual:
    value = np.add(primal(a), primal(b))
    if isinstance(a, Dual) and isinstance(b, Dual):
        tangent = a.tangent + b.tangent
    else:
        tangent = a.tangent if isinstance(a, Dual) else b.tangent
    return Dual(value, np.broadcast_to(tangent, (*value.shape, _k(a, b))))


def _subtract(a, b) -> Dual:
    value = np.subtract(primal(a), primal(b))
    if isinstance(a, Dual) and isinstance(b, Dual):
        tangent = a.tangent - b.tangent
    else:
        tangent = a.tangent if isinstance(a, Dual) else -b.tangent
    return Dual(value, np.broadcast_to(tangent, (*value.shape, _k(a, b))))


def _multiply(a, b) -> Dual:
    va, vb = primal(a), primal(b)
    tangent = 0.0
    if isinstance(a, Dual):
        tangent = a.tangent * np.asarray(vb)[..., None]
    if isinstance(b, Dual):
        tangent = tangent + np.asarray(va)[..., None] * b.tangent
    value = np.multiply(va, vb)
    return Dual(value, np.broadcast_to(tangent, (*value.shape, _k(a, b))))


def _divide(a, b) -> Dual:
    vb = np.asarray(primal(b))
    value = np.true_divide(primal(a), vb)
    tangent = _tangent(a)
    if isinstance(b, Dual):
        tangent = tangent - value[..., None] * b.tangent
    return Dual(value, np.broadcast_to(tangent / vb[..., None], (*value.shape, _k(a, b))))


def _negative(a: Dual) -> Dual:
    return Dual(np.negative(a.value), np.negative(a.tangent))


def _sqrt(a: Dual) -> Dual:
    value = np.sqrt(a.value)
    return Dual(value, a.tangent / (2.0 * value)[..., None])


def _comparison(ufunc: np.ufunc) -> typing.Callable:
    """A comparison: of the values (a branch decision)."""
    return lambda a, b: ufunc(primal(a), primal(b))


def _k(*arrays) -> int:
    return next(a.directions for a in arrays if isinstance(a, Dual))


_UFUNCS = {np.add: _add, np.subtract: _subtract, np.multiply: _multiply, np.true_divide: _divide,
           np.negative: _negative, np.sqrt: _sqrt,
           **{u: _comparison(u) for u in (np.equal, np.not_equal, np.less, np.less_equal, np.greater,
                                          np.greater_equal)}}


def _einsum(subscripts: str, *operands) -> Dual:
    """Product rule: one term per dual operand, its tangent (the directions' letter added)
    contracted with the other operands' values (:func:`_tangent_term`)."""
    inputs, output = subscripts.replace(" ", "").split("->")
    inputs = inputs.split(",")
    letter = next(c for c in reversed(string.ascii_letters) if c not in subscripts)
    values = [primal(o) for o in operands]
    tangent = 0.0
    for i, operand in enumerate(operands):
        if isinstance(operand, Dual):
            others = [(s, v) for j, (s, v) in enumerate(zip(inputs, values)) if j != i]
            tangent = tangent + _tangent_term(inputs[i] + letter, operand.tangent, others, output + letter)
    return Dual(np.einsum(subscripts, *values), tangent)


def _tangent_term(subscript: str, tangent: np.ndarray, others: list[tuple[str, np.ndarray]],
                  output: str) -> np.ndarray:
    """einsum of a tangent and constants ``others`` [(subscript, array)]: the constants contracted
    with each other first, then with the tangent as one batched matrix product."""
    if not others:
        return np.einsum(f"{subscript}->{output}", tangent)
    if len(others) > 1:
        kept = "".join(dict.fromkeys(c for s, _ in others for c in s if c in subscript or c in output))
        others = [(kept, np.einsum(",".join(s for s, _ in others) + "->" + kept, *(a for _, a in others)))]
    return _matrix_product(subscript, tangent, *others[0], output)


def _matrix_product(sa: str, a: np.ndarray, sb: str, b: np.ndarray, out: str) -> np.ndarray:
    """np.einsum(f"{sa},{sb}->{out}", a, b) as a batched matrix product (B, L, S) @ (B, S, R) of the
    indices in both and the output, in one and the output, in both only, R >= L: on the short
    axes of the segment integrals several times faster than einsum's loops. Any other pattern:
    einsum."""
    batch = [c for c in out if c in sa and c in sb]
    left, right = [c for c in out if c not in sb], [c for c in out if c not in sa]
    summed = [c for c in sa if c in sb and c not in out]
    if (len(set(sa)) < len(sa) or len(set(sb)) < len(sb) or len(batch) + len(left) + len(summed) != len(sa)
            or len(batch) + len(right) + len(summed) != len(sb)):
        return np.einsum(f"{sa},{sb}->{out}", a, b)
    size = dict(zip(sb, b.shape))
    size.update((c, n) for c, n in zip(sa, a.shape) if n != 1 or c not in size)  # the broadcast sizes
    if np.prod([size[c] for c in left]) > np.prod([size[c] for c in right]):
        return _matrix_product(sb, b, sa, a, out)  # matmul is fastest with the longer axis last
    a = np.broadcast_to(a, [size[c] for c in sa]).transpose([sa.index(c) for c in batch + left + summed])
    b = np.broadcast_to(b, [size[c] for c in sb]).transpose([sb.index(c) for c in batch + summed + right])
    n = [int(np.prod([size[c] for c in group], dtype=np.int64)) for group in (batch, left, summed, right)]
    product = np.matmul(a.reshape(n[0], n[1], n[2]), b.reshape(n[0], n[2], n[3]))
    order = batch + left + right
    return product.reshape([size[c] for c in order]).transpose([order.index(c) for c in out])


def _joined(function: typing.Callable, arrays: typing.Sequence, axis: int, ndim: int) -> Dual:
    """np.stack or np.concatenate of duals and constants along a value axis of ``ndim`` axes."""
    k = _k(*arrays)
    tangents = [a.tangent if isinstance(a, Dual) else np.zeros((*np.shape(a), k)) for a in arrays]
    return Dual(function([primal(a) for a in arrays], axis=axis), function(tangents, axis=_axis(axis, ndim)))


def _stack(arrays: typing.Sequence, axis: int = 0) -> Dual:
    return _joined(np.stack, arrays, axis, np.ndim(primal(arrays[0])) + 1)


def _concatenate(arrays: typing.Sequence, axis: int = 0) -> Dual:
    return _joined(np.concatenate, arrays, axis, np.ndim(primal(arrays[0])))


def _where(condition: np.ndarray, a, b) -> Dual:
    value = np.where(condition, primal(a), primal(b))
    k = _k(a, b)
    tangent = np.where(np.asarray(condition)[..., None], _tangent(a), _tangent(b))
    return Dual(value, np.broadcast_to(tangent, (*value.shape, k)))


def _sum(a: Dual, axis: int, keepdims: bool = False) -> Dual:
    """The sum along a value axis; the tangents' by einsum (np.sum along an inner axis is slow)."""
    value = np.sum(a.value, axis=axis, keepdims=keepdims)
    letters = string.ascii_letters[:a.tangent.ndim]
    summed = letters[_axis(axis, a.ndim)]
    tangent = np.einsum(f"{letters}->{letters.replace(summed, '')}", a.tangent)
    return Dual(value, tangent.reshape(*value.shape, a.directions))


def _cross(a, b) -> Dual:
    """Cross products along the last value axis."""
    va, vb = primal(a), primal(b)
    tangent = 0.0
    if isinstance(a, Dual):
        tangent = np.cross(a.tangent, np.asarray(vb)[..., None], axis=-2)
    if isinstance(b, Dual):
        tangent = tangent + np.cross(np.asarray(va)[..., None], b.tangent, axis=-2)
    return Dual(np.cross(va, vb), tangent)


def _roll(a: Dual, shift: int, axis: int) -> Dual:
    return Dual(np.roll(a.value, shift, axis=axis), np.roll(a.tangent, shift, axis=_axis(axis, a.ndim)))


def _swapaxes(a: Dual, axis1: int, axis2: int) -> Dual:
    return Dual(np.swapaxes(a.value, axis1, axis2),
                np.swapaxes(a.tangent, _axis(axis1, a.ndim), _axis(axis2, a.ndim)))


def _solve(a, b) -> Dual:
    """x = a^{-1} b of stacked matrices (..., m, m), (..., m, n); dx = a^{-1} (db - da x)."""
    va = primal(a)
    x = np.linalg.solve(va, primal(b))
    k = _k(a, b)
    rhs = _tangent(b)
    if isinstance(a, Dual):  # da x, summed over the m columns (faster than einsum on these shapes)
        rhs = rhs - sum(a.tangent[..., :, j, None, :] * x[..., j, None, :, None] for j in range(va.shape[-1]))
    rhs = np.broadcast_to(rhs, (*x.shape, k))
    dx = np.matmul(_inverse(va), rhs.reshape(*rhs.shape[:-2], rhs.shape[-2] * rhs.shape[-1]))
    return Dual(x, dx.reshape(rhs.shape))


def _inverse(a: np.ndarray) -> np.ndarray:
    """Inverses of stacked matrices (..., m, m), for the tangents: 2 x 2 ones by their adjugate."""
    if a.shape[-1] != 2:
        return np.linalg.inv(a)
    adjugate = np.stack([a[..., 1, 1], -a[..., 0, 1], -a[..., 1, 0], a[..., 0, 0]], axis=-1)
    return (adjugate / (a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0])[..., None]).reshape(a.shape)


_FUNCTIONS = {np.einsum: _einsum, np.stack: _stack, np.concatenate: _concatenate, np.where: _where,
              np.sum: _sum, np.cross: _cross, np.roll: _roll, np.swapaxes: _swapaxes, np.linalg.solve: _solve,
              np.zeros: None}  # np.zeros(..., like=dual): Dual.__array_function__
