"""Turning the antenna for the band, end to end: N1MM Logger+'s rotor messages on a real UDP
socket, through one running bridge (the App in-process) with a private mosquitto and two emulated
Rotor-EZ on real ptys, one the 20/15/10 m yagi's rotator and one the 40/80 m antenna's, both
answering to N1MM's one Rotor Description "Tower" (settings/bands.py, interfaces/loggers/commands.py
rule 5). The datagrams are the fact sheet's form (tests/support/udp_logger.py), the band in
``<freqband>`` as N1MM writes it (``14``, ``7``). Last, following WSJT-X with two radios: the
statuses of two WSJT-X instances on the bridge's WSJT-X port (tests/support/wsjtx.py).

What is asserted is what a user sees: the frames each controller received (the emulators' logs:
``AP1xxx<CR>`` is the Rotor-EZ's "store and go"), where each rotor really stands, the retained
R/status a new subscriber gets, and R/error. Absence is proven by order: after a message that
must move nothing, one that moves the same rotator; its frame is the first since.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from bridge.app import App
from bridge.emulators.base import LoggedFrame
from tests.integration.test_pointing_bridge import angle_between, locator_centre, reference_path
from tests.support import Probe, wait_until
from tests.support import wsjtx as w
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import retained_snapshot
from tests.support.ports import free_udp_port
from tests.support.rig import Rig
from tests.support.udp_logger import N1mmSender, n1mm_turn

HIGH, LOW = "high", "low"  # the 20/15/10 m yagi's rotator, the 40/80 m antenna's
TOWER = "Tower"  # N1MM's Rotor Description, the same for both antennas
BERLIN = locator_centre("JO62QM")  # the station
EMU = {"speed_deg_s": 90.0, "brake_delay_s": 0.5, "jitter_deg": 0, "start_az_deg": 10}
BRIDGE = {"brake_delay_s": 0.5, "settle_s": 0.3}


@dataclass
class Bench:
    rig: Rig
    n1mm: N1mmSender
    broker: Mosquitto
    wsjtx: tuple[str, int]  # WSJT-X's UDP port

    @property
    def probe(self) -> Probe:
        return self.rig.probe

    def moves(self, rid: str, since: float) -> list[bytes]:
        """The frames that moved or stopped ``rid``'s rotor since ``since`` (not the polls)."""
        log: list[LoggedFrame] = self.rig.emus[rid].log()
        return [
            f.data
            for f in log
            if f.time_s >= since and (f.data.startswith((b"AP", b"AM")) or f.data == b";")
        ]

    def settled_at(self, rid: str, az_deg: float, after: float) -> dict[str, Any]:
        """Wait until ``rid``'s rotor stands at ``az_deg`` and the bridge says so, idle."""
        self.rig.emus[rid].wait_for(
            lambda s: not s.is_moving and angle_between(s.az_deg, az_deg) <= 0.3, 15
        )

        def idle_there(m: Any) -> bool:
            doc = json.loads(m.payload)
            return doc["state"] == "idle" and angle_between(doc["bearing"], az_deg) <= 1

        topic = self.rig.topic(rid, "status")
        return dict(json.loads(self.probe.wait_for(topic, idle_there, 10, after).payload))

    def retained_bearing(self, rid: str) -> float:
        topic = self.rig.topic(rid, "status")
        retained = retained_snapshot(self.broker.port, topic)
        return float(json.loads(retained[topic])["bearing"])


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Bench]:
    tmp: Path = tmp_path_factory.mktemp("bands")
    with contextlib.ExitStack() as stack:
        broker = Mosquitto(tmp / "broker").start()
        stack.callback(broker.stop)
        probe = Probe(broker.port, "rotor/#")
        stack.callback(probe.close)
        rig = Rig(tmp, broker, probe)
        stack.callback(rig.close)
        port, wsjtx_port = free_udp_port(), free_udp_port()
        rig.sections = {
            "station": {"locator": "JO62QM"},
            "wsjtx": {"enabled": True, "port": wsjtx_port, "bind": "127.0.0.1"},
        }
        sender = N1mmSender(port)
        stack.callback(sender.close)
        for rid, bands in ((HIGH, ["20m", "15m", "10m"]), (LOW, ["40m", "80m"])):
            rig.add(
                rid,
                "rotorez",
                emu=EMU,
                n1mm_rotor_name=TOWER,
                n1mm_udp_port=port,
                bands=bands,
                **BRIDGE,
            )
        rig.app = App(rig.settings)
        rig.app.start()
        rig.ready(HIGH, 15)
        rig.ready(LOW, 15)
        yield Bench(rig, sender, broker, ("127.0.0.1", wsjtx_port))


def test_an_n1mm_message_for_20m_turns_the_20m_antenna_and_one_for_40m_the_other(
    bench: Bench,
) -> None:
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(TOWER, 120, freqband="14"))
    status = bench.settled_at(HIGH, 120, after=t)
    assert status["last_command_source"] == "n1mm"
    assert bench.moves(HIGH, t) == [b"AP1120\r"] and bench.moves(LOW, t) == []
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(TOWER, 250, freqband="7"))
    bench.settled_at(LOW, 250, after=t)
    assert bench.moves(LOW, t) == [b"AP1250\r"] and bench.moves(HIGH, t) == []
    assert bench.rig.emus[HIGH].state().az_deg == 120 and bench.rig.emus[LOW].state().az_deg == 250
    assert bench.retained_bearing(HIGH) == pytest.approx(120, abs=1)  # what a new client sees
    assert bench.retained_bearing(LOW) == pytest.approx(250, abs=1)


def test_a_band_nobody_has_moves_nothing_and_both_rotators_say_so(bench: Bench) -> None:
    high, low = (bench.rig.emus[r].state().az_deg for r in (HIGH, LOW))
    t = time.monotonic()
    bench.n1mm.send(n1mm_turn(TOWER, far(high), freqband="1.8"))  # 160 m: nobody's
    for rid in (HIGH, LOW):
        error = bench.probe.wait_for(bench.rig.topic(rid, "error"), lambda m: True, 10, t)
        doc = json.loads(error.payload)
        assert "no rotator is for 160m (high: 20m, 15m, 10m; low: 40m, 80m)" in doc["message"]
    # proof by order: the next message for each moves it, and its frame is the first since
    for rid, was, freqband in ((HIGH, high, "21.0"), (LOW, low, "3.5")):
        target = far(was)
        bench.n1mm.send(n1mm_turn(TOWER, target, freqband=freqband))
        bench.settled_at(rid, target, after=t)
        assert bench.moves(rid, t) == [f"AP1{target:03d}\r".encode()], rid


def far(az_deg: float) -> int:
    """A bearing well away from ``az_deg`` (a real move)."""
    return 330 if az_deg < 180 else 30


def test_a_name_only_one_rotator_answers_to_is_unchanged_by_bands(bench: Bench) -> None:
    """A datagram for another Rotor Description is not ours: nothing moves, nothing is said."""
    t = time.monotonic()
    before = len(bench.probe.on(bench.rig.topic(HIGH, "error")))
    bench.n1mm.send(n1mm_turn("Elsewhere", 200, freqband="14"))
    bench.n1mm.send(n1mm_turn(TOWER, far(bench.rig.emus[HIGH].state().az_deg), freqband="28.0"))
    wait_until(lambda: bench.moves(HIGH, t), 10, "the second datagram obeyed")
    assert len(bench.moves(HIGH, t)) == 1 and bench.moves(LOW, t) == []
    assert len(bench.probe.on(bench.rig.topic(HIGH, "error"))) == before


def test_with_two_radios_each_antenna_follows_the_wsjtx_on_its_band(bench: Bench) -> None:
    """SO2R: one WSJT-X per radio (``--rig-name``), rig1 on 20 m, rig2 on 40 m, both on the
    bridge's WSJT-X port, following on for both rotators: each antenna turns to the partner of
    the radio on its band (the 40 m antenna took rig1's program, heard first, and ignored
    rig2's for as long as it followed: session/follow.py rule 8)."""
    rig1 = w.StatusFields(
        dx_call="JA1ABC", dx_grid="PM95VQ", instance="WSJT-X - rig1", dial_hz=14_074_000
    )
    rig2 = w.StatusFields(
        dx_call="W1AW", dx_grid="FN31PR", instance="WSJT-X - rig2", dial_hz=7_074_000
    )
    for rid in (HIGH, LOW):
        bench.probe.publish(bench.rig.topic(rid, "follow"), "wsjtx")
        bench.probe.wait_value(bench.rig.topic(rid, "follow/state"), "wsjtx", 10)
    t = time.monotonic()
    for _ in range(3):  # every decoding period, rig1 first
        w.send(w.status(rig1), bench.wsjtx)
        w.send(w.status(rig2), bench.wsjtx)
    tokyo, new_york = (reference_path(BERLIN, locator_centre(g))[0] for g in ("PM95VQ", "FN31PR"))
    bench.settled_at(HIGH, round(tokyo), after=t)
    bench.settled_at(LOW, round(new_york), after=t)
    for rid in (HIGH, LOW):
        bench.probe.publish(bench.rig.topic(rid, "follow"), "off")
        bench.probe.wait_value(bench.rig.topic(rid, "follow/state"), "off", 10)


def test_when_the_two_radios_swap_bands_each_antenna_follows_the_one_come_to_it(
    bench: Bench,
) -> None:
    """SO2R, rig1 on 20 m and rig2 on 40 m, each antenna following the WSJT-X on its band; then
    the radios swap bands. Each antenna follows the program now on its band (each kept the one
    it followed, gone to the other band, and neither turned again: session/follow.py rule 8)."""
    before = {
        "rig1": w.StatusFields(
            dx_call="PY2ABC", dx_grid="GG66QK", instance="WSJT-X - rig1", dial_hz=14_074_000
        ),
        "rig2": w.StatusFields(
            dx_call="VK2XYZ", dx_grid="QF56OD", instance="WSJT-X - rig2", dial_hz=7_074_000
        ),
    }
    after = {
        "rig1": w.StatusFields(
            dx_call="JA1ABC", dx_grid="PM95VQ", instance="WSJT-X - rig1", dial_hz=7_074_000
        ),
        "rig2": w.StatusFields(
            dx_call="W1AW", dx_grid="FN31PR", instance="WSJT-X - rig2", dial_hz=14_074_000
        ),
    }
    for rid in (HIGH, LOW):
        bench.probe.publish(bench.rig.topic(rid, "follow"), "wsjtx")
        bench.probe.wait_value(bench.rig.topic(rid, "follow/state"), "wsjtx", 10)
    way = {
        g: round(reference_path(BERLIN, locator_centre(g))[0])
        for g in ("GG66QK", "QF56OD", "PM95VQ", "FN31PR")
    }
    t = time.monotonic()
    for _ in range(3):
        for rig in ("rig1", "rig2"):
            w.send(w.status(before[rig]), bench.wsjtx)
    bench.settled_at(HIGH, way["GG66QK"], after=t)
    bench.settled_at(LOW, way["QF56OD"], after=t)
    t = time.monotonic()
    for _ in range(3):  # every decoding period, after the swap
        for rig in ("rig1", "rig2"):
            w.send(w.status(after[rig]), bench.wsjtx)
    bench.settled_at(HIGH, way["FN31PR"], after=t)  # rig2's partner, now on 20 m
    bench.settled_at(LOW, way["PM95VQ"], after=t)  # rig1's, now on 40 m
    for rid in (HIGH, LOW):
        bench.probe.publish(bench.rig.topic(rid, "follow"), "off")
        bench.probe.wait_value(bench.rig.topic(rid, "follow/state"), "off", 10)
