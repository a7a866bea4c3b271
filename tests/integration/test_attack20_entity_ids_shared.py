"""Attack 20: two rotators whose entities ask Home Assistant for one entity id. homeassistant/
rule 8 gives ``sat``'s tracked elevation and ``sat_track``'s elevation two unique ids (they
were one, and Home Assistant dropped the second entity), but both configs still ask for the
entity id ``sensor.sat_track_elevation`` (``default_entity_id``). Home Assistant gives it to
whichever config it meets first and ``_2`` to the other, so a card written from
docs/homeassistant.md's table (``sensor.<id>_elevation`` for ``sat_track``) shows the other
antenna's tracked elevation: the settings refuse two rotator ids that ask for one entity id
for that reason ("dashboards pointed at the other antenna"), and this pair gets through. Real
mosquitto, two MD-01 emulators on real ptys; asserted: the retained discovery configs."""

from __future__ import annotations

import json
from collections import Counter

from bridge.app import App
from bridge.settings.pointing import StationSettings
from tests.support.mqtt import retained_snapshot
from tests.support.rig import Rig
from tests.support.waiting import wait_until

PREFIX = "homeassistant"


def test_no_two_entities_ask_home_assistant_for_one_entity_id(rig: Rig) -> None:
    rig.add("sat", model="md01")
    rig.add("sat_track", model="md01")
    station = StationSettings(latitude_deg=52.5, longitude_deg=13.4)
    rig.app = App(rig.settings.model_copy(update={"station": station}))
    rig.app.start()
    rig.ready("sat")
    rig.ready("sat_track")
    node = f"{PREFIX}/sensor/rotorbridge_rotor_r_{{}}/{{}}/config"
    both = (node.format("sat", "track_elevation"), node.format("sat_track", "elevation"))

    def configs() -> dict[str, bytes] | None:  # (the two entities' configs on the broker)
        snap = retained_snapshot(rig.broker.port, f"{PREFIX}/#")
        return snap if all(snap.get(topic) for topic in both) else None

    snap = wait_until(configs, what="both rotators' discovery configs")
    asked = Counter(
        json.loads(payload)["default_entity_id"]
        for topic, payload in snap.items()
        if topic.endswith("/config") and payload
    )
    assert asked["sensor.sat_track_elevation"] <= 1, "two configs ask for one entity id"
    assert [e for e, n in asked.items() if n > 1] == []
