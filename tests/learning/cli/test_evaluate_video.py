"""``usvsim evaluate --video``: the chosen validation episodes as a GIF, clear errors otherwise."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from learning.cli.evaluate import EvaluateArgs, run

MODELS = Path(__file__).resolve().parents[3] / "usvsim" / "models"
MODEL = str(MODELS / "positional-gaussian-trpo-study.pt")


def test_video_holds_the_chosen_episodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "episodes.gif"
    assert run(EvaluateArgs(MODEL, heldout=0, video=str(path), video_episodes="2,5")) == 0
    out = capsys.readouterr().out
    assert "15/15" in out and "validation episodes [2, 5]" in out
    n_frames = int(out.rsplit(", ", 1)[1].split()[0])
    # two successful episodes of ≥ 26 decisions (210 m to the goal circle at ≤ 4.03 m/s, the
    # fastest the autopilot lets the boat go while it turns), each + start frame + 1 s held
    assert n_frames >= 2 * (26 + 1 + 5)
    with Image.open(path) as gif:
        assert gif.size == (400, 400) and gif.n_frames >= 2 * 27  # PIL merges the held frames


@pytest.mark.parametrize(
    ("video", "episodes", "match"),
    [
        ("ep.avi", "0", r"--video must end in \.gif or \.mp4"),
        ("ep.gif", "15", r"--video-episodes must be 'all' or comma-separated indices 0\.\.14"),
        ("ep.gif", "a,b", "--video-episodes must be"),
    ],
)
def test_bad_video_options_exit_with_one_line(
    tmp_path: Path, video: str, episodes: str, match: str
) -> None:
    with pytest.raises(SystemExit, match=match):
        run(EvaluateArgs(MODEL, heldout=0, video=str(tmp_path / video), video_episodes=episodes))
    assert not (tmp_path / video).exists()
