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
the harm R25-3 named, for a tracking start instead of a target. The same behind a lane STOP
(R25-3's own case): the start is taken at once, tracking's first target waits for the marker
(session.py rule 13) and goes however late; on a virtual MD-01 the rotor turns to the sun
15 s after a 5 s expiry, where a target would have been dropped."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.core.model import Command, FollowQso, TrackBody
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.engine.test_halt_epoch import START_AZ, Bench
from tests.mqtt.test_review22_lost_lane_copy import markers_back, markers_back_late
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher, RecordingRotator


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


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    made = Bench(tmp_path)
    yield made
    made.close()


def test_a_stamped_track_start_behind_a_lane_stop_does_not_turn_the_rotor_after_its_expiry(
    bench: Bench,
) -> None:
    """The service, the judge and the session are the real ones (tests/engine/test_halt_epoch.py's
    bench); the markers lost in a flood as in R25-3's test."""
    v = bench.v
    pub = RecordingPublisher()
    svc = MqttService(
        Topics("rotor", {"v": "rotor"}),
        pub,
        wall=lambda: NOW_UNIX + v.now,
        clock=lambda: v.now,  # (the session's clock: the bench's virtual one)
    )
    svc.attach(bench.rot)
    pub.take()
    svc.on_lane_message("rotor/stop", b"", False)  # the remote's S, the lane first: on hold
    svc.on_message("rotor/stop", b"", False)  # its copy on the main connection
    sent = NOW_UNIX + v.now + 0.002  # (its clock 2 ms ahead: not taken for one before the S)
    svc.on_message("rotor/track", b"sun", False, stamp=Stamp.of(sent, 5.0))  # 5 s expiry
    v._take()  # noqa: SLF001
    v.run_for(1.0)
    assert bench.sets() == []  # (tracking's target waits for the marker)
    markers_back_late(svc, pub, v.run_for)  # (lost in a flood; one back 14 s on)
    v._take()  # noqa: SLF001
    v.run_for(40.0)
    assert bench.sets() == [] and abs(v.truth().az_deg - START_AZ) < 4, (
        "a track start stamped with a 5 s expiry turned the rotor 15 s after it was sent: now "
        f"at {v.truth().az_deg:.0f}, sent {bench.sets()}"
    )
