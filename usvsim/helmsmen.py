"""The registry of helmsmen that ``usvsim bench`` compares: the baselines and shipped policies.

:func:`available_helmsmen` maps a name to a factory that builds a fresh helmsman
(:class:`usvsim.evaluate.Helmsman`):

* ``los`` — :class:`baselines.los.LOSHelmsman`, LOS to the goal;
* ``los-avoid`` — :class:`baselines.avoid.AvoidHelmsman`, LOS plus collision-cone avoidance;
* one entry per trained policy shipped as ``usvsim/models/<name>.pt``, loaded with
  ``learning.checkpoint.load_helmsman(path)`` — only when that module can be imported (it does
  not exist yet; until then the registry holds the baselines alone).

A helmsman may declare the observation and action kinds it needs as attributes
``observation`` and ``action``; :func:`helmsman_kinds` reads them (defaults: positional,
gaussian).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from usvsim.evaluate import Helmsman

__all__ = ["MODELS_DIR", "HelmsmanFactory", "available_helmsmen", "helmsman_kinds"]

HelmsmanFactory = Callable[[], Helmsman]
MODELS_DIR = Path(__file__).resolve().parent / "models"


def _los() -> Helmsman:
    from baselines.los import LOSHelmsman

    return LOSHelmsman()


def _los_avoid() -> Helmsman:
    from baselines.avoid import AvoidHelmsman

    return AvoidHelmsman()


def _trained(models_dir: Path) -> dict[str, HelmsmanFactory]:
    """``{stem: loader}`` for every ``*.pt`` in ``models_dir``, if the checkpoint module exists."""
    files = sorted(models_dir.glob("*.pt")) if models_dir.is_dir() else []
    if not files:
        return {}
    try:
        checkpoint = importlib.import_module("learning.checkpoint")
    except ImportError:
        return {}
    load: Callable[[Path], Helmsman] = checkpoint.load_helmsman
    return {path.stem: partial(load, path) for path in files}


def available_helmsmen(models_dir: Path | None = None) -> dict[str, HelmsmanFactory]:
    """Name → factory of every available helmsman: the baselines first, then trained policies.

    ``models_dir`` defaults to :data:`MODELS_DIR` (the package's shipped models). A trained
    policy named like a baseline raises ``ValueError`` rather than hiding it.
    """
    helmsmen: dict[str, HelmsmanFactory] = {"los": _los, "los-avoid": _los_avoid}
    for name, factory in _trained(MODELS_DIR if models_dir is None else models_dir).items():
        if name in helmsmen:
            raise ValueError(f"trained model {name!r} clashes with a baseline's name")
        helmsmen[name] = factory
    return helmsmen


def helmsman_kinds(helmsman: Any) -> tuple[str, str]:
    """(observation kind, action kind) a helmsman declares; default (positional, gaussian)."""
    return (
        str(getattr(helmsman, "observation", "positional")),
        str(getattr(helmsman, "action", "gaussian")),
    )
