"""Review 87 (cold review of attack 28's settings rule 6): ``audit_file = "/dev/stdout"`` is
judged by where the judging process's own standard output happens to go.

Rule 6 now refuses a written file that is "a device (a character or block device)", links
followed. ``/dev/stdout`` is a link to the process's descriptor 1: under the systemd unit
(the journal's socket), in ``docker run -d`` (a pipe) or behind ``| tee`` it is no device and the
configuration is OK; in a terminal, ``docker run -it`` or ``ssh -t`` it is the terminal's pty
and the same file is refused: "audit_file /dev/stdout is a character device, not a file: the
bridge writes there, and what it writes would go to the device". So ``check-config`` typed in
a terminal refuses the file the service then runs with, and ``check-config | less`` says OK to
a file that ``rotor-bridge run`` in the terminal refuses with exit code 2. The audit writer
itself was made for such a path (runtime/audit.py ``_size``: what is not a regular file is
never rotated). Whichever verdict is right (a terminal is no rotator's serial port, and the
audit lines on one's own console is what a user asking for /dev/stdout wants), one file must
get one verdict.

Reproduced with ``python -m bridge check-config`` as its own process, its stdout a real
pseudo-terminal, then a pipe."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

from tests.support import ROOT, bridge_env, slow


def _check_config(cfg: Path, *, on_a_terminal: bool) -> int:
    """``rotor-bridge check-config -c cfg``'s exit code, its stdout a pty or a pipe."""
    args = [sys.executable, "-m", "bridge", "check-config", "-c", str(cfg)]
    env, cwd = bridge_env(), str(ROOT)
    if not on_a_terminal:
        done = subprocess.run(args, capture_output=True, env=env, cwd=cwd, timeout=slow(30))
        return done.returncode
    master, slave = os.openpty()

    def drain() -> None:  # (what it prints must not fill the pty and hold it)
        try:
            while os.read(master, 4096):
                pass
        except OSError:  # EIO: the last writer closed the slave
            pass

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        done = subprocess.run(
            args, stdout=slave, stderr=subprocess.PIPE, env=env, cwd=cwd, timeout=slow(30)
        )
    finally:
        os.close(slave)
        reader.join(slow(5))
        os.close(master)
    return done.returncode


def test_audit_file_dev_stdout_gets_one_verdict_wherever_stdout_goes(tmp_path: Path) -> None:
    cfg = tmp_path / "bridge.toml"
    cfg.write_text(
        f'state_file = "{tmp_path / "state.json"}"\naudit_file = "/dev/stdout"\n'
        '[[rotators]]\nid = "tower"\nmodel = "rotorez"\n'
        'port = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"\n'
    )
    piped = _check_config(cfg, on_a_terminal=False)
    on_a_terminal = _check_config(cfg, on_a_terminal=True)
    assert piped in (0, 2) and on_a_terminal in (0, 2)
    assert on_a_terminal == piped, f"piped: exit {piped}, on a terminal: exit {on_a_terminal}"
    assert piped == 0  # the verdict: the bridge's own output, by name (runtime/audit.py rule 11)
