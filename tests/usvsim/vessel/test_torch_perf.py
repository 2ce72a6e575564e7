"""``usvsim perf --device``: the torch plant's throughput beside the C kernel's, and its errors."""

from __future__ import annotations

import pytest
import torch

from usvsim.cli.main import main
from usvsim.evaluation.perf import torch_plant_rates


@pytest.mark.skipif(torch.cuda.is_available(), reason="a GPU is present")
def test_perf_on_cuda_without_a_gpu_exits_2_with_one_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["perf", "--device", "cuda", "--no-env"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("usvsim perf: device 'cuda' needs a CUDA GPU")


def test_perf_rejects_an_unknown_device(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["perf", "--device", "tpu"])
    assert exit_.value.code == 2
    assert "choose from 'cpu', 'torch-cpu', 'cuda'" in capsys.readouterr().err


def test_torch_cpu_rates_stand_beside_the_c_kernel() -> None:
    figures = torch_plant_rates("torch-cpu", sizes=(64,), seconds=0.3, rounds=1)
    rates = figures["boat_substeps_per_s"]
    assert set(rates) == {"C kernel N=1024", "float64 N=64", "float32 N=64"}
    assert all(rate > 0 for rate in rates.values())
    ratio = figures["over_C_kernel_N=1024"]["float64 N=64"]
    assert ratio == pytest.approx(rates["float64 N=64"] / rates["C kernel N=1024"], rel=0.01)
