"""Attack 12: ``stall_timeout_s`` is held to "longer than it takes a reading to show the rotor
turning" (settings/rotator.py rule 2: two moving polls and noise_deg at the azimuth's speed),
and the elevation is left out. A GS-232B's azimuth at 6 degrees a second shows a turn within
0.73 s, so stall_timeout_s = 1 is taken; its elevation, at the model's 2.5 degrees a second,
needs two polls and 2 degrees of noise, 1.2 s. Every elevation turn is then called stalled
("rotor stalled at 150° (no progress for 1 s): brake paddle pressed, rotor stuck ...") and
stopped short of its target (the antenna left at 12.5 for 20). So, slower, with
el_speed_deg_s = 0.5 and stall_timeout_s = 3. The value must be refused naming the key, or the
elevation's turn must reach its target. In virtual time on an emulated GS-232B."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from bridge.core.model import Target
from bridge.settings import ConfigError, settings_from
from tests.engine.virtual import VirtualRotator


@pytest.mark.parametrize(
    ("settings", "emulator"),
    [
        ({"stall_timeout_s": 1.0}, {}),
        ({"stall_timeout_s": 3.0, "el_speed_deg_s": 0.5}, {"el_speed_deg_s": 0.5}),
    ],
)
def test_a_stall_timeout_an_elevation_turn_cannot_meet_is_refused_or_never_stalls_it(
    rig: Callable[..., VirtualRotator], settings: dict[str, Any], emulator: dict[str, Any]
) -> None:
    try:
        rotator = {"id": "t", "model": "gs232b", "port": "/dev/ttyUSB0", **settings}
        settings_from({"rotators": [rotator]}, {})
    except ConfigError as refused:
        assert "stall_timeout_s" in str(refused)  # said, naming the key: nothing to run
        return
    v = rig(
        "gs232b",
        settings=settings,
        emulator={"start_az_deg": 150.0, "start_el_deg": 10.0, **emulator},
    )
    v.run_until(lambda r: r.statuses and r.status.available, 30, "online")
    v.run_for(3)
    t = v.now
    v.aim(Target(150.0, 20.0))  # the elevation alone turns
    v.run_for(60)
    assert [e.message for e in v.errors(since=t)] == []
    assert abs(v.truth().el_deg - 20.0) <= 1.0, v.truth()
