"""What every controller family provides: a sans-IO codec and a model spec that is pure data.

Rules (ARCHITECTURE.md, rules 1 and 2):
1. A codec turns typed commands into bytes and bytes into typed replies. It never touches a
   port, a clock, a thread or a sleep; timing values live on the ModelSpec as data.
2. ``feed()`` accepts any slicing of the byte stream (whole buffers, one byte at a time, junk
   around the frames) and yields the same replies. Junk is reported, never turned into a reading.
3. A position reply is only accepted while a reply is awaited (a query, or a command the
   controller answers with its position); ``awaiting_reply`` says so, ``expire_query`` gives up
   on it after the engine's reply timeout. Anything else is junk.
4. The engine, the MQTT topics and Home Assistant ask the spec's capabilities; nothing offers
   what the model cannot do.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol


@dataclass(frozen=True)
class PositionReply:
    az_deg: float
    el_deg: float | None = None
    motion_enabled: bool | None = None  # controllers with an automatic-motion switch (SatEL)
    controller_time: str | None = None  # the controller's own clock, as it prints it


@dataclass(frozen=True)
class VersionReply:
    version: str


@dataclass(frozen=True)
class JunkReply:
    """Bytes that are no valid reply (power-on noise, a banner, line garbage)."""

    data: bytes
    reason: str


Reply = PositionReply | VersionReply | JunkReply

# reason of a JunkReply for a frame that looked right but followed line noise: ask again
UNTRUSTED = "reading after line noise: not trusted"


class RetargetPolicy(enum.StrEnum):
    # The controller stops on a new bearing while turning and ignores bearings during its brake
    # delay (Rotor-EZ FAQ): stop, wait for stillness plus the brake delay, then send the target.
    STOP_AND_WAIT = "stop_and_wait"
    # The controller takes a new target at any time (SPID).
    DIRECT = "direct"


class Codec(Protocol):
    def encode_target(self, az_deg: float, el_deg: float | None) -> list[bytes]: ...
    def encode_stop(self) -> bytes: ...
    def encode_query(self) -> bytes | None: ...
    def expire_query(self) -> None: ...
    def encode_version(self) -> bytes | None: ...
    def encode_option(self, name: str, enabled: bool) -> bytes: ...
    def feed(self, data: bytes) -> list[Reply]: ...
    def awaiting_reply(self) -> bool: ...
    def harmless(self, junk: bytes) -> bool:
        """Is this non-reply text something a healthy controller emits (a banner, a log line)?"""
        ...

    def encode_enable(self) -> bytes | None:
        """Switch automatic motion on (SatEL ``g``); None where there is no such switch."""
        ...

    def encode_connect(self, now_unix: float) -> list[bytes]:
        """Frames to send right after the port opens (identify, version, clock, enable)."""
        ...

    def wire_target(self, az_deg: float, el_deg: float | None) -> tuple[float, float | None]:
        """The position the controller will actually be sent (after its rounding)."""
        ...


@dataclass(frozen=True)
class ModelSpec:
    """Everything the bridge needs to know about one controller model, as data."""

    name: str  # registry key, used in the configuration
    display_name: str
    manufacturer: str
    family: str
    codec_factory: Callable[[], Codec]
    baud: int
    bytesize: int = 8
    parity: str = "N"
    stopbits: int = 1
    can_report_position: bool = True
    has_elevation: bool = False
    has_version: bool = False
    options: tuple[str, ...] = ()
    brake_delay_s: float = 0.0
    retarget: RetargetPolicy = RetargetPolicy.DIRECT
    az_min_deg: float = 0.0
    az_max_deg: float = 360.0
    el_min_deg: float = 0.0
    el_max_deg: float = 0.0
    az_wraps: bool = True  # 0 and 360 are the same direction
    reply_timeout_s: float = 0.3
    inter_frame_gap_s: float = 0.0  # pause between the frames of one multi-frame command
    full_duplex: bool = True  # may a command be written while a reply is still coming?
    stop_interrupts: bool = False  # a stop may go out while a (slew) reply is owed
    reports_while_moving: bool = True  # False: silent until the after-move report (SatEL)
    nominal_el_speed_deg_s: float = 1.0
    # the controller takes whole degrees, rounded half up (False: finer, or learned at run time)
    whole_degrees: bool = False
    noise_deg: float = 0.0  # analog jitter of a still rotor's readings
    # typical speeds, until the user sets the real ones (az_speed_deg_s, el_speed_deg_s): travel
    # estimates without feedback (DCU-1), a silent slew's estimate and bound (SatEL)
    nominal_speed_deg_s: float = 6.0
    option_labels: dict[str, str] = field(default_factory=dict)

    def frame_time_s(self, nbytes: int) -> float:
        """Time the line needs to carry ``nbytes`` (start + data + parity + stop bits)."""
        bits = 1 + self.bytesize + (0 if self.parity == "N" else 1) + self.stopbits
        return nbytes * bits / self.baud
