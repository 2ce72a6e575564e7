"""The weather stress sets' table in docs/guide/weather.md is generated from the committed JSON
(benchmarks/weather_stress_table.py), not typed: the page holds exactly the script's output."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def _script():
    spec = importlib.util.spec_from_file_location(
        "weather_stress_table", ROOT / "benchmarks" / "weather_stress_table.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_docs_table_is_the_scripts_output_of_the_committed_json() -> None:
    data = ROOT / "docs" / "data"
    weather = json.loads((data / "stress-weather.json").read_text())
    calm = json.loads((data / "stress-weather-calm.json").read_text())
    table = _script().table(weather, calm)
    assert table in (ROOT / "docs" / "guide" / "weather.md").read_text()
    # the run the table reports: every weather set, 100 test episodes, nothing skipped
    assert weather["sets"] == calm["sets"] == ["wind-beam", "gusts", "sea-state-3", "sea-state-4"]
    assert weather["split"] == calm["split"] == "test"
    assert weather["episodes_per_set"] == calm["episodes_per_set"] == 100
    assert weather["helmsmen"] == calm["helmsmen"] and not weather["interrupted"]
