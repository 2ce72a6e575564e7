"""Does the COLREG reward (issue 41, :mod:`usvsim.task.colreg_reward`) pay for what the COLREG
scorer calls compliant? Classical helmsmen on episodes of the COLREG training members, the
reward replayed on their recorded tracks beside the scorer's compliance.

Each helmsman (``--helmsmen``, registry names) runs ``--episodes`` episodes of
:data:`usvsim.task.colreg_family.COLREG_FAMILY` (seed ``--seed``; training geometry, not the
suite's) with targets holding course (:func:`usvsim.evaluation.colreg_rollout.run_encounters`);
the tracks are scored by :func:`usvsim.evaluation.colreg.evaluate_colreg` and the reward terms
are computed per decision from the recorded true trajectory, as the env computes them (own
course over ground over the period's last second, the vessels at the period's end). Printed as
JSON: per helmsman, success, compliance (passed / scored encounters) and the mean per-episode
sum of each term::

    nice python benchmarks/colreg_reward_check.py --helmsmen los,vo,sb-mpc --episodes 40
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from usvsim.evaluation.colreg import evaluate_colreg, summarize_colreg
from usvsim.evaluation.colreg_rollout import run_encounters
from usvsim.helm.registry import make_helmsman
from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.colreg_reward import COLREG_TERMS, ColregReward, ColregRewardWeights, own_motion
from usvsim.task.openwater import vessel_motion
from usvsim.task.openwater_env import draw_family

DECISION_S, DT_S = 2.0, 0.1  # s, the task's decision period and plant step
STEPS = round(DECISION_S / DT_S)


def replay(records: list[Any], weights: ColregRewardWeights) -> dict[str, np.ndarray]:
    """Per-episode sums (E,) of each COLREG term over the recorded decisions."""
    e = len(records)
    d_max = max((len(r.trajectory) - 2) // STEPS + 1 for r in records)
    k = max(len(r.episode.vessels) for r in records)
    traj = np.zeros((e, d_max * STEPS + 1, 2))
    decisions = np.zeros(e, dtype=np.intp)
    p0, course, speed, ok = (
        np.zeros((e, k, 2)),
        np.zeros((e, k)),
        np.zeros((e, k)),
        np.zeros((e, k), bool),
    )
    for i, r in enumerate(records):  # dataclasses into arrays (not a hot path)
        n = len(r.trajectory)
        traj[i, :n], traj[i, n:] = r.trajectory[:, 0:2], r.trajectory[-1, 0:2]
        decisions[i] = (n - 1 + STEPS - 1) // STEPS
        for j, v in enumerate(r.episode.vessels):
            p0[i, j], course[i, j], speed[i, j], ok[i, j] = (
                (v.x0_n, v.y0_e),
                v.course_rad,
                v.speed_mps,
                True,
            )
    reward = ColregReward(weights, e)
    sums = {t: np.zeros(e) for t in COLREG_TERMS}
    for d in range(d_max):  # a loop over time; boats and vessels are arrays
        live = d < decisions
        period = traj[:, d * STEPS + 1 : (d + 1) * STEPS + 1]
        pos, chi, u, t_end = own_motion(period, np.full(e, STEPS), DT_S)
        v_pos, v_vel = vessel_motion(
            p0, course, speed, np.zeros_like(speed), (d * DECISION_S + t_end)[:, None]
        )
        terms = reward(pos, chi, u, v_pos, v_vel, ok & live[:, None], DECISION_S)
        for t in COLREG_TERMS:
            sums[t] += np.where(live, getattr(terms, t), 0.0)
    return sums


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--helmsmen", default="los,vo,sb-mpc")
    ap.add_argument("--episodes", type=int, default=40)
    ap.add_argument("--seed", type=int, default=41)
    args = ap.parse_args()
    episodes = draw_family(COLREG_FAMILY, args.seed, args.episodes)
    out: dict[str, Any] = {"episodes": args.episodes, "seed": args.seed, "helmsmen": {}}
    for name in args.helmsmen.split(","):
        run = run_encounters(make_helmsman(name), episodes)
        summary = summarize_colreg(evaluate_colreg(run.tracks))
        sums = replay(run.records, ColregRewardWeights())
        c = summary.compliance
        out["helmsmen"][name] = {
            "success_rate": float(np.mean([r.success for r in run.records])),
            "compliance_rate": None if c is None else c.rate,
            "encounters": summary.encounters,
            "by_type": {
                t: d["compliance_rate"] for t, d in summary.by_type.items() if d["encounters"]
            },
            "reward_per_episode": {t: float(v.mean()) for t, v in sums.items()},
            "reward_total_per_episode": float(sum(v.mean() for v in sums.values())),
        }
        print(name, json.dumps(out["helmsmen"][name]), flush=True)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
