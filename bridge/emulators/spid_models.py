"""What each SPID controller understands, as data (see spid.py for behaviour).

What the devices are: the Alfa/SPID Rot2Prog (az/el, 600 baud, silent after a set), the Rot1Prog
(azimuth only, 1200 baud, 5-byte replies in whole degrees) and the MD-01/MD-02 in ROT2 mode
(the Rot2Prog frames, a configurable line rate, a position frame after a set, a move command and
debug lines on the control port).

Frame: see spid.py. This module names the bytes, what each model does with them, and holds the
two pure frame layouts (position reply out, set command in) so spid.py keeps to behaviour.

Source documents: Hamlib 4.5.4's spid backend (its caps, spid.txt notes, traffic seen with
rotctl), the rot2prog package's PyPI page (the resolution table).

Rules:
1. A model is a ModelSpec: values and flags only, no code. A command byte a model lacks makes the
   frame invalid. The layout functions are pure: angles in, bytes out, and back.
2. Outcome strings are part of the emulator's public ground truth: tests of the bridge match on
   them, so they change only together with those tests.
3. Values the documents do not give are stated assumptions, marked "assumed" below.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum

START = 0x57  # 'W'
END = 0x20  # ' '
COMMAND_BYTES = 13
ROT2_REPLY_BYTES = 12
ROT1_REPLY_BYTES = 5
ASCII_ZERO = 0x30

K_STOP = 0x0F
K_STATUS = 0x1F
K_SET = 0x2F
K_MOVE = 0x14  # MD-01/02 only (Hamlib 903 `M`)

#: Move direction bits in H1 of a K 0x14 frame (spid.md section 4, "move").
DIR_LEFT = 0x01  # CCW: azimuth decreasing
DIR_RIGHT = 0x02  # CW: azimuth increasing
DIR_UP = 0x04
DIR_DOWN = 0x08

#: Every angle travels on the wire as (angle + 360); replies carry four digits of tenths
#: (Rot1Prog: three digits of degrees), so nothing outside this window can be reported.
WIRE_OFFSET_DEG = 360.0
MIN_ENCODABLE_DEG = -360.0
MAX_ENCODABLE_DEG = 639.0

#: Debug/log line placement for the MD-01 (`debug_lines=` option of Spid).
DEBUG_LINE_MODES = ("off", "before", "after")


class Outcome(StrEnum):
    """What the controller did with a frame (the `outcome` of a LoggedFrame)."""

    STATUS = "status"
    STOP = "stop"
    SET = "set"
    SET_CLAMPED = "set: clamped"  # a target beyond the mechanical limits; moved to the limit
    MOVE = "move"
    INVALID = "invalid"  # bad start/end, unknown K, non-ASCII digits, junk between frames


#: Outcomes of frames that started or re-targeted a move.
MOTION_OUTCOMES: frozenset[str] = frozenset({Outcome.SET, Outcome.SET_CLAMPED, Outcome.MOVE})


@dataclass(frozen=True)
class ModelSpec:
    """What one SPID controller understands and how it answers."""

    name: str
    title: str
    hamlib_model: int
    baud: int
    has_elevation: bool
    reply_bytes: int  # 12 (tenths, with PH/PV) or 5 (Rot1Prog, whole degrees, az only)
    resolutions_ppd: tuple[int, ...]  # pulses per degree the controller can be set to
    default_resolution_ppd: int
    replies_to_set: bool
    has_move: bool
    has_debug_lines: bool
    az_min_deg: float = -180.0
    az_max_deg: float = 540.0
    el_min_deg: float = -20.0
    el_max_deg: float = 210.0


MODELS: Mapping[str, ModelSpec] = {
    "rot2prog": ModelSpec(
        name="rot2prog",
        title="SPID Rot2Prog",
        hamlib_model=901,
        baud=600,
        has_elevation=True,
        reply_bytes=ROT2_REPLY_BYTES,
        resolutions_ppd=(1, 2, 4),
        default_resolution_ppd=2,
        replies_to_set=False,
        has_move=False,
        has_debug_lines=False,
    ),
    "rot1prog": ModelSpec(
        name="rot1prog",
        title="SPID Rot1Prog",
        hamlib_model=902,
        baud=1200,
        has_elevation=False,
        reply_bytes=ROT1_REPLY_BYTES,
        resolutions_ppd=(1,),  # whole degrees both ways; the frames carry no PH/PV
        default_resolution_ppd=1,
        replies_to_set=False,
        has_move=False,
        has_debug_lines=False,
        el_min_deg=0.0,
        el_max_deg=0.0,
    ),
    "md01": ModelSpec(
        name="md01",
        title="SPID MD-01/MD-02 (ROT2 mode)",
        hamlib_model=903,
        # assumed: the documents give only Hamlib's 600..460800 caps range. 115200 is a common
        # USB rate and one Hamlib 4.5.4 opens (460800, its default, it cannot).
        baud=115200,
        has_elevation=True,
        reply_bytes=ROT2_REPLY_BYTES,
        resolutions_ppd=(1, 2, 4, 10),  # 10 from the PyPI client, "presumably MD-01/02"
        default_resolution_ppd=2,  # assumed: the same as the Rot2Prog
        replies_to_set=True,
        has_move=True,
        has_debug_lines=True,
    ),
}


# -- frame layouts (pure) -----------------------------------------------------------------------


def reply_tenths(angle_deg: float, ppd: int) -> int:
    """(angle + 360) on the `ppd` grid (nearest pulse), in tenths rounded down (spid.py rule 8)."""
    pulses = math.floor((angle_deg + WIRE_OFFSET_DEG) * ppd + 0.5)
    return (pulses * 10) // ppd


def reply_whole_deg(angle_deg: float) -> int:
    """(angle + 360) to the nearest whole degree (Rot1Prog replies)."""
    return math.floor(angle_deg + WIRE_OFFSET_DEG + 0.5)


def position_reply(spec: ModelSpec, az_deg: float, el_deg: float, ppd: int) -> bytes:
    """`57 H1 H2 H3 H4 PH V1 V2 V3 V4 PV 20` (raw digits) or, on a Rot1Prog, `57 H1 H2 H3 20`."""
    if spec.reply_bytes == ROT1_REPLY_BYTES:
        degrees = reply_whole_deg(az_deg)
        return bytes([START, degrees // 100, degrees // 10 % 10, degrees % 10, END])
    az, el = reply_tenths(az_deg, ppd), reply_tenths(el_deg, ppd)
    az_digits = [az // 1000, az // 100 % 10, az // 10 % 10, az % 10]
    el_digits = [el // 1000, el // 100 % 10, el // 10 % 10, el % 10]
    return bytes([START, *az_digits, ppd, *el_digits, ppd, END])


def decode_reply(spec: ModelSpec, reply: bytes) -> tuple[float, float | None]:
    """What a client reads from position_reply() (the fact sheet's formula)."""
    if spec.reply_bytes == ROT1_REPLY_BYTES:
        return 100 * reply[1] + 10 * reply[2] + reply[3] - WIRE_OFFSET_DEG, None
    az = 1000 * reply[1] + 100 * reply[2] + 10 * reply[3] + reply[4]
    el = 1000 * reply[6] + 100 * reply[7] + 10 * reply[8] + reply[9]
    return round(az / 10 - WIRE_OFFSET_DEG, 1), round(el / 10 - WIRE_OFFSET_DEG, 1)


def _ascii_number(digits: bytes) -> int | None:
    if not digits or not all(0x30 <= b <= 0x39 for b in digits):
        return None
    return int(digits)


def set_targets(spec: ModelSpec, frame: bytes, ppd: int) -> tuple[float, float | None] | None:
    """(az, el) a 13-byte set frame asks for, or None if a digit the model reads is not ASCII."""
    if spec.reply_bytes == ROT1_REPLY_BYTES:  # three digits of whole degrees, then ASCII '0'
        degrees = _ascii_number(frame[1:4])
        if degrees is None or frame[4] != ASCII_ZERO:
            return None
        return degrees - WIRE_OFFSET_DEG, None
    h_pulses, v_pulses = _ascii_number(frame[1:5]), _ascii_number(frame[6:10])
    if h_pulses is None or v_pulses is None:
        return None
    # the controller's own ppd, not the command's PH/PV bytes; round() undoes /10 float noise
    return (
        round(h_pulses / ppd - WIRE_OFFSET_DEG, 6),
        round(v_pulses / ppd - WIRE_OFFSET_DEG, 6),
    )
