"""Review 73 (fbf6d6c1, state_store.py rule 13 beside rule 7): the update reads the state file
an earlier version kept at ``./~/...`` as its own, the same installation's, but takes the
installation's lock at the new path alone. An earlier version still running on that file (it
holds ``./~/rb/state.json.lock``, rule 7 as it was then: the update installed, the service not
restarted yet, and the new one started by hand to try it) does not stop the start: the two run
one installation, take turns on the broker under one client id, and each writes its own file
of the one state, the very case rule 7 refuses."""

from __future__ import annotations

from pathlib import Path

from bridge.runtime.state_store import held
from tests.faults.test_review69_state_file_tilde_moved import start_from_home, tilde_installation
from tests.support import Probe
from tests.support.mosquitto import Mosquitto
from tests.support.waiting import wait_until


def test_a_bridge_running_on_the_leftover_state_file_stops_the_start_that_reads_it(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    home, old, config = tilde_installation(tmp_path, broker)
    with held(old):  # the earlier version, still running on its file (rule 7's lock)
        bridge = start_from_home(home, config)
        try:
            wait_until(
                lambda: bridge.poll() is not None or probe.last("rotor/lock/state") is not None,
                10,
                "the start refused, or the bridge running",
            )
            running = probe.last("rotor/lock/state") is not None
        finally:
            bridge.terminate()
            _, err = bridge.communicate()
    assert not running, f"started beside the bridge running on {old}:\n{err}"
    assert bridge.returncode == 2 and "another rotor-bridge runs this installation" in err, err
