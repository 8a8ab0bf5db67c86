"""What one episode of a sweep is, its stable id, and the grid of episodes a sweep runs.

An :class:`Episode` is a value: a mission, a world, a seed, input overrides and an optional time
limit. Its id is a readable prefix plus a hash of those parameters only, so the same episode has
the same id in every sweep, on any machine, whatever the number of workers: that is what
``--resume`` matches on and what the results table is sorted by.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from maps.located import describe_value
from perception.geometry import Pose2D

MAX_EPISODES = 100_000
"""The largest grid a sweep accepts (a typo like ``--seeds 0-9999999`` is an input error)."""

MAX_SEED = 2**32 - 1
"""The largest seed ``bearings run --seed`` takes (checked here for every seed, not only the first)."""

_UNSAFE = re.compile(r"[^A-Za-z0-9.+=-]+")


class SweepInputError(ValueError):
    """Invalid sweep input; ``str(exc)`` is the one-line message for the user."""


def start_argument(pose: Pose2D) -> str:
    """An episode's ``start`` for a pose: ``x,y,theta`` with x, y in m to 0.1 mm and theta in degrees."""
    return f"{pose.x:.4f},{pose.y:.4f},{math.degrees(pose.theta):.3f}deg"


@dataclass(frozen=True)
class Episode:
    """One ``bearings run``: ``mission`` (file or shipped name), ``world`` (shipped name or file,
    ``"empty"`` for the empty plane), ``seed``, ``inputs`` (``--set name=value``; values are YAML
    text as on the command line, or plain scalars), ``max_time_s`` (the run's ``--max-time``,
    simulated seconds; None: the mission's own limit), ``start`` (the run's ``--start``: a
    start pose ``x,y,theta`` or a named pose of the world; None: the world's start) and
    ``output_dir`` (the run's ``--output-dir``, where the files the mission writes go; where the
    episode writes is not what it is, so it is not part of the id)."""

    mission: str
    world: str = "empty"
    seed: int = 0
    inputs: Mapping[str, Any] = field(default_factory=dict)
    max_time_s: float | None = None
    start: str | None = None
    output_dir: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "inputs", {str(k): v for k, v in sorted(dict(self.inputs).items())})

    def __hash__(self) -> int:
        return hash(self.id)

    @property
    def input_text(self) -> dict[str, str]:
        """The overrides as the ``--set`` text the run command receives."""
        return {name: _as_text(value) for name, value in self.inputs.items()}

    @property
    def parameters(self) -> dict[str, Any]:
        """Everything the episode's outcome depends on (the id hashes exactly this)."""
        parameters = {"mission": str(self.mission), "world": str(self.world), "seed": int(self.seed),
                      "inputs": self.input_text, "max_time_s": self.max_time_s}
        if self.start is not None:  # only when given: the ids of earlier sweeps stay what they were
            parameters["start"] = self.start
        return parameters

    @property
    def id(self) -> str:
        """``<mission>_<world>_<name=value>..._s<seed>_<hash>``: readable, unique, file-name safe."""
        canonical = json.dumps(self.parameters, sort_keys=True, separators=(",", ":"))
        digest = hashlib.sha256(canonical.encode("utf-8")).hexdigest()[:8]
        parts = [_stem(self.mission), _stem(self.world)]
        parts += [f"{safe_name(name)}={safe_name(value)}" for name, value in self.input_text.items()]
        parts.append(f"s{self.seed:04d}")
        if self.max_time_s is not None:
            parts.append(f"t{self.max_time_s:g}")
        if self.start is not None:
            parts.append(f"at={safe_name(self.start)}")
        return "_".join(parts) + f"_{digest}"

    @property
    def input_values(self) -> dict[str, Any]:
        """The overrides as values (YAML-parsed as the run command does), for tables and plots."""
        return {name: _as_value(text) for name, text in self.input_text.items()}

    def run_arguments(self, report: str | os.PathLike) -> list[str]:
        """The ``bearings run`` arguments of this episode, writing its report to ``report``."""
        argv = ["run", str(self.mission), "--sim", str(self.world), "--seed", str(self.seed),
                "--report", str(report), "--quiet"]
        for name, text in self.input_text.items():
            argv += ["--set", f"{name}={text}"]
        if self.max_time_s is not None:
            argv += ["--max-time", repr(float(self.max_time_s))]
        if self.start is not None:
            argv.append(f"--start={self.start}")  # '=': a pose may start with a minus sign
        if self.output_dir is not None:
            argv += ["--output-dir", str(self.output_dir)]
        return argv


def grid(
    missions: str | Sequence[str],
    worlds: Sequence[str],
    seeds: Iterable[int],
    sets: Mapping[str, Sequence[Any]] | None = None,
    *,
    max_time_s: float | None = None,
) -> list[Episode]:
    """Every combination of missions x worlds x ``sets`` values x seeds, sorted by episode id."""
    missions = [missions] if isinstance(missions, str) else list(missions)
    sets = dict(sets or {})
    names = sorted(sets)
    seeds = list(seeds)
    count = len(missions) * len(worlds) * len(seeds)
    for name in names:
        count *= len(sets[name])
    if count > MAX_EPISODES:
        raise SweepInputError(f"the grid has {count} episodes; at most {MAX_EPISODES} are allowed")
    episodes = []
    for mission, world, values in itertools.product(missions, worlds, itertools.product(*(sets[n] for n in names))):
        inputs = dict(zip(names, values, strict=True))
        episodes += [Episode(mission, world, seed, inputs, max_time_s) for seed in seeds]
    return sorted(episodes, key=lambda e: e.id)


# --------------------------------------------------------------------------------------------
# Command-line specs


def parse_seeds(spec: str, *, option: str = "--seeds") -> list[int]:
    """``0-99``, ``7``, ``0-3,10,20-22`` to a sorted list of distinct seeds (inclusive ranges)."""
    seeds: set[int] = set()
    for part in spec.split(","):
        text = part.strip()
        match = re.fullmatch(r"(\d+)(?:-(\d+))?", text)
        if match and max(len(n or "") for n in match.groups()) > len(str(MAX_SEED)):
            raise SweepInputError(f"{option}: seeds go from 0 to {MAX_SEED}, got {describe_value(text)}")
        if not match:
            raise SweepInputError(f"{option} {spec}: expected N, A-B or a comma-separated list of them, got {text!r}")
        first = int(match.group(1))
        last = int(match.group(2)) if match.group(2) is not None else first
        if last < first:
            raise SweepInputError(f"{option} {spec}: the range {text} is empty (write it as {last}-{first})")
        if last > MAX_SEED:
            raise SweepInputError(f"{option} {spec}: seeds go from 0 to {MAX_SEED}")
        if last - first >= MAX_EPISODES:
            raise SweepInputError(f"{option} {spec}: more than {MAX_EPISODES} seeds")
        seeds.update(range(first, last + 1))
    return sorted(seeds)


def parse_set(item: str) -> tuple[str, list[str]]:
    """``name=v1,v2,...`` to ``(name, [v1, v2, ...])``; commas inside [] {} or quotes don't split."""
    name, sep, values = item.partition("=")
    name = name.strip()
    if not sep or not name:
        raise SweepInputError(f"--set {item}: expected NAME=VALUE[,VALUE...]")
    parts = _split_values(values)
    if any(not p.strip() for p in parts):
        raise SweepInputError(f"--set {item}: empty value (expected NAME=VALUE[,VALUE...])")
    parts = [p.strip() for p in parts]
    if len(set(parts)) != len(parts):
        raise SweepInputError(f"--set {item}: a value is listed twice")
    return name, parts


def parse_sets(items: Sequence[str]) -> dict[str, list[str]]:
    """Every ``--set`` of the command line; one name may appear once."""
    sets: dict[str, list[str]] = {}
    for item in items:
        name, values = parse_set(item)
        if name in sets:
            raise SweepInputError(f"--set {name}: given twice (list every value in one --set {name}=v1,v2)")
        sets[name] = values
    return sets


def parse_worlds(spec: str) -> list[str]:
    """``lab,corridor`` to a list; world files that exist here are made absolute."""
    worlds = [w.strip() for w in spec.split(",")]
    if any(not w for w in worlds):
        raise SweepInputError(f"--sim {spec}: empty world name")
    if len(set(worlds)) != len(worlds):
        raise SweepInputError(f"--sim {spec}: a world is listed twice")
    return [absolute_if_file(w) for w in worlds]


def absolute_if_file(name: str) -> str:
    """A path that exists here becomes absolute (episodes run in other processes); names stay."""
    path = Path(name)
    return str(path.resolve()) if path.exists() else name


def _split_values(text: str) -> list[str]:
    parts: list[str] = []
    current: list[str] = []
    depth, quote = 0, ""
    for char in text:
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth = max(0, depth - 1)
        elif char == "," and depth == 0:
            parts.append("".join(current))
            current = []
            continue
        current.append(char)
    parts.append("".join(current))
    return parts


def _as_text(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, (int, float)):
        return repr(value)
    return json.dumps(value, separators=(",", ":"))  # lists and mappings: JSON is YAML flow syntax


def _as_value(text: str) -> Any:
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return text
    if isinstance(value, str):  # YAML 1.1 reads 1e3 as text; the mission loader reads YAML 1.2 floats
        try:
            return float(value)
        except ValueError:
            return value
    return value


def _stem(name: str) -> str:
    return safe_name(Path(str(name)).stem or str(name))


def safe_name(value: Any) -> str:
    """``value`` as a piece of a file name (letters, digits and . + = -), at most 32 characters."""
    return _UNSAFE.sub("-", str(value)).strip("-")[:32] or "-"
