"""What anyone may publish on an ACL-less broker, aimed at resources: huge messages (client.py
rule 18) and a backlog of retained topics planted under the base topic (owned.py rule 10),
against the bridge as a service process. What a user notices: the memory the bridge takes for
a huge message; what its log says at start behind a backlog.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import paho.mqtt.client as paho

from tests.support import wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Probe
from tests.support.rig import Rig
from tests.support.waiting import slow

HUGE = 100_000_000
PLANTED = 40_000  # retained topics planted under the base topic


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
        for leaf in ("target", "stop"):  # read by the broker before the clock below starts
            # (a busy machine's probe took 33 s to write one: the wait for the refusal ran out
            # while the second was still on its way, the refusal queued behind it)
            assert probe.publish(rig.t(leaf), b"7" * HUGE, timeout_s=60), f"{leaf}: no PUBACK"
        t = time.monotonic()
        probe.publish(rig.t("target"), "north")  # after them, in order: its refusal says
        # they were read; the refusal, not the first error after them: the emulator answers on
        # a thread of this process while the probe writes 200 MB, and on a busy machine a poll
        # went unanswered ("stopped answering") before the refusal came
        probe.wait_for(rig.t("error"), lambda m: b"north" in m.payload, after=t)
        grown = {pid: _peak_kb(pid) - before[pid] for pid in pids}
    assert all(kb < HUGE // 1000 // 4 for kb in grown.values()), (grown, bridge.log()[-2000:])


def test_a_backlog_of_planted_retained_topics_does_not_make_the_last_runs_offline_a_stranger(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """DEFECT (low, an attack pass; owned.py rule 10): with tens of thousands of retained
    topics planted under the base topic (``B/<junk>/availability``, anyone may publish them),
    the broker took more than a second to hand the bridge what it held, and the bridge's own
    ``offline`` of its last run, among them, was said as another client's ("a second bridge on
    this base topic?") on every start. Now nothing the broker held before the first look ended
    is news."""
    with Rig(tmp_path, broker, probe) as rig:
        rig.add("hf", "gs232b")
        rig.start_process(log_level="INFO")
        rig.ready("hf")
        rig.stop()  # its offline values stay retained
        planter = paho.Client(paho.CallbackAPIVersion.VERSION2, client_id="planter")
        planter.connect("127.0.0.1", broker.port)
        planter.loop_start()
        try:
            last = None
            for i in range(PLANTED):
                last = planter.publish(f"{rig.base}/junk{i}/availability", "online", retain=True)
            assert last is not None
            last.wait_for_publish(slow(30))
        finally:
            planter.loop_stop()
            planter.disconnect()
        bridge = rig.start_process(log_level="INFO")
        rig.ready("hf", timeout_s=slow(30))
        wait_until(lambda: "retained topic(s)" in bridge.log(), 30, "the first look to end")
        log = bridge.log()
    assert "another client published" not in log, log[-3000:]


def test_an_option_topic_of_60000_characters_is_refused_in_a_short_error(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """DEFECT (low, an attack pass): ``R/option/<60,000 characters>`` (a topic level the
    bridge subscribes to with ``option/+``) was refused with the whole name twice on
    ``R/error`` (the message and the command: 120 KB for each publish, to every dashboard and
    in the audit trail), and a group's ``G/option/<...>`` with it once for each member. Now the
    name is cut short where it is echoed."""
    with Rig(tmp_path, broker, probe) as rig:
        rig.add("hf", "gs232b")
        rig.add("vhf", "gs232b")
        rig.sections["groups"] = [{"id": "stack", "rotators": ["hf", "vhf"]}]
        rig.start()
        rig.ready("hf")
        name = "x" * 60_000
        for root in ("hf", "stack"):
            t = time.monotonic()
            probe.publish(f"rotor/{root}/option/{name}", "2")
            said = probe.wait_for(f"rotor/{root}/error", after=t)
            err = json.loads(said.payload)
            assert len(said.payload) < 2000, (len(said.payload), err["message"][:200])
            assert err["command"].startswith("option xxx") and err["command"].endswith("… '2'")
            if root == "hf":
                assert err["message"].startswith("GS-232B has no option 'xxx"), err["message"]
                assert "(60000 chars) (options: speed)" in err["message"], err["message"]
            else:
                assert err["message"].startswith("group stack takes a target and a stop only")
