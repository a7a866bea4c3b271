"""Huge messages on a broker anyone may publish to (client.py rule 18): the bridge as a service
process, a 100 MB payload published on its command topics. What a user notices: the memory
the bridge takes for it.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig

HUGE = 100_000_000


def _peak_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    raise AssertionError(f"no VmHWM for {pid}")


def _children(pid: int) -> list[int]:
    found = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    return [int(p) for p in found]


def test_a_huge_message_on_a_command_topic_is_not_read_by_the_bridge(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """DEFECT (medium, an attack pass): a 100 MB payload on ``R/target`` and ``R/stop`` was read
    whole by the main connection, the stop lane and the stop express: each process's memory
    went up by two or three times the payload, and kept much of it (a few of those would
    leave a Raspberry Pi to its out-of-memory killer). Now the broker is told in CONNECT not
    to send them: the processes' peak memory stays where it was."""
    with Rig(tmp_path, broker, probe) as rig:
        rig.add("hf", "gs232b")
        bridge = rig.start_process(log_level="INFO")
        rig.ready("hf")
        assert bridge.proc is not None
        pids = [bridge.proc.pid, *_children(bridge.proc.pid)]
        before = {pid: _peak_kb(pid) for pid in pids}
        for leaf in ("target", "stop"):
            probe.publish(rig.t(leaf), b"7" * HUGE)
        t = time.monotonic()
        probe.publish(rig.t("target"), "north")  # after them, in order: its refusal says
        err = json.loads(probe.wait_for(rig.t("error"), after=t).payload)  # they were read
        assert "north" in err["message"] or "north" in json.dumps(err), err
        grown = {pid: _peak_kb(pid) - before[pid] for pid in pids}
    assert all(kb < HUGE // 1000 // 4 for kb in grown.values()), (grown, bridge.log()[-2000:])
