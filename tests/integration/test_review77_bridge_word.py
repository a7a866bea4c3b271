"""Review 77: a second bridge whose base topic is ``rotor/bridge``, beside a live bridge on
``rotor``: its one rotator's topics are the first bridge's own ``B/bridge/...``
(``rotor/bridge/info``: its ``R/info``; ``rotor/bridge/state``: its ``R/state``, the first
bridge's last will topic). claim.py rule 5 reads ``rotor/bridge/info`` there as another
bridge's rotator's info, and ``rotor/bridge/availability`` beside it (which no bridge
publishes) as "not online": the first bridge counts as gone, only a warning, and the second
runs; its ``R/info`` (with its instance) then lands on the first bridge's ``B/bridge/info``,
where claim rule 4 reads it as a second live bridge on ``rotor``."""

from __future__ import annotations

from pathlib import Path

from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.rig import Rig
from tests.support.waiting import slow


def test_a_bridge_on_another_bridges_bridge_topics_is_refused_and_ends_nothing(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    with Rig(tmp_path / "a", broker, probe) as a, Rig(tmp_path / "b", broker, probe) as b:
        a.add("tower", emu={"start_az_deg": 0, "jitter_deg": 0})
        a.add("yagi", emu={"start_az_deg": 0, "jitter_deg": 0})
        first = a.start()
        a.ready("tower")
        a.ready("yagi")
        b.base = "rotor/bridge"  # its one rotator's topics are A's rotor/bridge/...
        b.add("mast", emu={"start_az_deg": 200, "jitter_deg": 0})
        second = b.start()
        wait_until(
            lambda: second.failed.is_set() or b.status("mast").available or first.failed.is_set(),
            what="the second bridge to refuse or run",
        )
        if not second.failed.is_set():  # (it ran: whatever it does to A shows in a while)
            first.failed.wait(slow(5))  # a quiet period for A, not a deadline
        assert second.failed.is_set() and not first.failed.is_set(), (
            second.failure,
            first.failure,
        )
