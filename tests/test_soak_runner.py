"""The soak runner's own decisions (tests/soak/runner.py): which rotator it sends a target to.

Found on seed 920127337: a Rot2Prog power-cycled mid-turn forgets its target and has no power-on
byte to say so, so the bridge calls it `stalled` about 10 s later ("send the target again") and
R/state stays `stalled` until the next command. The soak sent nothing to a rotator in that state,
so it waited on it to the end of the run and failed it "not healthy at the end". A stalled
rotator takes the next target like an idle one (docs/mqtt.md, what the states mean), as a user
told so would send it; but a stall never replaces an open command unjudged, which would hide a
lost one. Here the bridge's view is what a real broker holds (retained, as the bridge leaves it),
the rotator a Rot2Prog emulator on a pty, and what is checked is what the runner publishes.
"""

from __future__ import annotations

import random
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.faults.conftest import start_emulator
from tests.soak.runner import Expectation, Monitor, Rot, Soak
from tests.support import Probe, wait_until
from tests.support.mosquitto import Mosquitto


class _Rolls(random.Random):
    """Every roll in the middle: a target, never a refusable command, never a re-target."""

    def random(self) -> float:
        return 0.5

    def getrandbits(self, k: int) -> int:  # (the bearings picked: still random ones)
        return super().getrandbits(k)


@pytest.fixture
def soak(tmp_path: Path, broker: Mosquitto) -> Iterator[Soak]:
    s = Soak(minutes=1, seed=0, workdir=tmp_path)
    s.rng = _Rolls()
    s.t_start = time.monotonic()
    emu = start_emulator("rot2prog", tmp_path / "tty-spid", start_az_deg=90.0, start_el_deg=10.0)
    s.rots["spid"] = Rot("spid", "rot2prog", emu, 10.0)
    s.monitor = Monitor(broker.port, s)
    try:
        yield s
    finally:
        s.monitor.close()
        emu.close()


def bridge_says(soak: Soak, probe: Probe, availability: str, state: str) -> None:
    """The bridge's retained view of the rotator, seen by the runner's monitor."""
    for topic, value in (
        ("rotor/bridge/state", "online"),
        ("rotor/spid/availability", availability),
        ("rotor/spid/state", state),
    ):
        assert probe.publish(topic, value, retain=True)
    wait_until(
        lambda: (
            soak.monitor.value("rotor/spid/availability") == availability.encode()
            and soak.monitor.value("rotor/spid/state") == state.encode()
        ),
        what="the runner's view",
    )


def targets(probe: Probe) -> list[str]:
    probe.caught_up()
    return [m.text for m in probe.on("rotor/spid/target")]


def test_a_stalled_rotator_is_sent_its_next_target(soak: Soak, broker: Mosquitto) -> None:
    probe = Probe(broker.port, "rotor/spid/target")
    try:
        bridge_says(soak, probe, "online", "stalled")
        soak.command(soak.rots["spid"], time.monotonic())
        msg = probe.wait_for("rotor/spid/target")
        e = soak.rots["spid"].expectation
        assert e is not None and e.payload == msg.text  # and it is owed an arrival
        assert e.az % 5 == 0  # an accepted one, not a refused command's poison value
    finally:
        probe.close()


def test_an_offline_rotator_is_sent_nothing(soak: Soak, broker: Mosquitto) -> None:
    probe = Probe(broker.port, "rotor/spid/target")
    try:
        bridge_says(soak, probe, "offline", "offline")
        soak.command(soak.rots["spid"], time.monotonic())
        assert targets(probe) == []
        assert soak.rots["spid"].expectation is None
    finally:
        probe.close()


def test_a_stall_does_not_replace_an_open_command(soak: Soak, broker: Mosquitto) -> None:
    """Judged by its deadline: lost, unless a serial fault interrupted it."""
    probe = Probe(broker.port, "rotor/spid/target")
    try:
        bridge_says(soak, probe, "online", "stalled")
        rot = soak.rots["spid"]
        now = time.monotonic()
        rot.expectation = Expectation(200.0, 10.0, now, now + 60.0, "200 10")
        for seed in range(20):  # whatever the rolls: a re-target would be taken at 0.15 or less
            soak.rng = random.Random(seed)
            soak.command(rot, time.monotonic())
        assert targets(probe) == []
        assert rot.expectation.outcome is None and rot.expectation.payload == "200 10"
    finally:
        probe.close()
