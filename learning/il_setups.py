"""The four IL setups of the study (Vedeler 2019, Table 4.1) and their training run (GAIL).

============================  ===========  ===========  ===========================================
setup                         observation  action       networks (policy, critic, discriminator)
============================  ===========  ===========  ===========================================
``il-gaussian-positional``    positional   gaussian     MLP 400-300 tanh
``il-categorical-positional`` positional   categorical  MLP 400-300 tanh, 41 logits
``il-gaussian-radar``         radar+goal   gaussian     CNN 10×7×7/4, goal (and for D the action)
                                                        late, FC 400-300
``il-categorical-radar``      radar+goal   categorical  as above, 41 logits
============================  ===========  ===========  ===========================================

"radar" means ``radar+goal`` as in :mod:`learning.setups` (the image alone hides the goal once
the pole is passed). Each setup is a frozen dataclass: :meth:`ILSetup.trpo_config` and
:meth:`ILSetup.gail_config` give the configs of a run; a name plus a seed reproduces it.

What differs from the study, and why (measured in this repository, see the final report):

* a behavioural-cloning warm start (``bc_epochs``) before GAIL: the cloned policy already reaches
  the goal in most rollouts, so GAIL's discriminator compares state distributions that overlap
  from the first iteration; GAIL then corrects BC's compounding errors (BC alone passes the
  pole too close: the recorded action is the heading *achieved* in 2 s, smaller than the
  heading *commanded*);
* actions normalised before the discriminator, absorbing states (:mod:`learning.gail`).

:func:`train_il` is the run: load and filter the demonstrations (:mod:`learning.demonstrations`),
preprocess them (:mod:`learning.preprocess`), GAIL (:func:`learning.gail.train_gail`), validate
on the 15 episodes every ``validate_every`` iterations, keep the best checkpoint
(:mod:`learning.checkpoint` format; the discriminator in a ``latest.gail.pt`` sidecar for
resuming). ``python -m learning.il_setups SETUP`` runs it from the command line.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from learning.checkpoint import Checkpoint, PolicyHelmsman, load_checkpoint, save_checkpoint
from learning.demonstrations import DEMOS_DIR, load_recordings, quality_check
from learning.gail import GAILConfig, GAILStats, GAILTrainer, train_gail
from learning.likeness import expert_reference, likeness
from learning.preprocess import expert_data
from learning.setups import trpo_config_of
from learning.trpo import TRPOAgent, TRPOConfig
from usvsim.evaluate import evaluate, validation_episodes
from usvsim.fileio import atomic_open
from usvsim.vector_env import PoleAvoidanceVectorEnv

__all__ = ["IL_SETUPS", "ILRunResult", "ILSetup", "get_il_setup", "train_il"]


@dataclass(frozen=True)
class ILSetup:
    """One IL setup: task kinds, TRPO and GAIL hyperparameters (names as in the papers)."""

    name: str = "il-gaussian-positional"
    observation: str = "positional"
    action: str = "gaussian"
    iterations: int = 120  # budget of GAIL iterations
    num_envs: int = 16  # N
    steps_per_env: int = 64  # T; B = N·T = 1024
    gamma: float = 0.99
    gae_lambda: float = 0.97
    max_kl: float = 0.02  # δ, nats
    cg_iters: int = 10
    cg_damping: float = 0.1
    fvp_fraction: float = 0.25
    critic_lr: float = 1e-3
    critic_epochs: int = 5
    critic_minibatch: int = 256
    init_std_fraction: float = 0.5
    reward: str = "-log(1-D)"
    disc_lr: float = 3e-4
    disc_steps: int = 10
    disc_minibatch: int = 256
    gradient_penalty: float = 0.0
    entropy_bonus: float = 0.0
    absorbing: bool = True
    bc_epochs: int = 50
    bc_lr: float = 1e-3
    policy_warmup: int = 0  # GAIL iterations with the policy frozen after the warm start
    freeze_input_stats: bool = False  # keep the expert's input statistics (learning.gail)
    validate_every: int = 10
    study_success: float = 0.0  # the study's best validation success (Table 4.1)
    study_iterations: int = 0  # the study's iterations to it

    def trpo_config(self, seed: int = 0, iterations: int | None = None) -> TRPOConfig:
        return trpo_config_of(self, seed, iterations)

    def gail_config(self) -> GAILConfig:
        return GAILConfig(
            reward=self.reward,
            disc_lr=self.disc_lr,
            disc_steps=self.disc_steps,
            disc_minibatch=self.disc_minibatch,
            gradient_penalty=self.gradient_penalty,
            entropy_bonus=self.entropy_bonus,
            absorbing=self.absorbing,
            bc_epochs=self.bc_epochs,
            bc_lr=self.bc_lr,
            policy_warmup=self.policy_warmup,
            freeze_input_stats=self.freeze_input_stats,
        )

    def replace(self, **changes: object) -> ILSetup:
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


IL_SETUPS: dict[str, ILSetup] = {
    s.name: s
    for s in (
        ILSetup(
            "il-gaussian-positional",
            "positional",
            "gaussian",
            study_success=0.866,
            study_iterations=1700,
        ),
        ILSetup(
            "il-categorical-positional",
            "positional",
            "categorical",
            iterations=200,
            max_kl=0.01,  # δ 0.02 measured: 14/15 at best, validation swung 5-14/15
            study_success=1.0,
            study_iterations=2100,
        ),
        ILSetup(
            "il-gaussian-radar",
            "radar+goal",
            "gaussian",
            max_kl=0.01,
            policy_warmup=10,  # measured without: cloned 15/15 fell to 2/15 in 10 iterations
            freeze_input_stats=True,
            iterations=150,
            num_envs=8,
            steps_per_env=128,
            study_success=0.533,
            study_iterations=3700,
        ),
        ILSetup(
            "il-categorical-radar",
            "radar+goal",
            "categorical",
            max_kl=0.01,
            policy_warmup=10,  # measured without: cloned 15/15 fell to 2/15 in 10 iterations
            freeze_input_stats=True,
            iterations=150,
            num_envs=8,
            steps_per_env=128,
            study_success=0.866,
            study_iterations=5000,
        ),
    )
}


def get_il_setup(name: str) -> ILSetup:
    """The IL setup called ``name``; ``ValueError`` naming the known ones otherwise."""
    try:
        return IL_SETUPS[name]
    except KeyError:
        raise ValueError(f"unknown IL setup {name!r}; known: {', '.join(IL_SETUPS)}") from None


@dataclass
class ILRunResult:
    """The best validation record, every record, and where the checkpoints are."""

    best: dict[str, Any] | None
    history: list[dict[str, Any]]
    best_path: Path
    last_path: Path


def _checkpoint(agent: TRPOAgent, setup: ILSetup, args: dict[str, Any], rec: Any, hist: Any) -> Any:
    # Checkpoint.from_agent reads name, observation, action and the fields of the setup: an
    # ILSetup has them all (it is typed RLSetup there; see the report's hook request)
    return Checkpoint.from_agent(
        agent,
        setup,  # type: ignore[arg-type]
        train_args=args,
        validation=rec,
        history=hist,
    )


def train_il(
    setup: ILSetup,
    out_dir: str | Path,
    *,
    seed: int = 0,
    iterations: int | None = None,
    resume: bool = False,
    threads: int = 1,
    demos_dir: str | Path = DEMOS_DIR,
    log: Callable[[str], None] = print,
) -> ILRunResult:
    """Train ``setup`` by GAIL, writing into ``out_dir`` (the layout of ``usvsim train``):

    ``best.pt`` the best validation checkpoint (most successes, then the smallest path
    distance to the expert, :mod:`learning.likeness`), ``latest.pt`` the last one and
    ``latest.gail.pt`` its discriminator state; ``resume`` continues from those two.
    ``threads``: torch CPU threads (on 2 shared cores, 2 threads made an iteration 20× slower
    than 1 when measured)."""
    torch.set_num_threads(max(1, threads))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    best_path, last_path = out / "best.pt", out / "latest.pt"
    report = load_recordings(demos_dir)
    for path, why in report.errors.items():
        log(f"skipping {path}: {why}")
    kept = [r for r in report.recordings if not quality_check(r)]
    data = expert_data(kept, setup.observation, setup.action)
    log(f"{setup.name}: {len(kept)}/{len(report.recordings)} demonstrations, {len(data)} pairs")
    args = {"seed": seed, "iterations": iterations, "demos": len(kept)}
    history: list[dict[str, Any]] = []
    best: dict[str, Any] | None = None
    state = None
    if resume:
        ck = load_checkpoint(last_path)
        gail_state = torch.load(last_path.with_suffix(".gail.pt"), weights_only=True)
        state, history = {"agent": ck.agent, "gail": gail_state}, ck.history
        best = max(history, key=_rank) if history else None
    specs = validation_episodes()
    reference = expert_reference(specs)

    def callback(s: GAILStats, agent: TRPOAgent, gail: GAILTrainer) -> bool:
        nonlocal best
        if s.iteration % setup.validate_every and s.iteration != cfg.iterations:
            return False
        helm = PolicyHelmsman(agent, setup.observation, setup.action)
        recs = evaluate(helm, specs, observation=setup.observation, action=setup.action)
        rec = {
            "iteration": s.iteration,
            "env_steps": s.env_steps,
            "wall_time_s": s.wall_time_s,
            "successes": sum(r.success for r in recs),
            "n_episodes": len(recs),
            "success_rate": sum(r.success for r in recs) / len(recs),
            "mean_return": s.env_return,
            "min_pole_distance_m": min(r.min_pole_distance_m for r in recs),
            "kl": s.kl,
            "entropy": s.entropy,
            "expert_accuracy": s.expert_accuracy,
            "policy_accuracy": s.policy_accuracy,
            "goal_rate": s.goal_rate,
            "path_distance_m": likeness(recs, reference).path_distance_m,
        }
        history.append(rec)
        log(
            f"it {s.iteration:4d} {s.wall_time_s:6.0f}s val {rec['successes']:2d}/15 "
            f"min d_pole {rec['min_pole_distance_m']:5.1f} m  D acc E/π "
            f"{s.expert_accuracy:.2f}/{s.policy_accuracy:.2f}  goal {s.goal_rate:.2f}  "
            f"path-to-expert {rec['path_distance_m']:4.1f} m"
        )
        ck = _checkpoint(agent, setup, args, rec, history)
        if best is None or _rank(rec) > _rank(best):
            best = rec
            save_checkpoint(ck, best_path)
        save_checkpoint(ck, last_path)
        with atomic_open(last_path.with_suffix(".gail.pt"), "wb") as handle:
            torch.save(gail.state_dict(), handle)
        return False

    cfg = setup.trpo_config(seed, iterations)
    env_kwargs = {"observation": setup.observation, "action": setup.action}
    train_gail(
        setup.gail_config(),
        cfg,
        lambda n: PoleAvoidanceVectorEnv(n, **env_kwargs),
        data,
        callback=callback,
        state=state,
    )
    return ILRunResult(best, history, best_path, last_path)


def _rank(rec: dict[str, Any]) -> tuple[int, float]:
    """Most validation successes first, then the most expert-like path (the point of IL)."""
    d = rec.get("path_distance_m", math.inf)
    return int(rec["successes"]), -d if math.isfinite(d) else -math.inf


def main(argv: list[str] | None = None) -> int:
    """``python -m learning.il_setups SETUP [--out DIR] [--seed S] [--iterations K]``."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m learning.il_setups", description=__doc__)
    parser.add_argument("setup", choices=sorted(IL_SETUPS))
    parser.add_argument("--out", default="")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=None)
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--threads", type=int, default=1)
    a = parser.parse_args(argv)
    res = train_il(
        get_il_setup(a.setup),
        a.out or f"usvsim-results/train/{a.setup}-seed{a.seed}",
        seed=a.seed,
        iterations=a.iterations,
        resume=a.resume,
        threads=a.threads,
    )
    print(f"best: {res.best}; checkpoint {res.best_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
