"""The definition of a training sweep (:mod:`learning.experiments.sweep` runs it): a frozen
:class:`SweepSpec` (setups, seeds, a grid and/or random distributions over any training field,
the search algorithm, run options, the shipped-seed rule), the overrides of training fields
(:func:`apply_overrides`), the setup groups (:data:`SETUP_GROUPS`) and the trial folder names
(:func:`trial_dir_name`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from learning.experiments.il_setups import IL_SETUPS, ILSetup, get_il_setup
from learning.experiments.setups import SETUPS, RLSetup, get_setup
from usvsim.common.options import bounds, check_bounds

__all__ = [
    "SETUP_GROUPS",
    "Distribution",
    "SearchKind",
    "SweepSpec",
    "apply_overrides",
    "base_setup",
    "expand_setups",
    "parse_seeds",
    "trial_dir_name",
]

SearchKind = Literal["grid", "random", "optuna"]
SETUP_GROUPS: dict[str, tuple[str, ...]] = {
    "positional": (
        "rl-gaussian-positional",
        "rl-categorical-positional",
        "il-gaussian-positional",
        "il-categorical-positional",
    ),
    "radar": (
        "rl-gaussian-radar",
        "rl-categorical-radar",
        "il-gaussian-radar",
        "il-categorical-radar",
    ),
    # the study's four RL setups (not the PPO variants, not the open-water ``-ow`` setups)
    "rl": tuple(n for n, s in SETUPS.items() if not n.endswith("-ppo") and s.task == "pole"),
    "il": tuple(n for n, s in IL_SETUPS.items() if s.task == "pole"),
    # the open-water family's setups; those trained in traffic with the COLREG terms (issue 41)
    # form their own group
    "open-water": (
        *(n for n, s in SETUPS.items() if s.task == "open-water" and "-colreg" not in n),
        *(n for n, s in IL_SETUPS.items() if s.task == "open-water" and "-colreg" not in n),
    ),
    "colreg": (
        *(n for n in SETUPS if "-colreg" in n),
        *(n for n in IL_SETUPS if "-colreg" in n),
    ),
}
# fields of a setup that name it rather than tune it
_FIXED_FIELDS = {"name", "observation", "action", "study_iterations", "study_success", "task"}


@dataclass(frozen=True)
class Distribution:
    """A random-search / Optuna distribution over one training field.

    ``kind`` is ``uniform`` or ``loguniform`` (floats in [low, high]), ``randint`` (integers in
    [low, high)) or ``choice`` (one of ``values``). Text form (:meth:`parse`):
    ``loguniform:0.005:0.05``, ``randint:16:65``, ``choice:0.98,0.99``.
    """

    kind: Literal["uniform", "loguniform", "randint", "choice"]
    low: float = 0.0
    high: float = 0.0
    values: tuple[Any, ...] = ()

    @classmethod
    def parse(cls, text: str) -> Distribution:
        kind, _, rest = text.partition(":")
        parts = rest.split(":")
        if kind in ("uniform", "loguniform", "randint") and len(parts) == 2:
            low, high = float(parts[0]), float(parts[1])
            if not low < high or (kind == "loguniform" and low <= 0):
                raise ValueError(f"distribution {text!r}: need 0 < low < high (log) or low < high")
            return cls(kind, low, high)  # type: ignore[arg-type]
        if kind == "choice" and rest:
            return cls("choice", values=tuple(_parse_value(v) for v in rest.split(",")))
        raise ValueError(
            f"bad distribution {text!r}; allowed: uniform:LOW:HIGH, loguniform:LOW:HIGH, "
            "randint:LOW:HIGH, choice:A,B,..."
        )

    def to_tune(self) -> Any:
        from ray import tune

        if self.kind == "uniform":
            return tune.uniform(self.low, self.high)
        if self.kind == "loguniform":
            return tune.loguniform(self.low, self.high)
        if self.kind == "randint":
            return tune.randint(int(self.low), int(self.high))
        return tune.choice(list(self.values))


@dataclass(frozen=True)
class SweepSpec:
    """One sweep: which runs, how they are searched, and how the shipped seed is chosen."""

    name: str  # folder name under usvsim-results/sweep/
    setups: tuple[str, ...]  # setup names (learning.experiments.setups / il_setups)
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    grid: tuple[tuple[str, tuple[Any, ...]], ...] = ()  # (field, values): every combination
    random: tuple[tuple[str, Distribution], ...] = ()  # (field, distribution): drawn per trial
    search: SearchKind = "grid"  # grid; random (Tune's variant generator); optuna (TPE)
    # the ranges are those of `usvsim sweep`'s options (learning.cli.sweep.SweepArgs), checked
    # here too for a --config file
    samples: int = field(default=1, metadata=bounds(ge=1, le=100_000))  # random: per point
    search_seed: int = field(default=0, metadata=bounds(ge=0, lt=2**32))  # draws and TPE
    iterations: int = field(default=0, metadata=bounds(ge=0))  # budget per trial; 0: setup's
    validate_every: int = field(default=0, metadata=bounds(ge=0))  # 0: the setup's
    stop_after: int = field(default=3, metadata=bounds(ge=0))  # after N 15/15 in a row; 0: never
    n_envs: int = field(default=0, metadata=bounds(ge=1, le=65_536, zero_ok=True))  # 0: setup's
    time_budget_s: float = field(default=0.0, metadata=bounds(ge=0))  # per trial, s; 0: none
    threads: int = field(default=1, metadata=bounds(ge=1, le=1024))  # torch threads per trial
    heldout: int = field(default=200, metadata=bounds(ge=1, le=100_000))  # report only
    ship_rule: str = "median-validation"  # or "seed:K" (sweep_report.choose_shipped)
    # where each trial trains (usvsim train --device): cpu, or the torch env and device loop on
    # torch-cpu or cuda (the TRPO positional and open-water scene/radar setups)
    device: str = "cpu"

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # a --config file may hold anything
            value = getattr(self, f.name)
            kinds: dict[str, tuple[type, ...]] = {"int": (int,), "float": (int, float)}
            kind = kinds.get(str(f.type))
            if kind is not None and (isinstance(value, bool) or not isinstance(value, kind)):
                raise ValueError(f"sweep field {f.name} must be a number ({f.type}), not {value!r}")
        check_bounds(self)  # a UserError (a ValueError) naming the option and its range
        if not self.name or "/" in self.name or self.name.startswith("."):
            raise ValueError(f"sweep name {self.name!r}: a folder name is needed")
        if not self.setups or not self.seeds:
            raise ValueError("a sweep needs at least one setup and one seed")
        for name in self.setups:
            base = base_setup(name)
            for key, _ in (*self.grid, *self.random):
                apply_overrides(base, {key: _example_value(self, key)})
            every = self.validate_every or base.validate_every
            budget = self.iterations or base.algorithm_config.iterations
            if budget < every:
                raise ValueError(
                    f"{name}: {budget} iterations < validation every {every}: no validation, "
                    "no best.pt; raise --iterations or lower --validate-every"
                )
        if len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"seeds repeat: {self.seeds}")
        if self.search == "grid" and self.random:
            raise ValueError("random distributions need --search random or optuna")
        if self.search == "optuna" and (self.grid or not self.random):
            raise ValueError("--search optuna needs --random distributions and no --grid")
        if self.search == "optuna" and (len(self.setups) > 1 or len(self.seeds) > 1):
            raise ValueError("--search optuna tunes one setup on one seed (then sweep the seeds)")
        if self.ship_rule != "median-validation" and not self.ship_rule.startswith("seed:"):
            raise ValueError(f"ship rule {self.ship_rule!r}; allowed: median-validation, seed:K")
        if self.device != "cpu":
            self._check_device()

    def _check_device(self) -> None:
        """Every setup trains on :attr:`device` (``usvsim train --device``'s rule)."""
        from learning.experiments.il_setups import IL_SETUPS
        from learning.experiments.setups import SETUPS
        from learning.experiments.train_rl import device_env_maker, il_device_env_maker

        for name in self.setups:  # a ValueError naming what each takes
            if name in SETUPS:
                device_env_maker(SETUPS[name], self.device)
            elif name in IL_SETUPS:
                il_device_env_maker(IL_SETUPS[name], self.device)
            else:
                raise ValueError(f"--device {self.device}: no setup {name!r}")

    def to_json(self) -> dict[str, Any]:
        data = dataclasses.asdict(self)
        data["random"] = [[k, dataclasses.asdict(d)] for k, d in self.random]
        return json.loads(json.dumps(data))

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SweepSpec:
        """A spec from :meth:`to_json`'s form (or a hand-written config file; unknown keys
        raise ``ValueError``)."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"unknown sweep fields {unknown}; allowed: {sorted(known)}")
        d = dict(data)
        for key in ("setups", "seeds"):
            if key in d:
                d[key] = tuple(d[key])
        if "setups" in d:
            d["setups"] = expand_setups(d["setups"])
        grid = d.get("grid", ())
        d["grid"] = tuple(
            (k, tuple(v)) for k, v in (grid.items() if isinstance(grid, Mapping) else grid)
        )
        rand = d.get("random", ())
        d["random"] = tuple(
            (k, v if isinstance(v, Distribution) else _distribution(v))
            for k, v in (rand.items() if isinstance(rand, Mapping) else rand)
        )
        return cls(**d)


def _distribution(value: Any) -> Distribution:
    if isinstance(value, str):
        return Distribution.parse(value)
    return Distribution(**{**value, "values": tuple(value.get("values", ()))})


def _example_value(spec: SweepSpec, key: str) -> Any:
    for k, values in spec.grid:
        if k == key:
            return values[0]
    dist = dict(spec.random)[key]
    if dist.kind == "choice":
        return dist.values[0]
    return int(dist.low) if dist.kind == "randint" else dist.low


def _parse_value(text: str) -> Any:
    """``"0.01"`` → 0.01, ``"true"`` → True, ``"8"`` → 8; anything else stays a string."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def expand_setups(names: Sequence[str]) -> tuple[str, ...]:
    """Setup names with the groups of :data:`SETUP_GROUPS` expanded; unknown names raise."""
    out: list[str] = []
    for name in names:
        for setup in SETUP_GROUPS.get(name, (name,)):
            base_setup(setup)
            if setup not in out:
                out.append(setup)
    return tuple(out)


def parse_seeds(text: str) -> tuple[int, ...]:
    """``"0-4"`` → (0, 1, 2, 3, 4); ``"0,2,7"`` → (0, 2, 7)."""
    try:
        if "-" in text and "," not in text:
            lo, hi = (int(t) for t in text.split("-"))
            return tuple(range(lo, hi + 1))
        return tuple(int(t) for t in text.split(","))
    except ValueError:
        raise ValueError(f"bad --seeds {text!r}; allowed: a range 0-4 or a list 0,2,7") from None


def base_setup(name: str) -> RLSetup | ILSetup:
    try:
        return get_il_setup(name) if name.startswith("il-") else get_setup(name)
    except ValueError:
        known = (*SETUP_GROUPS, *SETUPS, *IL_SETUPS)
        raise ValueError(f"unknown setup {name!r}; known: {', '.join(known)}") from None


def apply_overrides(setup: Any, overrides: Mapping[str, Any]) -> Any:
    """``setup`` with training fields changed.

    A key is a dotted path into the setup (``validate_every``, ``algorithm_config.max_kl``,
    ``gail.bc_epochs``) or a bare field name looked up in the setup, then its
    ``algorithm_config``, its ``algorithm_config.network`` and (IL) its ``gail``: ``max_kl``,
    ``num_envs``, ``balanced_fusion``. Values are converted to the field's type. Unknown
    fields raise ``ValueError`` naming the allowed ones.
    """
    for key, value in overrides.items():
        setup = _replace_path(setup, _resolve_key(setup, key), value)
    return setup


def _resolve_key(setup: Any, key: str) -> tuple[str, ...]:
    if "." in key:
        path = tuple(key.split("."))
        candidates = [path, ("algorithm_config", *path)]
    else:
        candidates = [
            (key,),
            ("algorithm_config", key),
            ("algorithm_config", "network", key),
            ("gail", key),
        ]
    for path in candidates:
        if path[0] not in _FIXED_FIELDS and _has_path(setup, path):
            return path
    raise ValueError(
        f"unknown training field {key!r} for {setup.name}; allowed: {', '.join(_tunable(setup))}"
    )


def _has_path(obj: Any, path: Sequence[str]) -> bool:
    for name in path:
        if not dataclasses.is_dataclass(obj):
            return False
        if name not in {f.name for f in dataclasses.fields(obj)}:
            return False
        obj = getattr(obj, name)
    return not dataclasses.is_dataclass(obj) and path[-1] != "seed"


def _tunable(obj: Any, prefix: str = "") -> list[str]:
    names: list[str] = []
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if f.name in _FIXED_FIELDS or f.name == "seed":
            continue
        if dataclasses.is_dataclass(value):
            names += _tunable(value, f"{prefix}{f.name}.")
        else:
            names.append(prefix + f.name)
    return names


def _replace_path(obj: Any, path: Sequence[str], value: Any) -> Any:
    head = path[0]
    current = getattr(obj, head)
    if len(path) > 1:
        new = _replace_path(current, path[1:], value)
    elif isinstance(current, bool):
        new = value if isinstance(value, bool) else str(value).lower() in ("1", "true", "yes")
    elif isinstance(current, (int, float)):
        new = type(current)(value)
        if isinstance(current, int) and new != value:
            raise ValueError(f"{head} takes an integer, got {value!r}")
    else:
        new = value
    return dataclasses.replace(obj, **{head: new})


def trial_dir_name(setup: str, seed: int, overrides: Mapping[str, Any], search: str) -> str:
    """The run folder name of a trial: ``<setup>-seed<seed>``, then the grid values
    (``-max_kl=0.01``) or, for random draws, a hash of them (full precision, unique)."""
    name = f"{setup}-seed{seed}"
    if not overrides:
        return name
    text = json.dumps(dict(sorted(overrides.items())), sort_keys=True)
    if search == "grid":
        return name + "-" + ",".join(f"{k}={v}" for k, v in sorted(overrides.items()))
    return name + "-h" + hashlib.sha1(text.encode()).hexdigest()[:10]
