"""Tracking and following as commands start and end them (session.py rules 10 and 15): what a
start needs of the station and the controller, judged before anything is queued; the track and
follow commands, the sky worker's answer to a satellite's name, and the end that every other
command brings. It owns the tracker (tracking.py) and the follower (follow.py) and drops a
target of theirs still waiting (targets.py) when they end; what the status and the error events
must say it returns as a ``Done`` that the session applies. It never imports the session. The
judge (rotator.py) asks ``body_to_track`` or ``check_can_follow`` first (pure: the rotator's
facts in, the body or nothing out, or Refused saying what is missing), then the lock, the wind
and the lease.

Rules:
1. A start the session refuses (``refused``: the lock, the link, the wind; ``leased``: the
   control lease, judged by the session when a claim comes in the start's own batch or before
   its look-up's answer, session.py rule 23, and said with its sender for the audit trail) is
   an error and changes nothing. A start taken ends the other feature and any waiting target
   (one feature turns the rotor at a time), and the status names who started it
   (``Done.taken``).
2. ``off`` ends its own feature only; ``end`` (a stop, the lock, another target, a stall, the
   link, a cleared hold) ends both unless told otherwise. A target of a feature that ended
   never goes out after it.
3. A satellite's name answered by the sky worker starts tracking as the command would have,
   judged when the answer comes (tracking.py rule 8): the lock, the link, the wind, and the
   control lease as it is then (session.py rule 23: a look-up asked before another operator's
   claim and answered after it is refused, naming its sender for the audit trail).
4. A start the station cannot serve is refused by the judge as unsupported, naming the setting
   that is missing, whoever sent it: it never waits in the mailbox.
5. A satellite's name is not looked up by the judge (a file read, docs/architecture.md rule
   12): the sky worker answers it, and ``body_to_track`` says so with None.
6. A rotator whose bearing is an elevation (a box made for an elevation rotor, configured on
   its own: protocols/axes.py rule 6) is never sent an azimuth the bridge works out: a track
   or follow start, and a place (runtime/rotator.py ``_toward``), are refused as unsupported
   (``check_azimuth``), by the judge as rule 4 has it, and by the session too, whatever
   brought the start (attack 19: the sun's azimuth and a QSO partner's bearing each raised a
   dish as its elevation, nothing said).
7. A start's refusal may owe a halt to a turn not yet seen (parts.py rule 10, ``StartHalt``):
   owed while that feature is on (``owing``), so nothing is owed once it ends, however it
   ends (``off``, ``end``, the other feature's start, the sky worker's answer, its own step).
   The session tells the motion so at every step (session.py ``_step``: motion.py rule 4's
   ``owes_halt``), the one place (review 95: cleared only where the session ended a part
   itself, a hand after ``follow OFF`` was still held back a reading).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from bridge.core.errors import RefusalCode, Refused
from bridge.core.model import ErrorKind, Origin, Source
from bridge.protocols.axes import bearing_is_elevation
from bridge.protocols.base import ModelSpec
from bridge.session.actions import Report
from bridge.session.config import FollowConfig, WorkerConfig
from bridge.session.follow import Follow, Follower
from bridge.session.targets import Targets
from bridge.session.tracking import Track, Tracker
from bridge.sky import Body, SkyError
from bridge.sky.catalog import CatalogError, TleCatalog
from bridge.sky.worker import Answer

log = logging.getLogger(__name__)

# rule 6: what would send an azimuth to a rotator whose bearing is an elevation
TRACKING = "tracking sends the body's azimuth"
FOLLOWING = "following WSJT-X sends the QSO partner's bearing, an azimuth"
PLACE = "a place (a locator, coordinates, a call) is turned to by its bearing, an azimuth"


def check_azimuth(spec: ModelSpec, doing: str) -> None:
    """Rule 6: Refused if ``spec``'s bearing is an elevation; ``doing``: what would have sent it
    an azimuth (TRACKING, FOLLOWING, PLACE)."""
    if bearing_is_elevation(spec):
        raise Refused(
            RefusalCode.UNSUPPORTED,
            f"{doing}, and the {spec.display_name} ({spec.name}) turns an elevation rotor: its "
            "bearing is the elevation",
        )


def body_to_track(
    catalog: TleCatalog,
    spec: ModelSpec,
    has_sky: bool,
    name: str,
    tle: tuple[str, str, str] | None,
) -> Body | None:
    """The body to track, or None for a satellite to look up in the TLE file (rule 5)."""
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
    check_azimuth(spec, TRACKING)  # rule 6
    try:
        return catalog.body(name, tle)
    except (SkyError, CatalogError) as exc:
        raise Refused(RefusalCode.INVALID, str(exc)) from None


def check_can_follow(cfg: FollowConfig, spec: ModelSpec) -> None:
    """Following WSJT-X needs its messages and the station's position (rule 4), and a rotator
    that turns in azimuth (rule 6)."""
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
    check_azimuth(spec, FOLLOWING)


@dataclass(frozen=True)
class Done:
    """What a command did that the session must show: an error, or who started a feature."""

    error: Report | None = None
    taken: tuple[str, Origin | None] | None = None  # (source, origin) of a feature started


DONE = Done()


class FeatureCommands:
    def __init__(self, cfg: WorkerConfig, targets: Targets) -> None:
        self.name = cfg.rotator_id
        self.spec = cfg.spec
        self.targets = targets
        self.tracker = Tracker(cfg)
        self.follower = Follower(cfg)

    def track(self, track: Track, refused: str | None, leased: str | None = None) -> Done:
        """``leased``: why its sender may not start it under the lease now (rule 1)."""
        if track.body is None and track.lookup is None:
            self.tracker.end("off")  # rule 2
            self.targets.clear_from(Source.TRACKING)
            return DONE
        name = track.body.name if track.body is not None else track.lookup and track.lookup.name
        refused = refused or _azimuth_refused(self.spec, TRACKING)  # rule 6
        if refused is not None:
            return Done(Report(ErrorKind.REFUSED, refused, track.described or f"track {name}"))
        if leased is not None:  # rule 1: audited with its sender
            who = track.origin or Origin(track.source)
            return Done(Report(ErrorKind.REFUSED, leased, track.described or f"track {name}", who))
        if track.body is None:
            self.tracker.look_up(track)  # tracking.py rule 8: the answer comes as an input
            return DONE
        self.tracker.end("another body")
        self.follower.end(f"tracking {track.body.name}")
        self.targets.clear()
        self.tracker.start(track.body, track.from_file)
        log.info("%s: tracking %s", self.name, track.body.name)
        return Done(taken=(track.source.value, track.origin))

    def follow(
        self, follow: Follow, refused: str | None, now: float, leased: str | None = None
    ) -> Done:
        """``leased``: as ``track``'s."""
        if not follow.on:
            self.end("off", tracking=False)  # rule 2
            return DONE
        refused = refused or _azimuth_refused(self.spec, FOLLOWING)  # rule 6
        if refused is not None:
            return Done(Report(ErrorKind.REFUSED, refused, follow.described or "follow"))
        if leased is not None:  # rule 1: audited with its sender
            who = follow.origin or Origin(follow.source)
            return Done(Report(ErrorKind.REFUSED, leased, follow.described or "follow", who))
        self.tracker.end("following")
        self.targets.clear()
        self.follower.start(follow, now)
        return Done(taken=(follow.source.value, follow.origin))

    def answered(self, answer: Answer, refused: str | None, leased: str | None = None) -> Done:
        """The sky worker's answer: a satellite's name looked up (rule 3), or tracking's sky;
        ``leased``: why the look-up's sender may not start tracking under the lease now."""
        lookup = self.tracker.lookup
        if lookup is not None and answer.question == lookup.lookup:
            self.tracker.lookup = None
            body = answer.value
            if answer.failure is not None or not isinstance(body, Body):
                refusal = answer.failure or "no such satellite"
                return Done(Report(ErrorKind.REFUSED, refusal, lookup.described))
            track = Track(body, lookup.source, None, lookup.described, lookup.origin, lookup.lookup)
            return self.track(track, refused, leased)
        ends = self.tracker.answered(answer)
        if ends is not None:
            log.warning("%s: tracking ends: %s", self.name, ends)
            self.tracker.end(ends)
            self.targets.clear_from(Source.TRACKING)
        return DONE

    @property
    def owing(self) -> bool:
        """Rule 7: a refused start's halt is owed (parts.py rule 10) by tracking or following,
        while it is on; the session tells the motion at every step (motion.py rule 4)."""
        return self.tracker.owing or self.follower.owing

    def end(self, why: str, *, tracking: bool = True) -> None:
        """Tracking and following end (rule 2); ``{}`` in ``why``: the command's name."""
        if tracking and self.tracker.end(why.replace("{}", "track")):
            self.targets.clear_from(Source.TRACKING)
        if self.follower.end(why.replace("{}", "follow")):
            self.targets.clear_from(Source.WSJTX)


def _azimuth_refused(spec: ModelSpec, doing: str) -> str | None:
    """Rule 6, as the session says it: why a start is refused (None: it is not)."""
    try:
        check_azimuth(spec, doing)
    except Refused as exc:
        return exc.message
    return None
