"""``usvsim sweep --device``: the setups it accepts and a trial trained on the device loop."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


def test_a_device_sweep_checks_its_setups_and_asks_for_its_gpu_share() -> None:
    """--device: every setup must train there (usvsim train --device's rule); a trial asks Ray
    for its threads and, with a GPU share, that share."""
    from learning.experiments.sweep import SweepSpec, trial_resources

    spec = SweepSpec("d", ("rl-categorical-positional", "rl-gaussian-scene-ow"), (0,),
                     device="torch-cpu", threads=2)  # fmt: skip
    assert SweepSpec.from_json(spec.to_json()) == spec
    assert trial_resources(spec) == {"cpu": 2}
    assert trial_resources(spec, 0.25) == {"cpu": 2, "gpu": 0.25}
    SweepSpec("d", ("il-gaussian-positional", "il-gaussian-radar-ow"), (0,), device="torch-cpu")
    refused = ("il-gaussian-radar", "rl-gaussian-radar", "rl-gaussian-radar-ppo")
    for name in refused:
        with pytest.raises(ValueError, match="--device torch-cpu"):
            SweepSpec("d", (name,), (0,), device="torch-cpu")


@pytest.mark.slow
def test_a_torch_cpu_sweep_trains_its_trials_on_the_device(tmp_path: Path) -> None:
    """``usvsim sweep --device torch-cpu``: the trial's run folder records the device loop's
    command and the sweep reports it."""
    pytest.importorskip("ray.tune")
    out = tmp_path / "dev"
    main = "import sys; from usvsim.cli.main import main; sys.exit(main())"
    args = ["sweep", "--setups", "rl-categorical-positional", "--seeds", "0", "--iterations", "2"]
    args += ["--validate-every", "1", "--n-envs", "8", "--heldout", "3", "--no-shipped"]
    args += ["--device", "torch-cpu", "--out", str(out)]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    done = subprocess.run(
        [sys.executable, "-c", main, *args], capture_output=True, text=True, env=env, timeout=300
    )
    assert done.returncode == 0, done.stdout + done.stderr
    (trial,) = json.loads((out / "trials.json").read_text())
    summary = json.loads((out / "runs" / trial["dir"] / "summary.json").read_text())
    assert "--device torch-cpu" in summary["command"] and summary["iterations"] == 2
