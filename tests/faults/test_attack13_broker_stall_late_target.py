"""Attack 13: a target held up in a broker that stalls (frozen, not gone: a Raspberry Pi's SD
card writing mosquitto's persistence, a VM paused, a swap storm) and delivered when it runs on.

The bridge gives up on a stalled broker only after its keepalive has run out twice over (paho
pings after ``keepalive_s`` without a word from the broker and drops the connection after as
long again: up to a minute with the default 30 s), and nothing else tells it that what it
reads was published long before. A target Home Assistant published at the start of a 10 s
stall reaches the bridge when the broker runs on, and the rotor turns then, 10 s after the
operator asked and saw nothing happen: twice the age at which the house refuses a move from
its own console (web/commands.py MAX_AGE_S) or from the remote (``command_expiry_s``).
Now the bridge's network thread sees the stall as quiet while a heartbeat of its own is out
(heartbeat.py rule 11), and refuses an unstamped move until a beat sent after it is back.

Real parts: mosquitto (frozen with SIGSTOP), the bridge in-process, an emulated Rotor-EZ on a
pty, a paho client (the probe) as Home Assistant."""

from __future__ import annotations

import json
import time

from tests.support.mqtt import Message
from tests.support.rig import Rig

STALL_S = 10.0  # a quiet period, not a deadline (waiting.py rule 2): the broker's stall
LATE_S = 5.0  # the age at which the console and the remote refuse a move


def test_a_target_held_up_in_a_stalled_broker_does_not_turn_the_rotor_when_it_runs_on(
    rig: Rig,
) -> None:
    emu = rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    rig.broker.pause()
    try:
        sent = time.monotonic()
        # into the frozen broker's socket, its PUBACK not waited for: a wait of 5 s more made
        # the stall 15 s, 1.5 times the probe's keepalive, at which mosquitto may drop the
        # probe, whose paho then sends the target again as a new message once back (the
        # replay docs/mqtt.md says the bridge cannot tell), after the broker was quick again
        rig.probe.client.publish("rotor/target", "200", qos=1)
        during = turns_within(rig, rig.probe.mark(), STALL_S)  # the stall itself
    finally:
        resumed = time.monotonic()
        rig.broker.resume()
    assert not during  # (nothing reaches the bridge from a frozen broker)
    assert resumed - sent > LATE_S
    assert not turns_within(rig, rig.probe.mark(), STALL_S), (
        f"the rotor turned once the broker ran on, {resumed - sent:.1f} s after the target was sent"
    )
    assert abs(emu.state().az_deg - 10) <= 3
    refusal = rig.probe.wait_for("rotor/error", lambda m: b"held this up" in m.payload)
    assert json.loads(refusal.payload)["command"] == "target '200'"


def test_a_target_sent_once_the_broker_ran_on_turns_the_rotor(rig: Rig) -> None:
    """Refusing what a stalled broker held costs nothing once it is quick again: the bridge says
    on B/bridge/info that the broker holds its messages up while that lasts, and a target sent
    once it says so no more (moments after the broker ran on) turns the rotor."""
    rig.add("tower", emu={"start_az_deg": 10})
    rig.start()
    rig.ready("tower")
    since = rig.probe.mark()
    rig.broker.pause()
    try:
        said = said_within(rig, since, STALL_S)  # the stall itself
    finally:
        resumed = time.monotonic()
        rig.broker.resume()
    assert not said  # (nothing the bridge says reaches the probe through a frozen broker)
    late = rig.probe.wait_for(
        INFO, holds_up, after=resumed
    )  # said while it stalled, held with the rest
    rig.probe.wait_for(INFO, lambda m: not holds_up(m), after=late.t)  # quick again
    rig.probe.publish("rotor/target", "200")
    rig.arrived("tower", 200)


INFO = "rotor/bridge/info"


def holds_up(m: Message) -> bool:
    """B/bridge/info says that the broker holds the bridge's messages up."""
    return any("holds up" in p for p in json.loads(m.payload).get("problems", []))


def said_within(rig: Rig, since: int, seconds: float) -> bool:
    """Whether B/bridge/info says the broker holds messages up within ``seconds`` (a quiet
    period: waiting.py rule 2)."""
    try:
        rig.probe.wait(lambda m: m.topic == INFO and holds_up(m), seconds, start=since, quiet=True)
    except AssertionError:
        return False
    return True


def turns_within(rig: Rig, since: int, seconds: float) -> bool:
    """Whether the bridge says ``moving`` within ``seconds`` (a quiet period: the caller
    expects it not to, waiting.py rule 2)."""
    try:
        rig.probe.wait(
            lambda m: m.topic == "rotor/state" and m.payload == b"moving",
            seconds,
            start=since,
            quiet=True,
        )
    except AssertionError:
        return False
    return True
