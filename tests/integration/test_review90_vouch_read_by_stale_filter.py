"""Review 90: claim.py rule 5's vouch reads (``vouch_reads``: the bridge info and state on the
base topic a not-online, unstopped stamp names) are subscribed after the first hello only when
no other filter of the bridge reads them (client.py ``_reads_only``), and the look keeps what
arrives on them only once its hello is back (look.py ``saw``: ``reads`` is set then). A stamp
naming a base topic one level under the looking bridge's (``rotor/shack`` under ``rotor``) has
its ``rotor/shack/bridge/state`` read by stale.py's filter ``rotor/+/bridge/state``: the
broker sends its retained ``online`` before the first hello, when the look does not keep it,
and never again, as the topic is not subscribed anew. So live bridge A on ``rotor/shack``,
whose tower has ``topic = "rotor/tower"`` and its controller off, is taken for gone by a
bridge started on ``rotor`` with a rotator ``tower``, which runs: once the controller is
switched on, one target on ``rotor/tower/target`` turns both rotors."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe, slow, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig


def test_a_live_bridge_nested_one_level_under_the_looking_bridge_vouches_for_its_rotator(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.base = "rotor/shack"  # bridge A, its tower's topic of its own rotor/tower
        tower = a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0}, topic="rotor/tower")
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        tower.set_silent(True)  # the tower's controller switched off
        first = a.start()
        a.ready("yagi")
        probe.wait_value("rotor/tower/availability", "offline")
        probe.wait_value("rotor/shack/bridge/state", "online")
        b.base = "rotor"  # bridge B: its rotator tower's topics are rotor/tower, A's tower's
        mast = b.add("tower", emu={"start_az_deg": 200, "jitter_deg": 0})
        b.add("dish", emu={"start_az_deg": 0, "jitter_deg": 0})  # (two: each on its own root)
        second = b.start()
        if not second.failed.is_set():  # refused at once is the fix; started, its rotator answers
            wait_until(
                lambda: b.status("tower").available or second.failed.is_set(),
                what="the second bridge's rotator to answer",
            )
        t = probe.caught_up()
        tower.set_silent(False)  # switched on: the live bridge's tower answers
        probe.wait_for("rotor/tower/status", lambda m: b'"bearing":0.0' in m.payload, after=t)
        probe.publish("rotor/tower/target", "90")
        tower.wait_for(lambda s: abs(s.az_deg - 90) <= 3 and not s.is_moving, slow(15))
        after = mast.state()
        assert (after.az_deg, after.is_moving) == (200, False), after
        assert second.failed.is_set() and not first.failed.is_set()
