"""What the hardware drivers share: the fault they raise, settings helpers, stamping clocks.

Faults: a driver whose device stops working during a run (lost link, no data for too long, the
device closed) sets its ``fault`` attribute to a one-line reason and from then on raises
:class:`DriverFault` from the calls the runner makes every tick (``drive()``, ``odometry()``,
``state()``, ``move()``, ...). ``stop()``, ``halt()`` and ``close()`` never raise: they are the
safety path. ``DriverFault`` is an ``OSError``, so code that already treats device errors as
``OSError`` keeps working; the runner turns it into a FAILURE whose reason is the message.

Opening: an opener raises ``OSError`` (``ConnectionError``, ``TimeoutError``, ``FileNotFoundError``
...) with a message naming the device when it cannot be opened, and :class:`maps.store.InputError`
when the settings themselves are invalid.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from pydantic import BaseModel, Field, ValidationError

from maps.store import Diagnostic, InputError

Stamp = Callable[[], float]
M = TypeVar("M", bound=BaseModel)


class DriverFault(OSError):  # noqa: N818 - the name the runner and the docs use
    """A device failed during a run; ``str(exc)`` is the one-line reason (raised once faulted)."""


def quantity(default: Any, description: str, unit: str, *, ge: float | None = None, le: float | None = None) -> Any:
    """A pydantic field with its unit in the description and in the JSON schema, and a range."""
    return Field(default, description=f"{description} [{unit}]", ge=ge, le=le, json_schema_extra={"unit": unit})


def build_settings(model: type[M], settings: M | Mapping[str, Any] | None, fields: Mapping[str, Any],
                   *, where: str) -> M:
    """A validated settings model from a model, a mapping, or keyword arguments (the loader of today).

    Invalid settings raise :class:`InputError` with one diagnostic per problem, located at
    ``where`` (e.g. ``"base (pioneer)"``) since the opener does not know the profile's file.
    """
    if isinstance(settings, model):
        if fields:
            raise TypeError(f"give {model.__name__} or keyword settings, not both")
        return settings
    data = dict(settings or {})
    data.update(fields)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise InputError([Diagnostic(where, 0, 0, _message(error)) for error in exc.errors()]) from None


def _message(error: Mapping[str, Any]) -> str:
    location = ".".join(str(part) for part in error.get("loc", ()))
    text = str(error.get("msg", "invalid"))
    if error.get("type") == "extra_forbidden":
        text = "unknown setting"
    return f"{location}: {text}" if location else text


def monotonic_stamp(clock: Stamp | None) -> Stamp:
    """The function that stamps readings: the given clock, else ``time.monotonic``."""
    return clock if clock is not None else time.monotonic
