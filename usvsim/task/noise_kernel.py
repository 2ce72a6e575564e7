"""The compiled per-boat noise streams: NumPy's ``Generator(PCG64).standard_normal``, N boats in
one C call, number for number.

:class:`usvsim.task.scenario.BoatNoise` serves boat i the sequence
``numpy.random.default_rng(seed_i).standard_normal(∞)``. Its NumPy path buffers each boat's
numbers and refills them boat by boat from the boat's ``Generator``; NumPy's normal costs about
15 ns there, most of it an unpredictable branch on the sign and a call through a pointer per
number. This kernel keeps each boat's PCG64 state (two 128-bit words, (N, 4) uint64) and draws in
C, OpenMP over boats:

- PCG64 is PCG-XSL-RR 128/64 (O'Neill 2014, "PCG: a family of simple fast space-efficient
  statistically good algorithms for random number generation", HMC-CS-2014-0905), the
  generator behind NumPy's ``PCG64``: step the 128-bit LCG, then output the xor-folded state
  rotated by its top six bits.
- The normal is NumPy's ziggurat (Marsaglia & Tsang 2000, 256 layers), whose first test
  decides about 99 % of numbers from the 64-bit draw alone: the kernel does that test itself,
  without a branch on the sign, with NumPy's own layer tables (``wi``: layer widths, ``ki``:
  acceptance limits). The rest (wedges and the tail) is handed to NumPy's own
  ``random_standard_normal`` (its C API, ``libnpyrandom``), fed the same 64-bit draw first and
  then the boat's stream.
- Seeding is NumPy's too: ``default_rng(seed)`` runs ``SeedSequence(seed)`` (O'Neill's
  ``seed_seq_fe`` hash mixing into four 32-bit words, then four 64-bit output words) and seeds
  PCG64's state and increment from them; the kernel does the same in C for seeds below 2⁶⁴.
- The tables are not copied from NumPy's source: :func:`load_kernel` reads them out of
  ``random_standard_normal`` itself at load time, by feeding it chosen 64-bit draws (a width is
  the value returned for the smallest non-zero draw of a layer; a limit is found by bisection
  as the first draw that leaves the fast test).

So the numbers equal NumPy's bit for bit, and the loader checks that they do (4,096 numbers of
four seeds, seeded in C, against ``Generator.standard_normal``) before it hands the kernel out.
Where the library does not build (no compiler, no ``libnpyrandom``) or the check fails, it
returns None and ``BoatNoise`` keeps its NumPy path.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from usvsim.common.cbuild import load_function

__all__ = ["KERNEL_SOURCE", "NoiseKernel", "load_kernel", "pcg64_states"]

KERNEL_SOURCE = r"""
#include <stdint.h>

/* numpy.random's C API (numpy/random/bitgen.h): a bit generator as NumPy's samplers take it */
typedef struct bitgen {
  void *state;
  uint64_t (*next_uint64)(void *st);
  uint32_t (*next_uint32)(void *st);
  double (*next_double)(void *st);
  uint64_t (*next_raw)(void *st);
} bitgen_t;

extern double random_standard_normal(bitgen_t *bitgen_state);  /* libnpyrandom */

typedef unsigned __int128 u128;
#define PCG_MULT ((((u128)0x2360ED051FC65DA4ULL) << 64) | 0x4385DF649FCCF645ULL)
#define MASK52 0x000FFFFFFFFFFFFFULL

static inline uint64_t pcg_next(u128 *s, u128 inc) {  /* PCG-XSL-RR 128/64: step, then output */
  *s = *s * PCG_MULT + inc;
  const uint64_t x = (uint64_t)(*s >> 64) ^ (uint64_t)*s;
  const unsigned rot = (unsigned)(*s >> 122);
  return (x >> rot) | (x << ((-rot) & 63));
}

/* a boat's stream as a bitgen_t, the draw already taken (`pending`) served first */
typedef struct { u128 s, inc; uint64_t pending; int has_pending; } replay_t;
static uint64_t replay_u64(void *st) {
  replay_t *r = (replay_t *)st;
  if (r->has_pending) { r->has_pending = 0; return r->pending; }
  return pcg_next(&r->s, r->inc);
}
static uint32_t replay_u32(void *st) { return (uint32_t)replay_u64(st); }  /* unused by normals */
static double replay_double(void *st) {  /* NumPy's next_double of a 64-bit generator */
  return (double)(replay_u64(st) >> 11) * (1.0 / 9007199254740992.0);
}

/* a wedge or tail draw: NumPy's sampler from `draw` on; the stream's state passes by value so
   that the callers' states stay in registers */
typedef struct { double x; u128 s; } slow_t;
static __attribute__((noinline)) slow_t slow_normal(u128 s, u128 inc, uint64_t draw) {
  replay_t r = {s, inc, draw, 1};
  bitgen_t bg = {&r, replay_u64, replay_u32, replay_double, replay_u64};
  const double x = random_standard_normal(&bg);
  slow_t out = {x, r.s};
  return out;
}

static double WI[256];
static uint64_t KI[256];

/* a scripted bitgen_t for reading the tables: `first`, then zero draws of layer 2 (accepted at
   once, ending any rejection loop); doubles are 0.5 and counted */
typedef struct { uint64_t first; int calls; int doubles; } probe_t;
static uint64_t probe_u64(void *st) {
  probe_t *p = (probe_t *)st;
  return p->calls++ == 0 ? p->first : 2u;
}
static uint32_t probe_u32(void *st) { return (uint32_t)probe_u64(st); }
static double probe_double(void *st) { ((probe_t *)st)->doubles++; return 0.5; }

static double probe(uint64_t draw, int *fast) {
  probe_t p = {draw, 0, 0};
  bitgen_t bg = {&p, probe_u64, probe_u32, probe_double, probe_u64};
  const double x = random_standard_normal(&bg);
  *fast = p.doubles == 0 && p.calls == 1;
  return x;
}

/* layer idx's width: the value of the draw with |r| = 1 (x = 1 * wi, exact); its limit: the
   first |r| that leaves the fast test (bisection). Returns 0, or -1 where a probe misbehaves. */
int usv_normal_tables(double *wi, uint64_t *ki) {
  for (int idx = 0; idx < 256; ++idx) {
    int fast;
    WI[idx] = probe((1ULL << 9) | (uint64_t)idx, &fast);
    if (!(WI[idx] > 0.0) || WI[idx] > 1e-14) return -1;
    uint64_t lo = 0, hi = MASK52 + 1;  /* fast(r) <=> r < KI: find the first r not fast */
    while (lo < hi) {
      const uint64_t mid = lo + (hi - lo) / 2;
      probe((mid << 9) | (uint64_t)idx, &fast);
      if (fast) lo = mid + 1; else hi = mid;
    }
    KI[idx] = lo;
    wi[idx] = WI[idx];
    ki[idx] = KI[idx];
  }
  return 0;
}

/* NumPy's seeding of default_rng(seed): SeedSequence(seed) (O'Neill's seed_seq_fe hash mixing:
   a pool of four 32-bit words) gives four 64-bit words, the PCG64 state and increment seeds */
#define INIT_A 0x43b0d7e5u
#define MULT_A 0x931e8875u
#define INIT_B 0x8b51f9ddu
#define MULT_B 0x58f38dedu
#define MIX_MULT_L 0xca01f9ddu
#define MIX_MULT_R 0x4973f715u

static inline uint32_t hashmix(uint32_t value, uint32_t *hash_const) {
  value ^= *hash_const;
  *hash_const *= MULT_A;
  value *= *hash_const;
  return value ^ (value >> 16);
}

static inline uint32_t mix(uint32_t x, uint32_t y) {
  const uint32_t r = MIX_MULT_L * x - MIX_MULT_R * y;
  return r ^ (r >> 16);
}

static inline void pcg_step(u128 *s, u128 inc) { *s = *s * PCG_MULT + inc; }

/* the PCG64 states ((N, 4) rows `boats`) of default_rng(seed) for n seeds below 2^64 */
void usv_pcg64_seed(int n, const uint64_t *seeds, const int64_t *boats, uint64_t *states) {
  for (int b = 0; b < n; ++b) {
    uint32_t entropy[2] = {(uint32_t)seeds[b], (uint32_t)(seeds[b] >> 32)};
    const int words = entropy[1] ? 2 : 1;  /* the seed's 32-bit words, least first; 0 is [0] */
    uint32_t pool[4], hash_const = INIT_A;
    for (int i = 0; i < 4; ++i) pool[i] = hashmix(i < words ? entropy[i] : 0u, &hash_const);
    for (int src = 0; src < 4; ++src)
      for (int dst = 0; dst < 4; ++dst)
        if (src != dst) pool[dst] = mix(pool[dst], hashmix(pool[src], &hash_const));
    uint32_t out[8], h = INIT_B;
    for (int i = 0; i < 8; ++i) {
      uint32_t v = pool[i % 4] ^ h;
      h *= MULT_B;
      v *= h;
      out[i] = v ^ (v >> 16);
    }
    uint64_t w[4];
    for (int i = 0; i < 4; ++i) w[i] = (uint64_t)out[2 * i] | ((uint64_t)out[2 * i + 1] << 32);
    const u128 init_state = ((u128)w[0] << 64) + w[1];
    const u128 init_seq = ((u128)w[2] << 64) + w[3];
    u128 s = 0;
    const u128 inc = (init_seq << 1) | 1u;
    pcg_step(&s, inc);
    s += init_state;
    pcg_step(&s, inc);
    uint64_t *st = states + 4 * boats[b];
    st[0] = (uint64_t)(s >> 64); st[1] = (uint64_t)s;
    st[2] = (uint64_t)(inc >> 64); st[3] = (uint64_t)inc;
  }
}

static inline double draw_normal(u128 *s, u128 inc) {
  const uint64_t draw = pcg_next(s, inc);
  const int idx = (int)(draw & 0xFF);
  const uint64_t rabs = (draw >> 9) & MASK52;
  union { double d; uint64_t u; } x = {.d = (double)rabs * WI[idx]};
  x.u ^= ((draw >> 8) & 1) << 63;  /* the sign bit: NumPy's x = -x, without a branch */
  if (__builtin_expect(rabs < KI[idx], 1)) return x.d;
  const slow_t r = slow_normal(*s, inc, draw);  /* wedge or tail: NumPy's sampler */
  *s = r.s;
  return r.x;
}

#define LANES 4  /* boats drawn side by side: their PCG steps overlap in the pipeline */

/* m standard normals for each of the n boats `boats` (rows of `out`, (n, m)), advancing their
   PCG64 states in `states` ((N, 4): state high, state low, increment high, increment low).
   Threads only from 65,536 numbers: one thread draws a number in ~3.1 ns and waking the
   second (passive wait) costs ~70 us, so below that one thread is faster (2026-12-03, quiet:
   256 boats x 80 numbers 65 us in one thread, 103 us in two; 1,024 x 80: 227 / 183 us) */
void usv_boat_normals(int n, const int64_t *boats, uint64_t *states, int m, double *out) {
  const int groups = (n + LANES - 1) / LANES;
  #pragma omp parallel for schedule(static) if((long)n * m >= 65536)
  for (int g = 0; g < groups; ++g) {
    const int first = g * LANES, lanes = n - first < LANES ? n - first : LANES;
    if (lanes == LANES) {
      u128 s0, s1, s2, s3, i0, i1, i2, i3;
      uint64_t *st[LANES];
      for (int j = 0; j < LANES; ++j) st[j] = states + 4 * boats[first + j];
      s0 = ((u128)st[0][0] << 64) | st[0][1]; i0 = ((u128)st[0][2] << 64) | st[0][3];
      s1 = ((u128)st[1][0] << 64) | st[1][1]; i1 = ((u128)st[1][2] << 64) | st[1][3];
      s2 = ((u128)st[2][0] << 64) | st[2][1]; i2 = ((u128)st[2][2] << 64) | st[2][3];
      s3 = ((u128)st[3][0] << 64) | st[3][1]; i3 = ((u128)st[3][2] << 64) | st[3][3];
      double *o = out + (long)first * m;
      for (int k = 0; k < m; ++k) {
        o[k] = draw_normal(&s0, i0);
        o[m + k] = draw_normal(&s1, i1);
        o[2 * m + k] = draw_normal(&s2, i2);
        o[3 * m + k] = draw_normal(&s3, i3);
      }
      st[0][0] = (uint64_t)(s0 >> 64); st[0][1] = (uint64_t)s0;
      st[1][0] = (uint64_t)(s1 >> 64); st[1][1] = (uint64_t)s1;
      st[2][0] = (uint64_t)(s2 >> 64); st[2][1] = (uint64_t)s2;
      st[3][0] = (uint64_t)(s3 >> 64); st[3][1] = (uint64_t)s3;
    } else {
      for (int j = 0; j < lanes; ++j) {
        uint64_t *st = states + 4 * boats[first + j];
        u128 s = ((u128)st[0] << 64) | st[1];
        const u128 inc = ((u128)st[2] << 64) | st[3];
        double *o = out + (long)(first + j) * m;
        for (int k = 0; k < m; ++k) o[k] = draw_normal(&s, inc);
        st[0] = (uint64_t)(s >> 64);
        st[1] = (uint64_t)s;
      }
    }
  }
}
"""


def pcg64_states(seeds: list[int]) -> NDArray[np.uint64]:
    """The PCG64 states of ``numpy.random.default_rng(seed)`` for each seed, (n, 4) uint64:
    state high, state low, increment high, increment low (NumPy's own seeding)."""
    out = np.empty((len(seeds), 4), dtype=np.uint64)
    mask = (1 << 64) - 1
    for row, seed in enumerate(seeds):
        st = np.random.PCG64(seed).state["state"]
        s, inc = int(st["state"]), int(st["inc"])
        out[row] = (s >> 64, s & mask, inc >> 64, inc & mask)
    return out


class NoiseKernel:
    """The loaded ``usv_boat_normals``: :meth:`draw` m normals for each of ``boats``."""

    def __init__(self, fn: Callable[..., None], seed_fn: Callable[..., None]) -> None:
        self._fn = fn
        self._seed_fn = seed_fn

    def seed(self, boats: NDArray[np.intp], seeds: list[int], states: NDArray[np.uint64]) -> None:
        """Set rows ``boats`` of ``states`` to the PCG64 states of ``default_rng(seed)``: in C
        for seeds in [0, 2⁶⁴), else by NumPy (:func:`pcg64_states`, which also rejects what
        NumPy rejects)."""
        boats = np.ascontiguousarray(boats, dtype=np.int64)
        in_c = all(isinstance(s, (int, np.integer)) and 0 <= s < 2**64 for s in seeds)
        if not in_c:
            states[boats] = pcg64_states(seeds)
            return
        words = np.array([int(s) for s in seeds], dtype=np.uint64)
        if words.shape != boats.shape:
            raise ValueError(f"need one seed per boat ({boats.size}), got {len(seeds)}")
        if boats.size:
            self._seed_fn(boats.size, words.ctypes.data, boats.ctypes.data, states.ctypes.data)

    def draw(self, boats: NDArray[np.intp], states: NDArray[np.uint64], m: int) -> NDArray:
        """(len(boats), m) normals; ``states`` (N, 4) C-contiguous uint64, advanced in place."""
        boats = np.ascontiguousarray(boats, dtype=np.int64)
        return self.draw_at(boats.size, boats.ctypes.data, states.ctypes.data, m)

    def draw_at(self, n: int, boats_address: int, states_address: int, m: int) -> NDArray:
        """:meth:`draw` given the addresses of ``boats`` (n int64) and ``states`` (a caller that
        draws often keeps them: reading an array's address costs about 2 µs)."""
        out = np.empty((n, m))
        if n and m:
            self._fn(n, boats_address, states_address, m, out.ctypes.data)
        return out


def _npyrandom_dir() -> Path | None:
    """NumPy's folder of ``libnpyrandom.a`` (its C API for samplers), where it ships one."""
    folder = Path(np.__file__).parent / "random" / "lib"
    return folder if any(folder.glob("*npyrandom*")) else None


@functools.cache
def load_kernel() -> NoiseKernel | None:
    """The compiled per-boat normals, tables read and output checked against NumPy, or None
    where the library does not build or load, or its numbers differ from NumPy's (module
    docstring). Built and loaded once per process."""
    lib_dir = _npyrandom_dir()
    if lib_dir is None:
        return None
    # NumPy's version joins the source, hence the cache key: its sampler is linked in statically
    source = f"/* numpy {np.__version__} */\n" + KERNEL_SOURCE
    link = [f"-L{lib_dir}", "-lnpyrandom"]
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    tables = load_function(source, "usv_normal_tables", [ptr, ptr], "noise", link)
    fn = load_function(source, "usv_boat_normals", [int_, ptr, ptr, int_, ptr], "noise", link)
    seed_fn = load_function(source, "usv_pcg64_seed", [int_, ptr, ptr, ptr], "noise", link)
    if tables is None or fn is None or seed_fn is None:
        return None
    tables.restype = ctypes.c_int
    wi, ki = np.zeros(256), np.zeros(256, dtype=np.uint64)
    if tables(wi.ctypes.data, ki.ctypes.data) != 0:
        return None
    kernel = NoiseKernel(fn, seed_fn)
    seeds = [0, 7, 2**32, 2**63 + 12345]  # one and two 32-bit words, NumPy's seeding included
    states = np.zeros((len(seeds), 4), dtype=np.uint64)
    kernel.seed(np.arange(len(seeds)), seeds, states)
    got = kernel.draw(np.arange(len(seeds)), states, 4096)
    ref = np.stack([np.random.default_rng(s).standard_normal(4096) for s in seeds])
    return kernel if np.array_equal(got, ref) else None
