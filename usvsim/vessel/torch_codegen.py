"""Torch code generated from the CasADi plant: the physics stays defined once, in the model.

:func:`torch_function_source` walks a CasADi SX Function's algorithm (``n_instructions()``,
``instruction_id/input/output/constant``, the ``casadi.OP_*`` codes) after merging common
subexpressions (``cse``, as the structure-of-arrays C kernel of :mod:`usvsim.vessel.soa` does) and
writes one Python function of batched torch operations, one statement per instruction, in the
same order: each input and output nonzero is a tensor of shape (N,) (one number per boat), any
dtype and device. The numbers are those of the C kernel up to the last bits of ``sin``, ``cos``,
``atan2``, ``pow`` and the C compiler's fused multiply-adds (tested:
``tests/usvsim/vessel/test_torch_plant.py``).

:func:`kernel_source` writes a whole module for one plant (vessel, autopilot, step): the
closed-loop step of :func:`usvsim.vessel.plant.build_closed_loop_step` (autopilot update, one RK4
step of the vessel ODE with actuators and current, heading wrapped), the surge trim
(:func:`usvsim.vessel.model.surge_trim`) that starts boats at speed, and the autopilot gains of the
design as numbers. The module needs torch only: no CasADi, no python-control, so the GPU path
runs where only torch and NumPy are installed. The default plant's module is committed as
:mod:`usvsim.vessel.torch_default_kernel` (``python -m usvsim.vessel.torch_codegen`` rewrites it;
a test checks that it equals what this module generates today); other plants are generated in
memory when CasADi is there (:mod:`usvsim.vessel.torch_plant`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from usvsim.vessel.sx_eval import EXACT_OPS
from usvsim.vessel.torch_plant import vessel_fingerprint
from usvsim.vessel.vessels import VesselParams

__all__ = [
    "DEFAULT_KERNEL_PATH",
    "DEFAULT_WEATHER_KERNEL_PATH",
    "TorchUnsupportedError",
    "default_kernel_source",
    "default_weather_kernel_source",
    "kernel_source",
    "torch_function_source",
    "weather_kernel_source",
]

#: Where the default plant's generated module lives (committed).
DEFAULT_KERNEL_PATH = Path(__file__).with_name("torch_default_kernel.py")
#: Where the default plant's generated weather step lives (committed).
DEFAULT_WEATHER_KERNEL_PATH = Path(__file__).with_name("torch_default_weather_kernel.py")


class TorchUnsupportedError(ValueError):
    """The Function uses an operation or input layout the torch generator does not write."""


def _op(name: str) -> int:
    return int(getattr(ca, name))


# torch expression of each operation on float operands {0}, {1} (tensors or Python floats): the
# same IEEE operation as CasADi's virtual machine (casadi/core/calculus.hpp) and the C kernel
_FLOAT_OPS: dict[int, str] = {
    _op("OP_ADD"): "{0} + {1}",
    _op("OP_SUB"): "{0} - {1}",
    _op("OP_MUL"): "{0} * {1}",
    _op("OP_DIV"): "{0} / {1}",
    _op("OP_NEG"): "-{0}",
    _op("OP_TWICE"): "2.0 * {0}",
    _op("OP_SQ"): "{0} * {0}",
    _op("OP_INV"): "torch.reciprocal({0})",
    _op("OP_SQRT"): "torch.sqrt({0})",
    _op("OP_FABS"): "torch.abs({0})",
    _op("OP_FLOOR"): "torch.floor({0})",
    _op("OP_CEIL"): "torch.ceil({0})",
    _op("OP_SIN"): "torch.sin({0})",
    _op("OP_COS"): "torch.cos({0})",
    _op("OP_TAN"): "torch.tan({0})",
    _op("OP_EXP"): "torch.exp({0})",
    _op("OP_LOG"): "torch.log({0})",
    _op("OP_TANH"): "torch.tanh({0})",
    _op("OP_ASIN"): "torch.asin({0})",
    _op("OP_ACOS"): "torch.acos({0})",
    _op("OP_ATAN"): "torch.atan({0})",
    _op("OP_SIGN"): "torch.sign({0})",
    _op("OP_ATAN2"): "torch.atan2({0}, {1})",
    _op("OP_POW"): "torch.pow({0}, {1})",
    _op("OP_CONSTPOW"): "torch.pow({0}, {1})",
    _op("OP_FMOD"): "torch.fmod({0}, {1})",
    _op("OP_COPYSIGN"): "torch.copysign({0}, {1})",
}
# operations whose first operand must be a tensor (a constant there is made one)
_TENSOR_FIRST = {
    _op(name)
    for name in (
        "OP_INV", "OP_SQRT", "OP_FABS", "OP_FLOOR", "OP_CEIL", "OP_SIN", "OP_COS", "OP_TAN",
        "OP_EXP", "OP_LOG", "OP_TANH", "OP_ASIN", "OP_ACOS", "OP_ATAN", "OP_SIGN", "OP_ATAN2",
        "OP_FMOD", "OP_COPYSIGN", "OP_DIV",
    )
}  # fmt: skip
_COMPARE: dict[int, str] = {
    _op("OP_LT"): "{0} < {1}",
    _op("OP_LE"): "{0} <= {1}",
    _op("OP_EQ"): "{0} == {1}",
    _op("OP_NE"): "{0} != {1}",
}
_LOGIC: dict[int, str] = {
    _op("OP_NOT"): "~{0}",
    _op("OP_AND"): "{0} & {1}",
    _op("OP_OR"): "{0} | {1}",
}
# NumPy twins, to fold an operation whose operands are all constants at generation time
_FOLD = EXACT_OPS


def _literal(value: float) -> str:
    """A Python expression of exactly ``value`` (repr round-trips a float)."""
    if math.isnan(value):
        return 'float("nan")'
    if math.isinf(value):
        return 'float("inf")' if value > 0 else '-float("inf")'
    return repr(float(value))


class _Writer:
    """Work slots of the algorithm as Python names, each holding a float tensor ("f"), a bool
    tensor ("b", a comparison's result) or a constant folded into its users."""

    def __init__(self) -> None:
        self.kind: dict[int, str] = {}
        self.const: dict[int, float] = {}
        self.lines: list[str] = []

    def float_operand(self, slot: int, tensor: bool = False) -> str:
        kind = self.kind[slot]
        if kind == "c":
            value = _literal(self.const[slot])
            return f"_full({value})" if tensor else value
        return f"v{slot}.to(_dtype)" if kind == "b" else f"v{slot}"

    def bool_operand(self, slot: int) -> str:
        kind = self.kind[slot]
        if kind == "c":
            return f"(_full({_literal(float(self.const[slot] != 0.0))}) != 0.0)"
        return f"v{slot}" if kind == "b" else f"(v{slot} != 0.0)"

    def assign(self, slot: int, expr: str, kind: str) -> None:
        self.lines.append(f"v{slot} = {expr}")
        self.kind[slot] = kind
        self.const.pop(slot, None)

    def fmin_fmax(self, op: int, out: int, a: int, b: int) -> None:
        """C's fmin/fmax (NaN ignored, x where x == y; the C kernel's stand-ins): torch.fmin and
        torch.fmax on tensors; with a constant c, a select (torch.where) with the same result."""
        cmp = "<=" if op == _op("OP_FMIN") else ">="
        ka, kb = self.kind[a], self.kind[b]
        if ka != "c" and kb != "c":
            name = "fmin" if op == _op("OP_FMIN") else "fmax"
            self.assign(out, f"torch.{name}({self.float_operand(a)}, {self.float_operand(b)})", "f")
        elif kb == "c":  # f(x, c) = x where x (cmp) c, else c (also where x is NaN)
            x, c = self.float_operand(a), self.float_operand(b)
            self.assign(out, f"torch.where({x} {cmp} {c}, {x}, {c})", "f")
        else:  # f(c, x) = c where x is NaN or not strictly beyond c, else x
            c, x = self.float_operand(a), self.float_operand(b)
            strict = "<" if op == _op("OP_FMIN") else ">"
            self.assign(out, f"torch.where({x} {strict} {c}, {x}, {c})", "f")


def _cse(fn: ca.Function) -> ca.Function:
    """``fn`` with common subexpressions merged (the C kernel's order of operations)."""
    if fn.n_out() != 1:
        raise TorchUnsupportedError("the Function must have one output")
    for i in range(fn.n_in()):
        if not (fn.sparsity_in(i).is_dense() and fn.size2_in(i) == 1):
            raise TorchUnsupportedError(f"input {i} of {fn.name()} is not a dense column")
    if not (fn.sparsity_out(0).is_dense() and fn.size2_out(0) == 1):
        raise TorchUnsupportedError(f"the output of {fn.name()} is not a dense column")
    if not fn.is_a("SXFunction"):
        raise TorchUnsupportedError(f"{fn.name()} is not an SX Function (expand it first)")
    sx_in = fn.sx_in()
    return ca.Function(fn.name(), sx_in, fn.call(sx_in), {"cse": True})


def torch_function_source(fn: ca.Function, name: str, doc: str) -> str:
    """Python source of ``def name(*inputs) -> tuple[Tensor, ...]`` computing ``fn`` on batches.

    Each argument is a sequence with one entry per nonzero of the Function's input of the same
    name: a tensor of shape (N,) (a float or 0-d tensor for a number shared by all boats); the
    result is a tuple with one (N,) tensor per output nonzero. The first argument's first entry
    must be a tensor (it sets dtype and device). Raises :class:`TorchUnsupportedError` for an
    operation without a torch twin here.
    """
    args = [fn.name_in(i) for i in range(fn.n_in())]
    fn = _cse(fn)
    op_input, op_output, op_const = _op("OP_INPUT"), _op("OP_OUTPUT"), _op("OP_CONST")
    op_assign, op_if_else_zero = _op("OP_ASSIGN"), _op("OP_IF_ELSE_ZERO")
    fminmax = (_op("OP_FMIN"), _op("OP_FMAX"))
    out = _Writer()
    outputs: list[str] = [""] * fn.nnz_out(0)
    for k in range(fn.n_instructions()):
        op, ins, res = fn.instruction_id(k), fn.instruction_input(k), fn.instruction_output(k)
        if op == op_input:
            out.assign(res[0], f"{args[ins[0]]}[{ins[1]}]", "f")
        elif op == op_const:
            out.kind[res[0]] = "c"
            out.const[res[0]] = float(fn.instruction_constant(k))
        elif op == op_output:
            outputs[res[1]] = out.float_operand(ins[0], tensor=True)
            if out.kind[ins[0]] == "f":  # the slot may be overwritten later: keep the tensor
                out.lines.append(f"o{res[1]} = v{ins[0]}")
                outputs[res[1]] = f"o{res[1]}"
        elif all(out.kind[i] == "c" for i in ins) and op in _FOLD:
            value = float(_FOLD[op](*(np.float64(out.const[i]) for i in ins)))
            out.kind[res[0]], out.const[res[0]] = "c", value
        elif op == op_assign:
            if out.kind[ins[0]] == "c":
                out.kind[res[0]], out.const[res[0]] = "c", out.const[ins[0]]
            else:
                out.assign(res[0], f"v{ins[0]}", out.kind[ins[0]])
        elif op in fminmax:
            out.fmin_fmax(op, res[0], ins[0], ins[1])
        elif op in _FLOAT_OPS:
            operands = [out.float_operand(i) for i in ins]
            if op in _TENSOR_FIRST and out.kind[ins[0]] == "c":
                operands[0] = out.float_operand(ins[0], tensor=True)
            if op == _op("OP_ATAN2") and out.kind[ins[1]] == "c":
                operands[1] = out.float_operand(ins[1], tensor=True)
            out.assign(res[0], _FLOAT_OPS[op].format(*operands), "f")
        elif op in _COMPARE:
            a, b = (out.float_operand(i) for i in ins)
            if out.kind[ins[0]] == "c" and out.kind[ins[1]] == "c":
                a = out.float_operand(ins[0], tensor=True)
            out.assign(res[0], _COMPARE[op].format(a, b), "b")
        elif op in _LOGIC:
            out.assign(res[0], _LOGIC[op].format(*(out.bool_operand(i) for i in ins)), "b")
        elif op == op_if_else_zero:  # C: c != 0 ? x : 0 (so a NaN x where c is 0 gives 0)
            x = out.float_operand(ins[1], tensor=True)
            out.assign(res[0], f"torch.where({out.bool_operand(ins[0])}, {x}, 0.0)", "f")
        else:
            raise TorchUnsupportedError(f"{fn.name()}: CasADi operation {op} has no torch twin")
    signature = ", ".join(f"{a}: Sequence[Any]" for a in args)
    body = "\n    ".join(out.lines)
    result = ", ".join(outputs) + ("," if len(outputs) == 1 else "")
    if len(f"    return ({result})") > 100:  # as ruff format wraps it: one per line
        result = "\n" + "".join(f"        {o},\n" for o in outputs) + "    "
    head = f"def {name}({signature}) -> tuple[torch.Tensor, ...]:"
    if len(head) > 100:  # as ruff format wraps it
        head = f"def {name}(\n    {signature}\n) -> tuple[torch.Tensor, ...]:"
    return (
        f"{head}\n"
        f'    """{doc}"""\n'
        f"    _ref = {args[0]}[0]\n"
        f"    _dtype = _ref.dtype\n\n"
        f"    def _full(value: float) -> torch.Tensor:\n"
        f"        return torch.full_like(_ref, value)\n\n"
        f"    {body}\n"
        f"    return ({result})\n"
    )


_HEADER = '''"""GENERATED from the CasADi plant by :mod:`usvsim.vessel.torch_codegen`: do not edit.

Plant: vessel {vessel!r} (fingerprint {fingerprint}), autopilot {kind!r} ({config}), step
{dt_s!r} s. :func:`closed_loop_step` is :func:`usvsim.vessel.plant.build_closed_loop_step`
(autopilot update, one RK4 step with actuators and current, heading wrapped) and
:func:`surge_drag` is :func:`usvsim.vessel.model.surge_trim`, one torch statement per CasADi
instruction (:mod:`usvsim.vessel.torch_codegen`); ``GAINS`` is the design's
:meth:`usvsim.vessel.autopilot.AutopilotDesign.gains_vector`. Needs torch only.

Why this module is long: it is generated, one statement per instruction of the CasADi plant.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

VESSEL = "{vessel}"
VESSEL_FINGERPRINT = "{fingerprint}"
AUTOPILOT = "{kind}"
DT_S = {dt_s!r}  # s, plant step
CRUISE_SPEED_MPS = {cruise!r}  # m/s, the design's speed (default speed reference)
NX = {nx}  # plant state size
NS = {ns}  # closed-loop state size: plant state, then the controller's
GAINS = (
{gains}
)

'''


def _plant_fields(vessel: VesselParams, config: Any, dt_s: float) -> dict[str, Any]:
    """The header fields naming the plant a generated module is for (vessel, its fingerprint,
    the autopilot and its design, the step)."""
    from usvsim.vessel.autopilot import AutopilotConfig

    return {
        "vessel": vessel.name,
        "fingerprint": vessel_fingerprint(vessel),
        "kind": config.kind,
        "config": "the default design" if config == AutopilotConfig() else repr(config),
        "dt_s": float(dt_s),
    }


def kernel_source(vessel: VesselParams, autopilot: object | None = None, dt_s: float = 0.1) -> str:
    """The torch module (Python source) of the plant of ``vessel`` with ``autopilot`` (an
    :class:`usvsim.vessel.autopilot.AutopilotConfig`, default the default PID) at step ``dt_s``
    (s); see the module docstring."""
    from usvsim.vessel.autopilot import NC, AutopilotConfig, design_autopilot
    from usvsim.vessel.model import NX, surge_trim
    from usvsim.vessel.plant import build_closed_loop_step

    config = AutopilotConfig() if autopilot is None else autopilot
    if not isinstance(config, AutopilotConfig):
        raise TypeError(f"autopilot must be an AutopilotConfig, got {type(config).__name__}")
    design = design_autopilot(vessel, config)
    step = build_closed_loop_step(vessel, config.kind, dt_s)
    u = ca.SX.sym("u")
    drag = ca.Function("surge_drag", [u], [surge_trim(vessel, u)], ["u"], ["drag"])
    header = _HEADER.format(
        **_plant_fields(vessel, config, dt_s),
        cruise=float(design.cruise_speed_mps),
        nx=NX,
        ns=NX + NC,
        gains="\n".join(f"    {_literal(float(g))}," for g in design.gains_vector()),
    )
    step_doc = (
        "One plant step of N boats: s[13] (x, c), w[4] (psi_ref rad, U_ref m/s, V_c m/s,\n"
        "    beta_c rad), g[25] (GAINS) -> s_next[13]; each entry (N,) or a shared number."
    )
    drag_doc = "Surge drag (N) at surge speed u[0] (m/s, (N,)): the trim thrust."
    return (
        header
        + "\n"
        + torch_function_source(step, "closed_loop_step", step_doc)
        + "\n\n"
        + torch_function_source(drag, "surge_drag", drag_doc)
    )


def default_kernel_source() -> str:
    """The committed module's text: the default vessel, default autopilot, 0.1 s step."""
    from usvsim.vessel.vessels import get_vessel

    return kernel_source(get_vessel("default"), None, 0.1)


_WEATHER_HEADER = '''"""GENERATED weather step (usvsim.vessel.torch_codegen): do not edit.

Plant: vessel {vessel!r} (fingerprint {fingerprint}), autopilot {kind!r} ({config}), step
{dt_s!r} s, in wind and waves. :func:`weather_step` is
:func:`usvsim.vessel.weather_plant.build_weather_step` with standard-normal innovations
(sensed heading and yaw rate, wave filter, autopilot on what it senses, one RK4 step with current,
wind and wave drift, gust and wave motion advanced); :func:`sensed_offsets` is
:func:`usvsim.vessel.weather_plant.sensed_offsets_expr` (what the GNSS position, compass and gyro
add to the true state). One torch statement per CasADi instruction; the autopilot's yaw model
and the observer's turn damping are in the numbers (``YAW_MODEL``, ``TURN_DAMPING``). Needs
torch only.

Why this module is long: it is generated, one statement per instruction of the CasADi plant.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

VESSEL = "{vessel}"
VESSEL_FINGERPRINT = "{fingerprint}"
AUTOPILOT = "{kind}"
DT_S = {dt_s!r}  # s, plant step
NWI = {nwi}  # per-boat inputs (usvsim.vessel.weather_plant.WEATHER_INPUTS)
NWS = {nws}  # weather states after the closed loop's (WEATHER_STATES)
YAW_MODEL = ({yaw_m!r}, {yaw_d!r})  # kg m², N m s/rad: the autopilot's design model
TURN_DAMPING = {turn!r}  # N m s²/rad², the wave filter observer's d₂

'''


def weather_kernel_source(
    vessel: VesselParams, autopilot: object | None = None, dt_s: float = 0.1
) -> str:
    """The torch module (Python source) of the weather step of ``vessel`` with ``autopilot``
    (default the default PID) at step ``dt_s`` (s), as :class:`usvsim.task.batch.PoleAvoidanceBatch`
    steps boats in weather (``WeatherPlant(plant, innovations="normal")``)."""
    from usvsim.vessel.autopilot import AutopilotConfig
    from usvsim.vessel.plant import NS, Plant
    from usvsim.vessel.weather_plant import NWI, NWS, WeatherPlant, sensed_offsets_expr

    config = AutopilotConfig() if autopilot is None else autopilot
    if not isinstance(config, AutopilotConfig):
        raise TypeError(f"autopilot must be an AutopilotConfig, got {type(config).__name__}")
    weather = WeatherPlant(Plant(vessel, config, dt_s), innovations="normal")
    s, w = ca.SX.sym("s", NS + NWS), ca.SX.sym("w", NWI)
    offsets = ca.Function("sensed_offsets", [s, w], [sensed_offsets_expr(s, w)], ["s", "w"], ["d"])
    header = _WEATHER_HEADER.format(
        **_plant_fields(vessel, config, dt_s),
        yaw_m=weather.yaw_model[0],
        yaw_d=weather.yaw_model[1],
        turn=float(weather.turn_damping),
        nwi=NWI,
        nws=NWS,
    )
    step_doc = (
        f"One plant step of N boats in weather: s[{NS + NWS}] (x, c, m), w[{NWI}] (psi_ref rad,\n"
        "    U_ref m/s, V_c m/s, beta_c rad, the episode's weather inputs), g (the plant's\n"
        "    GAINS), e[3] (standard normals: gust, wave motion x2) -> s_next; each entry (N,)\n"
        "    or a shared number."
    )
    offsets_doc = (
        "[dn m, de m, dpsi rad, dr rad/s] the sensors add to the true state, from s (x, c, m)\n"
        "    and the weather inputs w."
    )
    return (
        header
        + "\n"
        + torch_function_source(weather.step_function, "weather_step", step_doc)
        + "\n\n"
        + torch_function_source(offsets, "sensed_offsets", offsets_doc)
    )


def default_weather_kernel_source() -> str:
    """The committed weather module's text: the default vessel, default autopilot, 0.1 s."""
    from usvsim.vessel.vessels import get_vessel

    return weather_kernel_source(get_vessel("default"), None, 0.1)


def main() -> None:
    """Rewrite :data:`DEFAULT_KERNEL_PATH` and :data:`DEFAULT_WEATHER_KERNEL_PATH` from the
    CasADi plant."""
    DEFAULT_KERNEL_PATH.write_text(default_kernel_source())
    print(f"wrote {DEFAULT_KERNEL_PATH}")
    DEFAULT_WEATHER_KERNEL_PATH.write_text(default_weather_kernel_source())
    print(f"wrote {DEFAULT_WEATHER_KERNEL_PATH}")


if __name__ == "__main__":
    main()
