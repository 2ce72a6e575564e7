"""The generated tables of the "Training in traffic" page (``guide/traffic-training.md``), from
the code and the committed JSON, so that the page cannot drift from them:

- ``colreg-reward-weights``: :class:`usvsim.task.colreg_reward.ColregRewardWeights`, each
  field's default and the unit/source comment written on its line in the class;
- ``traffic-setups``: the ``-colreg`` RL and IL setups (:mod:`learning.experiments.setups`,
  :mod:`learning.experiments.il_setups`) with the fields that make them traffic setups;
- ``colreg-likeness``: ``docs/data/colreg-likeness.json`` (``benchmarks/colreg_likeness.py``)
  as :func:`usvsim.evaluation.colreg_likeness_bench.likeness_markdown` renders it.
"""

from __future__ import annotations

import inspect
import json
import re
from dataclasses import fields
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"
LIKENESS_JSON = DATA / "colreg-likeness.json"


def field_comments(cls: type) -> dict[str, str]:
    """``name: type = value  # comment`` lines of a dataclass's source: name -> comment."""
    pattern = re.compile(r"^\s+(\w+): [^=]+=.*?#\s*(.+)$")
    found = {}
    for line in inspect.getsource(cls).splitlines():
        match = pattern.match(line)
        if match:
            found[match.group(1)] = match.group(2).strip()
    return found


def reward_weights_markdown() -> str:
    """The COLREG reward's weights: term, default, unit and source (the field's comment)."""
    from usvsim.task.colreg_reward import COLREG_TERMS, ColregRewardWeights

    comments = field_comments(ColregRewardWeights)
    weights = ColregRewardWeights()
    lines = ["| field | default | unit, per what; rule (source) |", "|---|---|---|"]
    for f in fields(weights):
        if f.name == "params":
            continue
        if f.name not in comments:
            raise ValueError(f"ColregRewardWeights.{f.name} has no unit/source comment")
        name = f"`{f.name}`" + (" (term)" if f.name in COLREG_TERMS else "")
        lines.append(f"| {name} | {getattr(weights, f.name):g} | {comments[f.name]} |")
    return "\n".join(lines) + "\n"


def traffic_setups_markdown() -> str:
    """Every ``-colreg`` setup of the RL and IL registries with its traffic fields."""
    from learning.experiments.il_setups import IL_SETUPS
    from learning.experiments.setups import SETUPS

    lines = [
        "| setup | method | observation | episodes | COLREG reward terms | starts from | targets |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in SETUPS.values():
        if "colreg" not in s.name:
            continue
        family = f"{1 - s.colreg_share:.0%} open-water family, {s.colreg_share:.0%} COLREG"
        if s.colreg_suite_goals:
            family += " (goals 250-850 m, as far as the suite's)"
        safety = f" + safety margin (w = {s.safety_reward:g})" if s.safety_reward else ""
        start = s.init_policy or "new networks"
        if s.init_policy_required:
            start = "a trained checkpoint (`--init-policy FILE`)"
        observation = s.observation
        if s.radar_frames > 1:
            observation += f", the last {s.radar_frames} images (radar memory)"
        lines.append(
            f"| `{s.name}` | RL ({type(s.algorithm_config).__name__.removesuffix('Config')}) "
            f"| {observation} | {family} | {s.colreg_reward or '(none)'}{safety} "
            f"| {start} "
            f"| {'reactive (vo)' if s.reactive_targets else 'hold course'} |"
        )
    from learning.experiments.il_setups import COLREG_EPISODE_SHARE

    for il in IL_SETUPS.values():
        if "colreg" not in il.name:
            continue
        demos = " + ".join(f"`usvsim/demos/{d}`" for d in il.demos.split("+"))
        episodes = "the demonstrations' COLREG encounters"
        if il.family == "open-water+colreg":
            share = COLREG_EPISODE_SHARE
            episodes = f"{1 - share:.0%} open-water family, {share:.0%} COLREG"
        observation = il.observation
        if il.radar_frames > 1:
            observation += f", the last {il.radar_frames} images (radar memory)"
        lines.append(
            f"| `{il.name}` | IL (GAIL on {demos}) | {observation} "
            f"| {episodes} | – | new networks | hold course |"
        )
    return "\n".join(lines) + "\n"


def likeness_table() -> str:
    """``docs/data/colreg-likeness.json`` as a table, or a note that it is not there."""
    if not LIKENESS_JSON.is_file():
        return "*(no `docs/data/colreg-likeness.json` yet)*\n"
    from usvsim.evaluation.colreg_likeness_bench import likeness_markdown

    text = likeness_markdown(json.loads(LIKENESS_JSON.read_text()))
    return text.split("\n", 2)[2]  # without its own "# ..." title line and the blank after it
