"""The one registry of helmsmen: every helmsman ``usvsim bench``, ``usvsim bridge`` and the
notebooks can name.

===========================  ===================================================================
name                         helmsman
===========================  ===================================================================
``straight``                 :class:`usvsim.helm.protocol.StraightAheadHelmsman` (sanity check)
``random``                   :class:`usvsim.helm.protocol.RandomHelmsman` (sanity check)
``los``                      :class:`baselines.los.LOSHelmsman`, LOS to the goal
``los-avoid``                :class:`baselines.avoid.AvoidHelmsman`, LOS + collision cone
``vo``                       :class:`baselines.velocity_obstacle.VOHelmsman`, LOS + velocity
                             obstacles with COLREG (Kuwata et al. 2014), ``scene`` observation
``sb-mpc``                   :class:`baselines.sbmpc.SBMPCHelmsman`, scenario-based MPC with
                             COLREG costs (Johansen et al. 2016), ``scene`` observation
``vo-radar``                 :class:`baselines.vo_radar.VORadarHelmsman`: ``vo`` on the tracks of
                             its radar (:mod:`usvsim.nav.tracker`), ``radar+nav`` observation
``sb-mpc-radar``             :class:`baselines.sbmpc_radar.SBMPCRadarHelmsman`: ``sb-mpc`` on the
                             same tracks, ``radar+nav`` observation
``<model>``                  each trained policy shipped as ``usvsim/models/<model>.pt``, named
                             observation-action-algorithm-task (``usvsim models``, e.g.
                             ``scene-categorical-gail-openwater``), also by the names it was
                             published under (its card's ``former_names``, e.g.
                             ``il-categorical-scene-ow``; :func:`model_aliases`)
a path to a ``.pt`` file     a checkpoint written by ``usvsim train``
===========================  ===================================================================

:func:`available_helmsmen` lists the compared ones (baselines, then shipped models);
:func:`make_helmsman` builds any of the table and :func:`select_helmsmen` turns a list of names
and checkpoint paths (``usvsim bench --helmsmen``) into labelled factories, duplicates removed.
This module is the only place where the simulator
reaches :mod:`learning` (to load a checkpoint as a helmsman), so the simulator's layers never
depend on the learning code.

A helmsman may declare the observation and action kinds it needs as attributes
``observation`` and ``action``; :func:`helmsman_kinds` reads them (defaults: positional,
gaussian).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

from usvsim.common.errors import UserError
from usvsim.helm.protocol import Helmsman, RandomHelmsman, StraightAheadHelmsman
from usvsim.task.batch import ActionKind, parse_action_kind
from usvsim.task.observations import ObservationKind, parse_observation_kind

__all__ = [
    "ALL",
    "MODELS_DIR",
    "SANITY_HELMSMEN",
    "HelmsmanFactory",
    "available_helmsmen",
    "checkpoint_facts",
    "helmsman_kinds",
    "load_checkpoint_helmsman",
    "make_helmsman",
    "model_aliases",
    "model_path",
    "select_helmsmen",
]

HelmsmanFactory = Callable[[], Helmsman]
MODELS_DIR = Path(__file__).resolve().parents[1] / "models"
SANITY_HELMSMEN = ("straight", "random")
ALL = "all"  # --helmsmen all: every available helmsman, every shipped file


def _los() -> Helmsman:
    from baselines.los import LOSHelmsman

    return LOSHelmsman()


def _los_avoid() -> Helmsman:
    from baselines.avoid import AvoidHelmsman

    return AvoidHelmsman()


def _vo() -> Helmsman:
    from baselines.velocity_obstacle import VOHelmsman

    return VOHelmsman()


def _vo_radar() -> Helmsman:
    from baselines.vo_radar import VORadarHelmsman

    return VORadarHelmsman()


def _sbmpc() -> Helmsman:
    from baselines.sbmpc import SBMPCHelmsman

    return SBMPCHelmsman()


def _sbmpc_radar() -> Helmsman:
    from baselines.sbmpc_radar import SBMPCRadarHelmsman

    return SBMPCRadarHelmsman()


def load_checkpoint_helmsman(path: str | Path) -> Helmsman:
    """The policy of a checkpoint file as a helmsman; ``ValueError`` if it cannot be read."""
    from learning.experiments.checkpoint import CheckpointError, load_helmsman

    try:
        return load_helmsman(path)
    except CheckpointError as err:
        raise UserError(str(err)) from None


def checkpoint_facts(path: str | Path) -> dict[str, Any]:
    """What a checkpoint file records about itself, for its model card
    (:mod:`usvsim.evaluation.model_cards`): setup, observation, action, algorithm, seed,
    code_commit (git revision), best_iteration (of its validation record, or None), date
    (YYYY-MM-DD, UTC). ``UserError`` if it cannot be read."""
    from learning.experiments.checkpoint import CheckpointError, load_checkpoint

    try:
        ckpt = load_checkpoint(path)
    except CheckpointError as err:
        raise UserError(str(err)) from None
    validation = ckpt.validation or {}
    return {
        "setup": ckpt.setup,
        "observation": ckpt.observation,
        "action": ckpt.action,
        "algorithm": ckpt.algorithm,
        "seed": int(ckpt.train_args.get("seed", ckpt.agent.get("config", {}).get("seed", 0))),
        "code_commit": ckpt.git_revision,
        "best_iteration": validation.get("iteration"),
        "date": ckpt.created_utc[:10],
    }


def available_helmsmen(models_dir: Path | None = None) -> dict[str, HelmsmanFactory]:
    """Name → factory of every compared helmsman: the baselines first, then trained policies.

    ``models_dir`` defaults to :data:`MODELS_DIR` (the package's shipped models); every ``*.pt``
    in it is one entry named by its stem. A trained policy named like a baseline raises
    ``ValueError`` rather than hiding it.
    """
    helmsmen: dict[str, HelmsmanFactory] = {
        "los": _los,
        "los-avoid": _los_avoid,
        "vo": _vo,
        "sb-mpc": _sbmpc,
        "vo-radar": _vo_radar,
        "sb-mpc-radar": _sbmpc_radar,
    }
    folder = MODELS_DIR if models_dir is None else models_dir
    for path in sorted(folder.glob("*.pt")) if folder.is_dir() else []:
        if path.stem in helmsmen or path.stem in (*SANITY_HELMSMEN, ALL):
            raise ValueError(f"trained model {path.stem!r} clashes with a baseline's name")
        helmsmen[path.stem] = partial(load_checkpoint_helmsman, path)
    return helmsmen


def model_aliases(models_dir: Path | None = None) -> dict[str, str]:
    """Former name → file stem of each shipped model whose card (``models.json``, entry
    ``card.former_names``) lists it: the names published results and the notes use (the
    training setup's name, e.g. ``il-categorical-scene-ow``); a name that is already a
    helmsman's is not an alias.

    Read here from the JSON (not through :mod:`usvsim.evaluation.model_cards`, which checks the
    cards) so that the registry stays below the evaluation block.
    """
    import json

    folder = MODELS_DIR if models_dir is None else models_dir
    index = folder / "models.json"
    if not index.is_file():
        return {}
    try:
        entries = json.loads(index.read_text())["models"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise UserError(f"{index}: unreadable model index ({type(exc).__name__})") from exc
    taken = {p.stem for p in folder.glob("*.pt")} | {"los", "los-avoid", "vo", "sb-mpc"}
    taken |= {"vo-radar", "sb-mpc-radar", *SANITY_HELMSMEN, ALL}
    aliases: dict[str, str] = {}
    for stem, entry in entries.items():
        for former in (entry.get("card") or {}).get("former_names", []):
            if former not in taken and (folder / f"{stem}.pt").is_file():
                aliases[former] = stem
    return aliases


def model_path(name: str, models_dir: Path | None = None) -> Path:
    """The shipped file of model ``name`` (its file stem or a former name, :func:`model_aliases`);
    ``usvsim/models/<name>.pt`` (which may not exist) for any other name.

    A training setup's shipped model is found by the setup's name this way: every former name
    is the setup's.
    """
    folder = MODELS_DIR if models_dir is None else models_dir
    stem = name if (folder / f"{name}.pt").is_file() else model_aliases(folder).get(name, name)
    return folder / f"{stem}.pt"


def make_helmsman(name: str, action: ActionKind = "gaussian") -> Helmsman:
    """Any helmsman of the module's table, by name or checkpoint path.

    ``action`` is the action kind of the sanity helmsmen (``straight``, ``random``); the others
    declare their own.

    Raises
    ------
    UserError
        (a ``ValueError``) for unknown names and unreadable checkpoints.
    """
    if name == "straight":
        return StraightAheadHelmsman(action=action)
    if name == "random":
        return RandomHelmsman(action=action)
    registry = available_helmsmen()
    if name in registry:
        return registry[name]()
    aliases = model_aliases()
    if name in aliases:
        return registry[aliases[name]]()
    if Path(name).is_file():
        return load_checkpoint_helmsman(name)
    raise UserError(_unknown(name, registry))


def _unknown(name: str, registry: dict[str, HelmsmanFactory]) -> str:
    return (
        f"unknown helmsman {name!r}; choose {', '.join((*SANITY_HELMSMEN, *registry))}, "
        "a model's former name (usvsim models) or a checkpoint file (.pt)"
    )


def select_helmsmen(
    names: Sequence[str], action: ActionKind = "gaussian"
) -> dict[str, HelmsmanFactory]:
    """Label → factory of each helmsman in ``names`` (names of the table or checkpoint paths).

    Duplicates are dropped (first one kept, order kept); an empty ``names`` or ``["all"]``
    selects every :func:`available_helmsmen`. A checkpoint path is labelled by its file stem
    (``runs/a/best.pt`` -> ``best``); nothing is loaded yet.

    Raises
    ------
    UserError
        For an unknown name, or two different paths or names with the same label.
    """
    registry = available_helmsmen()
    if not names or list(names) == [ALL]:
        return dict(registry)
    aliases = model_aliases()
    chosen: dict[str, HelmsmanFactory] = {}
    sources: dict[str, str] = {}
    factory: HelmsmanFactory
    for name in names:
        if name in SANITY_HELMSMEN:
            label, factory = name, partial(make_helmsman, name, action)
        elif name in registry:
            label, factory = name, registry[name]
        elif name in aliases:
            label, factory = name, registry[aliases[name]]
        elif Path(name).is_file():
            label, factory = Path(name).stem, partial(load_checkpoint_helmsman, name)
        else:
            raise UserError(_unknown(name, registry))
        if label in sources and sources[label] != name:
            raise UserError(
                f"helmsmen {sources[label]!r} and {name!r} would share the label {label!r}; "
                "rename one of the checkpoint files"
            )
        sources[label] = name
        chosen.setdefault(label, factory)
    return chosen


def helmsman_kinds(helmsman: Any) -> tuple[ObservationKind, ActionKind]:
    """(observation kind, action kind) a helmsman declares; default (positional, gaussian).

    Raises
    ------
    ValueError
        If the helmsman declares a kind that does not exist.
    """
    return (
        parse_observation_kind(getattr(helmsman, "observation", "positional")),
        parse_action_kind(getattr(helmsman, "action", "gaussian")),
    )
