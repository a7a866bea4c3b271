"""Attack 28: a wind reading of ``-0`` (a weather station's rounding of a tiny negative offset,
``-0.0`` from a sensor's float) is taken, since it is not below 0, and shown as it came:
``R/status`` says ``"speed_kmh":-0.0`` and Home Assistant's *Wind* sensor reads -0.0 km/h. A
speed has no sign; the reading is 0 (or, as the house standard has it for input no speed is,
dropped and said)."""

from __future__ import annotations

import json

import pytest

from tests.support import wait_until
from tests.support.mqtt import Message
from tests.support.rig import Rig

TOPIC = "weather/station/wind"
WAIT_S = 10.0  # the status after a reading: one engine turn, on a loaded machine


def test_a_wind_reading_of_minus_zero_is_shown_as_no_wind_with_a_sign(
    rig: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    rig.add(
        "tower",
        "md01",
        wind_topic=TOPIC,
        wind_unit="m/s",
        wind_park_above=20,
        wind_release_below=10,
        wind_park_az_deg=90,
    )
    rig.start()
    rig.ready("tower")
    rig.probe.publish(TOPIC, "3")  # 10.8 km/h, shown first: what the -0 changes from
    rig.probe.wait(lambda m: m.topic == "rotor/status" and _speed(m.payload) == 10.8, WAIT_S)
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "-0")  # alone: readings that come together are taken at their most

    def taken_or_dropped() -> bool:
        shown = [_speed(m.payload) for m in _statuses(rig, mark)]
        return any(s != 10.8 for s in shown) or "reading dropped" in caplog.text

    wait_until(taken_or_dropped, WAIT_S, "the -0 reading shown, or dropped and said")
    shown = [m.payload for m in _statuses(rig, mark)]
    assert not [p for p in shown if b'"speed_kmh":-0' in p], shown


def _statuses(rig: Rig, mark: int) -> list[Message]:
    return [m for m in rig.probe.messages[mark:] if m.topic == "rotor/status"]


def _speed(payload: bytes) -> object:
    return (json.loads(payload).get("wind") or {}).get("speed_kmh")
