"""A neighbour on the LAN holding connections open to every TCP port of the bridge and to its
console, against the process's open-files limit (app.py rule 5): the bridge as a service
process under a low soft limit, its controller unplugged and plugged back while the
connections are held. What a user notices: whether the rotator comes back online, and what
the log says.
"""

from __future__ import annotations

import resource
import socket
from pathlib import Path

from tests.support.console import web_section
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.mqtt import Probe
from tests.support.process import fd_limited
from tests.support.rig import Rig

HELD = 2000  # connections opened to each port, held idle (the ports' caps, then the kernel's)


def _hold(ports: list[int]) -> list[socket.socket]:
    held: list[socket.socket] = []
    for _ in range(HELD):
        for port in ports:
            s = socket.socket()
            s.setblocking(False)
            s.connect_ex(("127.0.0.1", port))
            held.append(s)
    return held


def _ports() -> dict[str, int]:
    keys = ("rotctld_port", "gs232_port", "easycomm_port", "dcu1_port")
    return {key: free_port() for key in keys}


def test_connections_held_to_every_port_leave_room_to_reopen_the_controller(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """DEFECT (high, an attack pass): under a soft limit of 256 open files (hard: more), idle
    connections to the four TCP ports and the console took every descriptor the process had
    (each port holds up to 81, the console 512), and a controller unplugged meanwhile could
    not be opened again ("Too many open files", every retry) for as long as they were held:
    the rotator offline, its stop owed. Now the soft limit is raised at start to what the
    ports may hold and a spare, and said."""
    own = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(own[0], 6 * HELD + 512), own[1]))
    ports = _ports()
    try:
        with Rig(tmp_path, broker, probe, spawn=fd_limited(256, max(4096, own[0]))) as rig:
            web = rig.sections["web"] = web_section()
            rig.add("hf", "gs232b", **ports)
            bridge = rig.start_process(log_level="INFO")
            rig.ready("hf")
            held = _hold([*ports.values(), web["port"]])
            try:
                rig.unplug_and_replug("hf")
            except AssertionError as exc:
                raise AssertionError(f"{exc}\n{bridge.log()[-2000:]}") from None
            finally:
                for s in held:
                    s.close()
            log = bridge.log()
    finally:
        resource.setrlimit(resource.RLIMIT_NOFILE, own)
    assert "open-files limit raised from 256 to " in log, log[-2000:]
    assert "Too many open files" not in log, log[-2000:]


def test_a_hard_limit_too_low_for_the_ports_is_said_at_start(
    tmp_path: Path, broker: Mosquitto, probe: Probe
) -> None:
    """The limit cannot be raised past the hard one: the log says what to set it to."""
    with Rig(tmp_path, broker, probe, spawn=fd_limited(256, 256)) as rig:
        rig.add("hf", "gs232b", **_ports())
        bridge = rig.start_process(log_level="INFO")
        rig.ready("hf")
        log = bridge.log()
    assert "the process may open 256 files (ulimit -n; systemd: LimitNOFILE)" in log, log
    assert "set the limit to " in log, log
