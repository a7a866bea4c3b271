"""Stop and lock from both MQTT connections, in the order lastword.py decides (service.py rule
5): the stop lane's messages, the main connection's halts, the markers and their resend, the
retained halts. lastword.py decides; this carries its decisions out into the rotators, each
decision and the mailbox put it lets through under one lock.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from bridge.model import Origin, Source, Stop
from bridge.mqtt import payloads as pl
from bridge.mqtt.lastword import RESEND_S, LastWord
from bridge.mqtt.ports import Publisher, RotatorPort
from bridge.mqtt.topics import Topics

log = logging.getLogger(__name__)


def switch_on(payload: bytes) -> bool:
    try:
        return pl.parse_switch(payload)
    except pl.PayloadError:
        return False


def _switch_off(payload: bytes) -> bool:
    try:
        return not pl.parse_switch(payload)
    except pl.PayloadError:
        return False


class Halts:
    def __init__(
        self,
        topics: Topics,
        publisher: Publisher,
        rotators: dict[str, RotatorPort],
        clock: Callable[[], float],
        *,
        retain_is_live: bool,
        on_problem: Callable[[str, str], None] | None,
    ) -> None:
        self.topics = topics
        self._publisher = publisher
        self._rotators = rotators  # the service's: rotators attached later are seen here too
        self._clock = clock
        self.retain_is_live = retain_is_live
        self._on_problem = on_problem  # (topic, problem): a broker problem the bridge reports
        self.word = LastWord()
        self._lock = threading.Lock()  # two connections, two paho threads
        self._resend_timer: threading.Timer | None = None
        self._markers_denied = False

    def main_gone(self) -> None:
        """The main connection dropped, or is new (before its first message): holds end with
        clearing (lastword.py rule 5)."""
        with self._lock:
            for rid in self.word.main_gone():
                rot = self._rotators.get(rid)
                if rot is not None:
                    rot.release(0, clear=True)

    def lane_connected(self) -> None:
        with self._lock:
            self.word.lane_connected()

    def markers_denied(self) -> None:
        """The main connection cannot read the markers: the lane's halts hold nothing
        (lastword.py rule 7)."""
        with self._lock:
            self._markers_denied = True
        self.main_gone()

    def lane_markers_denied(self) -> None:
        """The lane cannot read its markers: no echo is expected (lastword.py rule 4)."""
        with self._lock:
            self.word.echoes = False

    def _holds_possible(self) -> bool:
        return self._publisher.up and not self._markers_denied

    def carry(
        self,
        rot: RotatorPort,
        kind: str,
        what: str,
        hold: int | None = None,
        origin: Origin | None = None,
        echo: bool = False,
    ) -> None:
        """A stop or a lock ON, into the mailbox (under the word lock: lastword.py's decision
        and the put are one step). ``origin``: who sent it; ``echo``: the main connection's
        copy of one the lane carried out (the audit trail has it once)."""
        if kind == "stop":
            rot.submit(Stop(Source.MQTT, origin), what, hold=hold, echo=echo)
        else:
            rot.set_lock(True, hold=hold, origin=origin, echo=echo)

    def _send_marker(self, n: int) -> None:
        self._publisher.publish_marker(self.topics.bridge_fence, self.word.marker(n))
        self._arm_resend()

    def _arm_resend(self) -> None:
        """One timer at most looks again in RESEND_S while a hold is out."""
        with self._lock:
            if self._resend_timer is not None or not self.word.holding:
                return
            timer = self._resend_timer = threading.Timer(RESEND_S, self._resend_marker)
        timer.daemon = True
        timer.start()

    def _resend_marker(self) -> None:
        """lastword.py rule 5: a marker the broker dropped is sent again (a new number)."""
        with self._lock:
            self._resend_timer = None
        self.resend_if_due()
        self._arm_resend()

    def resend_if_due(self) -> None:
        with self._lock:
            n = self.word.resend_due(self._clock())
        if n is None:
            return
        if n < 0:  # lastword.py rule 5: the broker drops them
            problem = (
                f"the bridge's own markers on {self.topics.bridge_fence} do not come back "
                "(does the broker's ACL deny that topic?): a stop from the stop lane can no "
                "longer hold back a target published before it"
            )
            log.error("%s", problem)
            self.markers_denied()
            if self._on_problem is not None:
                self._on_problem(self.topics.bridge_fence, problem)
            return
        log.info("a marker of the stop lane did not come back; sending another")
        self._publisher.publish_marker(self.topics.bridge_fence, self.word.marker(n))

    def marker_back(self, payload: bytes) -> None:
        with self._lock:
            n, released = self.word.marker_back(payload)
            for rid in released:
                rot = self._rotators.get(rid)
                if rot is not None:
                    rot.release(n)

    def on_lane_marker(self, payload: bytes) -> None:
        """The lane read its marker (lastword.py rule 4)."""
        with self._lock:
            self.word.lane_marker_back(payload)

    def replayed_halt(self, rot: RotatorPort, topic: str, kind: str, payload: bytes) -> None:
        """lastword.py rule 6 under MQTT 3.1.1: a replayed retained stop or lock ON, once."""
        what = pl.describe(kind, payload)
        with self._lock:
            if not self.word.retained_halt(topic, payload, replayed=True):
                log.debug("%s: retained %s on %s already carried out once", rot.id, kind, topic)
                return
            self.carry(rot, kind, what)
        self.report_retained_halt(rot, topic, kind, what)

    def report_retained_halt(self, rot: RotatorPort, topic: str, kind: str, what: str) -> None:
        rot.report_refusal(
            f"{kind} on {topic} was published retained: executed (stopping is always safe), "
            "but clear it with an empty retained message",
            what,
        )

    def on_lane(
        self, topic: str, payload: bytes, retain: bool, origin: Origin | None = None
    ) -> None:
        """The stop lane's messages (rule 5; lastword.py rules 2-4 and 6)."""
        if topic == self.topics.bridge_fence_lane:
            self.on_lane_marker(payload)
            return
        route = self.topics.route(topic)
        if route is None or (retain and not payload):
            return
        rotator_id, kind, _arg = route
        rot = self._rotators.get(rotator_id)
        if rot is None or kind not in ("stop", "lock"):
            return
        if kind == "lock" and not switch_on(payload):
            if retain or not _switch_off(payload):
                return  # the main connection refuses or reports it
            with self._lock:  # lastword.py rule 3: the only word while it is down
                if self._publisher.up:
                    return
                rot.set_lock(False, origin=origin)
            return
        if retain and not self.retain_is_live:
            self.replayed_halt(rot, topic, kind, payload)
            return
        what = pl.describe(kind, payload)
        with self._lock:
            marker = self.word.lane_halt(rotator_id, kind, self._clock(), self._holds_possible())
            if marker is None:
                log.debug("%s: %s on the stop lane: already carried out", rotator_id, kind)
                return  # lastword.py rule 4: the echo of the main connection's copy
            self.carry(rot, kind, what, hold=marker or None, origin=origin)
        if marker:
            self._send_marker(marker)

    def main_halt(
        self,
        rot: RotatorPort,
        topic: str,
        kind: str,
        what: str,
        retain: bool,
        origin: Origin | None = None,
    ) -> None:
        """A stop or lock ON read on the main connection: carried out in order (rule 1), noted
        for rule 4."""
        with self._lock:
            echo = self.word.lane_came_first(rot.id, kind)
            lane_marker = self.word.main_halt(rot.id, kind)
            self.carry(rot, kind, what, origin=origin, echo=echo)
        if lane_marker is not None:
            marker = self.word.marker(lane_marker)
            self._publisher.publish_marker(self.topics.bridge_fence_lane, marker)
        if retain:  # published retained, live (MQTT 5): carried out, and reported
            self.report_retained_halt(rot, topic, kind, what)

    def main_lock_off(self, rot: RotatorPort, origin: Origin | None = None) -> None:
        """A lock OFF read on the main connection (rule 8: not when older than a lane ON)."""
        with self._lock:
            if not self.word.main_lock_off(rot.id):
                log.info("%s: lock OFF published before a lock ON: the ON stands", rot.id)
                return
            rot.set_lock(False, origin=origin)

    def retained_deleted(self, topic: str) -> None:
        with self._lock:
            self.word.retained_halt(topic, b"", replayed=True)  # forgotten (rule 6)
