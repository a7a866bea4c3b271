"""Review 67 (claim rule 5): attack 18 is still open beside a running bridge of the version
before rule 5. Its ``B/bridge/info`` names no ``topics``, and rule 5 counts such an info as its
base topic alone: a new bridge on ``rotor/tower`` reads ``rotor/bridge/info`` (the station's,
``online``), finds ``tower`` is no name a bridge uses under a root (as review 93's ``site2``), and
starts on the station's rotator ``tower``, whose retained ``rotor/tower/availability``,
``state`` and ``bearing`` the station holds right there. A target on ``rotor/tower/target`` then
turns both rotors. That is the layout rule 5 was made for, in the order it happens on the air: a
second host freshly installed (the new version) beside a station not yet upgraded; and the
running station, being of the old version, says nothing either.

The station of the old version is this version's bridge whose info leaves ``topics`` out, as
the old one's did (docs/mqtt.md's table before rule 5: instance, host, pid, started, problems)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bridge.interfaces.mqtt.claim import Instance
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_bridge_on_an_old_stations_rotator_topic_never_turns_on_its_targets(
    tmp_path: Path, broker: Mosquitto, probe: Probe, monkeypatch: pytest.MonkeyPatch
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        old_id = a.settings.mqtt.effective_client_id()
        new_info = Instance.info

        def info(self: Instance, problems: list[str]) -> str:
            if self.id != old_id:
                return new_info(self, problems)
            doc = json.loads(new_info(self, problems))
            del doc["topics"]  # the station's version says no topics
            return json.dumps(doc, separators=(",", ":"))

        monkeypatch.setattr(Instance, "info", info)
        a.start()
        a.ready("tower")
        held = probe.wait_for("rotor/bridge/info", lambda m: b"problems" in m.payload, 10)
        assert b"topics" not in held.payload
        b.base = "rotor/tower"  # the second bridge's own topics are the station's tower's
        mast = b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        app = b.start()
        if not app.failed.is_set():  # refused at once is a fix; started, its rotator answers
            wait_until(
                lambda: b.status("mast").available or app.failed.is_set(),
                what="the second bridge's rotator to answer",
            )
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, 15)
        after = mast.state()
        assert (after.az_deg, after.is_moving) == (200, False), after
