"""One page per registered usvsim environment, from the env class's docstring (Gymnasium's
section order) and a rendered episode."""

from __future__ import annotations

import importlib
import inspect
import io
import re
from typing import Any

SECTIONS = (
    "Description",
    "Action Space",
    "Observation Space",
    "Rewards",
    "Starting State",
    "Episode End",
    "Arguments",
)
_ROLE = re.compile(r":(?:mod|class|func|data|meth|attr|obj):`~?([^`]+)`")


def _gymnasium() -> Any:
    """Gymnasium with usvsim's environments registered."""
    import gymnasium

    import usvsim  # noqa: F401  (registers the envs)

    return gymnasium


def env_ids() -> list[str]:
    """The ids ``import usvsim`` registers with Gymnasium, in registration order."""
    return [k for k in _gymnasium().registry if k.startswith("usvsim/")]


def slug(env_id: str) -> str:
    """``usvsim/PoleAvoidance-v0`` → ``poleavoidance-v0`` (the page's file name)."""
    return env_id.split("/", 1)[1].lower()


def _resolve(target: Any) -> Any:
    if not isinstance(target, str):
        return target
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def env_class(env_id: str) -> type:
    """The documented class: the single env if registered, else the vector env."""
    gymnasium = _gymnasium()
    spec = gymnasium.spec(env_id)
    return _resolve(spec.entry_point or spec.vector_entry_point)


def sections(doc: str) -> tuple[str, dict[str, str]]:
    """(summary, {title: body}) of a docstring with ``## Title`` sections."""
    text = _ROLE.sub(r"`\1`", inspect.cleandoc(doc))
    parts = re.split(r"^## +(.+?)\s*$", text, flags=re.MULTILINE)
    summary, found = parts[0].strip(), {}
    for title, body in zip(parts[1::2], parts[2::2], strict=True):
        found[title.strip()] = body.strip()
    return summary, found


def check_sections(env_id: str, found: dict[str, str]) -> None:
    """Every Gymnasium section present: a docstring that loses one fails the build."""
    missing = [s for s in SECTIONS if s not in found]
    if missing:
        raise ValueError(f"{env_id}: env docstring lacks the section(s) {', '.join(missing)}")


def _spaces(env_id: str) -> tuple[str, str]:
    gymnasium = _gymnasium()
    spec = gymnasium.spec(env_id)
    if spec.entry_point is not None:
        env = gymnasium.make(env_id)
        spaces = (repr(env.action_space), repr(env.observation_space))
    else:
        env = gymnasium.make_vec(env_id, num_envs=1)
        spaces = (repr(env.single_action_space), repr(env.single_observation_space))
    env.close()
    return spaces


def pole_episode_png() -> bytes:
    """Last frame of ``positional-gaussian-trpo-study`` on seed 3 of ``usvsim/PoleAvoidance-v0``."""
    import gymnasium
    import matplotlib.pyplot as plt
    import numpy as np

    from usvsim.helm.registry import make_helmsman

    helmsman = make_helmsman("positional-gaussian-trpo-study")
    helmsman.reset(1)
    env = gymnasium.make("usvsim/PoleAvoidance-v0", render_mode="rgb_array")
    obs, _ = env.reset(seed=3)
    done = False
    while not done:
        obs, _, terminated, truncated, _ = env.step(np.asarray(helmsman.act(obs[None]))[0])
        done = terminated or truncated
    frame = env.render()
    assert isinstance(frame, np.ndarray)  # render_mode="rgb_array": one (H, W, 3) frame
    buf = io.BytesIO()
    plt.imsave(buf, frame, format="png")
    env.close()
    return buf.getvalue()


POLE_CAPTION = (
    "The last frame of one episode: `positional-gaussian-trpo-study` on `env.reset(seed=3)`, "
    '`render_mode="rgb_array"` (`render()` after the last step; `docs/hooks/gen_envs.py`).'
)


def env_page(env_id: str, image: str | None, caption: str) -> str:
    """The Markdown page of ``env_id``; ``image``: the rendered episode's path on the site."""
    gymnasium = _gymnasium()
    spec = gymnasium.spec(env_id)
    cls = env_class(env_id)
    summary, found = sections(cls.__doc__ or "")
    check_sections(env_id, found)
    action, observation = _spaces(env_id)
    make = (
        f'gymnasium.make("{env_id}")'
        if spec.entry_point is not None
        else f'gymnasium.make_vec("{env_id}", num_envs=N)'
    )
    rows = [
        ("Single env", f"`{spec.entry_point}`" if spec.entry_point else "– (vector env only)"),
        ("Vector env", f"`{spec.vector_entry_point}`" if spec.vector_entry_point else "–"),
        ("Action space (defaults)", f"`{action}`"),
        ("Observation space (defaults)", f"`{observation}`"),
        ("Import", f"`import usvsim; {make}`"),
    ]
    lines = [f"# {env_id}", ""]
    if image:
        lines += [f"![{env_id}]({image})", "", f"*{caption}*", ""]
    lines += ["| | |", "|---|---|", *[f"| {k} | {v} |" for k, v in rows], "", summary, ""]
    for title in SECTIONS:
        lines += [f"## {title}", "", found[title], ""]
    for title, body in found.items():
        if title not in SECTIONS:
            lines += [f"## {title}", "", body, ""]
    lines += [
        "*Generated from the docstring of "
        f"`{cls.__module__}.{cls.__qualname__}` when this site is built.*",
        "",
    ]
    return "\n".join(lines)


def index_page(ids: list[str]) -> str:
    """The environments' overview."""
    lines = [
        "# Environments",
        "",
        "`import usvsim` registers these Gymnasium environments. Each page is generated from the "
        "environment's docstring, in the order of Gymnasium's own environment pages.",
        "",
        "| id | documented class |",
        "|---|---|",
    ]
    for env_id in ids:
        cls = env_class(env_id)
        lines.append(f"| [{env_id}]({slug(env_id)}.md) | `{cls.__module__}.{cls.__qualname__}` |")
    lines += [
        "",
        "How to use them with vector envs, wrappers and Stable-Baselines3: "
        "[Gymnasium and SB3](../guide/gymnasium.md).",
        "",
    ]
    return "\n".join(lines)
