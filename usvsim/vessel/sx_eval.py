"""A scalar CasADi SX Function evaluated element-wise by NumPy, with CasADi's numbers.

CasADi's virtual machine runs an SX Function's algorithm (``n_instructions()``,
``instruction_id/input/output/constant``) one double operation at a time. For the operations of
:data:`EXACT_OPS` (the four arithmetic operations, negation, square root, absolute value,
``fmin``/``fmax``), IEEE 754 fixes every result bit, so the same operations in the same order on
NumPy arrays give CasADi's numbers bit for bit, for N values in one pass instead of one CasADi
call per value (about 30 µs of call overhead for a handful of boats). Functions with any other
operation (``sin``, ``exp``, ``pow``: NumPy's SIMD routines may differ from C's libm in the last
bit) are not translated: :func:`numpy_function` returns None and the caller keeps CasADi.
:func:`usvsim.vessel.torch_codegen.torch_function_source` folds constants with the same table.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["EXACT_OPS", "numpy_function"]

#: CasADi operation codes whose NumPy twins round exactly as C does (IEEE 754 basic operations).
EXACT_OPS: dict[int, Callable[..., Any]] = {
    int(ca.OP_ADD): np.add,
    int(ca.OP_SUB): np.subtract,
    int(ca.OP_MUL): np.multiply,
    int(ca.OP_DIV): np.divide,
    int(ca.OP_NEG): np.negative,
    int(ca.OP_TWICE): lambda a: 2.0 * a,
    int(ca.OP_SQ): lambda a: a * a,
    int(ca.OP_SQRT): np.sqrt,
    int(ca.OP_FABS): np.abs,
    int(ca.OP_FMIN): np.fmin,
    int(ca.OP_FMAX): np.fmax,
}

_Step = tuple[int, Callable[..., Any] | None, tuple[int, ...], float]


def numpy_function(fn: ca.Function) -> Callable[[ArrayLike], NDArray[np.float64]] | None:
    """``fn`` (an SX Function of one scalar input and one scalar output) as a NumPy function
    evaluating it element-wise on an array, bit for bit (module docstring); None where ``fn``
    has another shape or an operation outside :data:`EXACT_OPS`."""
    if not (fn.is_a("SXFunction") and fn.n_in() == 1 and fn.n_out() == 1):
        return None
    if fn.nnz_in(0) != 1 or fn.nnz_out(0) != 1:
        return None
    program: list[_Step] = []  # (output slot, operation or None, input slots, constant)
    result = -1
    for k in range(fn.n_instructions()):
        op, ins, outs = fn.instruction_id(k), fn.instruction_input(k), fn.instruction_output(k)
        if op == ca.OP_CONST:
            program.append((outs[0], None, (), float(fn.instruction_constant(k))))
        elif op == ca.OP_INPUT:
            program.append((outs[0], None, (-1,), 0.0))  # slot -1: the input
        elif op == ca.OP_OUTPUT:
            result = ins[0]
        elif op in EXACT_OPS:
            program.append((outs[0], EXACT_OPS[op], tuple(ins), 0.0))
        else:
            return None

    def evaluate(x: ArrayLike) -> NDArray[np.float64]:
        work: dict[int, Any] = {-1: np.asarray(x, dtype=np.float64)}
        with np.errstate(all="ignore"):  # CasADi returns inf and NaN silently; so does this
            for out, f, ins, constant in program:
                if f is None:
                    work[out] = work[-1] if ins else np.float64(constant)
                else:
                    work[out] = f(*(work[i] for i in ins))
        return np.broadcast_to(work[result], work[-1].shape).astype(np.float64)

    return evaluate
