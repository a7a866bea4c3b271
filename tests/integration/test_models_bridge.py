"""The end-to-end checks every controller model passes alike: real mosquitto, real pyserial on
a pty, the bridge, and the model's emulator (written from the documents and judged by Hamlib's
rotctl). Each model is a row of data (MODELS): what it starts at, what to send it, where it
must end up, and the frame its emulator logs for a stop. What is special to a model (its
frames, its replies, its faults) stays in its own test_<family>_bridge.py."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import pytest

from tests.support.rig import Rig
from tests.support.waiting import wait_until


@dataclass(frozen=True)
class Model:
    model: str
    start: tuple[float, float | None]  # azimuth, elevation (None: an azimuth rotor)
    to: tuple[float, float | None]  # a target it reaches after a replug
    stop_frame: bytes  # the stop as its emulator logs it
    emu: dict[str, Any] = field(default_factory=dict)  # the variant's options

    def options(self) -> dict[str, Any]:
        az, el = self.start
        return {"start_az_deg": az, **({} if el is None else {"start_el_deg": el}), **self.emu}

    def payload(self, az: float, el: float | None) -> str:
        return f"{az:g}" if self.start[1] is None else f"{az:g} {el:g}"


MODELS = {
    "gs232a": Model("gs232a", (33, 3), (40, 10), b"S"),
    "gs232b": Model("gs232b", (50, 5), (40, 10), b"S"),
    "easycomm2": Model("easycomm2", (50, 5), (40, 10), b"SA"),
    "easycomm3": Model("easycomm3", (33, 3), (40, 10), b"SA"),
    "rt21": Model("rt21", (33.3, None), (40.2, None), b";"),
    "rot2prog": Model("rot2prog", (33, 3), (40, 10), b"\x57" + bytes(10) + b"\x0f\x20"),
    "rc2800": Model("rc2800", (33.3, 3), (40.2, 10), b"S"),
    "rc2800 echo+stream": Model(
        "rc2800", (33.3, 3), (40.2, 10), b"S", {"echo": True, "stream_s": 0.25}
    ),
    "rc2800-az": Model("rc2800-az", (33.3, None), (40.2, None), b"S", {"echo": True}),
}


def ready(rig: Rig, m: Model) -> Any:
    emu = rig.add("rotor", model=m.model, emu=m.options(), az_max_deg=300)
    rig.start()
    rig.probe.wait_value("rotor/availability", "online", timeout_s=15)
    rig.probe.wait_value("rotor/state", "idle", timeout_s=15)
    return emu


@pytest.mark.parametrize(
    "m",
    [MODELS[k] for k in ("gs232a", "easycomm3", "rt21", "rot2prog", "rc2800", "rc2800-az")]
    + [MODELS["rc2800 echo+stream"]],
    ids=["gs232a", "easycomm3", "rt21", "rot2prog", "rc2800", "rc2800-az", "rc2800-echo-stream"],
)
def test_offline_on_unplug_and_back_on_replug(rig: Rig, m: Model) -> None:
    ready(rig, m)
    rig.unplug_and_replug("rotor")
    rig.probe.publish("rotor/target", m.payload(*m.to))
    rig.arrived("rotor", *m.to, timeout_s=15)


@pytest.mark.parametrize(
    "m",
    [MODELS[k] for k in ("gs232b", "easycomm2", "rt21", "rc2800", "rc2800-az")],
    ids=["gs232b", "easycomm2", "rt21", "rc2800", "rc2800-az"],
)
def test_lock_and_limits_refuse_and_send_nothing_but_a_stop_still_goes(rig: Rig, m: Model) -> None:
    emu = ready(rig, m)
    refusals = [(m.payload(310, 10), "azimuth 310 outside")]
    if m.start[1] is None:
        refusals.append(("100 20", "no elevation"))  # an elevation it cannot do
    else:
        refusals.append(("100 181", "elevation 181 outside"))
    for payload, why in refusals:
        assert why in rig.refused("rotor", payload)
    rig.probe.publish("rotor/lock", "ON")
    rig.probe.wait_value("rotor/lock/state", "ON")
    assert "locked" in rig.refused("rotor", m.payload(120, 10))
    rig.probe.publish("rotor/stop", "STOP")  # never refused: on the wire even when locked
    emu.wait_for_frame(m.stop_frame, "stop", 10)
    assert emu.frames("move") == [] and emu.state().az_deg == m.start[0]


def test_a_controller_swapped_leaves_none_of_the_old_model_s_topics_retained(rig: Rig) -> None:
    """interfaces/mqtt/stale.py rule 5, a review: a user who swapped controllers (a Rot2Prog
    for a Rotor-EZ, a Rotor-EZ for a DCU-1) kept the old model's ``R/elevation``,
    ``R/version``, ``R/bearing`` and option states retained for ever, read by Node-RED flows and
    Home Assistant automations as the rotator's. The next start deletes them, and nothing the
    new models publish."""
    rig.add("dish", model="rot2prog", emu={"start_el_deg": 12})
    rig.add("mast", model="rotorez", emu={"version": "9.9"})
    rig.start()
    rig.ready("dish")
    rig.ready("mast")
    rig.probe.publish("rotor/mast/option/jam", "ON")
    rig.probe.wait_value("rotor/mast/option/jam/state", "ON")
    rig.probe.wait_value("rotor/mast/version", "9.9")
    old = {"rotor/dish/elevation", "rotor/mast/version", "rotor/mast/bearing"}
    old.add("rotor/mast/option/jam/state")
    assert old <= set(rig.retained())
    rig.stop()

    rig.rotators, rig.lines = [], {}  # the same rotators, each on another controller
    rig.add("dish", model="rotorez", emu={"version": "1.4S"})
    rig.add("mast", model="dcu1")
    t = rig.probe.caught_up()  # (the old models' last readings may come after a clock read)
    rig.start()
    rig.ready("dish", after=t)
    rig.ready("mast", after=t)
    rig.probe.wait_value("rotor/dish/version", "1.4S", after=t)
    wait_until(
        lambda: not old & set(rig.retained()),
        timeout_s=10,
        what="the old models' elevation, version, bearing and option state deleted",
    )
    rig.refused("dish", "north")  # (its error goes out after the deletions: they have come)
    for topic in old:  # each deleted once (an option state reads through two filters)
        assert [m.payload for m in rig.probe.on(topic) if m.t >= t] == [b""], topic
    left = rig.retained()
    assert left["rotor/dish/version"] == b"1.4S" and "rotor/dish/bearing" in left
    assert (left["rotor/mast/availability"], left["rotor/mast/state"]) == (b"online", b"unknown")
    assert json.loads(left["rotor/mast/info"])["model"] == "dcu1"


@pytest.mark.parametrize("protocol", ["5", "3.1.1"])
def test_one_rotator_on_the_base_topic_swapped_leaves_none_of_the_old_model_s_topics(
    rig: Rig, protocol: str
) -> None:
    """The same with one rotator, whose topics are the base topic's: its option states and
    availability are read through the owned-topic watch alone (client.py ``_filters``: a
    filter is subscribed once), and the old model's option state, version and bearing still go."""
    rig.add("mast", model="rotorez", emu={"version": "9.9"})
    rig.mqtt_extra["protocol"] = protocol
    rig.start()
    rig.ready("mast")
    rig.probe.publish("rotor/option/jam", "ON")
    rig.probe.wait_value("rotor/option/jam/state", "ON")
    rig.probe.wait_value("rotor/version", "9.9")
    old = {"rotor/option/jam/state", "rotor/version", "rotor/bearing"}
    assert old <= set(rig.retained())
    rig.stop()

    rig.rotators, rig.lines = [], {}
    rig.add("mast", model="dcu1")
    t = rig.probe.caught_up()
    rig.start()
    rig.ready("mast", after=t)
    wait_until(
        lambda: not old & set(rig.retained()),
        timeout_s=10,
        what="the old model's option state, version and bearing deleted",
    )
