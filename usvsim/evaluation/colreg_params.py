"""The COLREG evaluation's parameters: :mod:`usvsim.task.colreg_params`, where the scorer
(:mod:`usvsim.evaluation.colreg`) and the training reward (:mod:`usvsim.task.colreg_reward`)
both read them; this name stays for the scorer's users and ``python -m
usvsim.evaluation.colreg_params`` (the docs' parameter table)."""

from __future__ import annotations

from usvsim.task.colreg_params import (
    RANGE_SCALE,
    SHIP_SPEED_MPS,
    ColregParams,
    parameter_markdown,
    parameter_table,
)

__all__ = ["RANGE_SCALE", "SHIP_SPEED_MPS", "ColregParams", "parameter_markdown", "parameter_table"]

if __name__ == "__main__":
    print(parameter_markdown(), end="")
