"""A satellite's look-up under a STOP's hold (session.py rule 13): what the look-up tests of
reviews 37, 135, 137 and 141 share."""

from __future__ import annotations

from bridge.core.model import Source
from bridge.session.tracking import Track
from bridge.sky.catalog import TleCatalog
from bridge.sky.worker import LookupQuestion
from tests.engine.virtual import VirtualRotator


def look_up(v: VirtualRotator, catalog: TleCatalog, name: str, not_after_s: float | None) -> None:
    """A remote's ``track <name>`` (a look-up by name), taken now."""
    lookup = LookupQuestion(catalog, name)
    described = f"track {name}"
    v.mailbox.put_track(Track(None, Source.MQTT, lookup, described, not_after_s=not_after_s))
    v._take()
