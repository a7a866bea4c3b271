"""R/error's rate limit (bridge/interfaces/mqtt/limiter.py and the service), issue 14 item 6:
200,000 refused rotctld commands published 200,000 QoS 1 events; round trips rose to 6 s and the
bridge's memory grew from 42 to 174 MB and stayed."""

from __future__ import annotations

import json
import logging

import pytest

from bridge.core.model import ErrorEvent, ErrorKind
from bridge.interfaces.mqtt.limiter import EventLimiter
from bridge.interfaces.mqtt.service import MqttService
from bridge.interfaces.mqtt.topics import Topics
from tests.mqtt.test_service import RecordingPublisher, RecordingRotator


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def test_a_burst_then_a_steady_rate_and_the_next_one_counts_what_was_left_out() -> None:
    clock = Clock()
    lim = EventLimiter(clock, burst=5, rate_per_s=2.0)
    assert [lim.admit("r/error") for _ in range(8)] == [0, 0, 0, 0, 0, None, None, None]
    clock.t = 0.5  # one token back
    assert lim.admit("r/error") == 3
    assert lim.admit("r/error") is None
    assert lim.admit("other/error") == 0  # each rotator has its own
    clock.t = 100.0  # a quiet spell refills to the burst, never beyond
    assert [lim.admit("r/error") for _ in range(6)] == [1, 0, 0, 0, 0, None]


def test_a_flood_of_refusals_publishes_a_bounded_few_and_then_says_how_many() -> None:
    pub, clock = RecordingPublisher(), Clock()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, error_events_per_s=10, clock=clock)
    svc.attach(RecordingRotator("tower", "rotorez"))
    pub.take()
    event = ErrorEvent(ErrorKind.REFUSED, "azimuth 999 outside the limits 0..360", "P 999 0")
    for i in range(200_000):  # 18 s of a rotctld client looping P 999, as the attack did
        clock.t = i * 18.0 / 200_000
        svc.publish_event("tower", event)
    sent = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/error"]
    assert 50 + 10 * 18 - 1 <= len(sent) <= 50 + 10 * 18 + 1, len(sent)  # burst, then 10/s
    assert all("suppressed" not in e for e in sent[:50])
    clock.t += 0.1  # a quiet tenth of a second: one more may go
    svc.publish_event("tower", event)
    (last,) = [json.loads(p) for t, p, _r in pub.take()]
    assert "more error(s) before this not shown" in last["message"]
    shown = [*sent, last]  # every refusal is accounted for: shown, or counted in the next
    assert len(shown) + sum(e.get("suppressed", 0) for e in shown) == 200_001


def test_a_flood_of_refusals_never_hides_a_stall_or_a_stop_that_did_not_take() -> None:
    """Cold review M3: one bucket for every kind; after a refusal flood the error saying the
    rotor still turns after three stops was dropped and only counted."""
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, error_events_per_s=10)
    svc.attach(RecordingRotator("tower", "rotorez"))
    pub.take()
    refused = ErrorEvent(ErrorKind.REFUSED, "azimuth 999 outside the limits 0..360", "P 999 0")
    for _ in range(1000):
        svc.publish_event("tower", refused)
    pub.take()
    for kind in (ErrorKind.STOP, ErrorKind.STALLED, ErrorKind.SERIAL):
        svc.publish_event("tower", ErrorEvent(kind, "it matters", None))
    kinds = [json.loads(p)["kind"] for t, p, _r in pub.take() if t == "rotor/error"]
    assert kinds == ["stop", "stalled", "serial"]


def test_each_refusal_published_is_one_info_line_and_a_flood_as_few(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """An operator reading the log sees why nothing moved: one line per refusal on R/error,
    under the same limit, the next line counting what was left out."""
    pub, clock = RecordingPublisher(), Clock()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub, error_events_per_s=10, clock=clock)
    svc.attach(RecordingRotator("tower", "rotorez"))
    pub.take()
    caplog.set_level(logging.INFO, logger="bridge.interfaces.mqtt.service")
    event = ErrorEvent(ErrorKind.REFUSED, "azimuth 999 outside the limits 0..360", "P 999 0")
    for _ in range(1000):  # at one instant: the burst goes, the rest is counted
        svc.publish_event("tower", event)
    clock.t = 1.0  # ten more may go
    svc.publish_event("tower", event)
    sent = [json.loads(p) for t, p, _r in pub.take() if t == "rotor/error"]
    lines = [r.getMessage() for r in caplog.records if r.levelno == logging.INFO]
    assert len(lines) == len(sent) == 51
    assert lines[0] == "tower: refused P 999 0: azimuth 999 outside the limits 0..360"
    assert lines[-1] == (
        "tower: refused P 999 0: azimuth 999 outside the limits 0..360 "
        "(950 more error(s) before this not shown)"
    )


def test_a_refusal_in_the_log_is_one_line_however_the_payload_was_written(
    caplog: pytest.LogCaptureFixture,
) -> None:
    pub = RecordingPublisher()
    svc = MqttService(Topics("rotor", {"tower": "rotor"}), pub)
    svc.attach(RecordingRotator("tower", "rotorez"))
    caplog.set_level(logging.INFO, logger="bridge.interfaces.mqtt.service")
    forged = "target '1'\nINFO bridge: all is well" + "x" * 500
    svc.publish_event("tower", ErrorEvent(ErrorKind.REFUSED, "not a number", forged))
    svc.publish_event("tower", ErrorEvent(ErrorKind.STALLED, "no progress for 10 s", None))
    (line,) = [r.getMessage() for r in caplog.records if r.levelno == logging.INFO]
    assert "\n" not in line and "target '1'\\nINFO bridge" in line
    assert line.endswith("...: not a number") and len(line) < 300
