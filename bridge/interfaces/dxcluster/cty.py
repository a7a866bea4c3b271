"""AD1C's country files (cty.dat or cty.csv, from country-files.com): a call sign's entity.

The user downloads the file; the bridge reads it from disk once, at start-up (``load``), and
never downloads anything.

Rules:
1. Longitudes: both files give them WEST-positive (``-139.00`` is 139 degrees EAST, Japan);
   ``Entity.longitude_deg`` is east-positive like the rest of the project (core/geo.py).
2. A prefix line's overrides apply to that prefix or exact call alone: ``(cq)`` the CQ zone,
   ``[itu]`` the ITU zone, ``<lat/lon>`` the position (west-positive too), ``{cont}`` the
   continent; ``~tz~`` is read past. ``=CALL`` is an exact call, matched before any prefix.
3. ``lookup``: an exact call first, then the longest prefix of the call. What is looked up:
   upper case; a portable suffix (``/P``, ``/M``, ``/QRP``, ``/QRPP``, ``/A``) is dropped, and
   so are ``/LH`` and ``/LGT`` (a lighthouse), ``/R`` (a rover) and ``/B`` (a beacon), which
   say what a station is, not where (read as prefixes: Norway, Russia, China); ``/MM`` and
   ``/AM`` (maritime and aeronautical mobile) are in no entity (None); of two parts left
   (``F/G4ABC``, ``G4ABC/F``) the shorter one is the prefix that names the entity (equal
   lengths: the first).
3a. A lone digit is a call area, not a portable mark: the station is on the air from that
   area of its own country (``UA3ABC/9``: a Moscow call in Siberia, the commonest portable
   form in Russian spots). As loggers read it (JTDX's ``effective_prefix``, for one), the
   prefix looked up is the call's prefix (up to and including its last digit) with that
   digit replaced by the suffix's: ``UA9`` (Asiatic Russia); ``UA3ABC/2``, ``UA2``
   (Kaliningrad, an entity of its own); ``UA9ABC/3``, ``UA3``; a call without a digit gets
   the digit added. The home call's exact entry (``=UA3ABC``) is not its place there, so it
   is not looked at; an exact entry of the whole form (``=UA3ABC/9``) still comes first.
   Dropped as a portable mark, the digit left the call in its home area, 16 to 19 degrees
   off from Berlin (attack 26). A call area read this way may name another entity than the
   operator's (``KH6ABC/4`` reads ``KH4``, Midway), as in the loggers: AD1C's file lists
   such calls whole. With a prefix of another country as well (``F/G4ABC/9``), that prefix
   names the entity and the digit is read past.
4. A file that cannot be read or holds no entity raises CtyError naming the file and line;
   an odd line inside a good file is skipped and counted (``skipped``): AD1C's files are
   trusted, a hand-edited one should not stop the bridge. What is no regular file (a device,
   a pipe) or is larger than CTY_FILE_MAX cannot be read: it is opened without waiting, its
   kind looked at before a byte is read, and at most CTY_FILE_MAX bytes and one are read
   (attack 18: ``/dev/zero`` was read until the memory ran out, a FIFO nobody writes held the
   start for ever). The start and check-config judge a file by this one reading
   (interfaces/dxcluster/setup.py ``read_cty``).
5. A position no place has (a latitude outside -90..90, a longitude outside -180..180, or no
   number: a hand edit's slip, ``357.0`` for ``35.70``) is refused where it is read: an
   entity's header with its prefixes, a prefix's ``<lat/lon>`` override alone. Each is
   skipped and counted (rule 4) and said in ``refused``, naming the line and the entity or
   prefix, for the loader to log once (interfaces/dxcluster/setup.py); taken, it made every
   ``B/spots`` with a call of it raise in geo.great_circle (attack 12). A refused entity's
   prefixes and calls are kept, as no place (``lookup`` gives None for them): skipped, its
   calls went to the longest prefix left, another entity's (review 48: a slip in Hawaii's
   line placed every KH6 in the United States, its bearing the mainland's); a prefix whose
   override is refused is its entity's, at the entity's place. What ``refused`` quotes of the
   file (a name, a prefix, a number) is escaped and cut short (core/text.py ``quoted``): a
   line of a megabyte is no megabyte in the log (attack 18).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from bridge.core.readfile import NotRegular, TooLarge, read_regular
from bridge.core.text import quoted, shown_path

_OVERRIDE = re.compile(r"\((\d+)\)|\[(\d+)\]|<(-?[\d.]+)/(-?[\d.]+)>|\{(\w+)\}|~(-?[\d.]+)~")
_PLAIN = re.compile(r"=?[A-Z0-9/]+")
_DROPPED = frozenset({"P", "M", "QRP", "QRPP", "A", "LH", "LGT", "R", "B"})  # rule 3
_DIGITS = "0123456789"
_NOWHERE = frozenset({"MM", "AM"})
CTY_FILE_MAX = 16 << 20  # rule 4: AD1C's cty.csv is some 300 KB, the big cty.dat some 2 MB
_AD1C = "name AD1C's cty.dat or cty.csv"  # rule 4: what to do of a file that cannot be read


class CtyError(ValueError):
    pass


class _Nowhere(ValueError):
    """Rule 5: a position no place has; its text says which and why."""


def _position(lat_text: str, lon_text: str) -> tuple[float, float]:
    """Rule 5: (latitude, longitude) as the file gives them (west-positive), or _Nowhere."""
    lat, lon = float(lat_text), float(lon_text)
    if not (math.isfinite(lat) and -90.0 <= lat <= 90.0):
        raise _Nowhere(f"latitude {quoted(lat_text.strip())} is no place's (-90..90)")
    if not (math.isfinite(lon) and -180.0 <= lon <= 180.0):
        raise _Nowhere(f"longitude {quoted(lon_text.strip())} is no place's (-180..180)")
    return lat, lon


@dataclass(frozen=True)
class Entity:
    name: str
    continent: str
    cq_zone: int
    itu_zone: int
    latitude_deg: float
    longitude_deg: float  # east-positive (rule 1)
    prefix: str  # the entity's main prefix (``JA``)


@dataclass
class Cty:
    prefixes: dict[str, Entity | None]  # (None: a refused entity's, no place: rule 5)
    exact: dict[str, Entity | None]
    skipped: int = 0
    refused: list[str] = field(default_factory=list)  # rule 5: what was refused, and why

    def lookup(self, call: str) -> Entity | None:
        """Rule 3."""
        whole = call.strip().upper()
        if whole in self.exact:
            return self.exact[whole]  # (None: a refused entity's, rule 5)
        parts = [p for p in whole.split("/") if p]
        if not parts or any(p in _NOWHERE for p in parts[1:]):
            return None
        areas = [p for p in parts[1:] if len(p) == 1 and p in _DIGITS]  # rule 3a
        parts = [parts[0], *(p for p in parts[1:] if p not in _DROPPED and not p.isdigit())]
        if len(parts) == 1 and areas:
            base = _in_area(parts[0], areas[-1])  # rule 3a: no exact call of the home area
        elif len(parts) == 1:
            base = parts[0]
            if base in self.exact:
                return self.exact[base]
        else:
            base = min(parts[:2], key=len)  # the first of equals: min keeps it
        for end in range(len(base), 0, -1):
            if base[:end] in self.prefixes:
                return self.prefixes[base[:end]]  # (None: a refused entity's, rule 5)
        return None


def _in_area(call: str, digit: str) -> str:
    """Rule 3a: the prefix of ``call`` on the air from call area ``digit`` (``UA3ABC``, ``9``:
    ``UA9``): its prefix up to its last digit, that digit replaced; none: the digit added."""
    last = max(call.rfind(d) for d in _DIGITS)
    return call[:last] + digit if last >= 0 else call + digit


def _override(base: Entity, token: str) -> tuple[str, Entity]:
    """A prefix or ``=CALL`` with its overrides (rule 2), as (the text, its entity)."""
    changes: dict[str, object] = {}
    for m in _OVERRIDE.finditer(token):
        cq, itu, lat, lon, cont, _tz = m.groups()
        if cq:
            changes["cq_zone"] = int(cq)
        elif itu:
            changes["itu_zone"] = int(itu)
        elif lat and lon:
            north, west = _position(lat, lon)  # rule 5
            changes["latitude_deg"] = north
            changes["longitude_deg"] = -west
        elif cont:
            changes["continent"] = cont.upper()
    plain = _OVERRIDE.sub("", token).strip().upper()
    if not _PLAIN.fullmatch(plain):
        raise ValueError(token)
    return plain, replace(base, **changes) if changes else base  # type: ignore[arg-type]


def _add(cty: Cty, base: Entity | None, tokens: list[str], where: str) -> None:
    """The prefixes and calls of ``base`` (None: an entity refused, rule 5: kept as no place)."""
    for token in tokens:
        token = token.strip()
        if not token:
            continue
        entity: Entity | None
        try:
            if base is None:
                plain, entity = _OVERRIDE.sub("", token).strip().upper(), None
                if not _PLAIN.fullmatch(plain):
                    raise ValueError(token)
            else:
                plain, entity = _override(base, token)
        except _Nowhere as exc:  # rule 5: the prefix stays its entity's, at its place
            assert base is not None
            cty.skipped += 1
            cty.refused.append(
                f"{where}: {quoted(token)} of {quoted(base.name)}: {exc}; the entity's place taken"
            )
            plain, entity = _OVERRIDE.sub("", token).strip().upper(), base
            if not _PLAIN.fullmatch(plain):
                continue
        except ValueError:
            cty.skipped += 1
            continue
        if plain.startswith("="):
            cty.exact[plain[1:]] = entity
        else:
            cty.prefixes[plain] = entity


def _entity(name: str, cq: str, itu: str, cont: str, lat: str, lon: str, prefix: str) -> Entity:
    north, west = _position(lat, lon)  # rule 5
    return Entity(
        name.strip(),
        cont.strip().upper(),
        int(cq),
        int(itu),
        north,
        -west,  # rule 1
        prefix.strip().lstrip("*").upper(),
    )


def _refuse(cty: Cty, where: str, name: str, exc: _Nowhere) -> None:
    """Rule 5: an entity refused, said once."""
    cty.skipped += 1
    cty.refused.append(f"{where}: {quoted(name.strip())}: {exc}; its calls are placed nowhere")


def parse_dat(text: str) -> Cty:
    """cty.dat: a header line of 8 ``:``-ended fields, then prefixes up to ``;``."""
    cty = Cty({}, {})
    base: Entity | None = None
    nowhere = False  # rule 5: the header was refused: its prefixes are kept as no place
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        if not line[0].isspace():  # a header
            fields = line.split(":")
            base, nowhere = None, False
            try:
                name, cq, itu, cont, lat, lon, _utc, prefix = fields[:8]
                base = _entity(name, cq, itu, cont, lat, lon, prefix)
            except _Nowhere as exc:
                _refuse(cty, f"line {number}", fields[0], exc)
                nowhere = True
            except ValueError:
                cty.skipped += 1
            continue
        if base is None and not nowhere:
            cty.skipped += 1
            continue
        _add(cty, base, line.strip().rstrip(";").split(","), f"line {number}")
        if line.rstrip().endswith(";"):
            base, nowhere = None, False
    return cty


def parse_csv(text: str) -> Cty:
    """cty.csv: ``prefix,name,dxcc,continent,cq,itu,lat,lon,utc,prefixes;`` one entity a line."""
    cty = Cty({}, {})
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        fields = line.split(",", 9)
        base: Entity | None
        try:
            prefix, name, _dxcc, cont, cq, itu, lat, lon, _utc, rest = fields
            base = _entity(name, cq, itu, cont, lat, lon, prefix)
        except _Nowhere as exc:
            _refuse(cty, f"line {number}", fields[1], exc)
            base = None  # rule 5: its prefixes kept as no place
        except ValueError:
            cty.skipped += 1
            continue
        _add(cty, base, rest.strip().rstrip(";").split(), f"line {number}")
    return cty


def load(path: Path) -> Cty:
    """Rule 4: the file read and parsed; CtyError says what is wrong with it."""
    try:
        text = _read(path).decode("utf-8", errors="replace")
    except OSError as exc:
        raise CtyError(
            f"cty_file {shown_path(path)} cannot be read: {exc.strerror or exc}"
        ) from None
    first = next((line for line in text.splitlines() if line.strip()), "")
    csv = first.count(",") >= 9 and ":" not in first.split(",")[0]
    cty = parse_csv(text) if csv else parse_dat(text)
    if not any(e is not None for e in (*cty.prefixes.values(), *cty.exact.values())):
        raise CtyError(
            f"cty_file {shown_path(path)}: no entity in it (is it AD1C's cty.dat or cty.csv?)"
        )
    return cty


def _read(path: Path) -> bytes:
    """Rule 4: the file's bytes; OSError if it cannot be read, is no regular file or is
    larger than CTY_FILE_MAX (core/readfile.py)."""
    try:
        return read_regular(path, CTY_FILE_MAX)
    except NotRegular:
        raise OSError(f"it is no regular file (a device, a pipe or a folder): {_AD1C}") from None
    except TooLarge:
        raise OSError(f"it is larger than {CTY_FILE_MAX >> 20} MiB: {_AD1C}") from None
