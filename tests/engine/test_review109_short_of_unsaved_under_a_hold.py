"""Review 109 (Medium): 88df070b has the status say the ``short_of_deg`` it said before
"while a target waits to go and the controller answers" (controller.py ``_short_of_kept``),
priced in runtime/kept.py rule 9 as "a bridge killed in those moments (the brake's delay)".
But a target waits for more than the brake: one published after a STOP waits under the stop
express's hold (session/stops.py rule 5: "which no clock bounds"; an attack pass saw 45 s,
a firewall dropping the express's flow). The STOP rests the Rotor-EZ short of its target
while that target waits, so for as long as the hold lasts the state file keeps no
``short_of``, and R/status says none.

What a user sees: a Rotor-EZ turning to 300, the operator's STOP at about 200 and a new
bearing sent just after it; the express's flow is cut, the new bearing waits (the long hold
said). The bridge dies then (a power blip, the OOM killer, ``kill -9`` of what looks hung),
and the next start is unguarded: the first poll garbled into ``AM1;`` turns the rotor on to
300, unsaid (kept.py rule 9's own attack). In virtual time: the statuses handed to the
rotator's Kept on a real state file as runtime/rotator.py ``_status`` does, the next session
made from that file as runtime/rotator.py makes it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from bridge.core.model import MotionState, Source, Stop, Target
from bridge.runtime.kept import Kept
from bridge.runtime.state_store import StateStore
from bridge.session.session import RotatorSession
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
QUERY = b"AI1;"
HOLD_S = 45.0  # the express's flow cut: its hold lasts until its keepalive notices


def test_a_stop_short_of_the_target_is_kept_while_a_target_waits_under_a_hold(
    rig: Rig, tmp_path: Path
) -> None:
    v = rig("rotorez")
    v.run_until_state(MotionState.IDLE, 30)
    store = StateStore(tmp_path / "state.json")
    kept = Kept(store, v.cfg.rotator_id, v.cfg.spec, report=lambda *a: None)
    v.target(300)
    v.run_for(10)  # (on its way: not a deadline)
    assert v.truth().is_moving
    v.mailbox.put_express_hold(1)  # the operator's STOP, by the stop express ...
    v.mailbox.put(Stop(Source.MQTT))
    v.mailbox.put(Target(120.0))  # ... and a new bearing published just after it
    v._take()
    v.run_for(HOLD_S)  # (the express's flow cut: not a deadline)
    rest = v.truth().az_deg
    assert not v.truth().is_moving and rest < 280.0  # stopped short of 300, at rest
    for _t, status in v.statuses:  # (as runtime/rotator.py ``_status``)
        kept.seen_short_of(status.short_of_deg)
    store.flush()
    v.link_down(None)  # the bridge killed: the next start reads the file
    v.run_for(1)
    short_of = StateStore(tmp_path / "state.json").short_of(v.cfg.rotator_id)
    v.session = RotatorSession(v.cfg, short_of=short_of)
    v._do(v.session.start(v.now))
    v.garble_writes(QUERY, b"AM1;")  # (the first poll of the new session)
    v.link_up()
    v.run_for(60)  # (the rotor's run on to 300 would take less: not a deadline)
    assert v.truth().az_deg < rest + 20, (short_of, rest, v.truth().az_deg)  # not on to 300
