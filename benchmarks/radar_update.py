"""Cost of one radar TRPO update (issue 17), and what each candidate speed-up changes.

One batch of rl-gaussian-radar (64 boats × 64 decisions = 4096 radar+goal samples, its nets and
hyper-parameters: :data:`learning.experiments.setups.RADAR_TRPO`) is collected once; then
:meth:`learning.algorithms.trpo.TRPOAgent.update` runs on copies of the same agent and batch,
once per variant and round, the variants interleaved in each round (so that a change of the
machine's load hits all of them alike), one torch thread::

    python benchmarks/radar_update.py                   # 3 rounds, every variant
    python benchmarks/radar_update.py --rounds 5 --variants "as is" "bf16 critic"
    python benchmarks/radar_update.py --compare-training 10 --variants "as is" "bf16 critic"

``--compare-training N`` trains the setup (``--setup``, seed 0) N iterations under each variant
instead and prints each curve (return, KL, entropy per iteration, validation every 5): a
variant that changes only speed gives the same curve.

==========================  =================================================================
variant                     what changes (against the code as it is)
==========================  =================================================================
``as is``                   nothing: the reference
``unfolded``                the update without ``networks.fused_passes`` (as before
                            2026-12-03): ReLU, BatchNorm and the concatenation with the goal
                            as passes of their own; "as is" against it is the saving
``fvp torch.func.jvp``      J v of the Fisher-vector products by ``torch.func.jvp`` (the
                            forward pass again per product, as before 2026-12-03), not by
                            ``linearized.linearize_cnn_policy`` (the forward pass kept)
``fvp double backward``     Fisher-vector products by the double backward of the mean KL
                            (``kl_hessian_vector_product``, the MLP's; before: the CNN's too)
``channels-last``           images and conv weights in ``torch.channels_last``
``bf16 critic``             the critic (its fit and V(s)) under bfloat16 autocast (AMX)
``bf16 update``             the critic and the policy's trunk under bfloat16 autocast
``fvp 5 %``                 Fisher-vector products on 5 % of the batch (setup: 10 %)
``critic 1 epoch``          one critic epoch (setup: 2)
``critic minibatch 1024``   critic minibatches of 1024 rows (setup: 512)
==========================  =================================================================

Printed per variant: the median update wall-clock and CPU time (``time.process_time``: less
sensitive to other jobs on the machine) and the wall-clock split (:class:`UpdateTimes`), the
median CPU-time ratio to ``as is`` of the same rounds, and what the update did differently: the
largest change of any policy parameter against ``as is`` relative to the step itself (0: the
same update), and the accepted step's KL. Writes nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import dataclasses
import os
import statistics
import time
from collections.abc import Callable, Iterator
from typing import Any
from unittest import mock

import torch
from torch import Tensor

import learning.algorithms.linearized as linearized
import learning.algorithms.trpo as trpo
from learning.algorithms.loop import IterationStats, iterate
from learning.algorithms.rollout import RolloutBatch, RolloutCollector
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.algorithms.trust_region import get_flat, kl_hessian_vector_product, trainable_params
from learning.experiments.setups import get_setup
from learning.experiments.validation import validate

SETUP = "rl-gaussian-radar"


def _plain_passes(*nets: Any) -> contextlib.nullcontext[None]:
    """``networks.fused_passes`` switched off: the update's passes as before 2026-12-03."""
    return contextlib.nullcontext()


def _bf16(fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        with torch.autocast("cpu", dtype=torch.bfloat16):
            out = fn(*args, **kwargs)
        return out.float() if isinstance(out, Tensor) else out

    return wrapped


def _channels_last(agent: TRPOAgent) -> None:
    agent.policy.to(memory_format=torch.channels_last)
    agent.critic.to(memory_format=torch.channels_last)
    original = agent.policy_input

    def policy_input(obs: Any) -> Any:
        t = original(obs)
        t["radar"] = t["radar"].contiguous(memory_format=torch.channels_last)
        return t

    agent.policy_input = policy_input  # type: ignore[method-assign]


@contextlib.contextmanager
def variant(name: str, agent: TRPOAgent, batch: RolloutBatch | None) -> Iterator[None]:
    """Apply variant ``name`` (module table) to ``agent`` for the duration of the block."""
    cfg = agent.config
    with contextlib.ExitStack() as stack:
        if name == "unfolded":
            stack.enter_context(mock.patch.object(trpo, "fused_passes", _plain_passes))
        elif name == "fvp torch.func.jvp":
            stack.enter_context(mock.patch.object(linearized, "supports", lambda policy: False))
        elif name == "fvp double backward":
            patch = mock.patch.object(trpo, "fisher_vector_product", kl_hessian_vector_product)
            stack.enter_context(patch)
        elif name == "channels-last":
            _channels_last(agent)
        elif name == "bf16 critic":  # its fit and its V(s) for the advantages
            agent.critic.forward = _bf16(agent.critic.forward)  # type: ignore[method-assign]
        elif name == "bf16 update":  # the critic and the policy's trunk
            agent.critic.forward = _bf16(agent.critic.forward)  # type: ignore[method-assign]
            trunk = agent.policy.trunk
            trunk.forward = _bf16(trunk.forward)  # type: ignore[method-assign]
        elif name == "fvp 5 %":
            agent.config = dataclasses.replace(cfg, fvp_fraction=0.05)
        elif name == "critic 1 epoch":
            agent.config = dataclasses.replace(cfg, critic_epochs=1)
        elif name == "critic minibatch 1024":
            agent.config = dataclasses.replace(cfg, critic_minibatch=1024)
        elif name != "as is":
            raise ValueError(f"unknown variant {name!r}; known: {list(VARIANTS)}")
        yield


VARIANTS = (
    "as is",
    "unfolded",
    "fvp torch.func.jvp",
    "fvp double backward",
    "channels-last",
    "bf16 critic",
    "bf16 update",
    "fvp 5 %",
    "critic 1 epoch",
    "critic minibatch 1024",
)


def one_update(name: str, agent: TRPOAgent, batch: RolloutBatch) -> dict[str, Any]:
    """Time ``agent.update`` on copies of ``agent`` and ``batch`` under variant ``name``."""
    a, b = copy.deepcopy(agent), copy.deepcopy(batch)
    with variant(name, a, b):
        t, cpu = time.perf_counter(), time.process_time()
        stats = a.update(b)
        wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "times": dataclasses.asdict(stats.times),
        "kl": stats.kl,
        "theta": get_flat(trainable_params(a.policy)),
    }


def training_curve(setup_name: str, name: str, iterations: int, every: int) -> list[str]:
    """``iterations`` of ``setup_name`` (seed 0) under variant ``name``: per iteration the mean
    return, KL and entropy, and the validation successes every ``every`` iterations."""
    setup = get_setup(setup_name)
    config = setup.run_config(0, iterations)
    assert isinstance(config, TRPOConfig)
    env = setup.make_vector_env(config.num_envs)
    agent = TRPOAgent(env.single_observation_space, env.single_action_space, config)
    lines: list[str] = []

    def record(stats: IterationStats, agent: TRPOAgent) -> bool:
        val = ""
        if stats.iteration % every == 0:
            val = f" val {int(validate(agent, setup)['successes'])}/15"
        lines.append(
            f"{stats.iteration:3d} return {stats.mean_return:9.3f} kl {stats.kl:.5f} "
            f"entropy {stats.entropy:.5f}{val}"
        )
        return False

    try:
        with variant(name, agent, None):
            iterate(agent, env, record)
    finally:
        env.close()
    return lines


def compare_training(args: argparse.Namespace) -> None:
    """``--compare-training``: the same seed's curve as is and under each other variant."""
    curves = {n: training_curve(args.setup, n, args.compare_training, 5) for n in args.variants}
    print(f"{args.setup}, seed 0, {args.compare_training} iterations")
    for name, lines in curves.items():
        same = lines == curves[args.variants[0]]
        print(f"-- {name}" + (f" (identical to {args.variants[0]})" if same else ""))
        print("\n".join(lines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument(
        "--compare-training",
        type=int,
        default=0,
        metavar="ITERATIONS",
        help="instead: train --setup this many iterations under each variant, same seed",
    )
    parser.add_argument("--setup", default=SETUP, help="for --compare-training")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    if args.compare_training:
        compare_training(args)
        return
    setup = get_setup(SETUP)
    config = setup.run_config(0, 1)
    env = setup.make_vector_env(config.num_envs)
    agent = TRPOAgent(env.single_observation_space, env.single_action_space, config)
    batch = RolloutCollector(env, seed=0).collect(agent.sample, config.steps_per_env)
    agent.update(copy.deepcopy(batch))  # BatchNorm statistics and normaliser from the batch
    batch = RolloutCollector(env, seed=1).collect(agent.sample, config.steps_per_env)
    env.close()
    names = ["as is", *(v for v in args.variants if v != "as is")]
    theta0 = get_flat(trainable_params(agent.policy))
    one_update("as is", agent, batch)  # warm-up
    runs: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
    load = [os.getloadavg()[0]]
    for _ in range(args.rounds):
        for name in names:
            runs[name].append(one_update(name, agent, batch))
        load.append(os.getloadavg()[0])
    ref = runs["as is"]
    step = float((ref[0]["theta"] - theta0).abs().max())
    print(
        f"{SETUP}: one TRPO update on {config.batch_size} samples, {args.threads} torch thread(s),"
        f" median of {args.rounds} interleaved rounds, load average {min(load):.1f}-{max(load):.1f}"
    )
    print(
        f"{'variant':24s} {'wall s':>6s} {'CPU s':>6s} {'× as is':>7s}  batch / policy / critic s"
        "   Δθ / step   KL"
    )
    for name in names:
        r = runs[name]
        wall = statistics.median(x["wall_s"] for x in r)
        cpu = statistics.median(x["cpu_s"] for x in r)
        ratio = statistics.median(x["cpu_s"] / y["cpu_s"] for x, y in zip(r, ref, strict=True))
        parts = [
            statistics.median(x["times"][k] for x in r)
            for k in ("batch_s", "policy_step_s", "critic_s")
        ]
        change = float((r[0]["theta"] - ref[0]["theta"]).abs().max()) / step
        print(
            f"{name:24s} {wall:6.2f} {cpu:6.2f} {ratio:7.2f}  "
            f"{' / '.join(f'{p:.2f}' for p in parts):18s}"
            f"  {change:9.2e}  {r[0]['kl']:.4f}"
        )


if __name__ == "__main__":
    main()
