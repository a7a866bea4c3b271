"""Cold review 18: a hold the marker ends although the main connection never read its own
copy of the lane's STOP (lastword.py ``_passed``: "its main copy came before, or was lost:
either way none is to come").

lastword.py rule 2: a target the main connection reads before the marker "waits (held, not
sent), and the main connection's own copy of the stop ... drops every target older than it".
When that copy is lost (rule 5 names the case: "a broker that drops messages for a reader that
fell behind", QoS 0 on both connections, lane.py rule 2), nothing drops the targets published
before the STOP: the marker's plain release sends the one held, and a move published *before*
the STOP turns the rotor after it. Which of the held targets came before the STOP is then
unknowable; the hold ends as a plain release, not as a clearing one.

The service (service.py, halts.py, lastword.py) drives a Rotor-EZ session in virtual time
through a rotator that hands each call to the session's mailbox as runtime/rotator.py would.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import Command, Lock, MotionState, Stop, Target
from tests.engine.virtual import VirtualRotator
from tests.mqtt.test_service import RecordingRotator, service

Rig = Callable[..., VirtualRotator]
IDLE = MotionState.IDLE


class Bridged(RecordingRotator):
    """The service's calls, recorded and put in the session's mailbox (runtime/rotator.py)."""

    v: VirtualRotator

    def submit(
        self,
        command: Command,
        described: str | None = None,
        *,
        hold: int | None = None,
        echo: bool = False,
        since: int | None = None,
    ) -> None:
        super().submit(command, described, hold=hold, echo=echo, since=since)
        if isinstance(command, Stop):
            self.v.mailbox.put(command, hold=hold)
        elif isinstance(command, Lock):
            self.v.mailbox.put_lock(command.on, hold=hold)
        elif isinstance(command, Target):
            self.v.mailbox.put(command)
        self.v._take()

    def release(self, marker: int, *, clear: bool = False) -> None:
        super().release(marker, clear=clear)
        self.v.mailbox.put_release(marker, clear=clear)
        self.v._take()


def test_a_target_published_before_a_lane_stop_never_turns_the_rotor_after_it(rig: Rig) -> None:
    v = rig("rotorez")
    v.run_until_state(IDLE, 30)
    svc, pub, rots = service({"tower": "rotorez"})
    tower = Bridged("tower", "rotorez")
    tower.v = v
    svc.attach(tower)
    pub.take()
    start = v.truth().az_deg
    # published: target 300, then the operator's STOP. The lane reads the STOP first.
    svc.on_lane_message("rotor/stop", b"", False)
    (marker,) = [m for m in pub.take() if m[0] == "rotor/bridge/fence"]
    svc.on_message("rotor/target", b"300", False)  # published before the STOP: held
    # the broker dropped the main connection's copy of the STOP (a reader that fell behind);
    # the marker, published later, comes back
    svc.on_message(marker[0], marker[1].encode(), False)
    v.run_for(60)
    assert abs(v.truth().az_deg - start) < 4, (
        f"the target published before the STOP turned the rotor after it: now at "
        f"{v.truth().az_deg:.0f}, calls {tower.calls}"
    )
