"""Idiom Press Rotor-EZ (Hy-Gain rotors), RotorCard (Yaesu rotors) and Hy-Gain DCU-1: the codec.

Device: a serial board inside the rotator control box. 4800 baud 8N1, no flow control. Plain
ASCII commands, case-sensitive, no line ending unless stated; bearings are exactly three digits.
Sources: Idiom Press "Rotor-EZ Rotator Control Protocol" and its 2003 letter to Hamlib; Hamlib
4.5.4's rotorez backend (rotorez.c, README.rotorez) and its traffic on the wire, seen with rotctl.

Frames we send:
  ``AP1xxx\\r``        set target and execute (Rotor-EZ, RotorCard)
  ``AP1xxx;`` ``AM1;`` set target, then execute: the only form a DCU-1 takes
  ``AI1;``             ask the bearing; answer ``;xxx`` (4 bytes, no terminator)
  ``;``                stop (Rotor-EZ, RotorCard); ``AS1;`` on a DCU-1
  ``E e J j O o S s``  options on/off (Rotor-EZ only), write-only
  ``V``                version; the reply text is undocumented, we look for ``V<digits>``

Rules:
1. Only ``;`` + three ASCII digits in 000..360 is a bearing, and only while a query is open.
   Everything else (the 0xE0 power-on byte, the ``C2000 IDIOM V1.4S `` banner that follows an
   invalid command, a torn or foreign frame) is junk and is reported as such; the power-on
   byte as POWER_ON junk of its own (the board has forgotten its options). A frame that
   follows junk the board never sends (anything but the power-on byte and the banner's upper-case
   letters, digits, spaces and dots) within the same query is not trusted: it is reported as
   UNTRUSTED junk, so the engine asks again instead of publishing line noise as a bearing.
   A frame begun before a query (``;18`` of a reply the engine gave up on) is no beginning of
   that query's reply: it is noise, and the reply is not trusted (its rest, ``0``, made
   ``;180``, a reading one reply timeout old taken as the new query's answer).
2. The banner carries the firmware version; it is reported as a VersionReply whenever seen.
3. Targets are rounded half up to whole degrees. The Idiom boards take 000..360; the DCU-1 gets
   360 as 000 (Hamlib does the same "for DCU-1 compatibility"; both are north on a Hy-Gain).
4. The single letter ``S`` means "unstick on", never stop.
5. What a healthy board emits besides replies (the power-on byte, the banner) is harmless junk
   (``harmless``), also when the banner comes torn across reads, whatever the cuts: each piece
   that lies within a banner, or the beginning of one, as far as the junk so far goes. (A stop
   reaches an idle board twice when the stop express writes one too: interfaces/mqtt/express.py.)
   So is a banner's piece gathered with the power-on byte or whole banners before it (the two
   stops' banners read in one quiet spell, the second torn: seen in CI).
6. ``AI1;`` with one bit flipped (``I`` 0x49, ``M`` 0x4D) is ``AM1;``: turn to the bearing kept
   from the last ``AP1``. The spec says so (``unasked_moves``): the engine stops the first turn
   nobody asked for after the rotor was left short of its target (session/controller.py
   rule 10). The DCU-1 is never polled.
7. A query given up (``expire_query``) may still be answered (base.py rule 7): a whole bearing
   frame that comes while no query is open and its answer is owed is that late answer, said so
   (``JunkReply.late``: the engine learns from it how late the board answers, link.py rule
   12; before, a board that answered every poll 0.1 s late was 'not answering'). Like any
   bearing frame nobody asked for, it is never a reading and harmless (rule 5's known junk).
8. The connection's first stop (base.py rule 9) goes behind whatever half frame an unplug or
   a cut write left in the board, an open ``A`` frame that a ``;`` ends: ``AI`` then ``;`` is
   ``AI;``, invalid (the banner), and the rotor turns on until the stop goes again (attack
   22's exposure here: 12 degrees on a RotorCard). So on an Idiom board it is ``;`` twice:
   the first ends the half frame (whatever it makes of it: a bearing command while turning
   stops the rotor too, the emulator's rule 5), the second stops; to a rotor already still
   it is answered by the banner, harmless (rule 5). The DCU-1's ``AS1;`` is left as it is:
   every stop of its goes twice 0.1 s apart already (session/stops.py rule 6).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from bridge.core.model import SettingValue
from bridge.protocols.base import (
    Codec,
    HalfLine,
    HamlibRotType,
    JunkReason,
    JunkReply,
    LateAnswers,
    ModelSpec,
    PositionReply,
    Reply,
    RetargetPolicy,
    SendWhen,
    Setting,
    VersionReply,
    half_up,
)

OPTION_LETTERS: dict[str, tuple[bytes, bytes]] = {
    "endpoint": (b"E", b"e"),
    "jam": (b"J", b"j"),
    "overshoot": (b"O", b"o"),
    "unstick": (b"S", b"s"),
}
OPTION_LABELS = {
    "endpoint": "Endpoint option",
    "jam": "Jam protection",
    "overshoot": "Overshoot option",
    "unstick": "Unstick option",
}


POWER_ON_BYTE = 0xE0  # sent once when the board is switched on (Hamlib's README.rotorez)
_VERSION_RE = re.compile(rb"V(\d+(?:\.\d+)?[A-Za-z]?)[\s\x00;]")
# what a healthy board emits besides replies: the power-on byte, the banner after an invalid
# command (a stop while idle) and the version text; and a reply that came after its query was
# given up (a board busy printing banners answers late)
_KNOWN_JUNK = re.compile(rb"\xe0|C?\d*\s*IDIOM\s+V[0-9][0-9A-Za-z.]*\s?|;\d{3}")
_BOARD_BYTES = frozenset(b"\xe0 .0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ")
_JUNK_WINDOW = 64  # bytes of recent junk kept to find a version banner torn across reads
# the banner or its beginning at the end of the recent junk: a piece of a banner torn across
# reads (rule 5: a busy host reads "C2000 IDIOM V" and "1.4S " apart) is harmless too
_BANNER_SO_FAR = re.compile(
    rb"C\d*\s*(?:I(?:D(?:I(?:O(?:M(?:\s+(?:V[0-9A-Za-z.]*\s?)?)?)?)?)?)?)?\Z"
)


def _bearing_digits(az_deg: float, *, wrap_360: bool) -> int:
    value = half_up(az_deg, 1)
    if not 0 <= value <= 360:
        raise ValueError(f"bearing {az_deg} outside 0..360")
    if wrap_360 and value == 360:
        return 0
    return value


class RotorEzCodec(LateAnswers):
    """Codec for the Rotor-EZ command set. ``dcu1=True`` restricts it to the DCU-1 subset."""

    def __init__(self, *, dcu1: bool = False, options: bool = True) -> None:
        self._dcu1 = dcu1
        self._options = options and not dcu1
        self._buf = bytearray()
        self._junk_window = bytearray()
        self._queries_open = 0
        self._noisy = False  # bytes the board never sends arrived since the query was opened
        self._banner_so_far = bytearray()  # rule 5: the latest junk, as long as all banner
        self._left = b""  # rule 1: a frame begun before the query, reported at the next feed

    # -- encoding -------------------------------------------------------------------------
    def encode_target(self, az_deg: float, el_deg: float | None = None) -> list[bytes]:
        digits = _bearing_digits(az_deg, wrap_360=self._dcu1)
        if self._dcu1:
            return [b"AP1%03d;" % digits, b"AM1;"]
        return [b"AP1%03d\r" % digits]

    def wire_target(self, az_deg: float, el_deg: float | None = None) -> tuple[float, None]:
        return float(_bearing_digits(az_deg, wrap_360=self._dcu1)), None

    def awaiting_reply(self) -> bool:
        return bool(self._queries_open)

    def harmless(self, junk: bytes) -> bool:
        rest = _KNOWN_JUNK.sub(b"", junk)  # rule 5: what is left a banner under way (with a
        return not rest or self._banner_so_far.endswith(rest)  # power-on byte beside it too)

    def encode_enable(self) -> None:
        return None

    def encode_connect(self, now_unix: float) -> list[bytes]:
        return [] if self._dcu1 else [b"V"]

    def encode_stop(self) -> bytes:
        return b"AS1;" if self._dcu1 else b";"

    def encode_stop_after(
        self, half: HalfLine, axes: bytes | None = None, ready: bytes | None = None
    ) -> bytes:
        """Rule 8 (base.py rule 9): the connection's first stop, behind a half frame."""
        stop = self.encode_stop()
        return stop if half is HalfLine.NONE or self._dcu1 else stop + stop

    def encode_query(self) -> bytes | None:
        if self._dcu1:
            return None
        self._queries_open = 1
        self._noisy = False
        if self._buf:  # rule 1: (only a frame's beginning is ever left)
            self._left, self._noisy = bytes(self._buf), True
            self._buf.clear()
        return b"AI1;"

    def expire_query(self) -> None:
        if self._queries_open:  # rule 7: its answer may still come
            self._owe_late(1)
        self._queries_open = 0

    def encode_version(self) -> bytes | None:
        return None if self._dcu1 else b"V"

    def encode_option(self, name: str, enabled: bool) -> bytes:
        if not self._options or name not in OPTION_LETTERS:
            raise ValueError(f"option {name!r} not supported")
        on, off = OPTION_LETTERS[name]
        return on if enabled else off

    # -- decoding -------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[Reply]:
        buf = self._buf
        buf += data
        out: list[Reply] = []
        if self._left:  # rule 1 (a power-on byte among it is one all the same: the options)
            left, self._left = self._left, b""
            frame = left.replace(bytes([POWER_ON_BYTE]), b"")
            if len(frame) < len(left):
                on = bytes([POWER_ON_BYTE]) * (len(left) - len(frame))
                out.append(JunkReply(on, JunkReason.POWER_ON, "power-on byte"))
            if frame:
                out.append(JunkReply(frame, JunkReason.NOISE, "a frame begun before the query"))
        if 0 < len(buf) < 4 and buf[0] == 0x3B:  # a reply under way (byte by byte, mostly):
            return out  # what the loop below does with it (nothing to say until it is whole)
        junk = bytearray()
        buf = self._buf
        i = 0
        while i < len(buf):
            if buf[i] == POWER_ON_BYTE:
                self._flush_junk(junk, out)
                end = i + 1
                while end < len(buf) and buf[end] == POWER_ON_BYTE:
                    end += 1
                out.append(JunkReply(bytes(buf[i:end]), JunkReason.POWER_ON, "power-on byte"))
                i = end
                continue
            if buf[i] != 0x3B:  # ';'
                junk.append(buf[i])
                i += 1
                continue
            if len(buf) - i < 4:
                break  # a frame may be starting: wait for the rest
            frame = bytes(buf[i : i + 4])
            digits = frame[1:]
            if digits.isdigit() and int(digits) <= 360 and self._queries_open:
                self._flush_junk(junk, out)
                self._queries_open = 0
                if self._noisy:
                    out.append(JunkReply(frame, JunkReason.UNTRUSTED))
                else:
                    out.append(PositionReply(float(int(digits))))
                i += 4
                continue
            if digits.isdigit() and int(digits) <= 360:
                self._flush_junk(junk, out)
                if self._late_answer(frame, out):  # rule 7
                    i += 4
                    continue
                out.append(
                    JunkReply(frame, JunkReason.UNSOLICITED, "bearing frame without a query")
                )
                i += 4
                continue
            junk.append(buf[i])  # a lone ';' followed by something else: resync after it
            i += 1
        del buf[:i]
        self._flush_junk(junk, out)
        return out

    def _flush_junk(self, junk: bytearray, out: list[Reply]) -> None:
        if not junk:
            return
        if self._queries_open and any(b not in _BOARD_BYTES for b in junk):
            self._noisy = True
        self._junk_window += junk
        window, start = self._junk_window, len(self._junk_window) - len(junk)
        so_far = _BANNER_SO_FAR.search(window)
        if so_far is not None and so_far.start() <= start:
            self._banner_so_far += junk  # rule 5: all of it in a banner (or its beginning)
            del self._banner_so_far[: -2 * _JUNK_WINDOW]
        elif so_far is not None and not _KNOWN_JUNK.sub(b"", window[start : so_far.start()]):
            self._banner_so_far[:] = window[so_far.start() :]  # rule 5: whole ones before it
        else:
            self._banner_so_far.clear()
        match = _VERSION_RE.search(self._junk_window)
        if match:
            out.append(VersionReply(match.group(1).decode("ascii")))
            del self._junk_window[: match.end()]
        del self._junk_window[:-_JUNK_WINDOW]
        out.append(JunkReply(bytes(junk), JunkReason.NOISE, "not a reply frame"))
        junk.clear()


def _letter(name: str) -> Callable[[SettingValue], bytes]:
    """The encoder of one option: the codec's letter, upper-case for on, lower-case for off."""
    codec = RotorEzCodec()
    return lambda enabled: codec.encode_option(name, bool(enabled))


# the Rotor-EZ's options: sent only at rest (the board stops on any input while turning) and
# again after a power-on (it forgets them)
OPTION_SETTINGS = tuple(
    Setting(name, OPTION_LABELS[name], _letter(name), when=SendWhen.AT_REST, resend=True)
    for name in OPTION_LETTERS
)


def _spec(name: str, display: str, manufacturer: str, **kw: Any) -> ModelSpec:
    defaults: dict[str, Any] = dict(
        baud=4800,
        has_version=True,
        retarget=RetargetPolicy.STOP_AND_WAIT,
        az_min_deg=0.0,
        az_max_deg=360.0,
        az_wraps=True,
        reply_timeout_s=0.25,
        noise_deg=2.0,
        nominal_speed_deg_s=6.0,
        whole_degrees=True,
        query_bytes=4,  # AI1;
        reply_bytes=4,  # ;xxx
        hamlib_rot_type=HamlibRotType.OTHER,
        hamlib_folds_360=True,  # rotorez.c: "if (tmp == 360) tmp = 0"
    )
    defaults.update(kw)
    return ModelSpec(name=name, display_name=display, manufacturer=manufacturer, **defaults)


MODELS: dict[str, ModelSpec] = {
    "rotorez": _spec(
        "rotorez",
        "Rotor-EZ",
        "Idiom Press",
        codec_factory=RotorEzCodec,
        settings=OPTION_SETTINGS,
        brake_delay_s=5.0,
        unasked_moves="after-stop",  # AI1; one bit from AM1; (rule 6)
        stop_anytime=True,  # ';' at any time; a second one is answered by the banner (harmless)
        az_ends_at_north=False,  # a Hy-Gain rotor's stop is at south: north is mid-travel
        stop_at_south=True,
        hamlib_model=401,
        hamlib_info="Rotor-EZ",
    ),
    "rotorcard": _spec(
        "rotorcard",
        "RotorCard",
        "Idiom Press",
        codec_factory=lambda: RotorEzCodec(options=False),
        brake_delay_s=0.0,
        unasked_moves="after-stop",  # AI1; one bit from AM1; (rule 6)
        stop_anytime=True,
        hamlib_model=402,
        hamlib_info="RotorCard",
    ),
    "dcu1": _spec(
        "dcu1",
        "DCU-1",
        "Hy-Gain",
        codec_factory=lambda: RotorEzCodec(dcu1=True),
        can_report_position=False,
        has_version=False,
        brake_delay_s=5.0,
        inter_frame_gap_s=0.05,
        query_bytes=0,  # it cannot be asked
        reply_bytes=0,
        az_ends_at_north=False,  # a Hy-Gain rotor's stop is at south: north is mid-travel
        stop_at_south=True,
        hamlib_model=403,
        hamlib_info="DCU-1/DCU-1X",
    ),
}

_check: type[Codec] = RotorEzCodec  # RotorEzCodec satisfies the Codec protocol
