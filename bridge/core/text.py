"""Text the bridge takes from a user (a topic, a preset's name, a name in a command) and hands
on over MQTT: one rule for the settings, the MQTT payloads and the console, which is MQTT's
and mosquitto's. An MQTT string may hold no control character (U+0000-001F, U+007F-009F: a
broker drops the client at its CONNECT or PUBLISH, the will's topic among them), no lone
surrogate (what Python makes of a byte that is not UTF-8: it cannot be sent at all) and no
non-character (U+FDD0-FDEF, U+xFFFE, U+xFFFF). Everything else is text: a no-break space, a
zero-width joiner in Persian or an emoji, characters newer than Python's Unicode tables.
(``str.isprintable`` refuses all of those: a review found it refusing real users' names.)

And how a message quotes what a file or a sender wrote (``quoted``): escaped, and cut short at
QUOTED_MOST characters with its length said, so a file of one long line (a binary, a
compressed download, ``/dev/zero``) is no megabyte line in the journal (attack 18).

And how the bridge names a path in anything it says (``shown_path``): a refusal in the
settings, R/error and R/status's ``last_error``, a log line, check-config's report. A path may
be any bytes (the home folder's name above all: settings/base.py rule 3), and a byte that is
not UTF-8 is a lone surrogate in Python's text, which no UTF-8 holds: in a JSON payload it is
``\\udce9``, refused by a strict parser (Home Assistant's), and on a stream that encodes
strictly it ends the process in a UnicodeEncodeError (review 76). So it is escaped once, here,
as Python's stderr writes it (``\\udce9``), and every text naming a path goes through it.

And how a refusal quotes a number past a limit (``shown_past``): with as many digits as it
takes to stay past it. ``:g``'s six digits made ``360.00001`` "azimuth 360 outside 0..360", a
refusal that contradicts itself (attack 28); a number a user sent is never shown inside the
limits it was refused for, nor, for limits of bearings where north is 0 and 360 alike (a group
member's), a whole turn from inside them.
"""

from __future__ import annotations

import os
import re

__all__ = [
    "NOT_TEXT",
    "QUOTED_MOST",
    "bad_char",
    "entity_slug",
    "quoted",
    "shown_past",
    "shown_path",
]

# what a refusal says after the character: U+0001, {NOT_TEXT}
NOT_TEXT = "which MQTT does not carry (a control character, a lone surrogate or a non-character)"
# the most of what a file or a sender wrote that a message quotes (``quoted``): more than any
# satellite's or entity's name, far less than a line of a binary
QUOTED_MOST = 40


def bad_char(text: str) -> str | None:
    """The first character of ``text`` MQTT's strings may not hold, as ``U+XXXX``, or None
    when it holds none."""
    for c in text:
        n = ord(c)
        if (
            n <= 0x1F
            or 0x7F <= n <= 0x9F
            or 0xD800 <= n <= 0xDFFF
            or 0xFDD0 <= n <= 0xFDEF
            or n & 0xFFFE == 0xFFFE
        ):
            return f"U+{n:04X}"
    return None


_NOT_SLUG = re.compile(r"[^a-z0-9]+")


def entity_slug(text: str) -> str:
    """``text`` as Home Assistant writes it in an entity id (its ``slugify``): lower case, each
    run of other characters ('-', '_', '/' and the like) one '_', none at either end. An entity
    id may hold no '-' and no '__' (``valid_entity_id``): ``tower-`` asked for
    ``sensor.tower__bearing``, which Home Assistant makes ``sensor.tower_bearing``, the entity
    of a rotator ``tower`` beside it."""
    return _NOT_SLUG.sub("_", text.lower()).strip("_")


def quoted(text: str, most: int = QUOTED_MOST) -> str:
    """``text`` as a message quotes it: ``repr`` (a control character escaped), and past
    ``most`` characters its first ``most`` and its length (``'ab'… (9000 characters)``)."""
    if len(text) <= most:
        return repr(text)
    return f"{text[:most]!r}… ({len(text)} characters)"


def shown_path(path: str | bytes | os.PathLike[str] | os.PathLike[bytes]) -> str:
    """``path`` as the bridge names it in what it says: UTF-8 text, a byte that is not UTF-8
    (a lone surrogate in Python's text) escaped as ``\\udce9``, so ``/home/h\\udce9/rotor``."""
    text = os.fspath(path)
    if isinstance(text, bytes):  # its bytes: read as Python reads a path from the system
        text = text.decode("utf-8", "surrogateescape")
    return text.encode("utf-8", "backslashreplace").decode()


def shown_past(value: float, lo: float, hi: float, *, around: bool = False) -> str:
    """``value``, refused as outside ``lo..hi``, as a message quotes it: ``:g``'s six digits,
    or as many more as it takes not to read as inside (``360.00001`` past 0..360, not ``360``);
    a value inside (or no number) is shown as ``:g`` shows it. ``around``: bearings, north 0
    and 360 alike, so a number a whole turn from one inside reads as inside too (review 87: a
    group member's 359.9999999 past 0..90 is not ``360``, which is north, inside)."""
    turns = (0.0, 360.0, -360.0) if around else (0.0,)
    for digits in range(6, 18):
        shown = f"{value:.{digits}g}"
        if not any(lo <= float(shown) + turn <= hi for turn in turns):
            return shown
    return f"{value:g}"  # (17 digits give any float back: only a value inside gets here)
