"""A claim of the control lease while another operator's target waits out a Rotor-EZ's brake
delay (session.py rule 23), end to end: a real mosquitto, the emulated Rotor-EZ on a pty, MQTT 5
clients that name their operator. The rule is proven in virtual time in
tests/engine/test_lease_waiting_target.py; here, the bytes on the wire, R/error and R/audit."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest

from tests.integration.test_operators_bridge import Operator
from tests.support import wait_until
from tests.support.mqtt import Message
from tests.support.rig import Rig

BRAKE_S = 4.0  # long enough that the claim lands while 300 waits


@pytest.fixture
def operators(rig: Rig) -> Iterator[tuple[Operator, Operator]]:
    holder, other = Operator(rig.broker.port, "DL1ABC"), Operator(rig.broker.port, "G4XYZ")
    yield holder, other
    holder.close()
    other.close()


def test_a_claim_drops_the_target_another_operator_left_waiting_for_the_brake(
    rig: Rig, operators: tuple[Operator, Operator]
) -> None:
    holder, other = operators
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0, "brake_delay_s": BRAKE_S},
                  brake_delay_s=BRAKE_S)  # fmt: skip
    rig.start()
    rig.ready("tower")
    probe = rig.probe

    # G4XYZ turns it to 100, then mid-turn to 300: the stop goes out, 300 waits for the brake
    other.publish("rotor/target", "100")
    emu.wait_for(lambda s: s.is_moving, timeout_s=10)
    other.publish("rotor/target", "300")
    emu.wait_for_frame(b";", timeout_s=10)

    def waits(m: Message) -> bool:
        status = json.loads(m.text)
        return status["target"] == 300 and status["last_operator"] == "G4XYZ"

    probe.wait_for("rotor/status", waits)
    assert emu.state().in_brake_delay  # (300 not sent yet: the claim comes before it may be)

    # DL1ABC claims the lease: G4XYZ's waiting 300 is dropped, said and audited
    holder.publish("rotor/control/claim", json.dumps({"operator": "DL1ABC", "minutes": 30}))
    said = probe.wait_for("rotor/error", lambda m: "before it went out" in m.text)
    error = json.loads(said.text)
    assert error["kind"] == "refused" and error["command"] == "target az 300"
    assert error["message"].startswith(
        "target dropped before it went out: DL1ABC holds the rotator until "
    )
    assert error["message"].endswith("only they may turn it (control lease)")

    def dropped() -> list[dict[str, object]]:
        events = [json.loads(m.text) for m in probe.on("rotor/audit")]
        return [e for e in events if str(e["result"]).startswith("refused: target dropped")]

    wait_until(lambda: dropped() != [], 10, "the drop in R/audit")
    (line,) = dropped()
    assert (line["operator"], line["command"]) == ("G4XYZ", "target az 300")

    # the holder's own target goes out once the brake is off; 300 never did
    holder.publish("rotor/target", "200")
    emu.wait_for(lambda s: abs(s.az_deg - 200) <= 3.5 and not s.is_moving, timeout_s=20)
    sets = [f.data for f in emu.log() if f.data.startswith(b"AP1")]
    assert sets == [b"AP1100\r", b"AP1200\r"]
