"""``usvsim evaluate MODEL``: a trained policy on the validation and held-out episode sets.

``MODEL`` is a shipped model's name (``rl-gaussian-positional``: ``usvsim/models/<name>.pt``, the
names ``usvsim bench`` takes) or the path of a checkpoint file. Loads the checkpoint
(:func:`learning.experiments.checkpoint.load_checkpoint`, precise errors for a bad file), runs its
deterministic policy on the study's 15 validation episodes and on the 200 held-out episodes
(:mod:`usvsim.evaluation.episodes`), and prints one table::

    set         episodes  success  collision  min d_pole m (min / median)  mean t_goal s
    validation        15  15/15 (100.0 %)  0  ...

``min d_pole`` is each episode's closest approach to the pole (true positions, every 0.1 s);
the table gives its minimum and median over all episodes of the set, and the minimum over the
successful ones.

``--json`` prints the same as JSON instead, and nothing else on stdout (as ``usvsim bench --json``
and ``usvsim perf --json``); ``--json-out PATH`` writes it to a file (the deprecated ``--json
PATH`` still does, with a warning).

``--video PATH`` (``.gif``, or ``.mp4`` with moviepy: ``pip install "usvsim[video]"``) also
records the validation episodes chosen by ``--video-episodes`` (indices, e.g. ``0,3,7``, or
``all``) one after another, one top-view frame per 2 s decision
(:mod:`usvsim.task.render`, ``render_mode="rgb_array"``), 5 frames per second.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from learning.experiments.checkpoint import (
    CheckpointError,
    PolicyHelmsman,
    checkpoint_kinds,
    load_agent,
    load_checkpoint,
)
from learning.experiments.memory_start import setup_goal_mark
from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_write_text, check_writable_file, json_safe
from usvsim.common.options import bounds, legacy_path
from usvsim.evaluation.episodes import (
    EpisodeRecord,
    evaluate,
    format_records,
    heldout_episodes,
    validation_episodes,
)
from usvsim.task.env import PoleAvoidanceEnv
from usvsim.task.render import write_video
from usvsim.task.scenario import EpisodeSpec

__all__ = [
    "EvaluateArgs",
    "checkpoint_path",
    "episode_frames",
    "evaluation_row",
    "format_table",
    "run",
]


@dataclass(frozen=True)
class EvaluateArgs:
    """Evaluate a trained policy (a shipped model or a checkpoint) on the validation (15) and
    held-out episodes."""

    checkpoint: str  # a shipped model's name (rl-gaussian-positional) or a .pt checkpoint path
    heldout: int = field(default=200, metadata=bounds(ge=0, le=100_000))  # 0: validation only
    episodes: bool = False  # also print one line per validation episode
    json: bool = field(  # print the table as JSON only (stdout; NaN, e.g. no success: null)
        default=False, metadata=legacy_path("json_out")
    )
    json_out: str = ""  # also write the table as JSON to this path
    threads: int = field(default=2, metadata=bounds(ge=1, le=1024))  # torch CPU threads
    video: str = ""  # also write the chosen validation episodes as a video (.gif or .mp4)
    video_episodes: str = "0"  # validation episodes for --video: indices 0..14 (e.g. 0,3) or all


def evaluation_row(name: str, records: Sequence[EpisodeRecord]) -> dict[str, Any]:
    """Aggregates of one episode set (distances in m, times in s)."""
    d = np.array([r.min_pole_distance_m for r in records])
    ok = np.array([r.success for r in records])
    t_goal = np.array([r.time_to_goal_s for r in records])
    return {
        "set": name,
        "episodes": len(records),
        "successes": int(ok.sum()),
        "success_rate": float(ok.mean()),
        "collisions": int(sum(r.collision for r in records)),
        "min_pole_distance_m": float(d.min()),
        "median_pole_distance_m": float(np.median(d)),
        "min_pole_distance_successful_m": float(d[ok].min()) if ok.any() else math.nan,
        "mean_time_to_goal_s": float(np.nanmean(t_goal)) if np.isfinite(t_goal).any() else math.nan,
    }


def format_table(rows: Sequence[dict[str, Any]]) -> str:
    """The rows of :func:`evaluation_row` as a fixed-width table."""
    lines = [
        f"{'set':<11}{'episodes':>9}  {'success':<17}{'collisions':>10}  "
        f"{'min d_pole m (min / median / min successful)':<46}{'mean t_goal s':>13}"
    ]
    for r in rows:
        success = f"{r['successes']}/{r['episodes']} ({100 * r['success_rate']:.1f} %)"
        dist = (
            f"{r['min_pole_distance_m']:.1f} / {r['median_pole_distance_m']:.1f} / "
            f"{r['min_pole_distance_successful_m']:.1f}"
        )
        lines.append(
            f"{r['set']:<11}{r['episodes']:>9}  {success:<17}{r['collisions']:>10}  "
            f"{dist:<46}{r['mean_time_to_goal_s']:>13.1f}"
        )
    return "\n".join(lines)


def episode_frames(
    helmsman: Any, spec: EpisodeSpec, observation: Any, action: Any
) -> list[NDArray[np.uint8]]:
    """Top-view frames of one episode steered by ``helmsman``: the start, then one per decision."""
    env = PoleAvoidanceEnv(observation, action, render_mode="rgb_array")
    obs, _ = env.reset(options={"episode": spec})
    helmsman.reset(1)
    frames = [env.render()]
    done = False
    while not done:
        batched = {k: v[None] for k, v in obs.items()} if isinstance(obs, dict) else obs[None]
        obs, _, terminated, truncated, _ = env.step(np.asarray(helmsman.act(batched))[0])
        frames.append(env.render())
        done = terminated or truncated
    env.close()
    return frames


def _video_episodes(text: str, n: int) -> list[int]:
    """``"all"`` or comma-separated indices in 0..n-1; SystemExit naming what is allowed."""
    if text.strip() == "all":
        return list(range(n))
    try:
        chosen = [int(part) for part in text.split(",")]
    except ValueError:
        chosen = []
    if not chosen or any(not 0 <= i < n for i in chosen):
        raise SystemExit(
            f"usvsim evaluate: --video-episodes must be 'all' or comma-separated indices "
            f"0..{n - 1}, got {text!r}"
        )
    return chosen


def checkpoint_path(model: str) -> str:
    """The checkpoint file of ``model``: a shipped model's name or former name (as ``usvsim
    bench`` takes it, ``usvsim/models/<name>.pt``) or a path; :class:`UserError` naming both
    kinds otherwise."""
    from usvsim.helm.registry import MODELS_DIR, model_path

    shipped = model_path(model)
    if "/" not in model and shipped.is_file():
        return str(shipped)
    if Path(model).exists() or model.endswith(".pt"):
        return model  # a missing or unreadable file: load_checkpoint names what is wrong
    names = ", ".join(sorted(p.stem for p in MODELS_DIR.glob("*.pt")))
    raise UserError(f"unknown model {model!r}; choose a shipped model ({names}) or a .pt file")


def run(args: EvaluateArgs) -> int:
    """Run ``usvsim evaluate`` (module docstring); 0 on success."""
    torch.set_num_threads(max(1, args.threads))
    if args.heldout < 0:
        raise SystemExit("usvsim evaluate: --heldout must be >= 0")
    path = checkpoint_path(args.checkpoint)
    if args.json_out:
        check_writable_file(args.json_out, "--json-out")  # before the episodes, not after them
    video_episodes: list[int] = []
    if args.video:
        if not args.video.lower().endswith((".gif", ".mp4")):
            raise SystemExit(
                f"usvsim evaluate: --video must end in .gif or .mp4, got {args.video!r}"
            )
        video_episodes = _video_episodes(args.video_episodes, len(validation_episodes()))
        check_writable_file(args.video, "--video")
    try:
        ckpt = load_checkpoint(path)
        agent = load_agent(ckpt, path)
    except CheckpointError as err:
        raise SystemExit(f"usvsim evaluate: {err}") from None
    observation, action = checkpoint_kinds(ckpt)
    helmsman = PolicyHelmsman(
        agent, observation, action, goal_mark=setup_goal_mark(ckpt.setup_params)
    )
    sets = [("validation", validation_episodes())]
    if args.heldout:
        sets.append(("held-out", heldout_episodes(n=args.heldout)))
    rows, per_episode = [], ""
    for name, episodes in sets:
        records = evaluate(helmsman, episodes, observation=observation, action=action)
        rows.append(evaluation_row(name, records))
        if name == "validation" and args.episodes:
            per_episode = format_records(records)
    payload = {"checkpoint": path, "setup": ckpt.setup, "rows": rows}
    text = json.dumps(json_safe(payload), indent=2, allow_nan=False)
    if args.json:  # stdout holds the JSON and nothing else
        print(text)
    else:
        print(
            f"{path}: setup {ckpt.setup} ({ckpt.observation}, {ckpt.action}), "
            f"iteration {agent.iteration}, {agent.env_steps:,} env steps, "
            f"git {ckpt.git_revision}"
        )
        print(format_table(rows))
        if per_episode:
            print(per_episode)
    if args.json_out:
        atomic_write_text(args.json_out, text + "\n")
    if args.video:
        specs = validation_episodes()
        frames: list[NDArray[np.uint8]] = []
        for i in video_episodes:
            episode = episode_frames(helmsman, specs[i], observation, action)
            frames += episode + [episode[-1]] * 5  # hold each episode's end for 1 s
        try:
            write_video(frames, args.video, fps=5)
        except ImportError as err:
            raise SystemExit(f"usvsim evaluate: {err}") from None
        print(
            f"video: {args.video} (validation episodes {video_episodes}, {len(frames)} frames)",
            file=sys.stderr if args.json else sys.stdout,
        )
    sys.stdout.flush()
    return 0
