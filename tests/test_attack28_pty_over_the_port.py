"""Attack 28: a rotator's ``gs232_pty`` (or ``easycomm_pty``, ``dcu1_pty``) set to the path of
its own ``port`` (the two keys side by side in the file; the adapter's ``/dev/serial/by-id/``
name pasted into both) passes ``check-config`` ("config OK"). At the start the pty server
replaces the adapter's link (udev's, a symbolic link: ptylines.py takes a link there for a
leftover of its own) with one to its pty, and the rotator's worker then opens that path: the
bridge's own pty, not the controller. The rotator stays offline for good with ``controller on
... does not answer`` on R/error (the user checks the cable), and the adapter's by-id name is
gone until it is plugged in again. Reproduced with the Rotor-EZ emulator's link as the port and
the bridge as a process: the link pointed at a new /dev/pts after the start, and the only error
was "does not answer".

The files the bridge writes are no file another key names (settings rule 6); a pty's link is
one it writes, and this one is the port's. Refused, naming the key, exit code 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import cli


@pytest.mark.parametrize("key", ["gs232_pty", "easycomm_pty", "dcu1_pty"])
def test_a_pty_at_the_rotators_own_port_is_refused_naming_it(tmp_path: Path, key: str) -> None:
    by_id = tmp_path / "usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"
    by_id.symlink_to("/dev/null")  # udev's link to the adapter
    cfg = tmp_path / "bridge.toml"
    cfg.write_text(
        f'state_file = "{tmp_path / "state.json"}"\n'
        f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{by_id}"\n{key} = "{by_id}"\n'
    )
    out = cli("check-config", "-c", str(cfg))
    assert out.returncode == 2, out.stdout[-400:]
    assert key in out.stderr, out.stderr
