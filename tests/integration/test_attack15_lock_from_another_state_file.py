"""Attack 15: a lock ON set under one state file is dropped without a word by a start on
another state file that says OFF (runtime/kept.py rule 10).

The station's service keeps its state file (the lock OFF it saved after the last tower work).
The bridge is run once by hand, whose default ``state_file`` is another (the very case
docs/mqtt.md names for ``R/lock``); the operator locks the rotator there for tower work: that
run saves ON in its own file, and the broker holds ``R/lock/state`` ON. Then the service is
started again. Its file says OFF, so the file wins (kept.py rule 10: "OFF was written after the
ON the broker holds, or the ON is a stranger's"), and here neither is true: the OFF is older.
The rotator starts unlocked, ``R/lock/state`` is put back to OFF over the ON, and nothing says
so: no ``R/error``, no log line. The next target turns the rotor that someone locked to climb
the tower. Whichever way a fix goes (keep the lock the broker held, or say it was dropped), the
start must not pass over it in silence.
"""

from __future__ import annotations

import json

from bridge.runtime.rotator import HEARD_OVER_OFF_MESSAGE
from bridge.runtime.state_store import StateStore
from tests.support.rig import Rig


def test_a_lock_on_from_a_run_on_another_state_file_is_kept_or_said(rig: Rig) -> None:
    service, by_hand = rig.tmp / "service-state.json", rig.tmp / "by-hand-state.json"
    assert StateStore(service).set_locked("tower", False)  # the service's last word: OFF
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    probe = rig.probe

    # the run by hand: locked for tower work, saved in its own file, said on the broker
    rig.sections["state_file"] = str(by_hand)
    rig.start()
    rig.ready("tower")
    probe.publish("rotor/lock", "ON")
    probe.wait_value("rotor/lock/state", "ON")
    rig.stop()
    assert StateStore(by_hand).locked("tower")

    # the service again, on its own file
    after = probe.caught_up()
    rig.sections["state_file"] = str(service)
    rig.start()
    rig.ready("tower", after=after)
    probe.publish("rotor/target", "200")
    done = probe.wait_for(
        "rotor/audit", lambda m: json.loads(m.text)["command"] == "target '200'", after=after
    )
    refused = json.loads(done.text)["result"].startswith("refused")
    said = [
        m
        for m in probe.on("rotor/error")
        if m.t >= after and json.loads(m.text)["kind"] == "state" and "lock" in m.text
    ]
    assert refused or said, (
        f"lock/state {probe.last('rotor/lock/state')}, target {done.text}, "
        f"rotor at {emu.state().az_deg:.0f}: the broker's lock ON dropped without a word"
    )


def test_the_service_starts_locked_says_why_and_the_rotor_stays(rig: Rig) -> None:
    """The fix (kept.py rule 10): the file's OFF no longer outweighs the broker's ON. The
    service starts locked, says on ``R/error`` (kind ``state``) that the broker held a lock
    ON its file says was OFF, keeps ``R/lock/state`` ON and its own file ON (the next start is
    locked too), and the next target turns nothing."""
    service, by_hand = rig.tmp / "service-state.json", rig.tmp / "by-hand-state.json"
    assert StateStore(service).set_locked("tower", False)
    emu = rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
    probe = rig.probe
    rig.sections["state_file"] = str(by_hand)
    rig.start()
    rig.ready("tower")
    probe.publish("rotor/lock", "ON")
    probe.wait_value("rotor/lock/state", "ON")
    rig.stop()

    after = probe.caught_up()
    rig.sections["state_file"] = str(service)
    rig.start()
    rig.ready("tower", after=after)
    said = probe.wait_for(
        "rotor/error", lambda m: json.loads(m.text)["kind"] == "state", after=after
    )
    assert json.loads(said.text)["message"] == HEARD_OVER_OFF_MESSAGE
    probe.publish("rotor/target", "200")
    done = probe.wait_for(
        "rotor/audit", lambda m: json.loads(m.text)["command"] == "target '200'", after=after
    )
    assert json.loads(done.text)["result"].startswith("refused"), done.text
    assert [m.text for m in probe.on("rotor/lock/state") if m.t >= after] in ([], ["ON"])
    shown = probe.last("rotor/lock/state")
    assert shown is not None and shown.text == "ON"
    rig.stop()
    assert StateStore(service).locked("tower")  # the next start is locked too
    assert abs(emu.state().az_deg - 10) < 1 and not any(
        f.data.startswith((b"AP", b"AM")) for f in emu.log()
    )
