"""The spots kept: each with its position, bearing and distance from the station; what
``B/spots`` carries; the place of a call for ``R/target`` ``{"call": ...}``.

Rules:
1. A spot's position: a Maidenhead locator in its comment first (``JO01 <> PM95``: the one
   after ``>``, the DX's; otherwise the first one; ``RR73`` is WSJT-X's sign-off, never a
   locator), else its call's entity from the cty file (cty.py rule 3), else none (still
   listed, without a bearing). ``position`` says which: ``locator``, ``cty`` or null.
2. Kept: spots on the configured bands, the newest ``max_spots``, none older than
   ``max_age_s``. A spot's age is by its own time (the node's ``HHMM``, ``spot_time``: on the
   day of the bridge's wall clock, or the day before for a time more than SKEW_S ahead of it,
   midnight's wrap), so a spot a node replays at a new login (DX Spider's and AR-Cluster's
   last spots, attack 13) is as old as it says: one older than ``max_age_s`` is not taken,
   one younger leaves when its own time is ``max_age_s`` old, not ``max_age_s`` after it came
   again. The newer spot of a call on a band, by its own time, replaces the older one; an
   older one that comes after it is not taken (attack 13: a replayed 18:29 spot took the
   18:35 one's place, and a turn to the call went 22 degrees off, to where it was before);
   of two with the same minute, the one that came last. The list is newest first by the
   spots' own times. The wall clock only ever drops a spot sooner (house rule 7's safe
   side): the age is counted down on the monotonic clock from when it came (a wall clock
   set back keeps no spot longer than ``max_age_s`` after it was heard); a wall clock wrong
   by more than ``max_age_s`` drops every spot, said in the log (client.py rule 3), never
   keeps an old one. The age is judged where the book is read, not only where it is pruned:
   ``newest``, ``calls`` and ``as_json`` pass over a spot past ``max_age_s`` whether or not
   ``prune`` ran since (attack 26: while the node was down the client pruned once per
   back-off, up to a minute apart, and a call target turned to a spot 30 min 25 s old).
3. Bearings and distances are geo.great_circle's from [station] (the same function the
   pointing judge uses); without a station they are null, and so are the bearings of a
   place with no direction (the station's own, its antipode).
4. Thread-safe: the client's thread adds and prunes, the aim thread reads (one lock, held
   for dictionary work only: the cty lookup is done before taking it).
5. One spot never takes the list down: a spot whose entry cannot be made (a place the cty
   file's reader should have refused, cty.py rule 5; a bug) is left out of ``B/spots``, said
   once in the log while it is kept, and the list is made of the rest (attack 12: one spot
   at latitude 357 made every ``B/spots`` raise, and none was published until it aged out).
"""

from __future__ import annotations

import json
import logging
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime

from bridge.core import geo
from bridge.interfaces.dxcluster.cty import Cty
from bridge.interfaces.dxcluster.spots import Spot
from bridge.settings.dxcluster import band_of

log = logging.getLogger(__name__)

MAX_CALLS = 20  # Home Assistant's spot select lists this many calls at most
DAY_S = 86400.0
# rule 2: a spot this far ahead of the bridge's clock is of today (clocks differ: review 56, a
# node 6 minutes ahead of a host with 5 here had every spot taken for yesterday's, none kept)
SKEW_S = 1800.0
_LOCATORS = re.compile(r"(?<![A-Z0-9])[A-R]{2}[0-9]{2}(?:[A-X]{2}(?:[0-9]{2})?)?(?![A-Z0-9])")


@dataclass(frozen=True)
class Place:
    latitude_deg: float
    longitude_deg: float
    source: str  # "locator" or "cty"
    locator: str | None = None
    entity: str | None = None


@dataclass(frozen=True)
class Kept:
    spot: Spot
    band: str | None
    place: Place | None
    heard_s: float  # monotonic
    heard_wall: float
    spotted_wall: float  # rule 2: its own time (unix seconds), the day the bridge's
    until_s: float  # rule 2: monotonic, when it is max_age_s old by its own time


def spot_time(hhmm: str, now_wall: float) -> float:
    """Rule 2: the unix time of a spot's ``HHMM`` (UTC) heard at ``now_wall``: the latest of
    the day before, the day and the day after at that time that is at most SKEW_S ahead."""
    day = now_wall - now_wall % DAY_S
    t = day + int(hhmm[:2]) * 3600.0 + int(hhmm[2:]) * 60.0
    if t + DAY_S <= now_wall + SKEW_S:  # (just before midnight, a node whose clock is ahead)
        return t + DAY_S
    return t - DAY_S if t > now_wall + SKEW_S else t


def locator_in(comment: str) -> str | None:
    """Rule 1: the DX's locator in a spot's comment, or None."""
    text = comment.upper()
    found = [m for m in _LOCATORS.finditer(text) if m.group() != "RR73"]
    if not found:
        return None
    after = [m for m in found if ">" in text[: m.start()]]
    return (after or found)[0].group()


class Book:
    def __init__(
        self,
        cty: Cty | None,
        station: tuple[float, float] | None,
        *,
        max_spots: int = 50,
        max_age_s: float = 1800.0,
        bands: tuple[str, ...] = (),
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self._cty = cty
        self.station = station
        self._max = max_spots
        self._max_age_s = max_age_s
        self._bands = frozenset(bands)
        self._clock = clock
        self._wall = wall
        self._lock = threading.Lock()
        self._spots: list[Kept] = []  # newest first
        self._unlisted: set[Kept] = set()  # rule 5: left out of B/spots, said once
        self.too_old = 0  # rule 2: spots not taken for their own time (client.py logs them)
        self.last_too_old: tuple[str, float] | None = None  # (its HHMM, the wall clock then)

    def place(self, spot: Spot) -> Place | None:
        """Rule 1 (no lock: the cty data is read-only once loaded)."""
        locator = locator_in(spot.comment)
        if locator is not None:
            lat, lon = geo.parse_locator(locator)
            return Place(lat, lon, "locator", locator=locator)
        return self.entity_place(spot.call)

    def entity_place(self, call: str) -> Place | None:
        entity = self._cty.lookup(call) if self._cty is not None else None
        if entity is None:
            return None
        return Place(entity.latitude_deg, entity.longitude_deg, "cty", entity=entity.name)

    def add(self, spot: Spot) -> bool:
        """Rule 2: whether it is kept (False: not on a configured band, older than
        ``max_age_s`` by its own time, or older than the call's kept spot on its band)."""
        band = band_of(spot.freq_khz)
        if self._bands and band not in self._bands:
            return False
        now_s, now_wall = self._clock(), self._wall()
        spotted = spot_time(spot.time, now_wall)
        age_s = max(0.0, now_wall - spotted)
        if age_s > self._max_age_s:  # rule 2: a replay of a spot already gone
            self.too_old += 1
            self.last_too_old = (spot.time, now_wall)
            return False
        place = self.place(spot)
        with self._lock:
            same = next(
                (k for k in self._spots if (k.spot.call, k.band) == (spot.call, band)), None
            )
            if same is not None and same.spot == spot and same.spotted_wall == spotted:
                return True  # the same spot again (a replay): kept as it was
            if same is not None and same.spotted_wall > spotted:
                return False  # rule 2: older than the one kept
            until_s = now_s + self._max_age_s - age_s
            kept = Kept(spot, band, place, now_s, now_wall, spotted, until_s)
            rest = [k for k in self._spots if k is not same]
            # newest first by their own times; of the same minute, the one heard last first
            at = next((i for i, k in enumerate(rest) if k.spotted_wall <= spotted), len(rest))
            rest.insert(at, kept)
            self._spots = rest[: self._max]
            self._unlisted &= set(self._spots)
            return kept in self._spots

    def prune(self) -> bool:
        """Rule 2: the spots too old dropped; whether any was."""
        now_s = self._clock()
        with self._lock:
            before = len(self._spots)
            self._spots = [k for k in self._spots if k.until_s >= now_s]
            self._unlisted &= set(self._spots)
            return len(self._spots) != before

    def _young(self, now_s: float) -> list[Kept]:
        """Rule 2: the kept spots not past their age at ``now_s``, newest first, pruned or not
        (called with the lock held)."""
        return [k for k in self._spots if k.until_s >= now_s]

    def newest(self, call: str) -> Kept | None:
        """The newest spot of ``call`` (any case), if one is kept and not past its age."""
        wanted, now_s = call.strip().upper(), self._clock()
        with self._lock:
            return next((k for k in self._young(now_s) if k.spot.call == wanted), None)

    def calls(self) -> tuple[str, ...]:
        """The calls of the newest spots, each once, at most MAX_CALLS."""
        now_s = self._clock()
        with self._lock:
            calls = dict.fromkeys(k.spot.call for k in self._young(now_s))
        return tuple(calls)[:MAX_CALLS]

    def as_json(self) -> str:
        """``B/spots``: ``{"spots": [...]}``, newest first."""
        now_s = self._clock()
        with self._lock:
            spots = self._young(now_s)
        listed = []
        for k in spots:
            try:
                listed.append(self._one(k))
            except (ValueError, ArithmeticError) as exc:  # rule 5: the rest is listed
                self._left_out(k, exc)
        return json.dumps({"spots": listed}, separators=(",", ":"))

    def _left_out(self, k: Kept, exc: Exception) -> None:
        """Rule 5: ``k`` said in the log the first time it is left out."""
        with self._lock:
            if k in self._unlisted or k not in self._spots:
                return
            self._unlisted.add(k)
        log.warning("DX cluster: the spot of %s left out of the spots list: %s", k.spot.call, exc)

    def _one(self, k: Kept) -> dict[str, object]:
        s = k.spot
        heard = datetime.fromtimestamp(k.heard_wall, UTC).isoformat(timespec="seconds")
        doc: dict[str, object] = {
            "call": s.call,
            "frequency_khz": s.freq_khz,
            "band": k.band,
            "spotter": s.spotter,
            "time": f"{s.time}Z",
            "heard": heard.replace("+00:00", "Z"),
            "comment": s.comment,
            "position": None,
        }
        p = k.place
        if p is None:
            return doc
        doc.update(position=p.source, latitude=round(p.latitude_deg, 3))
        doc.update(longitude=round(p.longitude_deg, 3))
        if p.locator is not None:
            doc["locator"] = p.locator
        if p.entity is not None:
            doc["entity"] = p.entity
        if self.station is not None:
            path = geo.great_circle(*self.station, p.latitude_deg, p.longitude_deg)
            turn = path.has_direction  # rule 3: at the station or its antipode, no bearing
            doc["bearing_deg"] = round(path.short_path_deg, 1) if turn else None
            doc["long_path_deg"] = round(path.long_path_deg, 1) if turn else None
            doc["distance_km"] = round(path.distance_km)
        return doc
