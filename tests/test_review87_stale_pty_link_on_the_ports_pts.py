"""Review 87 (cold review of attack 28's settings rule 6): a pty's link left by a crashed run
refuses the next start when the pseudo-terminal number it points at is now the rotator's port.

A real set-up: the controller is reached over the network through ``socat
pty,link=/home/ham/ttyV0 tcp:shack-pi:4001`` (a pty whose link is the rotator's ``port``), and
the bridge offers ``gs232_pty`` for a logger. The bridge is killed (the out-of-memory killer, a
power blip of the USB hub that takes socat down with it); its pty's link stays behind, pointing
at ``/dev/pts/N``. socat starts again and the kernel hands it the lowest free number: that same
``/dev/pts/N``. ptylines.py rule 1 says such a leftover link is the bridge's own and is replaced
at the start, and settings rule 6 says so too ("a pty's path excepted, where a link to a crashed
run's pty is its own leftover"); but the port check follows the leftover's link
(``same_file(path, port)``), finds socat's pty there, and the start stops with exit code 2:
"gs232_pty ... is also rotators[0].port ..., a serial port: the pty's link would replace the
port's name" (it would not: the port's name is ``ttyV0``, untouched), and the rotator stays off
MQTT until someone removes the link by hand. Under the shipped unit with the link in
/run/rotor-bridge, systemd empties that folder after the crash; it bites a run in a terminal or
tmux, a container, or a unit of one's own with the link elsewhere (which, on exit code 2, is
not restarted either when it copies RestartPreventExitStatus=2).

Reproduced with a real pseudo-terminal standing in for socat's and a link to it at both names:
the config names two different files (ttyV0 and run/gs232), the pty's is a leftover link, and
check-config refuses it."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import cli


@pytest.fixture
def socat_pty() -> Iterator[str]:
    """A real pseudo-terminal, as socat's ``pty`` address makes one: its slave's name."""
    master, slave = os.openpty()
    try:
        yield os.ttyname(slave)
    finally:
        os.close(slave)
        os.close(master)


@pytest.mark.parametrize("key", ["gs232_pty", "easycomm_pty", "dcu1_pty"])
def test_a_crashed_runs_pty_link_on_the_ports_pts_number_does_not_stop_the_start(
    tmp_path: Path, socat_pty: str, key: str
) -> None:
    port = tmp_path / "ttyV0"
    port.symlink_to(socat_pty)  # socat pty,link=.../ttyV0
    (tmp_path / "run").mkdir()
    leftover = tmp_path / "run" / "gs232"
    leftover.symlink_to(socat_pty)  # the crashed bridge's link; the kernel reused its number
    cfg = tmp_path / "bridge.toml"
    cfg.write_text(
        f'state_file = "{tmp_path / "state.json"}"\n'
        f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{port}"\n{key} = "{leftover}"\n'
    )
    out = cli("check-config", "-c", str(cfg))
    assert out.returncode == 0, out.stderr[-600:]
    # the rotator's port is another name than the pty's: nothing of the port's would be replaced
    assert os.readlink(port) == socat_pty
