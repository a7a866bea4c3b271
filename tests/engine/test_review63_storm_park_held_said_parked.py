"""Review 63: a storm's park waiting under a STOP's hold is shown "Parked for the storm".

96431b35 and 9edee2df settled where a park that waits under the hold of a STOP sent just
before the storm (session.py rule 13, wind.py rule 8) goes; meanwhile it is owed and not sent,
as a park waiting for the lock OFF is. No clock ends such a hold (the stop express's hold lasts
until its word comes back; docs/architecture.md: a long one is only said on B/bridge/info).
For the lock OFF, R/status says ``waiting: true`` and Home Assistant's "Parked for the storm"
is off (docs/wind.md); under the hold R/status says ``waiting: false`` and Home Assistant's
"Parked for the storm" is ON, for as long as the hold lasts, while the rotor faces the storm
where it stood.

A Rotor-EZ at 90, its storm park at 180; the stop lane's STOP and its hold stood in for by
what it puts in the mailbox, as test_attack14_storm_park_dropped_by_a_clearing_release does.
Home Assistant's template rendered as tests/test_homeassistant.py renders them. In virtual
time."""

from __future__ import annotations

import json
from types import SimpleNamespace

from bridge.core.model import MotionState, Source, Stop
from bridge.features.wind import _storm, wind_json
from tests.engine.virtual import VirtualRotator
from tests.test_homeassistant import render

WIND = {"wind_topic": "weather/wind", "wind_park_above": 60, "park_az_deg": 180}
MARKER = 1
HELD_S = 60.0  # virtual: the hold's marker (or the express's word) not back yet


def ha_parked(v: VirtualRotator) -> str:
    assert v.status.wind is not None
    template = str(_storm(SimpleNamespace(topics=SimpleNamespace(status="rotor/status")))[
        "value_template"
    ])  # fmt: skip
    return render(template, json.dumps({"wind": wind_json(v.status.wind)}))


def test_a_storm_park_waiting_under_a_hold_is_not_shown_parked() -> None:
    with VirtualRotator("rotorez", settings=WIND) as v:
        v.run_until(lambda h: h.status.available, 10, "the controller answers")
        v.target(90.0)
        v.run_until(
            lambda h: abs(h.truth().az_deg - 90.0) < 2.0 and h.state is MotionState.IDLE,
            120,
            "at rest at 90",
        )
        v.mailbox.put(Stop(Source.MQTT), hold=MARKER)  # the operator's STOP, on the lane
        v._take()
        v.mailbox.put_wind(90.0)  # the storm's first reading: its park waits for the hold
        v._take()
        v.run_for(HELD_S)
        assert abs(v.truth().az_deg - 90.0) < 2.0  # nothing moved: the park waits
        wind = v.status.wind
        assert wind is not None and wind.storm
        assert (ha_parked(v), wind.waiting) == ("OFF", True)
