"""Review 67 (claim rule 5): a bridge that yields to an older overlapping bridge while running
stops its rotors and exits 1, but, as rule 4's yield (where the state topic is the other
bridge's), it sends no ``offline`` and disconnects cleanly (no will): its own
``B/bridge/state`` stays retained ``online`` with its info naming its rotator topics. Under rule
5 that state topic is its own, not the other's: the leftover says a live bridge for ever. The
older bridge's next start (an upgrade, a reboot) reads it at its first look and refuses (code 2,
which systemd does not restart), though the younger one is long gone."""

from __future__ import annotations

from pathlib import Path

from bridge.interfaces.mqtt.claim import Instance
from tests.support import Probe, retained_snapshot, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_the_older_bridge_starts_again_after_the_younger_one_yielded(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
        a.add("yagi")
        young = a.start()
        a.ready("tower")
        # the older bridge on rotor/tower (met at once: stood in for by its info and state)
        b.base = "rotor/tower"
        b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        older_id = b.settings.mqtt.effective_client_id()
        older = Instance(older_id, "elsewhere", 8, young.me.started_unix - 60, ("rotor/tower",))
        probe.publish("rotor/tower/bridge/info", older.info([]), retain=True)
        probe.publish("rotor/tower/bridge/state", "online", retain=True)
        wait_until(young.failed.is_set, 10, "the younger bridge yields")
        assert young.client.yielded
        a.stop()  # its process exits (code 1)
        # the older one is restarted (its clean stop said offline; it starts again)
        probe.publish("rotor/tower/bridge/state", "offline", retain=True)
        app = b.start()

        def said_online() -> bool:  # its look passed: it says its own state
            held = retained_snapshot(broker.port, "rotor/tower/bridge/state")
            return held.get("rotor/tower/bridge/state") == b"online"

        wait_until(
            lambda: app.failed.is_set() or said_online(),
            15,
            "the older bridge to run again, or to refuse",
        )
        held = retained_snapshot(broker.port, "rotor/bridge/state").get("rotor/bridge/state")
        assert not app.failed.is_set(), (app.failure, held)
