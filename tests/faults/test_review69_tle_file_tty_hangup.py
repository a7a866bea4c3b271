"""Review 69: 39f86c2c (sky/catalog.py rule 4) says what is no regular file "is not read", its
kind seen on the file opened without waiting; but it is opened, without O_NOCTTY. A service is
a session leader with no controlling terminal (systemd starts it so), and a terminal opened so
becomes its controlling terminal: ``tle_file`` naming a serial port (the rotator's own
``/dev/serial/by-id/...`` pasted into the wrong key) makes that line the bridge's terminal, and
when it hangs up (the adapter unplugged, a pty's other end closed) the kernel sends the bridge
SIGHUP, which the bridge takes for its terminal closing (app.py): "SIGHUP received, shutting
down", exit 0, which systemd's Restart=on-failure does not restart. The station is off the
air for good over a line that hung up, where an unplugged adapter is otherwise "port lost,
keeps trying". interfaces/web/files.py opens with
O_NOCTTY for this reason; the TLE reader (and the cty reader, 841e7277) do not."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from tests.support import slow, to_toml, wait_until
from tests.support.process import bridge_env


def test_a_tle_file_that_is_a_terminal_line_does_not_tie_the_bridge_to_it(tmp_path: Path) -> None:
    controller, line = os.openpty()
    tty = os.ttyname(line)
    os.close(line)
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": tmp_path / "state.json",
                "mqtt": {"host": "127.0.0.1", "port": 9},  # no broker: it keeps trying
                "tracking": {"tle_file": tty},
                "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
            }
        )
    )
    log = tmp_path / "bridge.log"
    with open(log, "wb") as out:
        bridge = subprocess.Popen(
            [sys.executable, "-m", "bridge", "run", "-c", str(config)],
            env=bridge_env(),
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # as systemd starts a service: a session of its own
        )
    try:
        wait_until(
            lambda: "is no regular file" in log.read_text() or bridge.poll() is not None,
            what="the TLE reader to look at the line",
        )
        assert bridge.poll() is None, log.read_text()
        fields = Path(f"/proc/{bridge.pid}/stat").read_text().rsplit(")", 1)[1].split()
        assert fields[4] == "0", f"the bridge's controlling terminal is now {tty} ({fields[4]})"
    finally:
        os.close(controller)  # the line hangs up (an adapter unplugged): a SIGHUP is sent now
        bridge.send_signal(signal.SIGTERM)  # (one already sent is taken first)
        code = bridge.wait(slow(15))
    said = log.read_text()
    assert "SIGHUP received" not in said, f"the bridge ended on the line's hangup:\n{said[-1500:]}"
    assert "SIGTERM received" in said and code == 0, said[-1500:]
