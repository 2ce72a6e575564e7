"""Does DNV's own trafficgen read the situation files usvsim writes? (issue 39)

Step 1 (usvsim's environment): every baseline situation shipped in
``usvsim/evaluation/data/trafficgen`` → a boat-scale usvsim episode without perturbation →
written back with :func:`usvsim.evaluation.trafficgen_io.write_situation` into OUT. Step 2 (an
environment with the ``trafficgen`` package, e.g. a separate virtual environment, so that its
dependencies never touch usvsim's): trafficgen's reader
(``trafficgen.read_files.read_generated_situation_files``, its pydantic schema) reads both folders
and the start positions, speeds over ground and headings of every ship are compared::

    python benchmarks/trafficgen_check.py write /tmp/tg-written
    python -m venv /tmp/tg && /tmp/tg/bin/pip install trafficgen==0.9.1
    /tmp/tg/bin/python benchmarks/trafficgen_check.py compare /tmp/tg-written

Step 2 prints the number of files each side read and the largest differences (m, kn, deg).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

SHIPPED = Path(__file__).resolve().parents[1] / "usvsim" / "evaluation" / "data" / "trafficgen"
EARTH_RADIUS_M = 6_371_000.0  # m, mean Earth radius (distances between nearby positions)


def write(out: Path) -> int:
    """Step 1 (module docstring)."""
    import numpy as np

    from usvsim.evaluation.imazu import ImazuConfig
    from usvsim.evaluation.trafficgen_io import read_situation, situation_episodes, write_situation

    exact = ImazuConfig(
        rotate=False, course_jitter_rad=0.0, speed_jitter=0.0, position_jitter_m=0.0
    )
    out.mkdir(parents=True, exist_ok=True)
    files = sorted(SHIPPED.glob("*.json"))
    for f in files:
        sit = read_situation(f)
        episode = situation_episodes(sit, np.random.default_rng(0), exact)
        write_situation(
            episode, out / f.name, sit.scale(), origin_deg=sit.origin_deg, title=sit.title
        )
    print(f"wrote {len(files)} situation files to {out}")
    return 0


def compare(written: Path) -> int:
    """Step 2 (module docstring)."""
    from trafficgen.read_files import read_generated_situation_files

    original = read_generated_situation_files(SHIPPED)
    back = read_generated_situation_files(written)
    print(f"trafficgen read {len(original)} shipped and {len(back)} usvsim-written files")
    worst = {"position_m": 0.0, "sog_kn": 0.0, "heading_deg": 0.0, "targets": 0}
    for a, b in zip(original, back, strict=True):
        worst["targets"] = max(worst["targets"], abs(len(a.target_ships) - len(b.target_ships)))
        for s, t in zip([a.own_ship, *a.target_ships], [b.own_ship, *b.target_ships], strict=False):
            p, q = s.waypoints[0].position, t.waypoints[0].position
            d_north = math.radians(p.lat - q.lat) * EARTH_RADIUS_M
            d_east = math.radians(p.lon - q.lon) * EARTH_RADIUS_M * math.cos(math.radians(p.lat))
            worst["position_m"] = max(worst["position_m"], math.hypot(d_north, d_east))
            worst["sog_kn"] = max(
                worst["sog_kn"], abs(s.waypoints[0].leg.sog - t.waypoints[0].leg.sog)
            )
            d_hdg = abs(math.remainder(s.initial.heading - t.initial.heading, 360.0))
            worst["heading_deg"] = max(worst["heading_deg"], d_hdg)
    print("largest differences:", ", ".join(f"{k} {v:.4g}" for k, v in worst.items()))
    return 0


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] not in ("write", "compare"):
        print("usage: python benchmarks/trafficgen_check.py write|compare FOLDER", file=sys.stderr)
        return 2
    return (write if argv[0] == "write" else compare)(Path(argv[1]))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
