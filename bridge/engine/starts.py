"""What starting a feature that turns the rotor by itself needs of the station and the
controller (tracking a body, following the QSO partner WSJT-X names), judged before anything
is queued. Pure: the rotator's facts in, the body or nothing out, or Refused saying what is
missing. The judge (rotator.py) asks this first, then the lock, the wind and the lease.

Rules:
1. A start the station cannot serve is refused as unsupported, naming the setting that is
   missing, whoever sent it: it never waits in the mailbox.
2. A satellite's name is not looked up here (a file read, docs/architecture.md rule 12): the
   sky worker answers it, and None says so.
"""

from __future__ import annotations

from bridge.engine.catalog import CatalogError, TleCatalog
from bridge.engine.config import FollowConfig
from bridge.errors import RefusalCode, Refused
from bridge.protocols.base import ModelSpec
from bridge.sky import Body, SkyError


def body_to_track(
    catalog: TleCatalog,
    spec: ModelSpec,
    has_sky: bool,
    name: str,
    tle: tuple[str, str, str] | None,
) -> Body | None:
    """The body to track, or None for a satellite to look up in the TLE file (rule 2)."""
    if not has_sky:
        raise Refused(
            RefusalCode.UNSUPPORTED,
            "tracking needs the station's position ([station] locator, or latitude_deg "
            "and longitude_deg)",
        )
    if not spec.can_report_position:
        raise Refused(
            RefusalCode.UNSUPPORTED,
            f"the {spec.display_name} cannot report where it points: tracking needs a "
            "controller that does",
        )
    try:
        return catalog.body(name, tle)
    except (SkyError, CatalogError) as exc:
        raise Refused(RefusalCode.INVALID, str(exc)) from None


def check_can_follow(cfg: FollowConfig) -> None:
    """Following WSJT-X needs its messages and the station's position (rule 1)."""
    if not cfg.wsjtx:
        raise Refused(
            RefusalCode.UNSUPPORTED, "following WSJT-X needs its messages: [wsjtx] enabled = true"
        )
    if cfg.station is None:
        raise Refused(
            RefusalCode.UNSUPPORTED,
            "following WSJT-X needs the station's position ([station] locator, or "
            "latitude_deg and longitude_deg): bearings are from there",
        )
