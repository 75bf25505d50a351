"""Branch-free elementary functions: the same bits for one sample or for a vectorised loop over lanes, on any CPU.

Every function here is built only from IEEE-754 double ``+ - * /``, ``sqrt``, comparisons and selects,
integer adds/shifts/ands and float<->int *bit casts* (no int<->float value conversion, which is poison in
LLVM for out-of-range values and not a single instruction on AVX2). No libm call, no FMA (numba emits no
``contract`` flags and we never use fastmath), no reassociation: so each result depends only on the
argument, whether LLVM vectorises the calling loop (SSE2, AVX2, AVX-512) or not. The algorithms and
coefficients are those of fdlibm / FreeBSD msun / musl (Sun Microsystems 1993, "Permission to use, copy,
modify, and distribute this software is freely granted"), made branch-free: every case is computed and the
answer chosen by selects.

Integer rounding uses the "shifter" trick: ``(y + 1.5*2^52) - 1.5*2^52`` is ``y`` rounded to the nearest
integer (ties to even) for ``|y| < 2^51``, and the low bits of ``y + 1.5*2^52`` *are* that integer
(two's complement), which a bit cast reads without any float->int conversion.

Why not the C library: a loop over lanes can be vectorised only if every call in it is inlined, and libm's
functions are calls (numba has no vector math library here); glibc also picks its own variant by CPU. These are
plain code, inlined and vectorised with the loop. Accuracy against a long-double reference (1e6 points per range,
``tests/numerics/test_elementary.py``, 2e5 seeded points per range; a scan of 8.4e6 points near exp's switch
points): exp 0.92 ulp, expm1 0.83, log 0.80, tanh 1.31, sin/cos 0.79 for |x| <= 1.6e6, x^0.26 0.87; special
values (0, -0, subnormals, +-inf, nan, the overflow and underflow thresholds) as glibc's. sin/cos beyond
|x| = 1.6e6, where the three-part reduction is no longer exact, return nan (the model never gets there: a
guard that trips beats a silently wrong sine).
"""

import math

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from numerics.jit import SCALAR


# ---------------------------------------------------------------------------------------------------------
# bit casts (LLVM `bitcast`: a no-op on the register, vectorises to nothing)
# ---------------------------------------------------------------------------------------------------------
@intrinsic
def as_int(typingctx, x):
    """The 64 bits of a float64 as an int64 (another float or an integer is converted to float64 first)."""
    if not isinstance(x, (types.Float, types.Integer)):
        return None

    def codegen(context, builder, signature, args):
        value = context.cast(builder, args[0], signature.args[0], types.float64)
        return builder.bitcast(value, ir.IntType(64))

    return types.int64(x), codegen


@intrinsic
def as_float(typingctx, i):
    """The float64 whose 64 bits are the int64 ``i``."""
    if not isinstance(i, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        value = context.cast(builder, args[0], signature.args[0], types.int64)
        return builder.bitcast(value, ir.DoubleType())

    return types.float64(i), codegen


if numba.config.DISABLE_JIT:  # pure Python (the mutation runs): the bit casts on Python ints, wrapped to int64
    def as_int(x):  # noqa: F811
        return int(np.float64(x).view(np.int64))

    def as_float(i):  # noqa: F811
        return float(np.int64((int(i) + 2**63) % 2**64 - 2**63).view(np.float64))


SHIFTER = 6755399441055744.0          # 1.5 * 2^52: (y + SHIFTER) - SHIFTER = rint(y) for |y| < 2^51
SHIFTER_BITS = 0x4338000000000000     # its bit pattern
SIGN_BIT = -9223372036854775808       # 0x8000000000000000 as int64
ABS_MASK = 0x7FFFFFFFFFFFFFFF

LN2_HI = 6.93147180369123816490e-01   # 0x3fe62e42fee00000: 32 bits, so k * LN2_HI is exact for |k| < 2^21
LN2_LO = 1.90821492927058770002e-10   # 0x3dea39ef35793c76: ln 2 - LN2_HI
INV_LN2 = 1.44269504088896338700e+00  # 0x3ff71547652b82fe

# fdlibm e_exp.c: Remez minimax of R(r^2) = r (e^r + 1)/(e^r - 1) on [0, 0.34658^2], |error| < 2^-59
EXP_P1 = 1.66666666666666019037e-01
EXP_P2 = -2.77777777770155933842e-03
EXP_P3 = 6.61375632143793436117e-05
EXP_P4 = -1.65339022054652515390e-06
EXP_P5 = 4.13813679705723846039e-08

# fdlibm s_expm1.c: scaled Remez coefficients of R1(r^2/2), |error| < 2^-61
EXPM1_Q1 = -3.33333333333331316428e-02
EXPM1_Q2 = 1.58730158725481460165e-03
EXPM1_Q3 = -7.93650757867487942473e-05
EXPM1_Q4 = 4.00821782732936239552e-06
EXPM1_Q5 = -2.01099218183624371326e-07

# fdlibm e_log.c / musl log.c: Remez of (log(1+f) - 2s)/s with s = f/(2+f), |error| < 2^-58.45
LG1 = 6.666666666666735130e-01
LG2 = 3.999999999940941908e-01
LG3 = 2.857142874366239149e-01
LG4 = 2.222219843214978396e-01
LG5 = 1.818357216161805012e-01
LG6 = 1.531383769920937332e-01
LG7 = 1.479819860511658591e-01

# fdlibm e_rem_pio2.c (medium case): pi/2 in three 33-bit pieces and their tails
INV_PIO2 = 6.36619772367581382433e-01  # 0x3fe45f306dc9c883
PIO2_1 = 1.57079632673412561417e+00    # 0x3ff921fb54400000
PIO2_1T = 6.07710050650619224932e-11
PIO2_2 = 6.07710050630396597660e-11    # 0x3dd0b4611a600000
PIO2_2T = 2.02226624879595063154e-21
PIO2_3 = 2.02226624871116645580e-21    # 0x3ba3198a2e000000
PIO2_3T = 8.47842766036889956997e-32
SIN_COS_MAX = 1.6e6                    # |x| up to which the reduction is exact (|n| < 2^20); beyond: nan

# FreeBSD k_sin.c / k_cos.c (Bruce Evans' 2008 branch-free k_cos): Remez on [-pi/4, pi/4]
S1 = -1.66666666666666324348e-01
S2 = 8.33333333332248946124e-03
S3 = -1.98412698298579493134e-04
S4 = 2.75573137070700676789e-06
S5 = -2.50507602534068634195e-08
S6 = 1.58969099521155010221e-10
C1 = 4.16666666666666019037e-02
C2 = -1.38888888888741095749e-03
C3 = 2.48015872894767294178e-05
C4 = -2.75573143513906633035e-07
C5 = 2.08757232129817482790e-09
C6 = -1.13596475577881948265e-11


@numba.njit(**SCALAR)
def pow2i(k):
    """2^k as a float for an int64 -1022 <= k <= 1023 (bit construction)."""
    return as_float((k + 1023) << 52)


@numba.njit(**SCALAR)
def exp(x):
    """e^x, fdlibm e_exp.c made branch-free (< 1 ulp, module docstring).

    x = k ln2 + r, |r| <= ln2/2 (Cody-Waite: k ln2 in two parts, LN2_HI exact in k * LN2_HI);
    e^r = 1 + r + r c/(2 - c) with c = r - r^2 R(r^2), R a degree-5 minimax polynomial (fdlibm).
    The result y * 2^k is formed as (y * 2^k1) * 2^k2 with k1 = floor(k/2): the first product is exact
    and normal, so subnormal results are rounded once, and 2^k1, 2^k2 are always normal.
    Edge cases: x > 709.78 -> inf, x < -745.13 -> 0 (gradual underflow in between), +-inf -> inf / 0,
    nan -> nan, +-0 -> 1.
    """
    xc = 710.0 if x > 710.0 else x          # nan passes both clamps (comparisons are false)
    xc = -750.0 if xc < -750.0 else xc
    t = xc * INV_LN2 + SHIFTER
    kf = t - SHIFTER
    hi = xc - kf * LN2_HI
    lo = kf * LN2_LO
    r = hi - lo
    z = r * r
    c = r - z * (EXP_P1 + z * (EXP_P2 + z * (EXP_P3 + z * (EXP_P4 + z * EXP_P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    k = as_int(t) - SHIFTER_BITS             # the integer k, exactly, without a conversion
    k1 = (((k + 2048) & 4095) >> 1) - 1024   # floor(k/2) for |k| < 2048; the mask lets LLVM use a logical
                                             # shift (AVX2 has no packed 64-bit arithmetic shift)
    return (y * pow2i(k1)) * pow2i(k - k1)


@numba.njit(**SCALAR)
def expm1(x):
    """e^x - 1, fdlibm s_expm1.c with each of its cases computed and selected (< 1 ulp).

    Same reduction as exp, with the correction c of the rounded r; expm1(r) from a rational form in
    r^2/2 with a degree-5 minimax polynomial (fdlibm). The reconstruction 2^k (expm1(r) + 1) - 1 is done
    in fdlibm's five ways (k = 0, -1, 1, 2..19, 20..56, other) to avoid cancellation; all are computed.
    Edge cases: |x| < 2^-54 -> x (so -0 -> -0, subnormals exact), x < -45 -> -1, x > 709.78 -> inf,
    -inf -> -1, +inf -> inf, nan -> nan.
    """
    xc = 710.0 if x > 710.0 else x
    xc = -45.0 if xc < -45.0 else xc
    t = xc * INV_LN2 + SHIFTER
    kf = t - SHIFTER
    hi = xc - kf * LN2_HI
    lo = kf * LN2_LO
    r = hi - lo
    c = (hi - r) - lo
    hfx = 0.5 * r
    hxs = r * hfx
    r1 = 1.0 + hxs * (EXPM1_Q1 + hxs * (EXPM1_Q2 + hxs * (EXPM1_Q3 + hxs * (EXPM1_Q4 + hxs * EXPM1_Q5))))
    tt = 3.0 - r1 * hfx
    e = hxs * ((r1 - tt) / (6.0 - r * tt))
    e = (r * (e - c) - c) - hxs              # for k = 0, c = 0: fdlibm's x*e - hxs
    k = as_int(t) - SHIFTER_BITS
    k1 = (((k + 2048) & 4095) >> 1) - 1024   # floor(k/2) for |k| < 2048; the mask lets LLVM use a logical
                                             # shift (AVX2 has no packed 64-bit arithmetic shift)
    s1 = pow2i(k1)
    s2 = pow2i(k - k1)
    kc = 0 if k < 0 else (60 if k > 60 else k)
    two_mk = pow2i(-kc)                      # 2^-k for the cases that use it
    y_k0 = r - e
    y_km1 = 0.5 * (r - e) - 0.5
    y_k1 = -2.0 * (e - (r + 0.5)) if r < -0.25 else 1.0 + 2.0 * (r - e)
    y_far = ((1.0 - (e - r)) * s1) * s2 - 1.0
    y_mid = (((1.0 - two_mk) - (e - r)) * s1) * s2
    y_high = (((r - (e + two_mk)) + 1.0) * s1) * s2
    y = y_high
    y = y_mid if k < 20 else y
    y = y_far if (k <= -2) | (k > 56) else y
    y = y_k1 if k == 1 else y
    y = y_km1 if k == -1 else y
    y = y_k0 if k == 0 else y
    return x if abs(x) < 5.551115123125783e-17 else y   # 2^-54; nan: the comparison is false, y is nan


# Cephes tanh.c (S. L. Moshier, 1984-1987): tanh x = x + x z P(z)/Q(z), z = x^2, for |x| < 0.625
# (P of degree 2, Q monic of degree 3; peak relative error 2.5e-16 in Cephes' own IEEE test)
TANH_P0 = -9.64399179425052238628e-1
TANH_P1 = -9.92877231001918586564e1
TANH_P2 = -1.61468768441708447952e3
TANH_Q0 = 1.12811678491632931402e2
TANH_Q1 = 2.23548839060100448583e3
TANH_Q2 = 4.84406305325125486048e3


@numba.njit(**SCALAR)
def tanh(x):
    """tanh x, Cephes tanh.c made branch-free (< 1.5 ulp, module docstring).

    |x| < 0.625: the Cephes rational form x + x z P(z)/Q(z); else 1 - 2/(e^(2|x|) + 1) with exp and |x|
    clamped to 22 (tanh 22 rounds to 1). Both are computed, one is selected; the sign is copied bit-wise
    (tanh(-0) = -0). +-inf -> +-1, nan -> nan, subnormal x -> x.
    """
    a = abs(x)
    a = 22.0 if a > 22.0 else a
    s = exp(2.0 * a)
    big = 1.0 - 2.0 / (s + 1.0)
    z = a * a
    small = a + a * z * ((TANH_P0 * z + TANH_P1) * z + TANH_P2) / (((z + TANH_Q0) * z + TANH_Q1) * z + TANH_Q2)
    y = small if a < 0.625 else big
    return as_float(as_int(y) | (as_int(x) & SIGN_BIT))


@numba.njit(**SCALAR)
def log(x):
    """Natural logarithm, musl log.c (fdlibm e_log.c's single-formula form), branch-free (< 1 ulp).

    x = 2^k (1 + f), sqrt(2)/2 < 1 + f < sqrt(2) (integer ops on the bits); s = f/(2 + f);
    log(1+f) = f - hfsq + s (hfsq + R(s^2)), R of degree 14 in s (fdlibm); + k ln2 in two parts.
    Subnormals are scaled by 2^54 first (select). Edge cases: +-0 -> -inf, x < 0 (and -inf) -> nan,
    +inf -> +inf, nan -> nan, 1 -> +0.
    """
    sub = x < 2.2250738585072014e-308
    xs = x * 18014398509481984.0 if sub else x
    ix = as_int(xs) + 0x00095F6200000000      # (0x3ff00000 - 0x3fe6a09e) << 32
    k = ((ix >> 52) & 0x7FF) - 1023 - (54 if sub else 0)
    ix = (ix & 0x000FFFFFFFFFFFFF) + 0x3FE6A09E00000000
    f = as_float(ix) - 1.0
    hfsq = 0.5 * f * f
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    t1 = w * (LG2 + w * (LG4 + w * LG6))
    t2 = z * (LG1 + w * (LG3 + w * (LG5 + w * LG7)))
    rr = t2 + t1
    dk = as_float(k + SHIFTER_BITS) - SHIFTER  # float(k), exactly, without a conversion
    y = s * (hfsq + rr) + dk * LN2_LO - hfsq + f + dk * LN2_HI
    y = math.inf if x == math.inf else y
    y = -math.inf if x == 0.0 else y
    y = math.nan if x < 0.0 else y
    return x if x != x else y


SPLITTER = 134217729.0                # 2^27 + 1 (Veltkamp/Dekker split)
POW_Y = 0.26                          # the double nearest 0.26, as in pow(x, 0.26)
POW_Y_HI = 0.25999999791383743        # its Veltkamp split: SPLITTER*y - (SPLITTER*y - y), 26 bits
POW_Y_LO = 2.086162576020456e-09      # POW_Y - POW_Y_HI, exact; POW_Y_HI + POW_Y_LO == POW_Y
assert POW_Y_HI == SPLITTER * POW_Y - (SPLITTER * POW_Y - POW_Y) and POW_Y_HI + POW_Y_LO == POW_Y


@numba.njit(**SCALAR)
def _split(a):
    c = SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


@numba.njit(**SCALAR)
def _two_prod(a, b):
    """p + e == a b exactly, Dekker (1971) without FMA; |a|, |b| < 2^995."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@numba.njit(**SCALAR)
def _log_dd(x):
    """log x as hi + lo with ~2^-60 relative error, for x > 0 finite (specials: the caller).

    musl log's reduction x = 2^k (1 + f) and polynomial R, but log(1+f) = 2s + s R(s^2) with s = f/(2+f)
    carried as s_hi + s_lo: 2+f by fast two-sum, s_hi (2+f) by Dekker's product, the division's residual
    exact, so s_lo is its quotient; k ln2_hi + 2 s_hi by two-sum (k ln2_hi and 2 s_hi are exact)."""
    sub = x < 2.2250738585072014e-308
    xs = x * 18014398509481984.0 if sub else x
    ix = as_int(xs) + 0x00095F6200000000
    k = ((ix >> 52) & 0x7FF) - 1023 - (54 if sub else 0)
    ix = (ix & 0x000FFFFFFFFFFFFF) + 0x3FE6A09E00000000
    f = as_float(ix) - 1.0
    u = 2.0 + f
    u_lo = f - (u - 2.0)                     # exact: 2 + f == u + u_lo
    s = f / u
    p, pe = _two_prod(s, u)
    s_lo = (((f - p) - pe) - s * u_lo) / u   # f - p is exact (Sterbenz)
    z = s * s
    w = z * z
    t1 = w * (LG2 + w * (LG4 + w * LG6))
    t2 = z * (LG1 + w * (LG3 + w * (LG5 + w * LG7)))
    rr = t2 + t1
    dk = as_float(k + SHIFTER_BITS) - SHIFTER
    a = dk * LN2_HI                          # exact
    b = 2.0 * s                              # exact
    hi = a + b
    bb = hi - a
    err = (a - (hi - bb)) + (b - bb)         # two-sum: a + b == hi + err
    lo = err + (((2.0 * s_lo) + s * rr) + dk * LN2_LO)
    h = hi + lo
    return h, lo - (h - hi)


@numba.njit(**SCALAR)
def _exp_tail(x, xl):
    """e^(x + xl) for a tail |xl| <~ ulp(x): exp with the tail folded into the reduction's low part."""
    xc = 710.0 if x > 710.0 else x
    xc = -750.0 if xc < -750.0 else xc
    t = xc * INV_LN2 + SHIFTER
    kf = t - SHIFTER
    hi = xc - kf * LN2_HI
    lo = kf * LN2_LO - xl
    r = hi - lo
    z = r * r
    c = r - z * (EXP_P1 + z * (EXP_P2 + z * (EXP_P3 + z * (EXP_P4 + z * EXP_P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    k = as_int(t) - SHIFTER_BITS
    k1 = (((k + 2048) & 4095) >> 1) - 1024   # floor(k/2) for |k| < 2048; the mask lets LLVM use a logical
                                             # shift (AVX2 has no packed 64-bit arithmetic shift)
    return (y * pow2i(k1)) * pow2i(k - k1)


@numba.njit(**SCALAR)
def pow026(x):
    """x^0.26 (the double 0.26, as pow(x, 0.26)) for the rolling-friction law (Eqs. 5.20, 5.22): < 1 ulp.

    exp(0.26 log x) with log x in double-double (_log_dd), 0.26 (hi + lo) by Dekker's product with 0.26's
    precomputed split, and exp of the double-double result (_exp_tail).
    Edge cases (C99 pow): +-0 -> +0, +inf and -inf -> +inf, x < 0 -> nan, nan -> nan, 1 -> 1.
    """
    h, h_lo = _log_dd(x)
    hh, hl = _split(h)
    p = POW_Y * h
    pe = ((POW_Y_HI * hh - p) + POW_Y_HI * hl + POW_Y_LO * hh) + POW_Y_LO * hl
    y = _exp_tail(p, pe + POW_Y * h_lo)
    y = math.nan if x < 0.0 else y
    y = math.inf if abs(x) == math.inf else y
    y = 0.0 if x == 0.0 else y
    return x if x != x else y


@numba.njit(**SCALAR)
def _sin_kernel(x, y):
    # FreeBSD k_sin.c with its "iy != 0" form (y = tail of the reduced argument), |x| <= pi/4
    z = x * x
    w = z * z
    r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6)
    v = z * x
    return x - ((z * (0.5 * y - v * r) - y) - v * S1)


@numba.njit(**SCALAR)
def _cos_kernel(x, y):
    # FreeBSD k_cos.c (2008, branch-free), |x| <= pi/4
    z = x * x
    w = z * z
    r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - x * y))


@numba.njit(**SCALAR)
def _reduce_pio2(x):
    """x = n pi/2 + (y0 + y1), fdlibm e_rem_pio2.c's medium case with all three rounds always taken:
    pi/2 to 33 + 33 + 33 + 53 bits, so y0 + y1 is accurate for |n| < 2^20 (|x| < 1.6e6).
    Returns (y0, y1, n mod 4)."""
    t = x * INV_PIO2 + SHIFTER
    fn = t - SHIFTER
    r = x - fn * PIO2_1                      # exact: fn * PIO2_1 is exact for |fn| < 2^20
    tt = r
    w = fn * PIO2_2
    r = tt - w
    err2 = (tt - r) - w                      # exact rounding error of round 2 (fast two-sum)
    tt = r
    w = fn * PIO2_3                          # round 3 replaces fn * PIO2_2T by fn * (PIO2_3 + PIO2_3T);
    r = tt - w                               # fdlibm takes it only after a cancellation, where err2 = 0,
    w = (fn * PIO2_3T - ((tt - r) - w)) - err2   # so taken always it must carry err2
    y0 = r - w
    y1 = (r - y0) - w
    return y0, y1, as_int(t) & 3


@numba.njit(**SCALAR)
def sin(x):
    """sin x (fdlibm s_sin.c, branch-free; < 1 ulp for |x| < 1.6e6, nan beyond).

    +-0 -> +-0, +-inf -> nan, nan -> nan.
    """
    y0, y1, q = _reduce_pio2(x)
    s = _sin_kernel(y0, y1)
    c = _cos_kernel(y0, y1)
    v = c if (q & 1) == 1 else s
    v = -v if (q & 2) == 2 else v
    return math.nan if abs(x) > SIN_COS_MAX else v


@numba.njit(**SCALAR)
def cos(x):
    """cos x, as sin (the encoders need both)."""
    y0, y1, q = _reduce_pio2(x)
    s = _sin_kernel(y0, y1)
    c = _cos_kernel(y0, y1)
    v = s if (q & 1) == 1 else c
    v = -v if ((q + 1) & 2) == 2 else v
    return math.nan if abs(x) > SIN_COS_MAX else v
