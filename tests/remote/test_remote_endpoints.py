"""``rotor-bridge remote``'s GS-232B, Easycomm II and PstRotator endpoints with real parts: a
mosquitto, the bridge on an emulated Rotor-EZ, the remote in this process, and the clients
the operator's programs are (Hamlib's ``rotctl -m 603`` on a pty and on a TCP port, a
PstRotator UDP client written from the protocol fact sheet) as the judges.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from bridge.emulators.rotorez_models import BEARING_OUTCOMES
from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.integration.test_dcu1_endpoint import ROTOR_EZ
from tests.integration.test_gs232_integration import EASYCOMM, GS232, gs232_ask, rotctl
from tests.remote.test_remote import OPERATOR
from tests.support import wait_until
from tests.support.mosquitto import free_port
from tests.support.remote import remote_published
from tests.support.rig import Rig
from tests.support.udp_logger import PstClient, minos_reply, reserve_pst_ports, tag
from tests.support.waiting import slow

pytestmark = pytest.mark.hamlib


class Endpoints:
    """The remote with every kind of endpoint onto the station's ``tower``."""

    def __init__(self, station: Rig, tmp_path: Path) -> None:
        self.gs232_port, self.easycomm_port = free_port(), free_port()
        while self.easycomm_port == self.gs232_port:
            self.easycomm_port = free_port()
        self.pst_port, self.pst_replies = reserve_pst_ports()
        self.gs232_pty = str(tmp_path / "rotor-gs232")
        self.easycomm_pty = str(tmp_path / "rotor-easycomm")
        self.remote = Remote(
            RemoteSettings(
                operator=OPERATOR,
                mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
                endpoints=[
                    {
                        "rotator": "tower",
                        "gs232_port": self.gs232_port,
                        "gs232_pty": self.gs232_pty,
                        "easycomm_port": self.easycomm_port,
                        "easycomm_pty": self.easycomm_pty,
                        "pst_udp_port": self.pst_port,
                    }
                ],
            )
        )
        self.lines = self.remote.start()

    def pst(self) -> PstClient:
        return PstClient(self.pst_port, replies=self.pst_replies)

    def stop(self) -> None:
        self.remote.stop()
        self.pst_replies.close()


@pytest.fixture
def endpoints(station: Rig, tmp_path: Path) -> Iterator[Endpoints]:
    e = Endpoints(station, tmp_path)
    yield e
    e.stop()


def remote_sees(e: Endpoints, station: Rig) -> bool:
    """The remote's view of the bearing is the station's."""
    return e.remote.rotators[0].status.bearing_deg == station.status("tower").bearing_deg


def test_the_start_line_names_every_endpoint(endpoints: Endpoints) -> None:
    e = endpoints
    assert e.lines == [
        f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on "
        f"gs232 127.0.0.1:{e.gs232_port}, easycomm 127.0.0.1:{e.easycomm_port}, "
        f"pst udp 127.0.0.1:{e.pst_port}, gs232 {e.gs232_pty}, easycomm {e.easycomm_pty}"
    ]
    assert os.readlink(e.gs232_pty).startswith("/dev/pts/")


def test_rotctl_on_the_remote_gs232_pty_turns_the_station_and_reads_it_on_tcp(
    station: Rig, endpoints: Endpoints, rotctl_path: str
) -> None:
    e = endpoints
    rotctl(rotctl_path, GS232, e.gs232_pty, "P", "120", "0")
    station.arrived("tower", 120)
    wait_until(lambda: station.status("tower").state == "idle", 10, "the bridge idle")
    wait_until(lambda: remote_sees(e, station), 10, "the remote's view of the bearing")
    bearing = station.status("tower").bearing_deg
    for model, where in ((GS232, e.gs232_port), (EASYCOMM, e.easycomm_pty)):
        az, el = rotctl(rotctl_path, model, where, "p").split()
        assert abs(float(az) - bearing) <= 0.5 and float(el) == 0
    rotctl(rotctl_path, GS232, e.gs232_port, "P", "200", "0")
    station.arrived("tower", 200)


def test_the_pst_endpoint_answers_az_with_the_station_bearing_and_turns_it(
    station: Rig, endpoints: Endpoints
) -> None:
    e = endpoints
    wait_until(lambda: remote_sees(e, station), 10, "the remote's view of the bearing")
    with e.pst() as client:
        name, value = minos_reply(client.ask("AZ"))
        assert name == "AZ" and abs(value - 10) <= 1
        client.command(tag("AZIMUTH", 75))
        station.arrived("tower", 75)
        wait_until(lambda: station.status("tower").state == "idle", 10, "the bridge idle")
        wait_until(lambda: remote_sees(e, station), 10, "the remote's view of the bearing")
        assert abs(minos_reply(client.ask("AZ"))[1] - 75) <= 1
        assert client.stray() is None  # the reply went to port + 1 only


def test_broker_away_refuses_at_once_and_nothing_moves_when_it_is_back(
    station: Rig, endpoints: Endpoints, caplog: pytest.LogCaptureFixture
) -> None:
    e = endpoints
    emu = station.emus["tower"]
    link = e.remote.link
    assert link is not None
    moves = len(emu.frames(*BEARING_OUTCOMES))
    station.broker.kill()
    wait_until(lambda: not link.up, 30, "the remote sees the broker gone")
    gs232_ask(e.gs232_port, b"W250 000\r", b"?>\r\n")  # refused, not queued
    gs232_ask(e.gs232_port, b"C2\r", b"?>\r\n")  # no stale number
    with caplog.at_level(logging.WARNING, logger="bridge.remote.rotator"):
        with e.pst() as client:
            client.command(tag("AZIMUTH", 300))
            client.send(b"<PST>AZ?</PST>")  # answered by nothing: no stale number
            assert client.reply(0.5) is None  # the wait is the thing under test: no reply
        wait_until(
            lambda: "pst <PST><AZIMUTH>300</AZIMUTH></PST> refused" in caplog.text,
            5,
            "the PST target logged as refused",
        )
    log_from = station.broker.log.stat().st_size
    station.broker.restart()
    wait_until(lambda: link.up, 30, "the remote back on the broker")
    station.ready("tower", 30)
    gs232_ask(e.gs232_port, b"S\r", b"")  # a marker behind anything sent again
    wait_until(lambda: b"stop" in remote_published(station.broker, log_from), 10, "the marker stop")
    assert remote_published(station.broker, log_from) == [b"stop"]
    assert len(emu.frames(*BEARING_OUTCOMES)) == moves


def test_a_pty_path_held_by_a_file_is_a_start_error_and_nothing_stays(
    station: Rig, tmp_path: Path
) -> None:
    path = tmp_path / "ttyS0"
    path.write_text("")
    port = free_port()
    s = RemoteSettings(
        operator=OPERATOR,
        mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
        endpoints=[{"rotator": "tower", "rotctld_port": port, "gs232_pty": str(path)}],
    )
    with pytest.raises(StartError, match=r"cannot link a pty at .*ttyS0.*gs232_pty"):
        Remote(s).start()
    assert path.read_text() == ""
    with socket.socket() as sock:  # the rotctld port was let go
        sock.bind(("127.0.0.1", port))


def test_the_command_line_serves_a_pty_and_removes_its_link_on_sigterm(
    station: Rig, tmp_path: Path, rotctl_path: str
) -> None:
    link = tmp_path / "rotor-gs232"
    conf = tmp_path / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\n[mqtt]\nport = {station.broker.port}\n'
        f'[[endpoints]]\ngs232_pty = "{link}"\n'
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line == f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on gs232 {link}\n"
        az, _ = rotctl(rotctl_path, GS232, str(link), "p").split()
        assert abs(float(az) - 10) <= 1
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(slow(10)) == 0
        assert not os.path.lexists(link)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_a_pst_port_beyond_loopback_is_warned_about(
    station: Rig, caplog: pytest.LogCaptureFixture
) -> None:
    """remote/__init__.py rule 4, as the TCP ports (interfaces/tcplines.py) have it: no login on
    UDP."""
    port, replies = reserve_pst_ports()
    remote = Remote(
        RemoteSettings(
            operator=OPERATOR,
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[{"rotator": "tower", "pst_udp_port": port, "pst_udp_bind": "0.0.0.0"}],
        )
    )
    try:
        with caplog.at_level(logging.WARNING, logger="bridge.remote.run"):
            remote.start()
    finally:
        remote.stop()
        replies.close()
    assert (
        f"PstRotator UDP for tower listens on 0.0.0.0:{port}: it has no authentication, anyone "
        "who can reach this address can turn the antenna"
    ) in caplog.messages


def test_the_remote_dcu1_and_gs232a_endpoints_turn_read_and_stop_the_station(
    station: Rig, tmp_path: Path, rotctl_path: str
) -> None:
    """The Windows loggers on the operator's computer: DCU-1 on a pty (Hamlib's Rotor-EZ back
    end as the judge) and on TCP (what DXView sends), GS-232A readings for ARSVCOM."""
    dcu1_port, gs232_port = free_port(), free_port()
    while gs232_port == dcu1_port:
        gs232_port = free_port()
    dcu1_pty = str(tmp_path / "rotor-dcu1")
    remote = Remote(
        RemoteSettings(
            operator=OPERATOR,
            mqtt={"host": "127.0.0.1", "port": station.broker.port, "base_topic": "rotor"},
            endpoints=[
                {
                    "rotator": "tower",
                    "dcu1_port": dcu1_port,
                    "dcu1_pty": dcu1_pty,
                    "gs232_port": gs232_port,
                    "gs232_replies": "A",
                }
            ],
        )
    )
    try:
        lines = remote.start()
        assert lines == [
            f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on gs232 127.0.0.1:{gs232_port}, "
            f"dcu1 127.0.0.1:{dcu1_port}, dcu1 {dcu1_pty}"
        ]
        rotctl(rotctl_path, ROTOR_EZ, dcu1_pty, "P", "150", "0")
        station.arrived("tower", 150)
        wait_until(lambda: station.status("tower").state == "idle", 10, "the bridge idle")
        wait_until(lambda: remote.rotators[0].status.bearing_deg == 150, 10, "the remote's view")
        az, _ = rotctl(rotctl_path, ROTOR_EZ, dcu1_pty, "p").split()
        assert float(az) == 150
        gs232_ask(gs232_port, b"C2\r", b"+0150+0000\r\n")
        emu = station.emus["tower"]
        with socket.create_connection(("127.0.0.1", dcu1_port), timeout=slow(5)) as dxview:
            dxview.sendall(b"AP1010;AM1;")
            emu.wait_for(lambda s: s.is_moving and s.az_deg < 120, 15)
            dxview.sendall(b";")
            stopped = emu.wait_for(lambda s: not s.is_moving, 5)
        assert stopped.az_deg > 20
    finally:
        remote.stop()
    assert not os.path.lexists(dcu1_pty)


def test_a_refused_datagram_cannot_write_a_line_of_its_own_in_the_remotes_log(
    station: Rig, endpoints: Endpoints, caplog: pytest.LogCaptureFixture
) -> None:
    """A PstRotator tag the bridge does not read may hold a line break, and the remote logged a
    refused datagram's words as they came: a line of the remote's log, forged by whoever can
    send it a datagram. The station's log escapes them (service.py rule 4); so does the
    remote's."""
    forged = "\nWARNING bridge.remote.run: the station says: all clear"
    with caplog.at_level(logging.WARNING, logger="bridge.remote.rotator"):
        with endpoints.pst() as client:
            client.command(tag("NOTE", forged), tag("AZIMUTH", 999))  # refused: out of range
        wait_until(lambda: "azimuth 999 outside" in caplog.text, 5, "the refusal logged")
    assert not any("\nWARNING" in r.getMessage() for r in caplog.records)
    assert "\\nWARNING bridge.remote.run" in caplog.text
