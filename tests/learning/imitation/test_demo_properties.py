"""Property tests (hypothesis) of the demonstration reader: random and mutated ``usvsim-demo/1``
files and metadata give a :class:`Recording` or a :class:`DemoFormatError` naming the file, never
another exception, within a deadline."""

from __future__ import annotations

import json
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from learning.imitation.demonstrations import (
    DEMOS_DIR,
    REQUIRED_METADATA,
    DemoFormatError,
    Recording,
    load_recording,
)

SOURCE = sorted(DEMOS_DIR.glob("demo_*.csv"))[0]
LINES = SOURCE.read_text().splitlines()[:60]  # metadata, header and ~60 s of samples
SETTINGS = settings(
    database=None,
    max_examples=300,
    deadline=1000,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
cells = st.one_of(
    st.text(max_size=10),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["", "nan", "inf", "-1e308", "123.0", "999", "gps", "radar", "compass"]),
)


@st.composite
def mutated_files(draw: st.DrawFn) -> str:
    """The shipped file's start with cells replaced, lines deleted, duplicated or swapped."""
    lines = list(LINES)
    for _ in range(draw(st.integers(1, 4))):
        k = draw(st.integers(1, len(lines) - 1))
        op = draw(st.sampled_from(["cell", "delete", "duplicate", "swap", "truncate"]))
        if op == "cell":
            parts = lines[k].split(",")
            parts[draw(st.integers(0, len(parts) - 1))] = draw(cells)
            lines[k] = ",".join(parts)
        elif op == "delete":
            del lines[k]
        elif op == "duplicate":
            lines.insert(k, lines[k])
        elif op == "swap":
            j = draw(st.integers(1, len(lines) - 1))
            lines[k], lines[j] = lines[j], lines[k]
        else:
            lines[k] = lines[k][: draw(st.integers(0, len(lines[k])))]
        if len(lines) < 3:
            break
    return "\n".join(lines) + "\n"


json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-1000, 1000), st.floats(), st.text(max_size=6)),
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=8,
)


@st.composite
def mutated_metadata(draw: st.DrawFn) -> str:
    magic, payload = LINES[0][2:].split(" ", 1)
    meta = json.loads(payload)
    key = draw(st.sampled_from([*REQUIRED_METADATA, "extra"]))
    if draw(st.booleans()):
        meta.pop(key, None)
    else:
        meta[key] = draw(json_values)
    return "\n".join([f"# {magic} {json.dumps(meta)}", *LINES[1:]]) + "\n"


def _load(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "demo.csv"
    path.write_bytes(data)
    try:
        rec = load_recording(path)
    except DemoFormatError as err:
        assert str(path) in str(err)
        return
    assert isinstance(rec, Recording)
    assert rec.gps_t_s.size >= 2 and rec.compass_t_s.size >= 2


@SETTINGS
@given(text=mutated_files())
def test_mutated_files_load_or_raise_demo_format_error(tmp_path: Path, text: str) -> None:
    _load(tmp_path, text.encode())


@SETTINGS
@given(text=mutated_metadata())
def test_mutated_metadata_loads_or_raises_demo_format_error(tmp_path: Path, text: str) -> None:
    _load(tmp_path, text.encode())


@SETTINGS
@given(raw=st.binary(max_size=400))
def test_random_bytes_raise_demo_format_error(tmp_path: Path, raw: bytes) -> None:
    _load(tmp_path, raw)
