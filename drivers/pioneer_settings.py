"""What a robot profile says about a Pioneer base, and which unit conversions the driver uses.

:class:`PioneerSettings` is the declared model of ``base: {driver: pioneer, ...}`` (units and
ranges; ``missions.profiles`` validates a profile against it). :func:`choose_model` decides the
conversion factors the way ARIA does: from the subclass the robot reports in its SYNC2 echo
(``p3dx``, ``p3at-sh``...), never from a guess in the profile. A profile may force other factors
only with ``model_override``, whose name says what it does; the choice and where it came from
(:class:`ModelChoice`) are shown by ``bearings doctor`` and written into the run report.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from drivers import arcos
from drivers.arcos import ModelParams
from drivers.common import quantity

ModelName = Literal["p3dx", "p3at", "p3dx-sh", "p3at-sh"]
SerialSpeed = Literal[9600, 19200, 38400, 57600, 115200]


class PioneerSettings(BaseModel):
    """A Pioneer base in a robot profile (``base: {driver: pioneer, port: ...}``)."""

    model_config = ConfigDict(extra="forbid")

    port: str = Field(min_length=1, description="serial device or pyserial URL: /dev/ttyUSB0, "
                      "socket://localhost:8101 (MobileSim/AMRISim), rfc2217://host:port")
    model_override: ModelName | None = Field(
        None, description="force the unit conversions of this model instead of the one the robot reports "
        "when it connects (its SYNC2 subclass); only for a robot that reports a wrong subclass. "
        "'bearings doctor' and the run report say when it is in use")
    baud: SerialSpeed = Field(
        9600, description="serial speed to connect at [bit/s] (the robot's HOST port default); ignored for "
        "socket:// URLs", json_schema_extra={"unit": "bit/s"})
    switch_baud: Literal[0, 9600, 19200, 38400, 57600, 115200] = Field(
        38400, description="after connecting on a serial device, move the link to this speed [bit/s] with "
        "HOSTBAUD when the robot's config packet allows it (as ARIA does); 0 stays at 'baud'",
        json_schema_extra={"unit": "bit/s"})
    reconnect: bool = Field(False, description="retry a lost link for reconnect_timeout before "
                            "reporting the fault (the robot's own watchdog stops it meanwhile)")
    reconnect_timeout: float = quantity(10.0, "how long to retry a lost link when reconnect is on", "s",
                                        ge=0.5, le=300.0)
    connect_timeout: float = quantity(5.0, "time allowed for the whole connection sequence", "s", ge=0.2, le=60.0)
    reply_timeout: float = quantity(0.5, "wait for each reply of the connection sequence before "
                                    "sending again", "s", ge=0.02, le=5.0)
    sip_timeout: float = quantity(0.5, "no SIP for this long is a lost link (the robot sends one every "
                                  "100 ms)", "s", ge=0.05, le=5.0)
    resend_period: float = quantity(0.2, "period of re-sending the current velocity command (a command "
                                    "at least every 0.5 s keeps the robot's watchdog quiet)", "s",
                                    ge=0.01, le=0.45)
    command_timeout: float = quantity(1.0, "no drive() call for this long while moving stops the base "
                                      "(guards against a stuck control loop)", "s", ge=0.05, le=60.0)
    max_speed: float | None = quantity(None, "forward speed limit (default: the model's)", "m/s",
                                       ge=0.01, le=2.2)
    max_turn_rate: float | None = quantity(None, "turn rate limit (default: the model's)", "deg/s",
                                           ge=1.0, le=500.0)
    sonar: bool = Field(True, description="enable the sonar rings")
    sonar_timeout: float = quantity(1.0, "a transducer not heard for this long reads as no data (nan) for the "
                                    "collision monitor (the ring fires in turn: about 0.5 s for all 16)", "s",
                                    ge=0.1, le=10.0)
    guard: bool = Field(True, description="while a session is open, a guard process holds the link and stops "
                        "the robot (STOP, ENABLE 0, CLOSE) if this process dies without closing it (a crash, "
                        "kill -9, a plugin's os._exit): within milliseconds instead of the firmware watchdog's "
                        "seconds (drivers/link_guard.py)")
    request_config: bool = Field(True, description="ask for the config packet when connecting (limits, "
                                 "firmware watchdog, serial number, whether HOSTBAUD is allowed; shown by "
                                 "'bearings doctor')")


@dataclass(frozen=True, slots=True)
class ModelChoice:
    """The conversion factors in use, the subclass the robot reported, and where the choice came from
    (``"robot"``: its SYNC2 subclass; ``"override"``: ``model_override`` in the profile)."""

    params: ModelParams
    reported: str
    source: Literal["robot", "override"]

    @property
    def origin(self) -> str:
        """One line saying where the factors came from."""
        if self.source == "robot":
            return f"the robot's SYNC2 subclass {self.reported!r}"
        return f"model_override in the profile (the robot reports {self.reported!r})"

    @property
    def warning(self) -> str | None:
        """Set when an override contradicts what the robot reports: odometry is then likely wrong."""
        reported = arcos.model_for(self.reported)
        if self.source != "override" or (reported is not None and reported.name == self.params.name):
            return None
        return (f"model_override {self.params.name} is in use but the robot reports {self.reported!r}: "
                f"distances are scaled by {self.params.dist_conv:g} mm per position unit instead of the "
                f"robot's {reported.dist_conv:g}" if reported is not None else
                f"model_override {self.params.name} is in use; the robot reports {self.reported!r}")

    def as_report(self) -> dict[str, Any]:
        """The choice as the run report and ``bearings doctor`` write it."""
        params = self.params
        return {"model": params.name, "source": self.source, "origin": self.origin, "reported_subclass": self.reported,
                "dist_conv_mm": params.dist_conv, "angle_conv_rad": params.angle_conv, "vel_conv": params.vel_conv,
                "range_conv": params.range_conv, "diff_conv": params.diff_conv}


def choose_model(reported: str, override: str | None, port: str) -> ModelChoice:
    """The factors for a robot that reported ``reported`` in SYNC2: its own, unless the profile sets
    ``model_override``; ``ConnectionError`` for a subclass this driver has no factors for."""
    if override is not None:
        return ModelChoice(arcos.MODELS[override], reported, "override")
    params = arcos.model_for(reported)
    if params is None:
        raise ConnectionError(f"the robot on {port} reports subclass {reported!r}, which this driver has no "
                              f"conversion factors for (known: {', '.join(arcos.MODELS)}); if it is one of "
                              "these, set model_override in the profile")
    return ModelChoice(params, reported, "robot")
