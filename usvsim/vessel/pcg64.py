"""NumPy's PCG64 uniforms generated inside the compiled step drivers, bit for bit.

A caller whose per-step inputs are ``Generator.random((N, n_sub, k))`` draws of NumPy's default
bit generator (PCG64) need not draw and pass that array: :class:`Pcg64Uniforms` holds the
generator's 128-bit state and increment, and the drivers of :mod:`usvsim.vessel.codegen` and
:mod:`usvsim.vessel.soa` generate each boat's numbers as its steps need them (each boat's
stream jumped ahead to its first draw). The numbers are NumPy's bit for bit (tested); what is
saved is drawing, storing and gathering N × n_sub × k doubles per call.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["PCG64_C_SOURCE", "Pcg64Uniforms"]

# NumPy's PCG64 in C (the prelude of every compiled step's source): the generator of
# numpy/random/src/pcg64/pcg64.h (pcg_setseq_128_xsl_rr_64: the 128-bit state stepped, then
# output as the rotated xor of its halves; O'Neill 2014) and Generator.random's double,
# (next64 >> 11) * 2^-53; the jump ahead by delta steps is Brown's (1994) affine power, as
# pcg_advance_lcg_128. Tested equal to Generator.random bit for bit.
PCG64_C_SOURCE = r"""
typedef unsigned __int128 usv_u128;
#define USV_PCG_MULT ((((usv_u128)2549297995355413924ULL) << 64) | 4865540595714422341ULL)
/* pcg = [state high, state low, increment high, increment low] */
static inline void usv_pcg_unpack(const unsigned long long* pcg, usv_u128* state,
                                  usv_u128* inc) {
  *state = ((usv_u128)pcg[0] << 64) | pcg[1];
  *inc = ((usv_u128)pcg[2] << 64) | pcg[3];
}
/* delta steps as one affine map: state -> mult * state + plus */
static inline void usv_pcg_stride(usv_u128 inc, unsigned long long delta, usv_u128* mult,
                                  usv_u128* plus) {
  usv_u128 acc_mult = 1, acc_plus = 0, cur_mult = USV_PCG_MULT, cur_plus = inc;
  while (delta > 0) {
    if (delta & 1) {
      acc_mult *= cur_mult;
      acc_plus = acc_plus * cur_mult + cur_plus;
    }
    cur_plus = (cur_mult + 1) * cur_plus;
    cur_mult *= cur_mult;
    delta >>= 1;
  }
  *mult = acc_mult;
  *plus = acc_plus;
}
static inline usv_u128 usv_pcg_advance(usv_u128 state, usv_u128 inc, unsigned long long delta) {
  usv_u128 mult, plus;
  usv_pcg_stride(inc, delta, &mult, &plus);
  return mult * state + plus;
}
static inline double usv_pcg_double(usv_u128* state, usv_u128 inc) {
  *state = *state * USV_PCG_MULT + inc;
  unsigned long long x = (unsigned long long)(*state >> 64) ^ (unsigned long long)*state;
  unsigned rot = (unsigned)(*state >> 122);
  x = (x >> rot) | (x << ((-rot) & 63u));
  return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}
"""


@dataclass(frozen=True)
class Pcg64Uniforms:
    """Per-step inputs (N, n_sub, nps) that are ``Generator.random((N, n_sub, nps))`` of a
    NumPy generator on a PCG64 bit generator whose 128-bit state is ``state`` and increment
    ``inc`` (``bit_generator.state["state"]``). The compiled drivers generate them as the steps
    need them (each boat's stream jumped to its first draw), the same numbers bit for bit
    without an (N, n_sub, nps) array in memory; :meth:`dense` draws that array in NumPy.
    """

    state: int
    inc: int

    @classmethod
    def take(cls, rng: np.random.Generator, count: int) -> Pcg64Uniforms | None:
        """The next ``count`` uniforms of ``rng``, which moves past them as ``rng.random``
        would (a buffered 32-bit half is kept); None where ``rng`` is not on PCG64."""
        bits = getattr(rng, "bit_generator", None)
        if type(bits) is not np.random.PCG64:
            return None
        before = bits.state
        bits.advance(count)  # one step per double; advance drops the buffered 32-bit half
        if before["has_uint32"]:
            after = bits.state
            bits.state = {**after, "has_uint32": 1, "uinteger": before["uinteger"]}
        return cls(int(before["state"]["state"]), int(before["state"]["inc"]))

    def words(self) -> NDArray[np.uint64]:
        """[state high, state low, increment high, increment low] for the C drivers."""
        mask = (1 << 64) - 1
        return np.array(
            [self.state >> 64, self.state & mask, self.inc >> 64, self.inc & mask],
            dtype=np.uint64,
        )

    def dense(self, shape: tuple[int, int, int]) -> NDArray[np.float64]:
        """The uniforms as an array of ``shape`` (N, n_sub, nps), drawn by NumPy."""
        bits = np.random.PCG64()
        bits.state = {
            "bit_generator": "PCG64",
            "state": {"state": self.state, "inc": self.inc},
            "has_uint32": 0,
            "uinteger": 0,
        }
        return np.random.Generator(bits).random(shape)
