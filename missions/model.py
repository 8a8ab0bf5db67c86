"""The top level of a mission file, declared as a model (the nodes below are checked by the loader).

Entries, their types, units and ranges are written once here: the loader validates a mission's
top level with it (located errors through :mod:`maps.located`, as for worlds and profiles), and
``bearings schema`` takes the JSON Schema of these entries from it. ``tree`` and ``sense`` hold
nodes, which depend on the registry a mission is loaded with: the loader checks them against
the node types' declared ports.
"""

from __future__ import annotations

import typing
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field

from behaviours.ports import TYPE_NAMES
from maps.located import FILE_MODEL_CONFIG

Point = Annotated[list[float], Field(min_length=2, max_length=2, description="[x, y] in metres")]
Rate = Annotated[float, Field(ge=0.1, le=1000.0, description="tick rate", json_schema_extra={"unit": "Hz"})]
MaxTime = Annotated[float, Field(gt=0.0, le=1e7, description="time limit (simulated or wall); FAILURE after it",
                                 json_schema_extra={"unit": "s"})]
Overrun = Annotated[float, Field(gt=0.0, le=60.0, description="how far a tick may overrun its period before the "
                                 "watchdog stops the base", json_schema_extra={"unit": "s"})]
Seed = Annotated[int, Field(ge=0, le=2**32 - 1, description="simulator seed")]
TypeName = Literal["float", "int", "bool", "str", "key", "list[float]", "any"]
assert set(typing.get_args(TypeName)) == set(TYPE_NAMES), "the mission input types are declared in behaviours.ports"


class InputDeclaration(BaseModel):
    """A mission input: ``name: {type, default, unit, description}``."""

    model_config = FILE_MODEL_CONFIG

    type: TypeName | None = Field(None, description="value type; default: inferred from the default")
    default: Any = Field(None, description="the value when --set does not give one; omit to require it")
    unit: str = Field("", max_length=40, description="unit of the value, for people and editors")
    description: str = Field("", max_length=2000)


class Evaluation(BaseModel):
    """Ground-truth references for simulation reports."""

    model_config = FILE_MODEL_CONFIG

    goal: Point | None = Field(None, description="where the robot should end [x, y], m")
    reference_path: Annotated[list[Point], Field(min_length=2, max_length=100_000)] | None = Field(
        None, description="the path the robot should follow, [[x, y], ...], m")
    frame: Literal["world", "start"] = Field(
        "world", description="world: the world's coordinates; start: relative to the robot's true start pose")


class MissionFile(BaseModel):
    """A mission file's top-level entries."""

    model_config = FILE_MODEL_CONFIG

    mission: str | None = Field(None, min_length=1, max_length=200, description="the mission's name (default: "
                                "the file name)")
    description: str = Field("", max_length=20_000)
    version: int | None = Field(None, ge=0, description="the mission's own version number")
    inputs: dict[str, Any] = Field(default_factory=dict, description="values substituted as ${name}, published as "
                                   "/mission/<name>; override with --set name=value")
    plugins: list[str] = Field(default_factory=list, max_length=100, description="Python modules, or .py files in "
                               "the mission's folder, whose @register node types the mission may use")
    rate: Rate = 10.0
    max_time: MaxTime | None = None
    overrun: Overrun = 1.0
    cameras: list[Annotated[str, Field(min_length=1)]] | None = Field(
        None, description="the cameras the mission grabs (default: every camera of the robot)")
    sense: list[Any] = Field(default_factory=list, description="nodes added to the data-gathering branch")
    tree: Any = Field(description="the root node of the task tree")
    evaluation: dict[str, Any] | None = Field(None, description="ground-truth references for simulation reports "
                                               "(see Evaluation)")


class RunArguments(BaseModel):
    """The numbers ``bearings run`` takes on its command line, with the same ranges as in missions."""

    model_config = FILE_MODEL_CONFIG

    rate: Rate | None = Field(None, alias="--rate")
    max_time: MaxTime | None = Field(None, alias="--max-time")
    overrun: Overrun | None = Field(None, alias="--overrun")
    seed: Seed = Field(0, alias="--seed")
    image_rate: float | None = Field(None, ge=0.0, le=1000.0, alias="--image-rate",
                                     description="camera images per second in a recording; 0: every frame")
    trace: float | None = Field(None, gt=0.0, le=3600.0, alias="--trace",
                                description="a trace line every this many seconds of run time")
