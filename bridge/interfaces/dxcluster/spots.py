"""DX cluster lines, sans-IO: bytes in, ``Spot`` values out (the client is client.py).

A cluster node (DX Spider, AR-Cluster, CC Cluster) sends its users text lines; a spot is one of
them, ``DX de SPOTTER:  FREQ_KHZ  CALL  comment  HHMMZ`` (the comment may be empty). The layout
is DX Spider's (``format_dx_spot``: ``"DX de %-7.7s%11.1f  %-12.12s %-s $t$loc"``, the comment
cut and padded to 30 characters), which the other nodes copy: the time ``HHMMZ`` comes after
the comment, and after the time at most one short field the node adds for a user who asked
for it (``$loc``): the spotter's locator (its ``wantgrid``: ``1234Z JO01``), a zone
(``wantdxitu``, ``wantdxcq``: ``%2d``, ``1234Z  14``) or a US state (``wantusstate``:
``1234Z MA``). Nothing else follows the time; a comment may hold a time of its own
(``QRV til 2300Z``), and the columns are not to be counted on (nodes and their users' settings
differ, as do calls longer than the fields).

Rules:
1. Sans-IO (house rule 1): ``Lines.feed`` takes any bytes, whole or byte by byte, and returns
   the complete lines; nothing here reads a socket or a clock.
2. A line longer than MAX_LINE_BYTES is dropped whole and counted (``long_lines``): what came
   of it so far and the rest up to its end of line are thrown away, so a node that never sends
   a line end costs at most that much memory.
3. ``parse_spot`` returns a Spot or None; a spot may follow other text on its line (a prompt
   the node left without a line end), but not a header a node puts before what a user wrote
   (``To ALL de M0BAD:``, ``WWV de VE7CC <18>:``, a talk's ``G4XYZ de M0BAD:``: ``_SAID``):
   an attack pass announced ``DX de EA5WU: 14026.0 JA1ABC cq FN30as 1830Z``, which took the
   place of EA5WU's real spot of JA1ABC, and a turn to the call would have gone to New York,
   not Japan. What is not a spot (a greeting, a prompt, an announcement, junk) is None, never
   an exception. The client counts what it drops. Bytes
   that are not UTF-8 are read as Latin-1 (a comment typed on an old node); the call, spotter
   and frequency are ASCII whatever the decoding.
4. A spot's call and spotter are upper case letters, digits and ``/`` (3 to 20 characters);
   its frequency 1 kHz to 300 GHz; its time ``HHMM`` with HH < 24 and MM < 60.
5. Parsing a line takes time linear in its length, whatever its bytes (a node, or whoever
   poses as one, chooses them; the parser runs beside the stop, docs/architecture.md rule 12):
   the head (spotter, frequency, call) is one anchored match whose parts cannot overlap (each
   class stops where the next one's first character starts), the tail (comment, time, an
   optional field after it) is read from the end with ``rfind``, and a line longer than
   MAX_LINE_BYTES is no spot. No pattern here has two quantifiers that can take the same
   characters (a regex that does backtracks in cubic time on a line of spaces).
6. The time is the last word when that ends in ``HHMMZ``; otherwise the last word must be a
   field the node puts after the time (``_AFTER_TIME``: a locator, a zone, a state) and the
   time ends the word before it; any other line is no spot. The last word is never taken for
   that field unchecked (attack 26: ``PM95 QRV til 2300Z  1829Z`` heard at 18:30 was dated
   by the comment's 2300Z, a spot of 23:00 yesterday, and never listed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

MAX_LINE_BYTES = 512  # rule 2: a spot line is under 100 characters
# rule 5: spotter, colon, spaces, frequency, spaces, call, and a space (or the end): no two
# neighbouring parts share a character, so the match never backtracks
_HEAD = re.compile(
    r"DX de (?P<spotter>[A-Z0-9/#-]{3,24}):? +(?P<freq>\d{1,9}(?:\.\d{1,3})?) +"
    r"(?P<call>[A-Z0-9/]{3,20})(?= |$)",
    re.ASCII | re.IGNORECASE,
)
_DIGITS = frozenset("0123456789")
# rule 6: what DX Spider puts after the time (its ``$loc``): the spotter's locator (4
# characters; 6 taken too), an ITU or CQ zone (``%2d``) or a US state
_AFTER_TIME = re.compile(r"[A-R]{2}[0-9]{2}(?:[A-X]{2})?|[0-9]{1,2}|[A-Z]{2}", re.ASCII | re.I)
# rule 3: the header before what a user said (an announcement, a talk, WWV and WCY): a call
# after "de", then a colon, an SSID and a <hour> between them at most
_SAID = re.compile(r"\bde +[A-Z0-9/#-]{3,24}(?: *<[^>]{0,8}>)? *:", re.ASCII | re.IGNORECASE)


@dataclass(frozen=True)
class Spot:
    call: str  # upper case, as spotted (``JA1ABC/P``)
    freq_khz: float
    spotter: str  # upper case, a skimmer's ``-#`` kept
    time: str  # ``HHMM`` UTC, as the node said it
    comment: str


def parse_spot(line: bytes | str) -> Spot | None:
    """Rule 3: one line (without its line end) as a Spot, or None."""
    if isinstance(line, bytes):
        try:
            text = line.decode("utf-8")
        except UnicodeDecodeError:  # a user's comment typed in Latin-1 (``ñ``): every byte is one
            text = line.decode("latin-1")
    else:
        text = line
    start = text.find("DX de ")  # after a prompt or junk too
    if start < 0 or len(text) > MAX_LINE_BYTES:  # rule 5
        return None
    if start > 0 and _SAID.search(text, 0, start):  # rule 3: what someone said, not a spot
        return None
    text = text[start:].strip("\r\n\x07 ")
    if not text.isprintable():  # so the only white space left is the space
        return None
    m = _HEAD.match(text)
    if m is None:
        return None
    tail = _tail(text[m.end() :])
    if tail is None:
        return None
    comment, hhmm = tail
    call = m["call"].upper()
    spotter = m["spotter"].upper()
    freq_khz = float(m["freq"])
    if not _is_call(call) or int(hhmm[:2]) > 23 or int(hhmm[2:]) > 59:
        return None
    if not 1.0 <= freq_khz <= 300e6:
        return None
    return Spot(call, freq_khz, spotter, hhmm, comment)


def _is_call(text: str) -> bool:
    """A call has a digit and a letter (``ABCDEF`` is a word, ``1234`` a number)."""
    return any(c in _DIGITS for c in text) and any(c.isalpha() for c in text)


def _time_at_end(token: str) -> bool:
    """``HHMMZ`` ends the token (``cq1829Z`` too: the comment may touch the time)."""
    return len(token) >= 5 and token[-1] in "Zz" and all(c in _DIGITS for c in token[-5:-1])


def _tail(rest: str) -> tuple[str, str] | None:
    """Rules 5 and 6: what follows the call (empty, or starting with a space) as (comment,
    HHMM): the time ends the last word; or, when the last word is what a node puts after the
    time (a locator, a zone, a state), the word before it. A time in the comment before the
    spot's own (``QRV til 2300Z  1829Z``) is the comment's."""
    rest = rest.rstrip(" ")
    if not rest:
        return None
    cut = rest.rfind(" ")  # rest starts with a space: cut >= 0
    last = rest[cut + 1 :]
    before = rest[:cut].rstrip(" ")
    word = before[before.rfind(" ") + 1 :]
    if _time_at_end(last):
        end = len(rest)
    elif before and _AFTER_TIME.fullmatch(last) and _time_at_end(word):
        end = len(before)
    else:
        return None
    return rest[: end - 5].strip(" "), rest[end - 5 : end - 1]


class Lines:
    """Rule 1 and 2: bytes in, whole lines out (``\\n`` ends one; ``\\r`` is dropped)."""

    def __init__(self, max_bytes: int = MAX_LINE_BYTES) -> None:
        self._max = max_bytes
        self._buffer = bytearray()
        self._skipping = False  # the rest of a long line
        self.long_lines = 0

    def reset(self) -> None:
        """A new connection: what was half a line is gone."""
        self._buffer.clear()
        self._skipping = False

    def feed(self, data: bytes) -> list[bytes]:
        out: list[bytes] = []
        start = 0
        while start < len(data):
            end = data.find(b"\n", start)
            piece = data[start:] if end < 0 else data[start:end]
            if not self._skipping:
                room = self._max - len(self._buffer)
                if len(piece) > room:
                    self.long_lines += 1
                    self._buffer.clear()
                    self._skipping = True
                else:
                    self._buffer += piece
            if end < 0:
                break
            if not self._skipping:
                out.append(bytes(self._buffer).replace(b"\r", b""))
            self._buffer.clear()
            self._skipping = False
            start = end + 1
        return out

    @property
    def pending(self) -> bytes:
        """What came after the last line end (a prompt has none: ``login: ``)."""
        return bytes(self._buffer)
