"""SatEL (VE5FP-compatible) az/el controller: the codec.

Device: a terminal-driven az/el controller. 9600 8N1, no flow control. Single-letter commands,
no echo, either case; replies are text lines ending in CR LF (or LF). Sources: the SatEL Az-EL
instruction manual, Appendix A ("Running the controller using a terminal"), and Hamlib 4.5.4's
satel backend (satel.c, its author's notes) and its traffic on the wire, seen with rotctl.

Frames we send: ``s`` stop rotors and disable automatic motion; ``x`` clear the stored points;
``?`` identify (-> ``SatEL``); ``tYYYY/MM/DD HH:MM:SS`` CR LF set the clock; ``g`` enable
automatic motion; ``z`` status report;
``p<az> <el>`` CR LF point (integers, no padding), answered by a status report when the move
ends. Not sent: ``*`` reset, ``2YYYY/MM/DD HH:MM:SS az el`` CR LF store a point.

The status report (7 lines): ``Motion ENABLED|DISABLED``, ``Mode ...``, ``Time: ...``,
``Azimuth = 000     Absolute = 000``, ``Elevation = 000``, an empty line,
``Number of stored positions: 00`` (plus trailing empty lines).

Rules:
1. The controller does no input validation and can be put into a bad state by input while it
   slews: after ``p`` nothing but a stop may be sent until the after-move report has come
   (ModelSpec: half duplex, ``stop_interrupts``, ``reports_while_moving`` False).
2. Connecting starts with ``s``, the one input allowed at any time: the bridge may have been
   restarted in the middle of a slew it knows nothing about. Then clear the stored points
   (``x``), identify, set the clock from the host (UTC), enable motion, ask for a report.
   Automatic motion also runs the points stored in the controller's memory, each at its time
   (the manual's introduction: loaded once, the controller moves the rotors by itself; a
   power cycle is taken to clear them, the manual naming only the position as kept in EEPROM,
   unverified):
   the bridge stores none, and one left there by another program (a pass loaded before the
   bridge took the port) would turn the rotor by itself once ``g`` went out, past the lock
   and every limit, unseen (a slew nobody asked for is answered by no report, and a poll
   into it is input while slewing). Cleared before the clock is set and before ``g``, no
   stored point ever moves it. The engine writes these one at a time, the stop first and then
   again until the stopped controller's report comes (a stop lost on the line must not let the
   rest into a slew), the rest each when the line takes it (session/link.py rule 14): what
   ``?`` and ``z`` owe is owed from their writes (``connect_written``).
3. Reports are read by their labels, never by fixed offsets; a report whose azimuth or elevation
   line does not parse is junk, not a reading. A report is complete at its stored-positions line.
   Its values are three digits, zero padded, always (the controller's printf; Hamlib reads them
   at fixed offsets): one of one or two digits lost a byte on the line (``Azimuth = 12`` for
   123, or ``10 `` for 100 with a bit flipped) and spoils the report like any noise in a value.
   Noise before a label is tolerated, noise inside a value spoils the report; a spoiled report
   that ends a slew still ends it (UNTRUSTED: the engine asks again at once). A report whose
   first line was lost (noise inside ``Motion``) is recognised by its other lines: it is a
   report all the same, spoiled, and it ends a slew (if it shows the point, rule 6).
4. Every point is preceded by ``g``: a stop or a reset disables automatic motion, and a point
   sent while it is disabled is silently ignored.
5. Each ``z`` and ``p`` owes one report; ``p``'s comes when the slew ends (how long that may
   take depends on the rotor: the engine's business, session/link.py). A spoiled report is the
   report a ``z`` owed all the same: that is settled, and the engine asks again (link.py rule
   11) without waiting out the reply timeout.
6. A report whose position can be read (even one that lost its first line) ends a slew only
   if it shows the point's position (within SLEW_END_TOLERANCE_DEG; 000 and 360 are one
   place) or a stop went out since the point. Any other report while a slew is owed was on
   its way before the point (an answer the engine had given up on): junk, and the slew is
   still owed. Taking it for the end would let the next poll into the slew. (A report whose
   position cannot be read cannot be checked: it ends the slew, and the engine asks again.)
7. Its rotors move in ten-degree steps (the manual, on aiming at Polaris: ``P0 34`` "would move
   to an azimuth of zero and an elevation of 30 degrees because it moves in ten degree steps"):
   a point is sent as the nearest multiple of STEP_DEG on each axis, the one place of the
   step it reaches whichever way it takes a value between (the manual's one example cannot
   tell down from nearest). The bridge then waits for, shows and judges the place the rotor
   really goes to. (An emulator turned as built: ``p126 36`` stopped the rotor at 120/30, its
   report was taken for an old one, 6 degrees from the point, the slew was stopped as
   overdue, tried again and the target given up; 124/34 ended in a stall 4 degrees short.)
"""

from __future__ import annotations

import re
import time

from bridge.protocols.base import (
    HamlibRotType,
    JunkReason,
    JunkReply,
    ModelSpec,
    PositionReply,
    Reply,
    RetargetPolicy,
    VersionReply,
    half_up_step,
)

# labels are searched anywhere in a line (noise before them is tolerated); a number must be
# followed by white space or the end of the line, so noise inside a number spoils the line
_MOTION = re.compile(r"Motion\s+(ENABLED|DISABLED)\s*$", re.IGNORECASE)
_TIME = re.compile(r"Time:\s*(\d{4}/\d{2}/\d{2} \d{2}:\d{2}:\d{2})\s*$")
_AZ = re.compile(r"Azimuth\s*=\s*(\d{3})(?=\s|$)")  # rule 3: three digits, zero padded
_EL = re.compile(r"Elevation\s*=\s*(\d{3})\s*$")
_STORED = re.compile(r"Number of stored positions:\s*(\d+)\s*$")
_BARE_TIME = re.compile(r"^\d{4}/\d{2}/\d{2} \d{2}:\d{2}:\d{2}$")
_MAX_LINE = 160
SLEW_END_TOLERANCE_DEG = 5  # relays coast a little past the point (rule 6)
STEP_DEG = 10  # rule 7: where the rotors can stop
# a status report as the manual and Hamlib show it: the size of the reply to a poll
_TYPICAL_REPORT = (
    b"Motion ENABLED\r\n"
    b"Mode 0 - azimuth break at NORTH\r\n"
    b"Time: 2001/00/00 00:00:07\r\n"
    b"Azimuth = 000     Absolute = 000\r\n"
    b"Elevation = 000\r\n"
    b"\r\n"
    b"Number of stored positions: 00\r\n"
    b"\r\n"
    b"\r\n"
)


class SatelCodec:
    def __init__(self) -> None:
        self._buf = bytearray()
        self._owed: list[str] = []  # "report" | "slew" | "ident", oldest first
        self._block: dict[str, str] | None = None
        self._point: tuple[int, int] | None = None  # where the owed slew goes; None once stopped

    # -- encoding -------------------------------------------------------------------------
    def encode_enable(self) -> bytes:
        return b"g"

    def encode_connect(self, now_unix: float) -> list[bytes]:
        clock = time.strftime("%Y/%m/%d %H:%M:%S", time.gmtime(now_unix)).encode()
        return [b"s", b"x", b"?", b"t" + clock + b"\r\n", b"g", b"z"]  # rule 2

    def connect_written(self, frame: bytes) -> None:
        """Rule 2: a connect frame just written owes its reply from now (PacedConnect)."""
        if frame == b"?":
            self._owed.append("ident")
        elif frame == b"z":
            self._owed.append("report")

    def encode_query(self) -> bytes:
        self._owed.append("report")
        return b"z"

    def encode_stop(self) -> bytes:
        self._point = None  # the slew's report, if owed, still comes (shortly), from anywhere
        return b"s"

    def encode_version(self) -> bytes:
        self._owed.append("ident")
        return b"?"

    def encode_option(self, name: str, enabled: bool) -> bytes:
        raise ValueError("the SatEL has no options")

    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        az, el = self.wire_target(az_deg, el_deg)
        assert el is not None
        self._owed.append("slew")
        self._point = (int(az), int(el))
        return [b"g", b"p%d %d\r\n" % (az, el)]

    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, float | None]:
        az = half_up_step(az_deg, STEP_DEG)  # rule 7
        el = half_up_step(el_deg or 0.0, STEP_DEG)
        if not (0 <= az <= 360 and 0 <= el <= 90):
            raise ValueError(f"target {az_deg}/{el_deg} outside 0..360 / 0..90")
        return float(az), float(el)

    # -- what is owed -------------------------------------------------------------------------
    def awaiting_reply(self) -> bool:
        return bool(self._owed)

    def expire_query(self) -> None:
        self._owed.clear()
        self._block = None

    def harmless(self, junk: bytes) -> bool:
        return junk.strip(b"\r\n ") == b""

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while True:
            end = self._buf.find(b"\n")
            if end == -1:
                if len(self._buf) > _MAX_LINE:
                    out.append(JunkReply(bytes(self._buf), JunkReason.NOISE, "line too long"))
                    self._buf.clear()
                break
            raw = bytes(self._buf[: end + 1])
            del self._buf[: end + 1]
            self._line(raw, out)
        return out

    def _line(self, raw: bytes, out: list[Reply]) -> None:
        line = raw.decode("latin-1").strip("\r\n").strip()
        if m := _MOTION.search(line):
            self._block = {"motion": m.group(1).upper()}
            return
        if self._block is not None:
            self._block_line(line, raw, out)
            return
        if _TIME.search(line) or _AZ.search(line) or _EL.search(line) or _STORED.search(line):
            self._block = {"motion": "?"}  # a report whose first line was lost (rule 3)
            self._block_line(line, raw, out)
        elif line.lower().endswith("satel"):
            self._settle("ident")
            out.append(VersionReply("SatEL"))
        elif line == "" or _BARE_TIME.match(line):
            out.append(JunkReply(raw, JunkReason.CHATTER, "blank line or clock echo"))
        else:
            out.append(JunkReply(raw, JunkReason.NOISE, "not a report line"))

    def _block_line(self, line: str, raw: bytes, out: list[Reply]) -> None:
        block = self._block
        assert block is not None
        if m := _TIME.search(line):
            block["time"] = m.group(1)
        elif m := _AZ.search(line):
            block["az"] = m.group(1)
        elif m := _EL.search(line):
            block["el"] = m.group(1)
        elif m := _STORED.search(line):
            self._block = None
            if "az" not in block or "el" not in block:
                self._spoiled(raw, "status report without azimuth or elevation", out)
                return
            az, el = int(block["az"]), int(block["el"])
            if az > 360 or el > 90:
                self._spoiled(raw, "status report out of range", out)
                return
            kind = next((k for k in self._owed if k in ("report", "slew")), "report")
            if kind == "slew" and not self._ends_slew(az, el):
                why = "status report from before the point (slew goes on)"
                out.append(JunkReply(raw, JunkReason.UNSOLICITED, why))
                return
            if block["motion"] == "?":
                self._spoiled(raw, "status report without its motion line", out)
                return
            self._settle(kind)
            out.append(
                PositionReply(
                    float(az),
                    float(el),
                    motion_enabled=block["motion"] == "ENABLED",
                    controller_time=block.get("time"),
                )
            )
        elif "Azimuth" in line or "Elevation" in line:
            self._block = None  # a garbled position line spoils the whole report
            self._spoiled(raw, "unreadable position line", out)
        elif "Mode" in line or "Time" in line or line == "":
            pass
        else:
            self._block = None
            self._spoiled(raw, "unexpected line inside a status report", out)

    def _ends_slew(self, az: int, el: int) -> bool:
        if self._point is None:
            return True
        to_az, to_el = self._point
        # 000 and 360 are the same place (the north stop); nothing else wraps: 002 is not
        # near 358, it is a whole turn away
        d_az = min(abs(a - b) for a in _north(az) for b in _north(to_az))
        return d_az <= SLEW_END_TOLERANCE_DEG and abs(el - to_el) <= SLEW_END_TOLERANCE_DEG

    def _spoiled(self, raw: bytes, why: str, out: list[Reply]) -> None:
        """A report that cannot be read. If it ended a slew, the slew is over all the same:
        say so (UNTRUSTED), so the engine asks for a fresh report instead of waiting on."""
        if "slew" in self._owed:
            self._owed.remove("slew")
            out.append(JunkReply(raw, JunkReason.UNTRUSTED, why))
        else:
            if "report" in self._owed:  # rule 5
                self._owed.remove("report")
            out.append(JunkReply(raw, JunkReason.SPOILED, why))

    def _settle(self, kind: str) -> None:
        if kind in self._owed:
            self._owed.remove(kind)
        elif self._owed and kind == "report":
            self._owed.pop(0)


def _north(az: int) -> tuple[int, ...]:
    return (0, 360) if az in (0, 360) else (az,)


MODELS: dict[str, ModelSpec] = {
    "satel": ModelSpec(
        name="satel",
        display_name="SatEL",
        manufacturer="SatEL (VE5FP)",
        codec_factory=SatelCodec,
        baud=9600,
        has_elevation=True,
        has_version=True,
        retarget=RetargetPolicy.STOP_AND_WAIT,
        az_min_deg=0.0,
        az_max_deg=360.0,
        el_min_deg=0.0,
        el_max_deg=90.0,
        az_wraps=True,
        full_duplex=False,
        stop_interrupts=True,
        reports_while_moving=False,
        connect_stops=True,  # rule 2
        # its own frames are each one flipped bit from a jog that runs until told otherwise
        # (z, s and p from r, t from u: an attack pass ran it past az_max_deg and el_max_deg):
        # every turn nobody asked for is stopped (set follow to turn it by its own commands)
        unasked_moves="stop",
        reply_timeout_s=2.0,
        noise_deg=1.0,
        # the rotor it usually drives, a Yaesu G-5500: 360 deg in 58-70 s, 180 deg in 67-81 s
        # (60/50 Hz mains); the published estimate during a slew and its bound come from these
        nominal_speed_deg_s=6.0,
        nominal_el_speed_deg_s=2.5,
        whole_degrees=True,
        steps_deg=STEP_DEG,  # rule 7
        query_bytes=1,  # z
        reply_bytes=len(_TYPICAL_REPORT),
        hamlib_model=2101,
        hamlib_rot_type=HamlibRotType.AZEL,
        hamlib_info="SatEL rotator",
    )
}
