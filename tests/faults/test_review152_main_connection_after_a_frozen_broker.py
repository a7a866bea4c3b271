"""Review 152 (cold review of 415730e0): connection.py rule 6 and docs/reliability.md say "a
broker that freezes answers no lane either, so the main connection still rides a frozen broker
out". It does not: a broker frozen a few seconds (SIGSTOP here; a host swapping, a VM paused
for a snapshot or a migration) leaves the stop and lock lanes' pings unanswered, they give
their connections up, and their next ones, waiting in the broker's listen queue, are accepted
the moment it runs again: each is "a lane answered anew after an unanswered ping", and the
main connection's path is put in doubt (``prove_path``) right when the broker works through
what the freeze held. A main connection that then has a backlog to read (what the broker sends
it held behind a flood: review 145's ``SlowPath``) does not see its PINGRESP within 2 s and is
given up by the bridge itself: its will says the bridge ``offline`` to every dashboard, and
what it was reading is thrown away. Before 415730e0 (the setting's keep-alive, 30 s) the same
freeze ended nothing on the main connection.

Real parts: mosquitto (frozen with SIGSTOP), the bridge in-process, an emulated Rotor-EZ on a
pty, a paho client at the broker's own port as the dashboard, the MQTT-aware proxy on the
bridge's path.

Now a guard: 415730e0 was taken back (the main connection keeps its keep-alive); any later
way of finding the main connection's dead path must pass it."""

from __future__ import annotations

import time
from pathlib import Path

from tests.faults.behind_a_proxy import lanes_behind, main_up_after_a_doubt, said_offline
from tests.faults.test_review145_stop_carriers_keepalive import SlowPath
from tests.support.waiting import slow, wait_until

# 415730e0's DEAD_PATH_S (taken back): how long after a dead path or a lane's return a
# doubted main connection was made again at most
DEAD_PATH_S = 12

FROZEN_S = 5.0  # the broker's freeze: the fault's length (not a wait for the bridge)


def test_a_frozen_broker_does_not_drop_a_main_connection_reading_a_backlog(
    tmp_path: Path,
) -> None:
    # a dashboard on the broker's own port; the bridge behind a SlowPath whose CONNACKs are prompt
    with lanes_behind(tmp_path, lambda port: SlowPath(port, 0.0)) as b:
        broker, proxy, probe, rig, app = b.broker, b.proxy, b.probe, b.rig, b.app
        main_id = rig.settings.mqtt.effective_client_id()
        mark = probe.mark()
        proxy.backlog(main_id)  # the main connection has a backlog to read
        broker.pause()
        try:
            time.sleep(FROZEN_S)  # the freeze: the fault's length
        finally:
            broker.resume()
        wait_until(app.lane.connected.is_set, slow(15), "the stop lane up again")

        def offline() -> list[str]:
            return said_offline(probe, mark)

        main_up = main_up_after_a_doubt(probe, mark, app, slow(DEAD_PATH_S), proxy.released)
        assert not offline() and main_up, (
            f"a broker frozen {FROZEN_S:g} s while the main connection read a backlog: "
            f"dashboards were shown {offline()} offline; the main connection up: {main_up}"
        )
