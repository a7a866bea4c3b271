"""Attack pass 26: the station's link to its broker goes dead mid-turn (a home router's reboot, a
mobile uplink), without a word to the broker: no FIN, so no last will until its keepalive runs out
(1.5 keepalives), and the station's bridge goes on turning the rotor to its target. The remote
still hears the station: its last heartbeat is under SILENT_S (6 s) old. The operator sees the
bearing stop changing and sends STOP: the remote takes the station for heard, so the STOP is no
halt "the station's bridge may not hear" (remote/rotator.py rule 3, ``until_heard``); the broker
acknowledges it (rotctld ``RPRT 0``), hands it to the dead connection, and it is gone. The
station's bridge, back on its broker with a clean session, never gets it, and nothing sends it
again: the rotor turns on to the end of its turn, 290 degrees, after a STOP answered ``RPRT 0``.
docs/remote.md: "A stop moves nothing and is never lost".

The route heals some 1.5 s later, halfway through the turn: a STOP sent again once the
station's bridge is heard again would still stop the rotor there. Real parts: mosquitto, the
station's bridge on an emulated Rotor-EZ, the remote in this process with a rotctld endpoint;
the station's bridge reaches the broker through a TCP link this test cuts (what either side
sends is lost, neither side is told) and heals (the dead connections closed, as both sides'
keepalives end them; the bridge connects again)."""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Iterator

import pytest

from bridge.remote.run import Remote
from bridge.remote.settings import RemoteSettings
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import ask
from tests.support.rig import Rig

START_AZ, TARGET_AZ = 10.0, 300.0


class CuttableLink:
    """A TCP link on a loopback port to ``target``. ``cut``: from then on every byte either side
    sends is read and dropped, and a new connection is taken and dropped likewise, while no side
    is told (a dead route). ``heal``: the connections made before are closed, as keepalives end
    them; new ones are forwarded."""

    def __init__(self, target: int) -> None:
        self.target = target
        self._cut = threading.Event()
        self._lock = threading.Lock()
        self._socks: list[socket.socket] = []
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._server.getsockname()[1])
        threading.Thread(target=self._accept, daemon=True).start()

    def cut(self) -> None:
        self._cut.set()

    def heal(self) -> None:
        with self._lock:
            dead, self._socks = self._socks, []
            self._cut.clear()
        for s in dead:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            s.close()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self._server.accept()
            except OSError:
                return
            with self._lock:
                self._socks.append(conn)
                if self._cut.is_set():  # a dead route: taken, never answered
                    threading.Thread(target=self._pipe, args=(conn, None), daemon=True).start()
                    continue
                upstream = socket.create_connection(("127.0.0.1", self.target))
                self._socks.append(upstream)
            for a, b in ((conn, upstream), (upstream, conn)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket | None) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if dst is not None and not self._cut.is_set():
                    dst.sendall(data)
        if dst is not None:
            with contextlib.suppress(OSError):
                dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._server.close()
        self.heal()


@pytest.fixture
def route(rig: Rig) -> Iterator[CuttableLink]:
    link = CuttableLink(rig.broker.port)
    yield link
    link.close()


@pytest.fixture
def station(rig: Rig, route: CuttableLink) -> Rig:
    rig.mqtt_extra["port"] = route.port  # the station's bridge reaches its broker over the route
    rig.add("tower", emu={"start_az_deg": START_AZ, "jitter_deg": 0, "speed_deg_s": 20.0})
    rig.start()
    rig.ready("tower")
    return rig


@pytest.mark.xfail(
    strict=True,
    reason="attack 26: a STOP sent as the station's route dies is answered RPRT 0 and lost",
)
def test_a_stop_sent_as_the_stations_route_dies_still_stops_the_rotor(
    station: Rig, route: CuttableLink
) -> None:
    port = free_port()
    remote = Remote(
        RemoteSettings(
            operator="DL1ABC",
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "tower", "rotctld_port": port}],
        )
    )
    remote.start()
    try:
        emu = station.emus["tower"]
        assert ask(port, f"P {TARGET_AZ:g} 0\n".encode()) == b"RPRT 0\n"
        wait_until(lambda: emu.state().az_deg > START_AZ + 20, 10, "the rotor turning")
        route.cut()  # the station's route dies mid-turn; the remote still hears it
        cut_az = emu.state().az_deg
        said = ask(port, b"S\n")  # the operator's STOP, at once
        # the route is dead while the rotor turns on some 30 degrees (1.5 s), then heals: the
        # station's bridge connects again, a clean session, and is heard again
        wait_until(lambda: emu.state().az_deg > cut_az + 30, 10, "the rotor turning on")
        route.heal()
        rotator = remote.rotators[0]
        wait_until(lambda: rotator.away() is None, 30, "the station's bridge back")
        wait_until(lambda: not emu.state().is_moving, 30, "the rotor still")
    finally:
        remote.stop()
    az = emu.state().az_deg
    assert said in (b"RPRT 0\n", b"RPRT -5\n", b"RPRT -6\n")
    assert abs(az - TARGET_AZ) > 30, f"STOP answered {said!r}; the rotor turned on to {az:.0f}"
