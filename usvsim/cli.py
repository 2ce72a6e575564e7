"""The ``usvsim`` command line.

Each sub-command has one frozen dataclass holding its options; argparse is built from it so
``--help`` lists every field with its default. Long work shows a progress bar; results are written
atomically.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["DemoArgs", "PerfArgs", "main"]


@dataclass(frozen=True)
class DemoArgs:
    """Print the vessel and autopilot design and save plant plots (PNG)."""

    vessel: str = "default"  # vessel preset: default, viknes830, viknes830_nr3224, cybership2
    autopilot: str = "pid"  # pid | rover | rover-tuned
    out: str = "usvsim-results/plant"  # folder for the PNG plots


@dataclass(frozen=True)
class PerfArgs:
    """Measure plant (and environment) throughput."""

    json: bool = False  # print JSON only
    seconds: float = 1.0  # measuring time per figure, s
    no_env: bool = False  # skip the environment figures


def _autopilot_config(name: str) -> Any:
    from usvsim.autopilot import AutopilotConfig

    try:
        return AutopilotConfig.from_name(name)
    except ValueError as err:
        raise SystemExit(f"usvsim: {err}") from None


def run_demo(args: DemoArgs) -> int:
    from tqdm import tqdm

    from usvsim.autopilot import design_report
    from usvsim.plant import Plant
    from usvsim.vessels import get_vessel

    try:
        vessel = get_vessel(args.vessel)
    except ValueError as err:
        raise SystemExit(f"usvsim: {err}") from None
    plant = Plant(vessel, autopilot=_autopilot_config(args.autopilot))
    print(design_report(vessel, plant.design, plant.dt_s))
    print(f"plant fast path: {plant.backend}")
    from usvsim import plant_plots

    out = Path(args.out)
    steps: list[tuple[str, Callable[[], Any]]] = [
        ("turning_circle.png", lambda: plant_plots.turning_circle_figure(plant)),
        ("heading_steps.png", lambda: plant_plots.heading_step_figure(plant)),
        ("bode.png", lambda: plant_plots.bode_figure(plant)),
        ("kalman_vs_gps.png", lambda: plant_plots.kalman_figure()),
    ]
    import matplotlib.pyplot as plt

    from usvsim.fileio import atomic_savefig

    for name, make in tqdm(steps, desc="plots", unit="plot", file=sys.stderr):
        fig = make()
        atomic_savefig(fig, out / name, dpi=120)
        plt.close(fig)
    print(f"plots written to {out}/: " + ", ".join(name for name, _ in steps))
    return 0


def run_perf(args: PerfArgs) -> int:
    from usvsim.perf import run_perf as measure

    if args.seconds <= 0:
        raise SystemExit("usvsim perf: --seconds must be > 0")
    result = measure(args.seconds, env=not args.no_env)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    plant = result["plant"]
    print(
        f"plant ({plant['backend']}): boat-substeps/s "
        + ", ".join(f"{k}: {v:,}" for k, v in plant["boat_substeps_per_s"].items())
    )
    print(
        f"  per-boat Python loop: {plant['per_boat_python_loop_boat_substeps_per_s']:,}/s; "
        f"batched N=1024 is {plant['batched_N1024_over_loop']}x faster"
    )
    env = result.get("env", {})
    for key, value in env.get("decision_steps_per_s", {}).items():
        print(f"env {key}: {value:,} decision steps/s")
    return 0


# name -> (module, options dataclass, one-line help); modules are imported only when their
# command is chosen, so `usvsim --help` does not pay for torch or pymavlink
COMMANDS: dict[str, tuple[str, str, str]] = {
    "bench": ("usvsim.bench", "BenchArgs", "compare every helmsman on validation and held-out"),
    "demo": ("usvsim.cli", "DemoArgs", "vessel and autopilot design, plant plots (PNG)"),
    "perf": ("usvsim.cli", "PerfArgs", "throughput of the plant and the environments"),
    "train": ("learning.train_cli", "TrainArgs", "train a policy (rl-* by TRPO, il-* by GAIL)"),
    "evaluate": ("learning.evaluate_cli", "EvaluateArgs", "evaluate a trained checkpoint"),
    "sitl": ("usvsim.sitl", "SitlArgs", "the usvsim plant as a MAVLink (Rover boat) vehicle"),
    "sitl-physics": (
        "usvsim.sitl_physics",
        "SitlPhysicsArgs",
        "physics backend for ArduPilot SITL",
    ),
    "bridge": ("usvsim.bridge", "BridgeArgs", "a helmsman steers an ArduPilot boat over MAVLink"),
}
_LOCAL_RUNNERS: dict[str, Callable[[Any], int]] = {"demo": run_demo, "perf": run_perf}


def _command(name: str) -> tuple[type, Callable[[Any], int]]:
    """The options dataclass and the run function of command ``name``."""
    import importlib

    module_name, cls_name, _ = COMMANDS[name]
    module = importlib.import_module(module_name)
    run = _LOCAL_RUNNERS.get(name) or module.run
    return getattr(module, cls_name), run


def _add_dataclass_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    comments = _field_comments(cls)
    for f in dataclasses.fields(cls):
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            # a field without a default is a positional argument
            parser.add_argument(f.name, help=comments.get(f.name))
            continue
        flag = "--" + f.name.replace("_", "-")
        help_text = f"{comments.get(f.name, '')} (default: {f.default})"
        if f.type in ("bool", bool):
            parser.add_argument(flag, dest=f.name, action="store_true", help=comments.get(f.name))
        else:
            kind = {"float": float, "int": int}.get(str(f.type), str)
            parser.add_argument(flag, dest=f.name, type=kind, default=f.default, help=help_text)


def _field_comments(cls: type) -> dict[str, str]:
    """The ``# comment`` after each field in the class source: the field's help text."""
    import inspect

    out: dict[str, str] = {}
    try:
        source = inspect.getsource(cls)
    except OSError:
        return out
    for line in source.splitlines():
        name, sep, rest = line.strip().partition(":")
        if sep and "#" in rest and name.isidentifier():
            out[name] = rest.split("#", 1)[1].strip()
    return out


def build_parser(chosen: str | None = None) -> argparse.ArgumentParser:
    """The parser; only the ``chosen`` command's options are built (its module imported)."""
    parser = argparse.ArgumentParser(
        prog="usvsim",
        description="usvsim: learn and test steering policies for unmanned surface vehicles.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_, _, summary) in COMMANDS.items():
        if name == chosen:
            cls, _ = _command(name)
            doc = (cls.__doc__ or summary).strip().splitlines()[0]
            _add_dataclass_arguments(sub.add_parser(name, help=summary, description=doc), cls)
        else:
            sub.add_parser(name, help=summary, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    chosen = next((a for a in args if not a.startswith("-")), None)
    parser = build_parser(chosen if chosen in COMMANDS else None)
    ns = parser.parse_args(args)
    if ns.command is None:
        parser.print_help()
        return 0
    cls, run = _command(ns.command)
    values = {k: v for k, v in vars(ns).items() if k != "command"}
    return run(cls(**values))


if __name__ == "__main__":
    sys.exit(main())
