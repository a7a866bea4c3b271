"""One ``[[rotators]]`` table: which controller, on which port, how it is polled and judged.

The keys for pointing (offset, presets, park, keep-out, tracking) are in settings/pointing.py,
the loggers' UDP endpoints in settings/loggers.py; this model includes both. What the engine
uses for a key left out is settings/defaults.py's to say; the ``effective_*`` properties here
ask it.

Rules:
1. Every key carries its meaning (``description``); a key whose default is the model's says so
   with ``unset`` (docs/configuration.md is generated from these, bridge/config_doc.py).
2. Limits, poll intervals and the silence timeout are judged together against the model, so a
   rotator that could not work is a configuration error naming the key; so is a line rate no
   controller is set to (BAUD_MIN..BAUD_MAX). ``stall_timeout_s`` is longer than it takes a
   reading to show the rotor turning on each axis it turns: two moving polls and its noise at
   that axis's speed (az_speed_deg_s; el_speed_deg_s, a composite's elevation box's noise by
   its own model), the error naming the axis and the time it needs.
3. The port is a name, never opened here: loading a configuration touches no hardware
   (check-config reports a port that does not exist as a warning). An empty name, or one
   with a NUL byte, names no port and is refused (check_port).
4. A composite rotator (protocols/axes.py) gives ``azimuth`` and ``elevation`` tables, each a
   model and a port, in place of ``model`` and ``port``: its ``model`` reads ``AZ+EL`` and its
   ``port`` both ports as their tables read them (``~/el`` in the home folder, settings/base.py
   rule 7: derived before, it kept ``~/el``, which no longer loaded: review 73); a model that
   cannot drive its axis, one port for both (however each is written), or ``model`` or
   ``port`` beside the tables is refused naming the key. Each box's port is judged in its own
   table, as ``azimuth.port`` or ``elevation.port``; the port of both is not judged again
   (settings/base.py rule 9; review 76: judged whole, an elevation box ``~/el`` in a home
   folder whose name is not UTF-8 was refused naming ``port``, which the file does not give).
"""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from bridge.core.text import shown_path
from bridge.pointing import Pointing
from bridge.protocols import REGISTRY
from bridge.protocols.axes import Axis, axis_spec, can_drive, composite_spec
from bridge.protocols.base import ModelSpec
from bridge.settings import defaults
from bridge.settings.bands import BandFields
from bridge.settings.base import Strict, check_name, check_named_path, home_path
from bridge.settings.errors import unknown_model
from bridge.settings.loggers import LoggerFields
from bridge.settings.mqtt import check_bind, check_topic
from bridge.settings.pointing import PointingFields, check_position
from bridge.settings.wind import WindFields

# rule 2: the line rates a controller is set to (300: below the slowest any model takes; 4
# Mbaud: the fastest a USB adapter does); a typo outside them (96 for 9600) is said when read,
# not an offline rotator or polls minutes apart (defaults.py derives the polls from the rate)
BAUD_MIN, BAUD_MAX = 300, 4_000_000

_SLUG = re.compile(r"^[a-z0-9][a-z0-9_-]{0,47}$")
# the controllers' protocols offered to programs: each has <key>_port, <key>_bind, <key>_pty
# (gs232/'s EMULATIONS has the same keys)
EMULATION_KEYS = ("gs232", "easycomm", "dcu1")
MODEL_DEFAULT = "the model's (see the model table)"


def check_port(v: str) -> str:
    """``v`` if it can name a serial port: not empty (an attack pass: the bridge tried to open
    "" for ever) and without a NUL byte (no path holds one; it ended the check of the ports in
    "embedded null byte", naming no key)."""
    if not v.strip():
        raise ValueError(
            "must name the serial port (`rotor-bridge ports` lists them), not be empty"
        )
    if "\0" in v:
        raise ValueError("must not hold a NUL byte (no path does)")
    return check_named_path(v)  # settings/base.py rule 6


class AxisSettings(Strict):
    """A rotator whose azimuth and elevation are turned by two controllers on two ports (an
    RT-21 for the azimuth and a GS-232B box for the elevation, say) gives an `azimuth` and an
    `elevation` table in place of `model` and `port`, each with these keys. The two are one
    rotator: one status, one judge of every command, and one STOP stops both."""

    model: str = Field(
        description="the controller that turns this axis (any model for the azimuth; for the "
        "elevation an az/el model, or rt21, prosistel-el or prosistel-el-a)",
        examples=["rt21"],
    )
    port: str = Field(
        description="that controller's serial port, not the other axis's",
        examples=["/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"],
    )
    baud: int | None = Field(
        None,
        ge=BAUD_MIN,
        le=BAUD_MAX,
        description="that controller's line rate, as set on it (300 to 4000000)",
        examples=[9600],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )

    @field_validator("model")
    @classmethod
    def _model(cls, v: str) -> str:
        if v not in REGISTRY:
            raise ValueError(unknown_model(v, list(REGISTRY)))  # settings/errors.py rule 4
        return v

    @field_validator("port")
    @classmethod
    def _port(cls, v: str) -> str:
        return check_port(v)


class RotatorSettings(PointingFields, LoggerFields, WindFields, BandFields):
    """``[[rotators]]``: one table per rotator controller (at least one)."""

    @model_validator(mode="before")
    @classmethod
    def _composite(cls, data: Any) -> Any:
        """Rule 4: the tables stand for ``model`` and ``port``."""
        if not isinstance(data, dict):
            return data
        if data.get("azimuth") is None and data.get("elevation") is None:
            return data
        tables = []
        for axis in Axis:
            table = data.get(axis.value)
            if not isinstance(table, dict) or "model" not in table or "port" not in table:
                raise ValueError(
                    f"{axis.value}: a composite rotator needs both tables, each "
                    '{ model = "...", port = "..." }'
                )
            tables.append(table)
        ports = []
        for axis, table in zip(Axis, tables, strict=True):  # (said so, not in the port of both)
            port = table["port"]
            if isinstance(port, str):
                try:
                    port = home_path(check_port(port))  # as the table's own port reads it
                except ValueError as exc:
                    raise ValueError(f"{axis.value}.port: {exc}") from None
            ports.append(port)
        az, el = tables
        model, port = f"{az['model']}+{el['model']}", f"{ports[0]}+{ports[1]}"
        for key, derived in (("model", model), ("port", port), ("baud", None)):
            if data.get(key) not in (None, derived):  # (what a dump of these settings says)
                raise ValueError(
                    f"{key} is given with azimuth/elevation tables: a composite rotator names "
                    "its model, port and baud in each table"
                )
        if ports[0] == ports[1]:  # (~/el and its home folder's path are one port)
            raise ValueError(f"elevation.port: {shown_path(ports[1])} is the azimuth's port too")
        return {**data, "model": model, "port": port}

    id: str = Field(
        description="a short name for topics and environment overrides: lower-case letters, "
        "digits, '-' and '_' (not 'bridge')",
        examples=["tower"],
    )
    name: str | None = Field(
        None,
        description="the name shown in dashboards and Home Assistant (at most 64 characters, "
        "no control character, no blank at either end)",
        examples=["Tower"],
        json_schema_extra={"unset": "the id"},
    )
    model: str = Field(
        description="the controller: " + ", ".join(sorted(REGISTRY)) + " (see the model "
        "table); not with azimuth/elevation tables",
        examples=["rotorez"],
    )
    port: str = Field(
        description="the serial port; a /dev/serial/by-id/ name survives re-plugging "
        "(`rotor-bridge ports` lists them). It need not exist when the bridge starts: the "
        "bridge keeps trying to open it. Not with azimuth/elevation tables",
        examples=["/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"],
    )
    azimuth: AxisSettings | None = Field(
        None,
        description="a composite rotator (its azimuth from one controller, its elevation from "
        "another): the azimuth's box, `{ model = ..., port = ... }`, with elevation, in place "
        "of model and port; any model",
        examples=[
            {
                "model": "rt21",
                "port": "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_AZ0001-if00-port0",
            }
        ],
        json_schema_extra={"unset": "model and port name one controller"},
    )
    elevation: AxisSettings | None = Field(
        None,
        description="the elevation's box of a composite rotator, a model that reports where "
        "it points: an az/el box used for its elevation (its azimuth is never turned), or an "
        "rt21, prosistel-el or prosistel-el-a box on the elevation rotor",
        examples=[
            {
                "model": "gs232b",
                "port": "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_EL0001-if00-port0",
            }
        ],
        json_schema_extra={"unset": "model and port name one controller"},
    )
    baud: int | None = Field(
        None,
        ge=BAUD_MIN,
        le=BAUD_MAX,
        description="the serial line's rate, as set on the controller (300 to 4000000)",
        examples=[9600],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    topic: str | None = Field(
        None,
        description="this rotator's topic root",
        examples=["shack/tower"],
        json_schema_extra={"unset": "mqtt.base_topic with one rotator, else <base_topic>/<id>"},
    )
    idle_poll_interval_s: float | None = Field(
        None,
        gt=0,
        le=3600,
        description="how often a still rotor is asked where it points; the model's default "
        "leaves the line at least 95 % free and is at least 1 s",
        examples=[2.0],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    moving_poll_interval_s: float = Field(
        0.2,
        gt=0,
        le=60,
        description="how often a turning rotor is asked; not longer than idle_poll_interval_s",
        examples=[0.5],
    )
    tolerance_deg: float = Field(
        3.0,
        ge=0,
        le=45,
        description="arrived when this close to the target and steady",
        examples=[1.0],
    )
    brake_delay_s: float | None = Field(
        None,
        ge=0,
        le=60,
        description="the controller's brake delay: after a stop the rotor is braking this "
        "long. A controller that stops on a new target gets none until it has passed (Rotor-EZ "
        "and DCU-1: a jumper, 5 s by default); one that takes a new bearing at any time (GS-232, "
        "Easycomm, SPID, RT-21, Prosistel, RC2800) works its brake itself and is sent it at once",
        examples=[5],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    stall_timeout_s: float = Field(
        10.0,
        gt=0,
        le=600,
        description='no progress this long while off target: the rotator is "stalled". Longer '
        "than it takes a reading to show a turn on each axis: two moving polls and noise_deg "
        "at az_speed_deg_s (and at el_speed_deg_s)",
        examples=[20],
    )
    settle_s: float = Field(
        1.5,
        gt=0,
        le=60,
        description="steady this long means stopped; at least two moving poll intervals (the "
        "bridge waits longer while a speed setting slows the rotor so much that noise_deg and "
        "a step of its readings take longer: a GS-232 at X1). Raise it for a rotor that slow "
        "at its configured speed. A value other than the default also ends the wait of a "
        "bridge just started for a turn under way at rest by it, sooner than a slow axis may "
        "show its move (the default, written out or not, waits for each axis's own time). A "
        "turn the controller finishes by itself after its port came back is still only once "
        "each axis shows no move for the longer of this and what noise_deg and a step of its "
        "readings take at that axis's speed",
        examples=[2.0],
    )
    deadband_deg: float = Field(
        2.0,
        ge=0,
        le=45,
        description="a still rotor's readings that change less than this are not published "
        "(but for the last degrees of a turn, on the way it turned, as it comes to rest)",
        examples=[1.0],
    )
    noise_deg: float | None = Field(
        None,
        ge=0,
        le=20,
        description="a still rotor's readings wander this much and are not movement; raise it "
        'if a dirty potentiometer keeps a still rotor "moving"',
        examples=[2.0],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    unasked_moves: Literal["follow", "stop", "after-stop"] | None = Field(
        None,
        description="a turn the bridge did not ask for (a hand at the controller's panel, or a "
        "poll a noisy line made a command): follow it; stop it once it is 5 degrees from where "
        "the rotor rested and say so on R/error; or after-stop: only the first after a STOP, a "
        "lock or a pass left the rotor short of its target. By default stop on an Easycomm "
        "box, whose poll is one flipped bit from a jog (set follow if you turn it at its "
        "panel; a composite's elevation box follows), on the SatEL, whose every frame is "
        "one from a jog, and on the RC2800, whose poll is one stray digit from a target (set "
        "follow if you turn it at its panel or by its presets; as a composite's elevation box "
        "too), after-stop on the Rotor-EZ and "
        "RotorCard, whose poll is one from 'turn to the last target', follow on the others",
        examples=["follow"],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    silence_timeout_s: float | None = Field(
        None,
        gt=0,
        le=600,
        description="no reply this long: the rotator is offline (one that answers only "
        "garbled replies after twice this; while it turns to a target, either may come sooner, "
        "before the turn could be called stalled, but not within half stall_timeout_s, nor 3 s, "
        "of the last reply). "
        "Longer than the idle poll interval; by default 3 s, or two idle polls and a reply "
        "time where that is longer",
        examples=[5],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    # at least 0.5 deg/s (a whole turn in 12 minutes): the wait for a SatEL's lost after-move
    # report is twice the travel time at these speeds, and a slip like 0.05 would make it hours
    az_speed_deg_s: float | None = Field(
        None,
        ge=0.5,
        le=360,
        description="how fast the rotor really turns in azimuth, 0.5 to 360: the DCU-1 "
        "estimates travel from it, the SatEL bounds its silent slews by it",
        examples=[4.5],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    el_speed_deg_s: float | None = Field(
        None,
        ge=0.5,
        le=360,
        description="the same in elevation (az/el models only)",
        examples=[2.5],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    az_min_deg: float | None = Field(
        None,
        description="the lowest azimuth the bridge accepts, on the controller's scale; only "
        "narrows the model's range",
        examples=[0],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    az_max_deg: float | None = Field(
        None,
        description="the highest azimuth the bridge accepts, on the controller's scale",
        examples=[350],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    el_min_deg: float | None = Field(
        None,
        description="the lowest elevation accepted (az/el models only)",
        examples=[0],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    el_max_deg: float | None = Field(
        None,
        description="the highest elevation accepted (az/el models only)",
        examples=[90],
        json_schema_extra={"unset": MODEL_DEFAULT},
    )
    rotctld_port: int | None = Field(
        None,
        ge=1,
        le=65535,
        description="a Hamlib rotctld-compatible TCP port for this rotator (Gpredict, loggers, "
        "`rotctl -m 2 -r 127.0.0.1:4533`); one port per rotator",
        examples=[4533],
        json_schema_extra={"unset": "no rotctld listener"},
    )
    rotctld_bind: str = Field(
        "127.0.0.1",
        description="the address the rotctld port listens on. rotctld has no authentication: "
        "anyone who can reach it can turn the antenna (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    rotctld_idle_timeout_s: float = Field(
        300.0,
        ge=1,
        le=86400,
        description="a rotctld client that sends nothing this long is disconnected",
        examples=[3600],
    )
    gs232_port: int | None = Field(
        None,
        ge=1,
        le=65535,
        description="a TCP port speaking Yaesu GS-232B for this rotator (programs that drive a "
        "GS-232 controller, `rotctl -m 603 -r 127.0.0.1:4535`); one port per rotator",
        examples=[4535],
        json_schema_extra={"unset": "no GS-232 listener"},
    )
    gs232_bind: str = Field(
        "127.0.0.1",
        description="the address the GS-232 port listens on. It has no authentication: anyone "
        "who can reach it can turn the antenna (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    easycomm_port: int | None = Field(
        None,
        ge=1,
        le=65535,
        description="a TCP port speaking Easycomm II for this rotator (`rotctl -m 202 -r "
        "127.0.0.1:4536`); one port per rotator",
        examples=[4536],
        json_schema_extra={"unset": "no Easycomm listener"},
    )
    easycomm_bind: str = Field(
        "127.0.0.1",
        description="the address the Easycomm port listens on. It has no authentication: "
        "anyone who can reach it can turn the antenna (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    gs232_pty: str | None = Field(
        None,  # (no min_length: pydantic refuses a home folder not UTF-8 then; base.py rule 4)
        description="Yaesu GS-232B on a pseudo-terminal, for programs that want a serial port "
        "(`rotctl -m 603 -r /run/rotor-bridge/gs232`): the path of a link to it, made at start "
        "and removed at the end; anything but a link already there is refused, and so is a "
        "rotator's serial port (by any name), another pty's path or a file the bridge writes. "
        "Under the "
        "systemd unit /tmp is the service's own (PrivateTmp): put links under /run/rotor-bridge",
        examples=["/run/rotor-bridge/gs232"],
        json_schema_extra={"unset": "no GS-232 pty"},
    )
    easycomm_pty: str | None = Field(
        None,
        description="Easycomm II on a pseudo-terminal (`rotctl -m 202 -r "
        "/run/rotor-bridge/easycomm`), linked at this path like gs232_pty",
        examples=["/run/rotor-bridge/easycomm"],
        json_schema_extra={"unset": "no Easycomm pty"},
    )
    gs232_replies: Literal["A", "B"] = Field(
        "B",
        description="the GS-232 port's and pty's readings: `B` as a GS-232B (`AZ=120  EL=000`: "
        "PstRotator, `rotctl -m 603`), `A` as a GS-232A (`+0120+0000`: ARSVCOM, PstRotatorAz "
        "set to GS-232A, `rotctl -m 601`)",
        examples=["A"],
    )
    dcu1_port: int | None = Field(
        None,
        ge=1,
        le=65535,
        description="a TCP port speaking the Hy-Gain DCU-1 / Idiom Rotor-EZ protocol for this "
        "rotator (DXView, DXbase, WriteLog, Win-EQF through a virtual COM port; `rotctl -m 401 "
        "-r 127.0.0.1:4537`); one port per rotator",
        examples=[4537],
        json_schema_extra={"unset": "no DCU-1 listener"},
    )
    dcu1_bind: str = Field(
        "127.0.0.1",
        description="the address the DCU-1 port listens on. It has no authentication: anyone "
        "who can reach it can turn the antenna (check-config warns off loopback)",
        examples=["0.0.0.0"],
    )
    dcu1_pty: str | None = Field(
        None,
        description="DCU-1 / Rotor-EZ on a pseudo-terminal (`rotctl -m 401 -r "
        "/run/rotor-bridge/dcu1`, a logger under Wine), linked at this path like gs232_pty",
        examples=["/run/rotor-bridge/dcu1"],
        json_schema_extra={"unset": "no DCU-1 pty"},
    )
    health_baseline_moves: int = Field(
        20,
        ge=3,
        le=1000,
        description="rotor health learns how the rotor turns from this many moves (its "
        "baseline; again after a health reset); az_speed_deg_s, where given, is the speed "
        "baseline from the start",
        examples=[30],
    )
    health_speed_drop_pct: float = Field(
        20.0,
        ge=5,
        le=90,
        description="rotor health warns when the recent moves differ from the baseline by "
        "more than this: a speed that much lower, the two directions that much further apart, "
        "a start delay or a coast that much longer",
        examples=[25],
    )

    @field_validator("name")
    @classmethod
    def _name(cls, v: str | None) -> str | None:
        return check_name(v)  # settings/base.py rule 5

    @field_validator("rotctld_bind", "gs232_bind", "easycomm_bind", "dcu1_bind")
    @classmethod
    def _port_bind(cls, v: str, info: ValidationInfo) -> str:
        return check_bind(v, str(info.field_name).replace("_bind", "_port"))

    @field_validator("id")
    @classmethod
    def _id(cls, v: str) -> str:
        if not _SLUG.fullmatch(v) or v == "bridge":  # fullmatch: $ passes a final newline
            raise ValueError(
                "must be a short slug: lower-case letters, digits, '-' or '_' (and not 'bridge')"
            )
        return v

    @field_validator("model")
    @classmethod
    def _model(cls, v: str) -> str:
        if "+" in v and all(part in REGISTRY for part in v.split("+", 1)):
            return v  # a composite's (rule 4; _limits checks that the tables are there)
        if v not in REGISTRY:
            raise ValueError(unknown_model(v, list(REGISTRY)))  # settings/errors.py rule 4
        return v

    @field_validator("port")
    @classmethod
    def _port(cls, v: str, info: ValidationInfo) -> str:
        return v if cls.judged_in_parts("port", info) else check_port(v)

    @classmethod
    def judged_in_parts(cls, name: str, info: ValidationInfo) -> bool:
        """Rule 4 (settings/base.py rule 9): a composite's port of both is its tables' ports,
        each judged as its own key (``azimuth.port``, ``elevation.port``; ``_composite`` made
        it of them, and refuses another), never as one joined text."""
        return name == "port" and "+" in str(info.data.get("model", ""))

    @field_validator("topic")
    @classmethod
    def _topic(cls, v: str | None) -> str | None:
        return None if v is None else check_topic(v)

    @model_validator(mode="after")
    def _limits(self) -> RotatorSettings:
        if ("+" in self.model) != (self.azimuth is not None):
            raise ValueError(f"unknown model {self.model!r}; see the model table")
        for axis, table in zip(Axis, self.axes, strict=False):  # () for one controller
            why = can_drive(REGISTRY[table.model], axis)
            if why is not None:
                raise ValueError(f"{axis.value}.model: {why}; it cannot turn the {axis.value}")
        spec = self.spec
        lo, hi = self.effective_az_limits
        if not spec.az_min_deg <= lo < hi <= spec.az_max_deg:
            raise ValueError(
                f"azimuth limits {lo:g}..{hi:g} must lie inside the {spec.display_name}'s "
                f"range {spec.az_min_deg:g}..{spec.az_max_deg:g} with min < max"
            )
        if spec.has_elevation:
            elo, ehi = self.effective_el_limits
            if not spec.el_min_deg <= elo < ehi <= spec.el_max_deg:
                raise ValueError(
                    f"elevation limits {elo:g}..{ehi:g} must lie inside the "
                    f"{spec.display_name}'s range {spec.el_min_deg:g}..{spec.el_max_deg:g}"
                )
        elif self.el_min_deg is not None or self.el_max_deg is not None:
            raise ValueError(f"the {spec.display_name} has no elevation axis (el_min/max_deg)")
        elif self.el_speed_deg_s is not None:
            raise ValueError(f"the {spec.display_name} has no elevation axis (el_speed_deg_s)")
        idle_s = self.effective_idle_poll_interval_s
        if self.moving_poll_interval_s > idle_s:
            raise ValueError(
                f"moving_poll_interval_s must not exceed idle_poll_interval_s ({idle_s:g})"
            )
        silence_s = self.silence_timeout_s
        if spec.can_report_position and silence_s is not None and silence_s <= idle_s:
            raise ValueError(
                f"silence_timeout_s {silence_s:g} must be longer than the idle poll interval "
                f"({idle_s:g} s): a controller asked that seldom would be declared offline "
                "between two polls"
            )
        if spec.can_report_position and self.settle_s < 2 * self.moving_poll_interval_s:
            raise ValueError(
                "settle_s must be at least two moving poll intervals: stillness needs two readings"
            )
        # a movement is more than the noise band, seen by two readings (an attack pass: 0.1 s
        # stalled every target before it turned; a review: settle_s has nothing to do with it),
        # on each axis the rotor turns (attack 12: held at the azimuth's speed alone, a GS-232B's
        # stall_timeout_s 1 was taken and every elevation turn was called stalled)
        if spec.can_report_position:
            for axis, noise_deg, speed_deg_s, speed_key in self._axes_shown():
                least_stall_s = 2 * self.moving_poll_interval_s + noise_deg / max(speed_deg_s, 1e-9)
                if self.stall_timeout_s <= least_stall_s:
                    raise ValueError(
                        f"stall_timeout_s {self.stall_timeout_s:g} must be longer than it takes "
                        f"a reading to show the rotor turning in {axis.value} "
                        f"({least_stall_s:.3g} s: two moving polls and noise_deg {noise_deg:g} "
                        f"at {speed_key} {speed_deg_s:g})"
                    )
        self.check_pointing(self.pointing)
        if self.wind_topic is not None and self.wind_park_az_deg is not None:  # wind.py rule 1
            az, el = self.wind_park_az_deg, self.park_el_deg
            check_position(self.pointing, "wind_park_az_deg", az, el)
        return self

    def _axes_shown(self) -> list[tuple[Axis, float, float, str]]:
        """Rule 2: each axis the rotator turns, with the noise its readings must move beyond to
        show a turn (a composite's elevation box's own model's, unless noise_deg is set) and its
        speed, named by its key."""
        az_speed, el_speed = self.effective_speeds_deg_s
        shown = [(Axis.AZIMUTH, self.effective_noise_deg, az_speed, "az_speed_deg_s")]
        if self.spec.has_elevation:
            el_noise = (
                self.axis_settings(Axis.ELEVATION).effective_noise_deg
                if self.axes
                else self.effective_noise_deg
            )
            shown.append((Axis.ELEVATION, el_noise, el_speed, "el_speed_deg_s"))
        return shown

    @property
    def spec(self) -> ModelSpec:
        if self.azimuth is not None and self.elevation is not None:  # rule 4
            return composite_spec(REGISTRY[self.azimuth.model], REGISTRY[self.elevation.model])
        return REGISTRY[self.model]

    @property
    def axes(self) -> tuple[AxisSettings, ...]:
        """A composite's (azimuth, elevation) boxes; () for one controller."""
        if self.azimuth is None or self.elevation is None:
            return ()
        return self.azimuth, self.elevation

    @property
    def ports(self) -> list[str]:
        """The serial ports this rotator opens."""
        return [t.port for t in self.axes] or [self.port]

    def axis_settings(self, axis: Axis) -> RotatorSettings:
        """A composite's one box as a rotator of its own (runtime/composite.py): its model, port
        and rate, with every other key of this rotator's."""
        table = self.axes[0 if axis is Axis.AZIMUTH else 1]
        own = {"model": table.model, "port": table.port, "baud": table.baud}
        return self.model_copy(update={**own, "azimuth": None, "elevation": None})

    def axis_spec(self, axis: Axis) -> ModelSpec:
        return axis_spec(REGISTRY[self.axes[0 if axis is Axis.AZIMUTH else 1].model], axis)

    @property
    def pointing(self) -> Pointing:
        """The judge's terms (settings/pointing.py) on this model and limits."""
        return self.pointing_for(self.spec, self.effective_az_limits, self.effective_el_limits)

    # -- what the engine uses: the user's value, else the default (settings/defaults.py) -------
    @property
    def settle_own(self) -> bool:
        """motion.py rule 4: a ``settle_s`` the user chose, one other than the default (the
        default written out in the file, as a copied or generated one has it, is no choice),
        ends a restart's wait for its found turn at rest by it, sooner than a slow axis's own
        time (review 93: ``settle_s = 1.5`` written out undid review 89's fix)."""
        default: float = type(self).model_fields["settle_s"].default
        return self.settle_s != default

    @property
    def effective_baud(self) -> int:
        return self.baud or self.spec.baud

    @property
    def effective_brake_delay_s(self) -> float:
        return self.spec.brake_delay_s if self.brake_delay_s is None else self.brake_delay_s

    @property
    def effective_noise_deg(self) -> float:
        return self.spec.noise_deg if self.noise_deg is None else self.noise_deg

    @property
    def effective_unasked_moves(self) -> str:
        return self.spec.unasked_moves if self.unasked_moves is None else self.unasked_moves

    def unasked_moves_of(self, axis: Axis) -> str:
        """A composite box's: the user's, else the azimuth box's model's, and for the
        elevation box its model's ``el_unasked_moves``: follow (no flipped bit of a poll turns
        an elevation, and that box's own azimuth channel turns nothing: session/controller.py
        rule 10) but on an RC2800, whose elevation poll is one stray byte from a target."""
        if self.unasked_moves is not None:
            return self.unasked_moves
        if axis is Axis.ELEVATION:
            return REGISTRY[self.axes[1].model].el_unasked_moves
        return self.axis_settings(axis).effective_unasked_moves

    @property
    def effective_track_step_deg(self) -> float:
        """How far the body moves before tracking sends the next target: the tolerance."""
        return self.tolerance_deg if self.track_step_deg is None else self.track_step_deg

    @property
    def effective_speeds_deg_s(self) -> tuple[float, float]:
        return self.spec.speeds_deg_s(self.az_speed_deg_s, self.el_speed_deg_s)

    @property
    def effective_idle_poll_interval_s(self) -> float:
        if self.idle_poll_interval_s is not None:
            return self.idle_poll_interval_s
        return defaults.idle_poll_interval_s(self.spec, self.effective_baud)

    @property
    def effective_silence_timeout_s(self) -> float:
        if self.silence_timeout_s is not None:
            return self.silence_timeout_s
        return defaults.silence_timeout_s(self.spec, self.effective_idle_poll_interval_s)

    @property
    def effective_el_limits(self) -> tuple[float, float]:
        spec = self.spec
        return (
            spec.el_min_deg if self.el_min_deg is None else self.el_min_deg,
            spec.el_max_deg if self.el_max_deg is None else self.el_max_deg,
        )

    @property
    def effective_az_limits(self) -> tuple[float, float]:
        spec = self.spec
        return (
            spec.az_min_deg if self.az_min_deg is None else self.az_min_deg,
            spec.az_max_deg if self.az_max_deg is None else self.az_max_deg,
        )
