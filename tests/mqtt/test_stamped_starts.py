"""service.py rule 9 (review 34): a stamped command that may turn the rotor and is no target
(a track or follow start, a feature's own command that moves, a preset) is handed to the judge
with its expiry on the steady clock (core/model.py ``Move.not_after_s``), read at once or kept
behind a waiting lock OFF and put at its marker (lastword.py rule 13), as a target is: the
session refuses it, or ends what it began, once the order of a STOP or lock held it past that
(session.py rule 13: tests/engine/test_session_last_word.py; the track start's whole story:
test_review34_stamped_track_waits.py; a call's: tests/dxcluster/test_call_expiry.py)."""

from __future__ import annotations

import pytest

from bridge.core.model import Command, FeatureCommand, FollowQso, GoToPreset, Move, TrackBody
from bridge.features import FEATURES
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.engine.test_feature_commands import TOY
from tests.mqtt.test_attack5_after_off import LockJudged
from tests.mqtt.test_review22_lost_lane_copy import markers_back
from tests.mqtt.test_service import NOW_UNIX, RecordingPublisher

STEADY_S = 1000.0  # the steady clock when the message is read


class Handed(LockJudged):
    """The service's rotator, keeping every command handed on as it came."""

    def __init__(self) -> None:
        super().__init__("tower", "rotorez")
        self.handed: list[Command] = []

    def submit(self, command: Command, described: str | None = None, **kw: object) -> None:  # type: ignore[override]
        self.handed.append(command)
        if not isinstance(command, FeatureCommand):  # (the recorder knows no feature's)
            super().submit(command, described, **kw)


@pytest.mark.parametrize(
    ("topic", "payload", "kind"),
    [
        ("rotor/track", b"sun", TrackBody),
        ("rotor/follow", b"wsjtx", FollowQso),
        ("rotor/beam", b"aim 200", FeatureCommand),
        ("rotor/preset", b"EU", GoToPreset),
    ],
)
@pytest.mark.parametrize("behind_off", [False, True], ids=["read", "kept-behind-a-lock-off"])
def test_a_stamped_start_is_handed_on_with_its_expiry(
    topic: str, payload: bytes, kind: type[Move], behind_off: bool
) -> None:
    pub = RecordingPublisher()
    topics = Topics("rotor", {"tower": "rotor"}, features=(*FEATURES, TOY))
    svc = MqttService(topics, pub, wall=lambda: NOW_UNIX, clock=lambda: STEADY_S)
    tower = Handed()
    svc.attach(tower)
    pub.take()
    if behind_off:
        svc.on_lane_message("rotor/lock", b"ON", False)  # the lane's ON: carried, on hold
        svc.on_message("rotor/lock", b"ON", False)  # its copy
        svc.on_message("rotor/lock", b"OFF", False)  # waits for the marker
    svc.on_message(topic, payload, False, stamp=Stamp.of(NOW_UNIX - 1.0, 5.0))  # sent 1 s ago
    if behind_off:
        assert not [c for c in tower.handed if isinstance(c, kind)]  # (kept)
        markers_back(svc, pub)
    assert not [c for c in tower.calls if c[0] == "refused"], tower.calls
    handed = [c for c in tower.handed if isinstance(c, kind)]
    assert [c.not_after_s for c in handed] == [STEADY_S + 4.0]  # its expiry, 4 s from now


def test_an_unstamped_start_has_no_expiry() -> None:
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, wall=lambda: NOW_UNIX)
    tower = Handed()
    svc.attach(tower)
    svc.on_message("rotor/track", b"sun", False)
    assert [c.not_after_s for c in tower.handed if isinstance(c, TrackBody)] == [None]
