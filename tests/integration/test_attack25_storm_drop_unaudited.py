"""Attack 25: a target a storm drops before it went out stays "executed" in the audit trail.

A Rotor-EZ takes a new bearing only at rest: an operator's second target, sent mid-turn, waits
out the brake delay after the stop it needed. A storm reading that comes meanwhile drops it
(session/wind.py rule 1, session.py ``_storm``): R/error says "target dropped: wind ...",
and the rotor never turns to it. The same drop for a lease (session.py rule 23)
is "said and audited": the audit line refuses the sender's command. The storm's is only said:
the audit file keeps ``target '300'`` ``executed`` and nothing after it, so the trail says the
operator sent the rotor to 300 and it was done, while it never turned there.

Real mosquitto, the Rotor-EZ emulator on a pty through pyserial, the App in-process.
"""

from __future__ import annotations

import json

from tests.support import wait_until
from tests.support.rig import Rig
from tests.support.waiting import slow

TOPIC = "weather/station/wind"
BRAKE_S = 3.0  # the brake delay the second target waits out: the storm comes in it


def _lines(rig: Rig) -> list[dict[str, object]]:
    assert rig.app is not None
    rig.app.audit.flush()
    path = rig.tmp / "audit.jsonl"
    return [json.loads(x) for x in path.read_text().splitlines()] if path.exists() else []


def test_a_target_the_storm_drops_is_refused_in_the_audit_trail(rig: Rig) -> None:
    rig.sections["audit_file"] = str(rig.tmp / "audit.jsonl")
    emu = rig.add(
        "tower",
        emu={"start_az_deg": 100, "brake_delay_s": BRAKE_S, "jitter_deg": 0},
        brake_delay_s=BRAKE_S,
        settle_s=0.3,
        park_az_deg=0,
        wind_topic=TOPIC,
        wind_park_above=60,
    )
    rig.start()
    rig.ready("tower")
    rig.probe.publish("rotor/target", "200")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 105, 10)  # turning to 200
    stops = len([f for f in emu.frames() if f.data == b";"])
    rig.probe.publish("rotor/target", "300")  # mid-turn: a stop, then 300 waits for the brake
    wait_until(
        lambda: len([f for f in emu.frames() if f.data == b";"]) > stops,
        slow(5),
        "the stop the new target needs",
    )
    mark = rig.probe.mark()
    rig.probe.publish(TOPIC, "100")  # a storm, inside the brake delay
    said = rig.probe.wait(
        lambda m: (
            m.topic == "rotor/error"
            and json.loads(m.payload)["message"].startswith("target dropped: wind")
        ),
        10,
        "the drop on R/error",
        mark,
    )
    assert json.loads(said.payload)["command"] == "target az 300"
    assert b"AP1300\r" not in [f.data for f in emu.frames()]  # the rotor never went to 300
    wait_until(
        lambda: any(e["command"] == "target '300'" for e in _lines(rig)),
        slow(5),
        "the operator's 300 in the audit file",
    )
    rig.probe.publish("rotor/target", "10")  # a marker after the drop: refused for the storm
    wait_until(
        lambda: any(e["command"] == "target '10'" for e in _lines(rig)),
        slow(5),
        "the marker in the audit file",
    )
    lines = _lines(rig)
    of_300 = [e for e in lines if "300" in str(e["command"])]
    assert any(str(e["result"]).startswith("refused") for e in of_300), (
        f"the rotor never turned to 300 (dropped by the storm, said on R/error); the audit "
        f"file says of it: {of_300}"
    )
