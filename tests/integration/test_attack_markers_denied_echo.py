"""A guard: 0785d896 did what is said below, and was reverted (6129c849).

An attack pass on lastword.py rules 4 and 7 (0785d896): with the main connection's markers
denied (the broker's ACL drops B/bridge/fence and B/bridge/hello) a lane halt is carried out
with no hold and is no longer counted as waiting for its main copy, so the main connection's
copy of a halt the lane carried out first is taken for a halt the main connection read first:
rule 4 notes an echo for the lane and publishes a lane marker. The lane's next stop of that
rotator, read before that lane marker, is dropped as the echo: a STOP the operator sent again
waits for the main connection, behind whatever it is reading (rule 7 says the lane is then
"speed alone", a halt earlier than the main connection alone). Real parts: mosquitto with an
ACL, the bridge (App), an emulated Rotor-EZ on a pty.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bridge.app import App
from tests.integration.test_broker_acl import acl_rig
from tests.integration.test_last_word import main_held_at
from tests.support.waiting import slow, wait_until


@contextmanager
def lane_held_at(app: App, topic: str, nth: int) -> Iterator[tuple[threading.Event, list[int]]]:
    """The stop lane stops reading at the ``nth`` message on ``topic`` until the block ends
    (yields the event set once it is held there, and the count of those read so far)."""
    halts = app.mqtt._halts
    handle = halts.on_lane
    release, held, seen = threading.Event(), threading.Event(), [0]

    def stuck(topic_: str, payload: bytes, *args: object, **kwargs: object) -> None:
        if topic_ == topic:
            seen[0] += 1
            if seen[0] == nth:
                held.set()
                release.wait(slow(30))
        handle(topic_, payload, *args, **kwargs)  # type: ignore[arg-type]

    halts.on_lane = stuck  # type: ignore[method-assign]
    try:
        yield held, seen
    finally:
        release.set()


def test_with_the_markers_denied_a_second_lane_stop_is_not_dropped_as_the_first_ones_echo(
    tmp_path: Path,
) -> None:
    acl = "topic readwrite rotor/#\ntopic deny rotor/bridge/fence\ntopic deny rotor/bridge/hello\n"
    with acl_rig(tmp_path, acl) as (rig, probe):
        rig.mqtt_extra = {"protocol": "5"}
        emu = rig.add("tower", emu={"start_az_deg": 10, "speed_deg_s": 4.0})
        app = rig.start()
        wait_until(lambda: not app.mqtt._word.markers, 20, "the markers off")
        rig.ready("tower")
        with main_held_at(app, "rotor/target", b"260") as at_260:
            with lane_held_at(app, "rotor/stop", 2) as (lane_held, lane_seen):
                with main_held_at(app, "rotor/target", b"100") as at_100:
                    probe.publish("rotor/target", "100")
                    wait_until(at_100.is_set, 10, "the main connection held before STOP 1")
                    probe.publish("rotor/stop", "STOP")  # STOP 1: the lane carries it out
                    wait_until(lambda: lane_seen[0] >= 1, 10, "the lane read STOP 1")
                    probe.publish("rotor/target", "250")  # published after STOP 1: obeyed
                    probe.publish("rotor/target", "260")  # (where the main connection waits)
                    probe.publish("rotor/stop", "STOP")  # STOP 2, the operator's again
                    wait_until(lane_held.is_set, 10, "the lane held at STOP 2")
                # the main connection reads the 100, STOP 1 (the copy of the lane's) and the
                # 250, and waits at the 260, a backlog behind: the rotor turns for 250
                wait_until(at_260.is_set, 10, "the main connection past the 250")
                emu.wait_for(lambda s: s.is_moving, 10)
            # the lane reads STOP 2 (published before the lane marker of STOP 1's copy):
            # carried out at once, it stops the rotor while the main connection is behind
            emu.wait_for(lambda s: not s.is_moving, 10)
