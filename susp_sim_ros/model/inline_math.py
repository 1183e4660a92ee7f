"""Elementary functions the compiled kernel inlines instead of calling the C maths library.

Every exponential in the model has a non-positive argument: Dahl elements ``expm1(-sigma |dx| / Fc)``,
tyre relaxation ``expm1(-|v| dt / L)``, the velocity scaling ``1 - exp(-(|v| - v_ref) / v_s)`` and the
tyre characteristic ``tanh`` (written through ``expm1(-2|x|)``). The kernel steps a block of vehicles
with SIMD instructions (see ``_kernel_template.py``); a call into libm cannot be vectorised and would
make the compiler step every vehicle of the block one by one. These are plain arithmetic without
branches, so they vectorise.

Accuracy: ``expm1_nonpos`` within 1 ulp of ``math.expm1`` on [-40, 0], ``tanh`` within 3 ulp of
``math.tanh`` (both tested); below -40 ``expm1`` is -1 to double precision; NaN stays NaN.

Method: Cody-Waite reduction ``x = k ln2 + r``, ``|r| <= ln2 / 2`` (fdlibm's split of ln2, exact for
the small ``k`` used here), Taylor polynomial of ``expm1(r)`` to degree 13 in Estrin's scheme
(truncation error below 1e-17 relative), then ``expm1(x) = 2^k expm1(r) + (2^k - 1)``, both parts
exact or single-rounded (for ``k = 0`` exactly ``expm1(r)``).
"""
from __future__ import annotations

import math

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

_LN2_HI = 6.93147180369123816490e-01  # fdlibm: ln2 with its low 32 bits zero, so k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e+00
_X_MIN = -40.0  # exp(-40) < 2^-57: below this expm1 rounds to -1
# divisor floor where a quotient is computed for every vehicle but kept only where the divisor is > 0
# (branch-free code evaluates both sides of a select)
TINY = 1e-300
# 1/n! for n = 2 .. 13
_C2, _C3, _C4, _C5, _C6, _C7 = 0.5, 1 / 6, 1 / 24, 1 / 120, 1 / 720, 1 / 5040
_C8, _C9, _C10 = 1 / 40320, 1 / 362880, 1 / 3628800
_C11, _C12, _C13 = 1 / 39916800, 1 / 479001600, 1 / 6227020800


@intrinsic
def _pow2(typingctx, k):
    """``2.0 ** k`` for an integral float ``k`` in [-1022, 1023], built from its exponent bits."""
    def codegen(context, builder, sig, args):
        i64 = ir.IntType(64)
        biased = builder.add(builder.fptosi(args[0], i64), ir.Constant(i64, 1023))
        bits = builder.shl(biased, ir.Constant(i64, 52))
        return builder.bitcast(bits, ir.DoubleType())
    return types.float64(types.float64), codegen


@njit(cache=True, inline="always")
def expm1_nonpos(x):
    """``exp(x) - 1`` for ``x <= 0`` (only that domain: positive ``x`` gives wrong results)."""
    x = _X_MIN if x < _X_MIN else x
    k = math.floor(x * _INV_LN2 + 0.5)
    r = (x - k * _LN2_HI) - k * _LN2_LO
    r2 = r * r
    r4 = r2 * r2
    q = (((_C2 + _C3 * r) + (_C4 + _C5 * r) * r2) + ((_C6 + _C7 * r) + (_C8 + _C9 * r) * r2) * r4
         + ((_C10 + _C11 * r) + (_C12 + _C13 * r) * r2) * (r4 * r4))
    e = r + r2 * q
    # NaN: any exponent; e is NaN and so is the result. (In compiled code an @intrinsic is called without
    # its typing context, which numba's stubs cannot express.)
    t: float = _pow2(k if k == k else 0.0)  # type: ignore[call-arg]
    return t * e + (t - 1.0)


@njit(cache=True, inline="always")
def tanh(x):
    """``tanh(x)`` as ``-e / (e + 2)`` with ``e = expm1(-2|x|)``, the sign of ``x`` restored."""
    e = expm1_nonpos(-2.0 * abs(x))
    y = -e / (e + 2.0)
    return y if x >= 0.0 else -y
