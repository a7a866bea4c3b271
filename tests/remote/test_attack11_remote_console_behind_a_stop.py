"""Attack 11's console hole on the remote, which serves the same console (remote/console.py,
interfaces/web/server.py rule 11): a script's target posted to the remote's console before the
remote's own rotctld STOP, read by the console's busy loop after it, must not reach the station.
Real parts: a mosquitto, the station's bridge on an emulated Rotor-EZ, the remote in this
process with its console and a rotctld port."""

from __future__ import annotations

import http.client
import json
import socket

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support import wait_until
from tests.support.console import ConsoleClient, web_section
from tests.support.mosquitto import free_port
from tests.support.rig import Rig
from tests.support.waiting import slow
from tests.web.test_attack11_console_behind_a_stop import console_loop_held


def test_a_remote_console_target_sent_before_the_remotes_rotctld_stop_never_reaches_the_station(
    station: Rig,
) -> None:
    web_port, rotctld_port = free_port(), free_port()
    settings = RemoteSettings(
        operator="DL1ABC",
        mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": rotctld_port}],
        web=web_section(web_port),
    )
    remote = Remote(settings)
    remote.start()
    try:
        console = ConsoleClient(web_port)
        console.session()
        assert remote.console is not None
        emu = station.emus["tower"]
        body = json.dumps({"command": "target", "az": 200}).encode()
        with socket.create_connection(("127.0.0.1", web_port), timeout=slow(10)) as script:
            with console_loop_held(remote.console) as held:
                wait_until(held.is_set, slow(10), "the console's loop busy")
                script.sendall(console.command_head("tower", body) + body)  # whole, in the kernel
                with socket.create_connection(("127.0.0.1", rotctld_port), timeout=slow(5)) as s:
                    s.sendall(b"S\n")  # after the target was sent
                    assert s.recv(100) == b"RPRT 0\n"
            response = http.client.HTTPResponse(script)
            response.begin()
            answer = response.status, response.read()
        assert answer[0] == 409 and b"stale" in answer[1], answer
        # a target sent after the stop goes; the one before it never reached the station
        assert console.command("tower", command="target", az=60).status == 200
        station.arrived("tower", 60)
        assert not [f.data for f in emu.frames(*BEARING_OUTCOMES) if b"200" in f.data]
    finally:
        remote.stop()
