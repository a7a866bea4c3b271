"""COLD REVIEW 34 (7d371f02): a stamped track start that waits for a STOP's order. Failed at
7d371f02; a start now carries its expiry (core/model.py ``Move``) and the session ends what it
began when the hold ends past it (session.py rule 13: tests/engine/test_session_last_word.py).

service.py rule 9 (and docs/mqtt.md): "A stamped move taken goes with its expiry on the steady
clock ...: one that waits in the bridge for the order of a STOP or lock ON (a lane hold and its
marker, lastword.py rule 13 ...) is dropped there once that has passed". Rule 11 counts a
track start among the moves, and the remote stamps its ``track`` as it stamps its ``target``
(docs/remote.md: "target, stop, lock, preset, park, nudge, track, with the expiry"). Only a
``Target`` or a ``Move`` is handed on with its expiry: a ``TrackBody`` is not, the session starts
tracking under the hold and tracking's first bearing goes when the marker comes back, however
late (review 25's R25-3, for ``track`` instead of ``P``: the markers lost in a flood, the rotor
began to track 14 s after a command sent with a 5 s expiry). The same holds for a follow start,
a call's target and a feature's command that moves.

What reaches the controller is modelled as in tests/mqtt/test_review22_lost_lane_copy.py (the
mailbox and the session's hold): a track start handed while a hold is up starts tracking whose
bearings wait for the hold's end; one handed with an expiry (``not_after_s``, were it given)
that has passed at that end is dropped, as session.py rule 13 drops a target.
"""

from __future__ import annotations

import pytest

from bridge.core.model import Command, Stop, TrackBody
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


class Tower(RecordingRotator):
    """The service's rotator, recording the track start handed on as it came, and each release
    with the time the session takes it (the steady clock)."""

    def __init__(self, steady: list[float]) -> None:
        super().__init__("tower", "gs232b")
        self._steady = steady

    def submit(self, command: Command, described: str | None = None, **kw: object) -> None:
        super().submit(command, described, **kw)  # type: ignore[arg-type]
        if isinstance(command, TrackBody):
            self.calls.append(("started", command))

    def release(self, marker: int, *, clear: bool = False) -> None:
        self.calls.append(("release", marker, clear, self._steady[0]))


def tracking_turned(calls: list[tuple[object, ...]]) -> bool:
    """Whether tracking turned the rotor: a start with no hold up, or one waiting when a
    release ends the hold (unless its expiry, if handed on, passed by then); a stop drops it."""
    hold: int | None = None
    waiting: TrackBody | None = None
    turned = False
    for call in calls:
        match call:
            case ("submit", Stop(), *rest):
                waiting = None
                if len(rest) > 1:
                    hold = max(hold or 0, int(str(rest[1])))
            case ("started", TrackBody() as track):
                if hold is None:
                    turned = True
                else:
                    waiting = track
            case ("release", marker, clear, at):
                if clear:
                    hold = waiting = None
                elif hold is not None and hold <= int(str(marker)):
                    hold = None
                    ends = getattr(waiting, "not_after_s", None)
                    if waiting is not None and (ends is None or float(str(at)) <= ends):
                        turned = True
                    waiting = None
    return turned


@pytest.mark.parametrize(
    ("backs", "goes"),
    [
        pytest.param((False, False, True), False, id="back-14s-after-it-was-sent"),
        pytest.param((True,), True, id="back-2s-after"),
    ],
)
def test_a_stamped_track_start_waiting_under_a_hold_does_not_turn_the_rotor_after_its_expiry(
    backs: tuple[bool, ...], goes: bool
) -> None:
    now = [NOW_UNIX]
    steady = [1000.0]
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: now[0], clock=lambda: steady[0]
    )
    tower = Tower(steady)
    svc.attach(tower)
    pub.take()
    # the remote's console: STOP, then "track sun" (stamped, 5 s expiry) right after it
    svc.on_lane_message("rotor/stop", b"", False)  # the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    svc.on_message("rotor/track", b"sun", False, stamp=Stamp.of(now[0], 5.0))  # fresh: waits
    assert not [c for c in tower.calls if c[0] == "refused"], tower.calls
    assert [c for c in tower.calls if c[0] == "started"], tower.calls
    pub.take()  # the marker, and the fresh one sent at the copy, lost (a flood)
    assert not tracking_turned(tower.calls)
    for wait_s, back in zip((2.0, 4.0, 8.0), backs, strict=False):  # lastword.py rule 5
        now[0] += wait_s
        steady[0] += wait_s
        svc._halts.resend_if_due()  # (the timer: a marker sent again)
        if back:
            markers_back(svc, pub)
        else:
            pub.take()  # lost again
    assert tracking_turned(tower.calls) is goes, (
        "a track start stamped with a 5 s expiry began to turn the rotor after it (it waited "
        f"under the hold, and nothing judged its expiry again), or not in time: {tower.calls}"
    )
