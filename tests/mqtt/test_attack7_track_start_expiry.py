"""Attack pass 7 on 7d371f02 (review 25, R25-3): "a stamped move that waits for the last
word's order goes only while its expiry lasts". Only a ``Target`` or a ``Move`` (preset, park,
nudge, place, path) carries the expiry (service.py ``_command``: ``isinstance(command, Target
| Move)``). A track start (``R/track sun``, a satellite) and a follow start (``R/follow ON``)
turn the rotor too (core/model.py ``turns_rotor``), are stamped and judged by rule 9 as any
move, and wait for the same order: kept behind a member's lock OFF that waits for its marker
(lastword.py rule 13, halts.py ``keep_after_off``: "a target, a track or follow start"), they
are put at the marker however late, with nothing that knows their expiry. The remote's
``R/track sun`` (5 s expiry), sent right after its lock OFF, its markers lost in a flood, starts
tracking and turns the rotor 14 s after it was sent, when the operator has given up on it:
the harm R25-3 named, for a tracking start instead of a target."""

from __future__ import annotations

import pytest

from bridge.core.model import Command, FollowQso, TrackBody
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


@pytest.mark.xfail(
    strict=True,
    reason="attack 7: a stamped track or follow start kept behind a waiting lock OFF carries "
    "no expiry and starts at the marker however late",
)
@pytest.mark.parametrize(("topic", "payload"), [("track", b"sun"), ("follow", b"wsjtx")])
def test_a_stamped_tracking_start_kept_behind_a_lock_off_does_not_start_after_its_expiry(
    topic: str, payload: bytes
) -> None:
    now = [NOW_UNIX]
    steady = [1000.0]
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: now[0], clock=lambda: steady[0]
    )
    tower = RecordingRotator("tower", "md01")
    handed: list[tuple[Command, float]] = []  # (what the rotator was given, and when)
    recorded = tower.submit

    def submit(command: Command, *args: object, **kw: object) -> None:
        handed.append((command, steady[0]))
        recorded(command, *args, **kw)  # type: ignore[arg-type]

    tower.submit = submit  # type: ignore[method-assign]
    svc.attach(tower)
    pub.take()
    # the remote: lock ON (the lane first: carried at once, on hold), its copy; lock OFF,
    # then the start (stamped, 5 s expiry) right after it: both wait for the marker
    svc.on_lane_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"ON", False)
    svc.on_message("rotor/lock", b"OFF", False)
    svc.on_message(f"rotor/{topic}", payload, False, stamp=Stamp.of(now[0], 5.0))
    assert not [c for c in tower.calls if c[0] == "refused"], tower.calls
    pub.take()  # the marker, and the fresh one sent at the copy, lost (the broker dropped them)
    for wait_s, back in ((2.0, False), (4.0, False), (8.0, True)):  # rule 5's back-off
        now[0] += wait_s
        steady[0] += wait_s
        svc._halts.resend_if_due()  # noqa: SLF001  (the timer: a marker sent again)
        if back:
            markers_back(svc, pub)
        else:
            pub.take()  # lost again in the flood
    starts = [
        (command, at)
        for command, at in handed
        if isinstance(command, TrackBody | FollowQso)
        and not (getattr(command, "not_after_s", None) or float("inf")) < at
    ]
    assert starts == [], (
        f"a {topic} start stamped with a 5 s expiry was handed on 14 s after it was sent, "
        f"with nothing to drop it: {tower.calls}"
    )
