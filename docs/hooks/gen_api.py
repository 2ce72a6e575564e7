"""API reference pages: one page per block of the picture, mkdocstrings' ``:::`` directives for
its main modules (rendered from their numpydoc docstrings)."""

from __future__ import annotations

import importlib.util

# page title -> the modules it documents, in the order of the architecture picture
API = {
    "vessel": ("usvsim.vessel.vessels", "usvsim.vessel.model", "usvsim.vessel.autopilot",
               "usvsim.vessel.plant"),
    "nav": ("usvsim.nav.sensors", "usvsim.nav.kalman", "usvsim.nav.filter"),
    "task": ("usvsim.task.scenario", "usvsim.task.env", "usvsim.task.vector_env",
             "usvsim.task.openwater", "usvsim.task.openwater_env", "usvsim.task.observations",
             "usvsim.task.reward", "usvsim.task.sb3"),
    "helm": ("usvsim.helm.protocol", "usvsim.helm.registry"),
    "evaluation": ("usvsim.evaluation.episodes", "usvsim.evaluation.bench",
                   "usvsim.evaluation.stress"),
    "mavlink": ("usvsim.mavlink.bridge", "usvsim.mavlink.sitl", "usvsim.mavlink.mission"),
    "guidance": ("guidance",),
    "baselines": ("baselines.los", "baselines.avoid", "baselines.velocity_obstacle"),
    "learning": ("learning.algorithms.trpo", "learning.algorithms.ppo", "learning.algorithms.gae",
                 "learning.imitation.gail", "learning.experiments.setups",
                 "learning.experiments.il_setups"),
}  # fmt: skip


def pages() -> dict[str, str]:
    """{``api/NAME.md``: Markdown} for every block; a module that no longer exists is left out."""
    out = {}
    for name, modules in API.items():
        present = [m for m in modules if importlib.util.find_spec(m) is not None]
        body = "\n\n".join(f"::: {m}" for m in present)
        out[f"api/{name}.md"] = f"# `{name}`\n\n{body}\n"
    links = "\n".join(f"- [{name}]({name}.md): " + ", ".join(f"`{m}`" for m in mods)
                      for name, mods in API.items())  # fmt: skip
    out["api/index.md"] = (
        "# API reference\n\nGenerated from the numpydoc docstrings by mkdocstrings, one page per "
        f"block of the [architecture](../guide/architecture.md).\n\n{links}\n"
    )
    return out
