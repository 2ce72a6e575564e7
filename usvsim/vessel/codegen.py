"""Batched evaluation of a CasADi step function: compiled C generated from it, or CasADi ``map``.

The CasADi Function stays the single source of truth. Two compiled kernels are generated from it:

- ``soa`` (the default): structure-of-arrays C written from the Function's algorithm by
  :mod:`usvsim.vessel.soa`, the loop over a block of boats innermost and vectorised (AVX-512 on
  this CPU), built with ``-O3 -march=native`` and, where that build fails, a portable one;
- ``scalar``: the C code of ``casadi.CodeGenerator`` wrapped in a small driver that loops over
  boats (OpenMP across cores) and over sub-steps, keeping each boat's state in registers/cache.

Each shared library is compiled on first use with the system C compiler and cached by the hash of
its source, flags, compiler and CPU. Both agree with the CasADi Function to rounding (1e-9
relative is tested). Measured on 2 cores (``usvsim perf``): see the README.

A per-step input (e.g. sensor noise) can be passed as :class:`GatheredSteps`, a pool of numbers
per boat and a small layout table: the driver builds each step's input itself, so no
(N, steps, inputs) array is built in Python; NumPy's uniforms can be passed as
:class:`usvsim.vessel.pcg64.Pcg64Uniforms`, a generator state from which the driver generates
them. :meth:`BatchStepper.run_recorded` writes only a trajectory's leading states and the final
state. The generated code's ``fmod``, ``fmax`` and ``fmin``
calls go to exact stand-ins (same bits as the C library, fewer cycles; see ``_EXACT_LIBM``).

Where no C compiler is found the fallback evaluates ``Function.map(N, "thread", 2)`` in CasADi's
virtual machine: the same numbers to rounding, 20-60× slower.
"""

from __future__ import annotations

import ctypes
import os
import re
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.common.cbuild import CompileError, cache_dir, compile_library, cpu_signature
from usvsim.vessel.pcg64 import PCG64_C_SOURCE, Pcg64Uniforms
from usvsim.vessel.soa import BLOCK, SoaUnsupportedError, soa_source

__all__ = [
    "BACKENDS",
    "SOA_BUILDS",
    "BatchStepper",
    "CompileError",
    "GatheredSteps",
    "cache_dir",
]

#: ``auto``: the fastest that builds (soa, else scalar, else casadi); ``compiled``: soa, else
#: scalar, else an error; ``soa``, ``scalar``, ``casadi``: that one only.
Backend = Literal["auto", "compiled", "soa", "scalar", "casadi"]
BACKENDS: tuple[Backend, ...] = ("auto", "compiled", "soa", "scalar", "casadi")
# -fno-plt and -Bsymbolic: calls between the generated functions go straight to them, not
# through the PLT; they change how functions are called, never what they compute
_CFLAGS = [
    "-O3",
    "-march=native",
    "-fPIC",
    "-shared",
    "-fopenmp",
    "-fno-fast-math",
    "-fno-plt",
    "-Wl,-Bsymbolic",
]
# The structure-of-arrays kernel: builds tried in turn until one compiles and links. No
# fast-math: -fno-math-errno only stops errno from being set (so that sqrt vectorises). Tuning
# (measured on this CPU, the order of independent instructions only): scheduling before register
# allocation, aware of register pressure (the kernel keeps ~100 values live), 1.15x; 512-bit
# vectors, 1.4x the 256-bit ones GCC prefers here. -Wl,-z,defs turns a vector function missing
# from an older libmvec into a link error here, not a failure at call.
_SOA_BASE = [
    "-O3",
    "-fPIC",
    "-shared",
    "-fopenmp",
    "-fno-fast-math",
    "-fno-math-errno",
    "-fno-plt",
    "-Wl,-Bsymbolic",
]
_SOA_TUNED = [*_SOA_BASE, "-fschedule-insns", "-fsched-pressure"]
_SOA_NATIVE = ["-march=native", "-mprefer-vector-width=512"]
_SOA_VECTOR_MATH = ["-DUSV_SIMD_MATH", "-Wl,-z,defs", "-lmvec"]
#: The structure-of-arrays builds in the order tried: (name, compiler flags).
SOA_BUILDS: tuple[tuple[str, list[str]], ...] = (
    ("native+libmvec", [*_SOA_TUNED, *_SOA_NATIVE, *_SOA_VECTOR_MATH]),
    ("native", [*_SOA_TUNED, *_SOA_NATIVE]),
    ("portable+libmvec", [*_SOA_TUNED, *_SOA_VECTOR_MATH]),  # the compiler's default target
    ("portable", _SOA_BASE),  # plain -O3 and OpenMP: any GCC-compatible compiler
)


# Exact stand-ins for three C library functions the generated code calls. Each returns the
# library's (glibc's) bits for every input: an fmod result is always exactly representable, so
# x - n·y with the right integer n, computed by one FMA, is it (n from the rounded quotient,
# corrected by one where the quotient rounded across an integer; infinities, NaN, y = 0 and huge
# quotients go to the library); fmax/fmin return the non-NaN argument and x when x == y (so
# ±0 as glibc). usv_fmod is never inlined and fmax/fmin are called only from CasADi's
# out-of-line helpers, so the generated arithmetic (and its FMA contraction) compiles exactly as
# before: only the calls get cheaper.
_EXACT_LIBM = r"""
#include <math.h>
__attribute__((noinline)) static double usv_fmod(double x, double y) {
  if (!isfinite(x) || !isfinite(y) || y == 0.0 || fabs(x / y) >= 9007199254740992.0)
    return fmod(x, y);
  double n = trunc(x / y);
  double r = fma(-n, y, x);
  double away = (x < 0.0) == (y < 0.0) ? 1.0 : -1.0;  /* sign of the quotient */
  if (r != 0.0 && (r < 0.0) != (x < 0.0)) { n -= away; r = fma(-n, y, x); }
  else if (fabs(r) >= fabs(y)) { n += away; r = fma(-n, y, x); }
  return r == 0.0 ? copysign(0.0, x) : r;
}
static inline double usv_fmax(double x, double y) {
  return isnan(x) ? y : (isnan(y) ? x : (x >= y ? x : y));
}
static inline double usv_fmin(double x, double y) {
  return isnan(x) ? y : (isnan(y) ? x : (x <= y ? x : y));
}
"""

_DRIVER = r"""
#include <string.h>
#define NS {ns}
#define NPS {nps}
/* per-step input (k, j) of boat i: pool[i, index[k, j]] * factor[k, j], or factor[k, j] where
   index[k, j] < 0 (see GatheredSteps); where pcg is given, the uniforms of Pcg64Uniforms.
   traj (N, n_sub, n_rec) receives the first n_rec states after each sub-step, last (N, NS)
   (where given) the final state */
void usv_batch(int n, int n_sub, const double* s0, const double* shared_in,
               const double* per_boat, int n_per_boat, const double* pool, int n_pool,
               const long long* index, const double* factor,
               const unsigned long long* pcg, int n_rec, double* traj, double* last) {{
  usv_u128 pcg_state = 0, pcg_inc = 0;
  if (pcg) usv_pcg_unpack(pcg, &pcg_state, &pcg_inc);
  #pragma omp parallel for schedule(static) if(n >= 64)
  for (int i = 0; i < n; ++i) {{
    double s[NS], s_next[NS], e[NPS > 0 ? NPS : 1];
    const casadi_real* arg[{sz_arg}];
    casadi_real* res[{sz_res}];
    casadi_int iw[{sz_iw} + 1];
    casadi_real w[{sz_w} + 1];
    const double* row = pool ? pool + (long)i * n_pool : 0;
    usv_u128 lane = pcg ? usv_pcg_advance(pcg_state, pcg_inc,
                                          (unsigned long long)i * n_sub * NPS) : 0;
    memcpy(s, s0 + (long)i * NS, sizeof(s));
    for (int k = 0; k < n_sub; ++k) {{
      arg[0] = s;
      arg[1] = per_boat + (long)i * n_per_boat;
      arg[2] = shared_in;
      if (NPS > 0) {{
        for (int j = 0; j < NPS; ++j) {{
          if (pcg) {{
            e[j] = usv_pcg_double(&lane, pcg_inc);
            continue;
          }}
          long long c = index[k * NPS + j];
          e[j] = c >= 0 ? row[c] * factor[k * NPS + j] : factor[k * NPS + j];
        }}
        arg[3] = e;
      }}
      res[0] = s_next;
      {fname}(arg, res, iw, w, 0);
      memcpy(s, s_next, sizeof(s));
      memcpy(traj + ((long)i * n_sub + k) * n_rec, s_next, n_rec * sizeof(double));
    }}
    if (last) memcpy(last + (long)i * NS, s, sizeof(s));
  }}
}}
"""


def _generate_source(fn: ca.Function) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        name = "gen.c"
        gen = ca.CodeGenerator(name, {"with_header": False, "casadi_real": "double"})
        gen.add(fn)
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            gen.generate()
        finally:
            os.chdir(cwd)
        body = (Path(tmp) / name).read_text()
    for libm in ("fmod", "fmax", "fmin"):  # whole-word calls only, not casadi_fmax( etc.
        body = re.sub(rf"\b{libm}\(", f"usv_{libm}(", body)
    driver = _DRIVER.format(
        ns=fn.size1_in(0),
        nps=fn.size1_in(3) if fn.n_in() == 4 else 0,
        sz_arg=fn.sz_arg(),
        sz_res=fn.sz_res(),
        sz_iw=fn.sz_iw(),
        sz_w=fn.sz_w(),
        fname=fn.name(),
    )
    return _EXACT_LIBM + PCG64_C_SOURCE + body + driver


def _compile(source: str, flags: list[str] | None = None) -> Path:
    """The shared library of ``source`` built with ``flags`` (default: the scalar path's)."""
    flags = _CFLAGS if flags is None else flags
    # the scalar path's key is unchanged (its libraries stay cached); others add the CPU
    return compile_library(source, flags, "" if flags is _CFLAGS else cpu_signature())


@dataclass(frozen=True)
class GatheredSteps:
    """Per-step inputs (N, n_sub, nps) given as a pool of numbers per boat and a layout.

    Entry (i, k, j) is ``pool[i, index[k, j]] * factor[k, j]`` where ``index[k, j] >= 0`` and the
    constant ``factor[k, j]`` where ``index[k, j] < 0``. Shapes: ``pool`` (N, M) float64,
    ``index`` (n_sub, nps) int64 in [-1, M), ``factor`` (n_sub, nps) float64. The compiled path
    builds each entry when the step needs it, without an (N, n_sub, nps) array in memory;
    :meth:`dense` builds that array in NumPy (the same products).
    """

    pool: NDArray[np.float64]
    index: NDArray[np.int64]
    factor: NDArray[np.float64]

    def dense(self) -> NDArray[np.float64]:
        """The per-step inputs as an (N, n_sub, nps) array."""
        gathered = self.pool[:, np.maximum(self.index, 0)] * self.factor
        return np.where(self.index >= 0, gathered, self.factor)


def _load_kernel(
    fn: ca.Function, kernel: str, record: int | None = None, block: int = BLOCK
) -> tuple[Callable[..., None], str]:
    """The compiled batch function (``usv_soa_batch`` or ``usv_batch``, one signature) of ``fn``
    and the name of its build.

    Raises :class:`CompileError` where no build succeeds, :class:`SoaUnsupportedError` where the
    structure-of-arrays generator lacks an operation of ``fn``.
    """
    # libgomp reads its wait policy once, when the first kernel loads it: passive (a thread done
    # with its boats sleeps at the barrier) unless the user set one. The default, spinning a
    # while, made 2 threads 6x slower than 1 on this 2-core machine while other jobs ran (the
    # spinning thread burns the CPU time its partner needs); quiet, it costs nothing measurable.
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    scalar = _generate_source(fn)
    if kernel == "scalar":
        batch, build = ctypes.CDLL(str(_compile(scalar))).usv_batch, "scalar"
    else:
        source, failures = soa_source(fn, scalar, block, record), []
        for build, flags in SOA_BUILDS:
            try:
                lib = _compile(source, flags)
            except CompileError as err:
                failures.append(f"{build}: " + (str(err).strip().splitlines() or ["failed"])[-1])
                continue
            batch = ctypes.CDLL(str(lib)).usv_soa_batch
            break
        else:
            raise CompileError("no structure-of-arrays build succeeded: " + " | ".join(failures))
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    batch.argtypes = [
        *(int_, int_),  # n, n_sub
        *(ptr, ptr),  # s0, shared
        *(ptr, int_),  # per_boat, its width
        *(ptr, int_, ptr, ptr),  # pool, its width, index, factor (GatheredSteps)
        ptr,  # Pcg64Uniforms.words (or NULL)
        int_,  # states recorded per sub-step
        *(ptr, ptr),  # trajectory out, final state out (or NULL)
    ]
    batch.restype = None
    return batch, build


#: What :meth:`BatchStepper.run` takes as per-step inputs.
PerStep = NDArray[np.float64] | GatheredSteps | Pcg64Uniforms


class BatchStepper:
    """Evaluate ``fn(s, per_boat, shared[, per_step]) -> s_next`` for N boats, ``n_sub`` steps.

    ``fn`` has three or four inputs (state, per-boat input held over the steps, input shared by
    all boats, and optionally an input per boat and step, e.g. sensor noise) and one output of
    the state's size. :meth:`run` returns the trajectory of states after each sub-step.

    ``backend`` (see ``Backend``) picks the kernel; :attr:`kernel` says which one runs
    (``soa``, ``scalar`` or ``casadi``) and :attr:`backend` whether it is compiled.
    ``record``: the count of leading states :meth:`run_recorded` will mostly record, which the
    structure-of-arrays driver copies in a loop of constant length (default: the whole state;
    any count works). ``block``: boats per vector block of that kernel (a multiple of 8; a
    boat's numbers do not depend on it).
    """

    def __init__(
        self,
        fn: ca.Function,
        backend: Backend = "auto",
        record: int | None = None,
        block: int = BLOCK,
    ) -> None:
        if fn.n_in() not in (3, 4) or fn.n_out() != 1 or fn.size1_out(0) != fn.size1_in(0):
            raise ValueError("BatchStepper needs fn(state, per_boat, shared[, per_step]) -> state")
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")
        self.fn = fn
        self.ns, self.na, self.ng = fn.size1_in(0), fn.size1_in(1), fn.size1_in(2)
        self.nps = fn.size1_in(3) if fn.n_in() == 4 else 0
        self._maps: dict[int, ca.Function] = {}
        self._batch: Callable[..., None] | None = None
        self.kernel: str = "casadi"
        self.build: str = "casadi"  # which compiled build runs (a name of SOA_BUILDS, "scalar")
        errors: list[str] = []
        for kernel in ("soa", "scalar"):
            if backend not in ("auto", "compiled", kernel):
                continue
            try:
                self._batch, self.build = _load_kernel(fn, kernel, record, block)
            except (CompileError, SoaUnsupportedError) as err:
                errors.append(f"{kernel}: {err}")
                continue
            self.kernel = kernel
            break
        if self._batch is None and backend not in ("auto", "casadi"):
            raise CompileError("; ".join(errors))
        self.backend: str = "casadi" if self._batch is None else "compiled"

    def run(
        self,
        s0: NDArray[np.float64],
        per_boat: NDArray[np.float64],
        shared: NDArray[np.float64],
        n_sub: int,
        per_step: PerStep | None = None,
    ) -> NDArray[np.float64]:
        """Trajectory (N, n_sub, ns) from states s0 (N, ns), inputs (N, na), shared (ng,) and,
        for a four-input ``fn``, per-step inputs (N, n_sub, nps), their :class:`GatheredSteps`
        or :class:`Pcg64Uniforms`."""
        return self.run_recorded(s0, per_boat, shared, n_sub, per_step, self.ns, final=False)[0]

    def run_recorded(
        self,
        s0: NDArray[np.float64],
        per_boat: NDArray[np.float64],
        shared: NDArray[np.float64],
        n_sub: int,
        per_step: PerStep | None,
        record: int,
        *,
        final: bool = True,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """As :meth:`run`, recording only the first ``record`` states of each sub-step: the
        trajectory (N, n_sub, record) and the final state (N, ns) (the same numbers as
        :meth:`run`'s, fewer bytes written). ``final=False`` (:meth:`run`'s call): the
        compiled kernel writes no final state and returns an empty (0, ns) array for it."""
        s0 = np.ascontiguousarray(s0, dtype=np.float64)
        per_boat = np.ascontiguousarray(per_boat, dtype=np.float64)
        shared = np.ascontiguousarray(shared, dtype=np.float64)
        n = s0.shape[0]
        # the C code trusts these sizes: check them here
        if s0.ndim != 2 or s0.shape[1] != self.ns:
            raise ValueError(f"state must have shape (N, {self.ns}), got {s0.shape}")
        if per_boat.shape != (n, self.na):
            raise ValueError(
                f"per-boat input must have shape ({n}, {self.na}), got {per_boat.shape}"
            )
        if shared.shape != (self.ng,):
            raise ValueError(f"shared input must have shape ({self.ng},), got {shared.shape}")
        if not isinstance(n_sub, (int, np.integer)) or n_sub < 1:
            raise ValueError(f"n_sub must be a positive integer, got {n_sub!r}")
        if not 1 <= record <= self.ns:
            raise ValueError(f"record must lie in [1, {self.ns}], got {record!r}")
        steps = self._checked_steps(per_step, n, int(n_sub))
        if self._batch is not None:
            traj = np.empty((n, n_sub, record))
            last = np.empty((n, self.ns) if final else (0, self.ns))
            gathered = steps if isinstance(steps, GatheredSteps) else None
            words = steps.words() if isinstance(steps, Pcg64Uniforms) else None
            self._batch(
                n,
                n_sub,
                s0.ctypes.data,
                shared.ctypes.data,
                per_boat.ctypes.data,
                self.na,
                None if gathered is None else gathered.pool.ctypes.data,
                0 if gathered is None else gathered.pool.shape[1],
                None if gathered is None else gathered.index.ctypes.data,
                None if gathered is None else gathered.factor.ctypes.data,
                None if words is None else words.ctypes.data,
                record,
                traj.ctypes.data,
                last.ctypes.data if final else None,
            )
            return traj, last
        fmap = self._maps.get(n)
        if fmap is None:
            fmap = self._maps[n] = self.fn.map(n, "thread", 2)
        dense: NDArray[np.float64] | None = None
        if isinstance(steps, Pcg64Uniforms):
            dense = steps.dense((n, int(n_sub), self.nps))
        elif steps is not None:
            dense = steps.dense()
        full = np.empty((n, n_sub, self.ns))
        s = s0.T
        for k in range(n_sub):
            extra = () if dense is None else (dense[:, k, :].T,)
            s = np.asarray(fmap(s, per_boat.T, shared, *extra))
            full[:, k, :] = s.T
        return np.ascontiguousarray(full[:, :, :record]), full[:, -1].copy()

    def _checked_steps(
        self, per_step: PerStep | None, n: int, n_sub: int
    ) -> GatheredSteps | Pcg64Uniforms | None:
        """``per_step`` as contiguous :class:`GatheredSteps` of checked shapes (the C code
        trusts them) or the :class:`Pcg64Uniforms` given; an (N, n_sub, nps) array becomes a
        pool read in order."""
        if not self.nps:
            if per_step is not None:
                raise ValueError("this step function takes no per-step input")
            return None
        if per_step is None:
            raise ValueError("this step function needs a per-step input")
        if isinstance(per_step, Pcg64Uniforms):
            return per_step
        if not isinstance(per_step, GatheredSteps):
            dense = np.ascontiguousarray(per_step, dtype=np.float64)
            if dense.shape != (n, n_sub, self.nps):
                raise ValueError(
                    f"per-step input must have shape ({n}, {n_sub}, {self.nps}), got {dense.shape}"
                )
            in_order = np.arange(n_sub * self.nps, dtype=np.int64).reshape(n_sub, self.nps)
            return GatheredSteps(dense.reshape(n, -1), in_order, np.ones((n_sub, self.nps)))
        pool = np.ascontiguousarray(per_step.pool, dtype=np.float64)
        index = np.ascontiguousarray(per_step.index, dtype=np.int64)
        factor = np.ascontiguousarray(per_step.factor, dtype=np.float64)
        if pool.ndim != 2 or pool.shape[0] != n:
            raise ValueError(f"per-step pool must have shape ({n}, M), got {pool.shape}")
        if index.shape != (n_sub, self.nps) or factor.shape != (n_sub, self.nps):
            raise ValueError(
                f"per-step index and factor must have shape ({n_sub}, {self.nps}), got "
                f"{index.shape} and {factor.shape}"
            )
        if index.max(initial=-1) >= pool.shape[1]:
            raise ValueError(f"per-step index reaches past the pool's {pool.shape[1]} columns")
        return GatheredSteps(pool, index, factor)
