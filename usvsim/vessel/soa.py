"""Structure-of-arrays C for a CasADi step Function: the loop over boats innermost, vectorised.

:func:`soa_source` walks the Function's algorithm (``Function.n_instructions()``,
``instruction_id/input/output/constant``) and writes one C loop over a block of boats whose body
is that algorithm, one statement per instruction on per-boat scalars. Inputs and outputs are
arrays over the block (``s[k * B + j]`` is state k of boat j), so the compiler turns the loop
into vector code (``#pragma omp simd``): eight boats per AVX-512 instruction. Common
subexpressions are merged first (CasADi's ``cse``: the same operations on the same operands). The
algorithm's ``sin``, ``cos``, ``fmod``, ``fmin`` and ``fmax`` go to branch-free inline stand-ins;
other C-library functions (``atan2``, ...) to glibc's vector math library (libmvec) where
``-DUSV_SIMD_MATH`` is given, else to the C library (then the loop stays scalar).

Numbers (tested: ``tests/usvsim/vessel/test_soa.py``): arithmetic, ``sqrt``, ``fabs``,
comparisons, ``fmin``/``fmax`` and ``fmod`` give CasADi's virtual machine's results, up to the
compiler's fused multiply-add contraction (as in the scalar generated code); ``sin`` and ``cos``
are within 1 ulp of glibc's (tested on 250k arguments), libmvec's ``atan2`` within 4 ulp of the
correctly rounded value (glibc manual, "Errors in Math Functions"). No fast-math:
``-fno-math-errno`` only stops ``errno`` from being set, it changes no number.

The stand-ins cover the arguments a plant meets: ``fmod`` (exact, the C library's bits) where
``|x / y| < 2⁵⁰``, ``sin`` and ``cos`` where ``|x| < 10⁵``. Elsewhere (and for NaN and
infinities) the kernel flags the boat and the driver recomputes that boat's sub-step with the
scalar CasADi-generated function, which calls the C library.

The driver (``usv_soa_batch``) has the scalar driver's signature (``usv_batch`` in
:mod:`usvsim.vessel.codegen`): blocks of B boats go to OpenMP threads; per block the state stays in
block arrays over all sub-steps (a block short of B boats is filled with copies of its first,
so that every boat runs through the same vector code: a boat's numbers do not depend on the
batch it is in), each sub-step's per-step input is gathered from its pool
(:class:`usvsim.vessel.codegen.GatheredSteps`) or generated
(:class:`usvsim.vessel.pcg64.Pcg64Uniforms`, the block's eight streams in vector code) into a
block array, and each sub-step's leading states (all, or a count given) are written to the
(N, n_sub, count) trajectory, the last state to its own array.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["BLOCK", "SoaUnsupportedError", "soa_source"]

#: Boats per block: the vector loop's length (a multiple of 8 doubles, one AVX-512 register);
#: 8, 16 and 32 measured within 5 % of each other at N = 1024, and 8 costs least at N = 1
#: (the weather plant's larger kernel runs in blocks of 16: usvsim.vessel.weather_plant).
BLOCK = 8


class SoaUnsupportedError(ValueError):
    """The Function uses an operation or input layout the generator does not write."""


def _op(name: str) -> int:
    return int(getattr(ca, name))


# C expression of each supported operation on its operands {0} and {1}: the same operation, in
# the same rounding, as CasADi's virtual machine (casadi/core/calculus.hpp)
_EXPR: dict[int, str] = {
    _op("OP_ASSIGN"): "{0}",
    _op("OP_ADD"): "{0} + {1}",
    _op("OP_SUB"): "{0} - {1}",
    _op("OP_MUL"): "{0} * {1}",
    _op("OP_DIV"): "{0} / {1}",
    _op("OP_NEG"): "-{0}",
    _op("OP_TWICE"): "2.0 * {0}",
    _op("OP_SQ"): "{0} * {0}",
    _op("OP_INV"): "1.0 / {0}",
    _op("OP_SQRT"): "sqrt({0})",
    _op("OP_FABS"): "fabs({0})",
    _op("OP_FLOOR"): "floor({0})",
    _op("OP_CEIL"): "ceil({0})",
    _op("OP_COPYSIGN"): "copysign({0}, {1})",
    _op("OP_SIGN"): "({0} < 0.0 ? -1.0 : ({0} > 0.0 ? 1.0 : {0}))",
    _op("OP_LT"): "(double)({0} < {1})",
    _op("OP_LE"): "(double)({0} <= {1})",
    _op("OP_EQ"): "(double)({0} == {1})",
    _op("OP_NE"): "(double)({0} != {1})",
    _op("OP_NOT"): "(double)(!{0})",
    _op("OP_AND"): "(double)(({0} != 0.0) & ({1} != 0.0))",
    _op("OP_OR"): "(double)(({0} != 0.0) | ({1} != 0.0))",
    _op("OP_IF_ELSE_ZERO"): "({0} != 0.0 ? {1} : 0.0)",
    _op("OP_FMIN"): "usv_vfmin({0}, {1})",
    _op("OP_FMAX"): "usv_vfmax({0}, {1})",
    _op("OP_FMOD"): "usv_vfmod({0}, {1})",
}
# other C library functions: vectorised by libmvec where USV_SIMD_MATH is defined
_LIBM_UNARY = ("tan", "exp", "log", "tanh", "asin", "acos", "atan")
_LIBM_BINARY = ("atan2", "pow")
for _name in _LIBM_UNARY:
    _EXPR[_op(f"OP_{_name.upper()}")] = _name + "({0})"
for _name in _LIBM_BINARY:
    _EXPR[_op(f"OP_{_name.upper()}")] = _name + "({0}, {1})"
_EXPR[_op("OP_CONSTPOW")] = "pow({0}, {1})"
_EXPR[_op("OP_SIN")] = "usv_vsin({0})"
_EXPR[_op("OP_COS")] = "usv_vcos({0})"
_LIBM_OF_OP = {_op(f"OP_{name.upper()}"): name for name in (*_LIBM_UNARY, *_LIBM_BINARY)}
_LIBM_OF_OP[_op("OP_CONSTPOW")] = "pow"

_HELPERS = r"""
#include <math.h>
#include <string.h>
/* always: GCC's inliner stops at its growth limits in a kernel this long, and a call left in
   the loop stops the vectoriser */
#define USV_INLINE static inline __attribute__((always_inline))
/* fmin/fmax with the C library's results (NaN ignored, x returned when x == y, so ±0 as glibc),
   branch-free so that they vectorise */
USV_INLINE double usv_vfmax(double x, double y) {
  return isnan(x) ? y : (isnan(y) ? x : (x >= y ? x : y));
}
USV_INLINE double usv_vfmin(double x, double y) {
  return isnan(x) ? y : (isnan(y) ? x : (x <= y ? x : y));
}
/* fmod with the C library's bits where |x / y| < 2^50: the remainder is exactly representable,
   so x - n y with the right integer n, by one FMA, is it. n comes from x * (1 / y) (1 / y is
   folded where y is a constant, as 2 pi is: no division), within 2 ulp of x / y, so at most one
   off, and is corrected by one where it is. Elsewhere (NaN, infinities, huge quotients) the
   kernel flags the sub-step (usv_vfmod_special) and the driver recomputes it with the C
   library. */
USV_INLINE double usv_vfmod_special(double x, double y) { /* y = inf: fma(-0, inf, x) is NaN */
  double quotient_ok = fabs(x * (1.0 / y)) < 1125899906842624.0 ? 0.0 : 1.0;
  return fabs(y) <= 1.7976931348623157e308 ? quotient_ok : 1.0;
}
USV_INLINE double usv_vtrunc(double q) { /* trunc(q) for |q| < 2^53 (sign of 0 aside) */
  double a = fabs(q);
  double t = (a + 4503599627370496.0) - 4503599627370496.0; /* a rounded to an integer */
  t = t > a ? t - 1.0 : t;
  return copysign(a < 4503599627370496.0 ? t : a, q); /* from 2^52 on a is an integer */
}
USV_INLINE double usv_vfmod(double x, double y) {
  double n = usv_vtrunc(x * (1.0 / y)); /* trunc() would not vectorise (trapping math) */
  double r = fma(-n, y, x);
  double away = (x < 0.0) == (y < 0.0) ? 1.0 : -1.0; /* sign of the quotient */
  /* n - away where r and x differ in sign (r != 0), n + away where |r| >= |y|: select only */
  double step = fabs(r) >= fabs(y) ? away : 0.0;
  step = r != 0.0 ? (copysign(1.0, r) != copysign(1.0, x) ? -away : step) : step;
  r = fma(-(n + step), y, x);
  return r == 0.0 ? copysign(0.0, x) : r;
}
/* sin and cos inline (a call to a vector library spills every register): x = k pi/2 + r with
   |r| <= pi/4 by Cody-Waite reduction (pi/2 in three parts, 159 bits; the first step exact, the
   others by FMA), fdlibm's minimax polynomials on [-pi/4, pi/4] (error below 1 ulp; musl
   src/math/__sin.c, __cos.c), the quadrant k mod 4. For |x| < 1e5 only: elsewhere (and for NaN
   and infinities) the kernel flags the sub-step (usv_vtrig_special). */
USV_INLINE double usv_vtrig_special(double x) { return fabs(x) < 1e5 ? 0.0 : 1.0; }
USV_INLINE double usv_vround(double x) { /* nearest integer (ties to even), |x| < 2^51 */
  return (x + 6755399441055744.0) - 6755399441055744.0;
}
USV_INLINE double usv_ksin(double x) {
  const double S1 = -0x1.5555555555549p-3, S2 = 0x1.111111110f8a6p-7,
               S3 = -0x1.a01a019c161d5p-13, S4 = 0x1.71de357b1fe7dp-19,
               S5 = -0x1.ae5e68a2b9cebp-26, S6 = 0x1.5d93a5acfd57cp-33;
  double z = x * x, w = z * z;
  double r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
  return x + z * x * (S1 + z * r);
}
USV_INLINE double usv_kcos(double x) {
  const double C1 = 0x1.555555555554cp-5, C2 = -0x1.6c16c16c15177p-10,
               C3 = 0x1.a01a019cb159p-16, C4 = -0x1.27e4f809c52adp-22,
               C5 = 0x1.1ee9ebdb4b1c4p-29, C6 = -0x1.8fae9be8838d4p-37;
  double z = x * x, w = z * z;
  double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
  double hz = 0.5 * z, one_hz = 1.0 - hz;
  return one_hz + (((1.0 - one_hz) - hz) + z * r);
}
/* r = x - k pi/2 and m = k mod 4 in {0, 1, 2, 3}; the quadrant's sign and sin/cos choice by
   arithmetic on m and one select (nested selects on masks do not vectorise in GCC 12) */
USV_INLINE double usv_vreduce(double x, double* m) {
  double k = usv_vround(x * 0x1.45f306dc9c883p-1);
  *m = k - 4.0 * usv_vround(0.25 * k - 0.375);
  double r = fma(-k, 0x1.921fb54442d18p+0, x);
  r = fma(-k, 0x1.1a62633145c07p-54, r);
  return fma(-k, -0x1.f1976b7ed8fbcp-110, r);
}
USV_INLINE double usv_vsin(double x) { /* [s, c, -s, -c][m] */
  double m, r = usv_vreduce(x, &m);
  double h = usv_vround(0.5 * m - 0.25); /* m >= 2 */
  double v = m - 2.0 * h != 0.0 ? usv_kcos(r) : usv_ksin(r);
  v = (1.0 - 2.0 * h) * v;
  return x == 0.0 ? x : v; /* sin(-0) = -0 (the reduction gives +0) */
}
USV_INLINE double usv_vcos(double x) { /* [c, -s, -c, s][m] */
  double m, r = usv_vreduce(x, &m);
  double h = usv_vround(0.5 * m - 0.25), odd = m - 2.0 * h;
  double v = odd != 0.0 ? usv_ksin(r) : usv_kcos(r);
  return (1.0 - 2.0 * (h + odd - 2.0 * h * odd)) * v; /* - for m = 1, 2 */
}
"""

_DEFINES = r"""
#undef NS
#undef NPS
#define B {block}
#define NS {ns}
#define NA {na}
#define NPS {nps}
#define NPS1 (NPS > 0 ? NPS : 1)
#define NREC {record}
/* usv_pcg_double for the B boats of a block at once: each boat's 128-bit state as two 64-bit
   halves, the product by the multiplier modulo 2^128 from 64-bit products (the high half of
   the low product from 32-bit pieces), so that the loop vectorises; the same numbers
   (tested against Generator.random) */
USV_INLINE void usv_pcg_doubles(unsigned long long* restrict hi, unsigned long long* restrict lo,
                                usv_u128 inc, double* restrict out) {{
  const unsigned long long m_hi = (unsigned long long)(USV_PCG_MULT >> 64);
  const unsigned long long m_lo = (unsigned long long)USV_PCG_MULT;
  const unsigned long long i_hi = (unsigned long long)(inc >> 64);
  const unsigned long long i_lo = (unsigned long long)inc;
  const unsigned long long b0 = m_lo & 0xffffffffULL, b1 = m_lo >> 32;
  #pragma omp simd
  for (int j = 0; j < B; ++j) {{
    unsigned long long l = lo[j], h = hi[j];
    unsigned long long a0 = l & 0xffffffffULL, a1 = l >> 32;
    unsigned long long p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    unsigned long long mid = (p00 >> 32) + (p01 & 0xffffffffULL) + (p10 & 0xffffffffULL);
    unsigned long long high = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    unsigned long long new_lo = l * m_lo + i_lo;
    unsigned long long new_hi = high + h * m_lo + l * m_hi + i_hi + (new_lo < i_lo ? 1ULL : 0ULL);
    lo[j] = new_lo;
    hi[j] = new_hi;
    unsigned long long x = new_hi ^ new_lo;
    unsigned long long rot = new_hi >> 58;
    x = (x >> rot) | (x << ((64ULL - rot) & 63ULL));
    out[j] = (double)(long long)(x >> 11) * (1.0 / 9007199254740992.0);
  }}
}}
"""

_DRIVER = r"""/* the scalar generated function, for the boats whose sub-step the kernel flags */
static void usv_scalar_lane(int j, const double* s, const double* wb, const double* g,
                            const double* e, double* out) {{
  {{
    double sj[NS], wj[NA > 0 ? NA : 1], ej[NPS1], oj[NS];
    const casadi_real* arg[{sz_arg}];
    casadi_real* res[{sz_res}];
    casadi_int iw[{sz_iw} + 1];
    casadi_real w[{sz_w} + 1];
    for (int m = 0; m < NS; ++m) sj[m] = s[m * B + j];
    for (int m = 0; m < NA; ++m) wj[m] = wb[m * B + j];
    for (int m = 0; m < NPS; ++m) ej[m] = e[m * B + j];
    arg[0] = sj; arg[1] = wj; arg[2] = g; arg[3] = ej;
    res[0] = oj;
    {fname}(arg, res, iw, w, 0);
    for (int m = 0; m < NS; ++m) out[m * B + j] = oj[m];
  }}
}}

void usv_soa_batch(int n, int n_sub, const double* s0, const double* shared_in,
                   const double* per_boat, int n_per_boat, const double* pool, int n_pool,
                   const long long* index, const double* factor,
                   const unsigned long long* pcg, int n_rec, double* traj, double* last) {{
  int n_blocks = (n + B - 1) / B;
  /* Pcg64Uniforms: boat i's draws start (i n_sub NPS) steps after the given state; one boat's
     stride as an affine map, each block's first boat by a jump */
  usv_u128 pcg_state = 0, pcg_inc = 0, boat_mult = 1, boat_plus = 0;
  if (pcg) {{
    usv_pcg_unpack(pcg, &pcg_state, &pcg_inc);
    usv_pcg_stride(pcg_inc, (unsigned long long)n_sub * NPS, &boat_mult, &boat_plus);
  }}
  /* dynamic: on a loaded machine a thread that runs takes the blocks of one that waits.
     Threads only from 2,048 boat-substeps: one takes ~90 ns, waking a second thread ~70 us
     (2026-12-03, quiet, plant + filter, 20 sub-steps: 64 boats 142 us in one thread, 153 us
     in two; 128 boats 248 / 211 us; 256 boats 485 / 358 us) */
  #pragma omp parallel for schedule(dynamic, 1) if((long)n * n_sub >= 2048)
  for (int b = 0; b < n_blocks; ++b) {{
    double state[2][NS * B] __attribute__((aligned(64)));
    double *s = state[0], *s_next = state[1];
    double wb[(NA > 0 ? NA : 1) * B] __attribute__((aligned(64)));
    double e[NPS1 * B] __attribute__((aligned(64)));
    double flag[B] __attribute__((aligned(64)));
    int i0 = b * B, nb = n - i0 < B ? n - i0 : B;
    /* a block short of B boats is filled up with copies of its first: every boat goes through
       the same vector code, so a boat's numbers do not depend on the batch it is in */
    unsigned long long lane_hi[B] __attribute__((aligned(64)));
    unsigned long long lane_lo[B] __attribute__((aligned(64)));
    usv_u128 lane = 0;
    for (int j = 0; j < B; ++j) {{
      long i = i0 + (j < nb ? j : 0);
      for (int m = 0; m < NS; ++m) s[m * B + j] = s0[i * NS + m];
      for (int m = 0; m < NA; ++m) wb[m * B + j] = per_boat[i * n_per_boat + m];
      if (pcg) {{
        if (j == 0)
          lane = usv_pcg_advance(pcg_state, pcg_inc, (unsigned long long)i0 * n_sub * NPS);
        else if (j < nb)
          lane = boat_mult * lane + boat_plus;
        else /* a filled-up boat repeats the block's first */
          lane = ((usv_u128)lane_hi[0] << 64) | lane_lo[0];
        lane_hi[j] = (unsigned long long)(lane >> 64);
        lane_lo[j] = (unsigned long long)lane;
      }}
    }}
    for (int k = 0; k < n_sub; ++k) {{
      for (int m = 0; m < NPS; ++m) {{
        if (pcg) {{
          usv_pcg_doubles(lane_hi, lane_lo, pcg_inc, e + m * B);
          continue;
        }}
        long long c = index[k * NPS + m];
        double f = factor[k * NPS + m];
        for (int j = 0; j < B; ++j)
          e[m * B + j] = c >= 0 ? pool[(i0 + (j < nb ? j : 0)) * (long)n_pool + c] * f : f;
      }}
      usv_soa_kernel(s, wb, shared_in, e, s_next, flag);
      for (int j = 0; j < nb; ++j)
        if (flag[j] != 0.0) usv_scalar_lane(j, s, wb, shared_in, e, s_next);
      for (int j = 0; j < nb; ++j) {{
        double* row = traj + ((long)(i0 + j) * n_sub + k) * n_rec;
        /* loops of constant length for the whole state and the count the stepper was built
           for (a loop of variable length costs the weather plant 3 % of its call) */
        if (n_rec == NS)
          for (int m = 0; m < NS; ++m) row[m] = s_next[m * B + j];
        else if (n_rec == NREC)
          for (int m = 0; m < NREC; ++m) row[m] = s_next[m * B + j];
        else
          for (int m = 0; m < n_rec; ++m) row[m] = s_next[m * B + j];
      }}
      double* done = s;
      s = s_next;
      s_next = done;
    }}
    if (last)
      for (int j = 0; j < nb; ++j)
        for (int m = 0; m < NS; ++m) last[(long)(i0 + j) * NS + m] = s[m * B + j];
  }}
}}
"""


def _simd_declarations(libm: set[str]) -> str:
    """Declarations that let the vectoriser call libmvec's variants of ``libm`` functions."""
    lines = ["#ifdef USV_SIMD_MATH"]
    for name in sorted(libm):
        args = "double, double" if name in _LIBM_BINARY else "double"
        lines.append(f'extern double {name}({args}) __attribute__((simd("notinbranch"), const));')
    lines.append("#endif")
    return "\n".join(lines) + "\n"


def _check_layout(fn: ca.Function) -> None:
    if fn.n_in() not in (3, 4) or fn.n_out() != 1:
        raise SoaUnsupportedError("the step Function must have 3 or 4 inputs and one output")
    for i in range(fn.n_in()):
        if not (fn.sparsity_in(i).is_dense() and fn.size2_in(i) == 1):
            raise SoaUnsupportedError(f"input {i} of {fn.name()} is not a dense column")
    if not (fn.sparsity_out(0).is_dense() and fn.size2_out(0) == 1):
        raise SoaUnsupportedError(f"the output of {fn.name()} is not a dense column")
    if not fn.is_a("SXFunction"):
        raise SoaUnsupportedError(f"{fn.name()} is not an SX Function (expand it first)")


def _kernel(fn: ca.Function) -> tuple[str, set[str]]:
    """``usv_soa_kernel``: one sub-step of B boats, and the C library functions it calls."""
    _check_layout(fn)
    # common subexpressions once (sin ψ of RK4's first stage and of the autopilot, ...): the
    # same operations on the same operands, so the same numbers
    sx_in = fn.sx_in()
    fn = ca.Function(fn.name(), sx_in, fn.call(sx_in), {"cse": True})
    op_input, op_output, op_const = _op("OP_INPUT"), _op("OP_OUTPUT"), _op("OP_CONST")
    op_fmod, op_trig = _op("OP_FMOD"), (_op("OP_SIN"), _op("OP_COS"))
    # input i, nonzero m of boat j: state, per-boat and per-step inputs are block arrays, the
    # shared input one number for all boats, read before the loop (a load the compiler sinks
    # into a select's branch would need a masked load of one address, which does not vectorise)
    source = {0: "s[{m} * B + j]", 1: "wb[{m} * B + j]", 2: "g{m}", 3: "e[{m} * B + j]"}
    shared = ", ".join(f"g{m} = g[{m}]" for m in range(fn.nnz_in(2))) if fn.nnz_in(2) else ""
    body: list[str] = []
    libm: set[str] = set()
    for k in range(fn.n_instructions()):
        op = fn.instruction_id(k)
        if op == op_input:
            i, m = fn.instruction_input(k)
            body.append(f"w{fn.instruction_output(k)[0]} = {source[i].format(m=m)};")
        elif op == op_output:
            m = fn.instruction_output(k)[1]
            body.append(f"out[{m} * B + j] = w{fn.instruction_input(k)[0]};")
        elif op == op_const:
            value = float(fn.instruction_constant(k))
            # hexadecimal: the constant's exact bits; inf and nan by name
            literal = value.hex() if value == value and abs(value) != float("inf") else None
            if literal is None:
                literal = "NAN" if value != value else ("-INFINITY" if value < 0 else "INFINITY")
            body.append(f"w{fn.instruction_output(k)[0]} = {literal};")
        elif op in _EXPR:
            args = [f"w{a}" for a in fn.instruction_input(k)]
            if op == op_fmod:
                body.append(f"special += usv_vfmod_special({args[0]}, {args[1]});")
            elif op in op_trig:
                body.append(f"special += usv_vtrig_special({args[0]});")
            body.append(f"w{fn.instruction_output(k)[0]} = {_EXPR[op].format(*args)};")
            if op in _LIBM_OF_OP:
                libm.add(_LIBM_OF_OP[op])
        else:
            raise SoaUnsupportedError(f"{fn.name()}: CasADi operation {op} has no C stand-in here")
    work = ", ".join(f"w{i}" for i in range(fn.sz_w()))
    shared_decl = f"const double {shared};" if shared else ""
    lines = "\n      ".join(body)
    kernel = f"""
/* one sub-step of B boats; flag[j] != 0 where boat j needs the C library (a count as a
   double: an int |= here made GCC branch). B is a constant: no remainder loop, whose code (and
   C-library calls) could differ from the vector loop's */
static void usv_soa_kernel(const double* restrict s, const double* restrict wb,
                           const double* restrict g, const double* restrict e,
                           double* restrict out, double* restrict flag) {{
  {shared_decl}
  #pragma omp simd
  for (int j = 0; j < B; ++j) {{
      double special = 0.0;
      double {work};
      {lines}
      flag[j] = special;
  }}
}}
"""
    return kernel, libm


def soa_source(
    fn: ca.Function, scalar_source: str, block: int = BLOCK, record: int | None = None
) -> str:
    """C source of ``usv_soa_batch`` for ``fn(s, per_boat, shared[, per_step]) -> s_next``.

    ``scalar_source`` is the scalar CasADi-generated code of ``fn`` (it defines the function
    named ``fn.name()``), used for sub-steps with special ``fmod`` arguments; ``record`` the
    count of leading states recorded per sub-step that gets a loop of constant length besides
    the whole state's (default: the whole state). Raises :class:`SoaUnsupportedError` for an
    operation without a stand-in here.
    """
    if block < 8 or block % 8:
        raise ValueError(f"block must be a positive multiple of 8 boats, got {block}")
    kernel, libm = _kernel(fn)
    defines = _DEFINES.format(
        block=block,
        ns=fn.size1_in(0),
        na=fn.size1_in(1),
        nps=fn.size1_in(3) if fn.n_in() == 4 else 0,
        record=fn.size1_in(0) if record is None else int(record),
    )
    driver = _DRIVER.format(
        sz_arg=max(fn.sz_arg(), 4),
        sz_res=fn.sz_res(),
        sz_iw=fn.sz_iw(),
        sz_w=fn.sz_w(),
        fname=fn.name(),
    )
    return _HELPERS + _simd_declarations(libm) + scalar_source + defines + kernel + driver
