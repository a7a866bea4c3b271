"""Who is turning it, as the status says, in virtual time: ``last_operator`` follows the command
the status names (``last_command_source``), and ``control`` the lease the judge put in."""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import Control, MotionState, Origin, Source, Stop, Target
from tests.engine.test_session_pointing import settled
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]


def test_the_status_names_who_sent_the_last_command(rig: Rig) -> None:
    v = rig("rotorez", settings={"park_az_deg": 0, "park_after_idle_s": 30},
            emulator={"start_az_deg": 90})  # fmt: skip
    v.run_until_state(MotionState.IDLE, 30)
    assert v.status.last_operator is None
    v.aim(Target(120, origin=Origin(Source.MQTT, "DL1ABC")))
    v.run_until(settled(120), 60, "at 120")
    assert (v.status.last_command_source, v.status.last_operator) == ("mqtt", "DL1ABC")
    v.command(Stop(Source.ROTCTLD, Origin(Source.ROTCTLD, None, "192.168.1.20")))
    v.run_for(1)
    assert (v.status.last_command_source, v.status.last_operator) == (
        "rotctld",
        "rotctld 192.168.1.20",
    )
    v.run_until(lambda v: v.status.parked, 120, "parked by itself")
    assert (v.status.last_command_source, v.status.last_operator) == ("auto-park", None)


def test_the_status_shows_the_lease_it_is_told_of(rig: Rig) -> None:
    v = rig("rotorez", emulator={"start_az_deg": 90})
    v.run_until_state(MotionState.IDLE, 30)
    held = Control("DL1ABC", v.wall() + 600)
    v.mailbox.put_control(held)
    v.command()  # the batch taken, as the worker takes it
    assert v.status.control == held and v.published()[-1].control == held
    v.mailbox.put_control(None)
    v.command()
    assert v.status.control is None
