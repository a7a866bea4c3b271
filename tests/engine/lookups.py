"""A satellite's look-up under a STOP's hold (session.py rule 13): what the look-up tests of
reviews 37, 135, 137 and 141 share."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bridge.core.model import MotionState, Source, Stop
from bridge.session.follow import Follow, Heard
from bridge.session.tracking import Track
from bridge.sky import Sky
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.test_catalog import ISS, three_line
from tests.engine.test_composite import FAST, FINE, online
from tests.engine.test_session_tracking import SUN_EPOCH, sun_up_somewhere
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def look_up(v: VirtualRotator, catalog: TleCatalog, name: str, not_after_s: float | None) -> None:
    """A remote's ``track <name>`` (a look-up by name), taken now."""
    lookup = LookupQuestion(catalog, name)
    described = f"track {name}"
    v.mailbox.put_track(Track(None, Source.MQTT, lookup, described, not_after_s=not_after_s))
    v._take()


@contextmanager
def az_el_at_rest(tmp_path: Path) -> Iterator[tuple[VirtualComposite, Path]]:
    """An RT-21 azimuth box and a GS-232B elevation box, the sun up over the station, both
    answering and at rest; and a TLE file with the ISS in it (reviews 137 and 141)."""
    path = tmp_path / "sats.txt"
    path.write_text(three_line(("ISS (ZARYA)", ISS)))
    lat, lon = sun_up_somewhere(SUN_EPOCH)
    with VirtualComposite(
        "rt21", "gs232b", settings=FINE, emulators=FAST, sky=Sky(lat, lon), wall_epoch_s=SUN_EPOCH
    ) as v:
        v.run_until(online, 20, "both boxes answer")
        v.run_until(lambda h: h.status.state is MotionState.IDLE and h.now > 5, 200, "idle")
        yield v, path


def following_under_a_hold(v: VirtualRotator) -> None:
    """A STOP whose marker is late holds the rotator; WSJT-X following is started in time
    under the hold, a QSO partner heard (reviews 37 and 135)."""
    v.mailbox.put(Stop(Source.MQTT), hold=1)  # a STOP whose marker is late
    v._take()
    v.mailbox.put_follow(Follow(True, described="follow"))  # in time, under the hold
    v.mailbox.put_heard(Heard("JA1ABC", "PM95", False))
    v._take()
