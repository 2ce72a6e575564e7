"""benchmarks/tracker_quality.py: bad input is one line and exit 2; the interval comparison."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
SCRIPT = ROOT / "benchmarks" / "tracker_quality.py"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(SCRIPT), *args], capture_output=True, text=True, cwd=ROOT, timeout=300
    )


def test_a_radar_image_of_the_wrong_shape_is_one_line_and_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "frame.npy"
    np.save(bad, np.zeros((2, 1, 50, 100), dtype=np.uint8))
    done = _run("--image", str(bad))
    assert done.returncode == 2
    lines = [ln for ln in done.stderr.splitlines() if ln.startswith("tracker_quality:")]
    assert len(lines) == 1 and "(N, 1, 50, 119)" in lines[0] and "(2, 1, 50, 100)" in lines[0]
    assert "Traceback" not in done.stderr


def test_a_good_frame_prints_its_detections(tmp_path: Path) -> None:
    frame = np.zeros((1, 1, 50, 119), dtype=np.uint8)
    frame[0, 0, 25, 59] = 255  # row 25: 100-104 m, column 59: dead ahead
    path = tmp_path / "frame.npy"
    np.save(path, frame)
    done = _run("--image", str(path))
    assert done.returncode == 0
    assert "image 0: range 102.0 m, bearing 0.0 deg" in done.stdout


def test_better_and_worse_need_each_rate_outside_the_other_interval() -> None:
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        from tracker_quality import separated  # type: ignore[import-not-found]
    finally:
        sys.path.remove(str(SCRIPT.parent))

    def row(rate: float, lo: float, hi: float) -> dict[str, float]:
        return {"success_rate": rate, "success_ci95_low": lo, "success_ci95_high": hi}

    vo, radar = row(1.0, 0.963, 1.0), row(0.96, 0.902, 0.984)
    assert separated(vo, radar) == 1 and separated(radar, vo) == -1
    assert separated(row(0.99, 0.946, 0.998), vo) == 0  # 0.99 lies inside vo's interval
