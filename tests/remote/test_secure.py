"""``rotor-bridge remote`` the way it is deployed: the station's mosquitto with a TLS listener
(certificates of our own authority, made here with openssl), a password file (mosquitto_passwd)
and an access list, configured as docs/deployment.md prints it (its mosquitto.conf and ACL
blocks are read from there, so they cannot drift); the station's bridge on an emulated Rotor-EZ
logs in as the station user, the remote as the operator. Hamlib's ``rotctl -m 2`` is the
remote's client (the judge).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho
import pytest
from paho.mqtt.enums import CallbackAPIVersion
from pydantic import SecretStr

from bridge.remote.run import Remote, StartError
from bridge.remote.settings import RemoteSettings
from tests.faults.conftest import Pki, mosquitto_password_file
from tests.remote.test_remote import rotctl
from tests.support import ROOT, Probe, wait_until
from tests.support.mosquitto import Mosquitto, free_port
from tests.support.rig import Rig
from tests.support.waiting import slow

pytestmark = pytest.mark.hamlib

DEPLOYMENT = ROOT / "docs" / "deployment.md"
OPERATOR = "DL1ABC"
STATION_USER, OPERATOR_USER = "station", "dl1abc"
PASSWORDS = {STATION_USER: "station-S3cret", OPERATOR_USER: "operator-S3cret"}


def documented(first_line: str) -> str:
    """The fenced block of docs/deployment.md that starts with ``first_line``."""
    found = re.search(rf"```\w*\n({re.escape(first_line)}\n.*?)```", DEPLOYMENT.read_text(), re.S)
    assert found, f"docs/deployment.md has no fenced block starting {first_line!r}"
    return found.group(1)


def documented_acl() -> str:
    return documented("# /etc/mosquitto/rotor.acl")


def documented_broker_conf(files: dict[str, Path]) -> str:
    """The broker's configuration as docs/deployment.md prints it, on this test's files; its
    listener is the test's own (Mosquitto writes it: a free port on loopback)."""
    conf = documented("# /etc/mosquitto/conf.d/rotor.conf")
    assert "\nlistener 8883\n" in conf
    conf = conf.replace("\nlistener 8883\n", "\n")
    for documented_path, path in files.items():
        assert documented_path in conf, documented_path
        conf = conf.replace(documented_path, str(path))
    assert "/etc/" not in conf.replace("# /etc/mosquitto/conf.d/rotor.conf", ""), conf
    return conf


@dataclass
class Secure:
    """The station's broker with TLS, logins and the documented access list."""

    broker: Mosquitto
    pki: Pki
    tmp: Path

    def secret(self, user: str, password: str | None = None) -> Path:
        path = self.tmp / f"{user}-password"
        path.write_text((password or PASSWORDS[user]) + "\n")
        os.chmod(path, 0o600)
        return path

    def mqtt(self, user: str, password: str | None = None, ca: str = "ca.crt") -> dict[str, Any]:
        """An ``[mqtt]`` table that logs in as ``user`` over TLS, trusting ``ca``."""
        return {
            "host": "127.0.0.1",
            "port": self.broker.port,
            "username": user,
            "password_file": str(self.secret(user, password)),
            "tls": {"enabled": True, "ca_file": str(self.pki.path(ca))},
        }

    def login(self, user: str, topic_filter: str = "#") -> Probe:
        """A probe logged in as ``user`` over TLS (no client certificate: passwords only)."""
        return Probe(
            self.broker.port,
            topic_filter,
            username=user,
            password=PASSWORDS[user],
            tls={"ca_certs": str(self.pki.path("ca.crt"))},
        )


@pytest.fixture
def secure(tmp_path: Path) -> Iterator[Secure]:
    pki = Pki(tmp_path / "pki")
    passwd = mosquitto_password_file(tmp_path / "passwd", PASSWORDS)
    acl = tmp_path / "rotor.acl"
    acl.write_text(documented_acl())
    files = {
        "/etc/mosquitto/certs/station.crt": pki.path("server.crt"),
        "/etc/mosquitto/certs/station.key": pki.path("server.key"),
        "/etc/mosquitto/passwd": passwd,
        "/etc/mosquitto/rotor.acl": acl,
    }
    # user root: read the files in the test's private temp dir (no effect unless root)
    conf = "user root\nset_tcp_nodelay true\n" + documented_broker_conf(files)
    broker = Mosquitto(tmp_path / "broker", extra_conf=conf).start()
    yield Secure(broker, pki, tmp_path)
    broker.stop()


@pytest.fixture
def station(secure: Secure) -> Iterator[Rig]:
    probe = secure.login(STATION_USER)
    with Rig(secure.tmp, secure.broker, probe) as rig:
        rig.mqtt_extra = secure.mqtt(STATION_USER)
        rig.add("tower", emu={"start_az_deg": 10, "jitter_deg": 0})
        rig.start()
        rig.ready("tower", 20)
        yield rig
    probe.close()


def remote_settings(secure: Secure, port: int, **mqtt: Any) -> RemoteSettings:
    return RemoteSettings(
        operator=OPERATOR,
        mqtt={**secure.mqtt(OPERATOR_USER), "base_topic": "rotor", **mqtt},
        endpoints=[{"rotator": "tower", "rotctld_port": port}],
        info_wait_s=10,
    )


def test_rotctl_through_tls_and_logins_turns_the_station_rotator_and_reads_it_back(
    secure: Secure, station: Rig, rotctl_path: str
) -> None:
    port = free_port()
    remote = Remote(remote_settings(secure, port))
    lines = remote.start()
    try:
        assert lines == [
            f"{OPERATOR} -> 127.0.0.1: tower (rotorez, 0..360) on rotctld 127.0.0.1:{port}"
        ]
        rotctl(rotctl_path, port, "P", "120", "0")
        station.arrived("tower", 120)
        wait_until(lambda: station.status("tower").state == "idle", 10, "the bridge idle")
        wait_until(
            lambda: remote.rotators[0].status.bearing_deg == station.status("tower").bearing_deg,
            10,
            "the remote has the station's final bearing",
        )
        az, el = rotctl(rotctl_path, port, "p").split()
        assert abs(float(az) - 120) <= 3.5 and float(el) == 0
    finally:
        remote.stop()


def test_the_operator_cannot_forge_the_station_state(secure: Secure, station: Rig) -> None:
    """The access list binds: what the operator's user publishes on the bridge's topics reaches
    no one and is not kept; its commands do reach the station (the marker proves it)."""
    forged = {
        "rotor/status": b'{"bearing":321.0,"state":"idle","forged":true}',
        "rotor/availability": b"offline",
        "rotor/bridge/state": b"offline",
        "rotor/info": b"{}",
    }
    operator = paho.Client(CallbackAPIVersion.VERSION2, client_id="forger", protocol=paho.MQTTv5)
    operator.username_pw_set(OPERATOR_USER, PASSWORDS[OPERATOR_USER])
    operator.tls_set(ca_certs=str(secure.pki.path("ca.crt")))
    operator.connect("127.0.0.1", secure.broker.port)
    operator.loop_start()
    start = station.probe.mark()
    try:
        for topic, payload in forged.items():
            operator.publish(topic, payload, qos=1, retain=True).wait_for_publish(5)
        # a command the operator may send, behind the forgeries on one connection: when it
        # reaches the station's user, anything the broker let through would have come first
        operator.publish("rotor/stop", b"stop", qos=1).wait_for_publish(5)
        station.probe.wait(lambda m: m.topic == "rotor/stop", 10, "the operator's stop", start)
    finally:
        operator.loop_stop()
        operator.disconnect()
    seen = station.probe.messages[start:]
    assert not [m for m in seen if m.topic in forged and m.payload == forged[m.topic]]
    # what a newcomer gets is still the station's own word
    fresh = secure.login(STATION_USER, "rotor/#")
    try:
        wait_until(lambda: all(fresh.last(t) for t in forged), 10, "the retained topics")
        retained = {m.topic: m.payload for m in fresh.messages if m.retain}
    finally:
        fresh.close()
    for topic, payload in forged.items():
        assert retained.get(topic) != payload, topic
    assert retained["rotor/availability"] == b"online"
    assert retained["rotor/bridge/state"] == b"online"
    assert b'"forged"' not in retained["rotor/status"]


def start_remote_process(
    secure: Secure, tmp: Path, password: str | None = None, ca: str = "ca.crt"
) -> subprocess.CompletedProcess[str]:
    mqtt = secure.mqtt(OPERATOR_USER, password, ca)
    conf = tmp / "remote.toml"
    conf.write_text(
        f'operator = "{OPERATOR}"\ninfo_wait_s = 20\n[mqtt]\nhost = "127.0.0.1"\n'
        f"port = {mqtt['port']}\n"
        f'username = "{OPERATOR_USER}"\npassword_file = "{mqtt["password_file"]}"\n'
        f'[mqtt.tls]\nenabled = true\nca_file = "{mqtt["tls"]["ca_file"]}"\n'
        f"[[endpoints]]\nrotctld_port = {free_port()}\n"
    )
    argv = [sys.executable, "-m", "bridge", "remote", "-c", str(conf)]
    return subprocess.run(argv, capture_output=True, text=True, timeout=slow(60), check=False)


@pytest.mark.parametrize(
    ("password", "ca", "said"),
    [
        ("not-the-password", "ca.crt", r"refused the login .*Not authorized.*mqtt\.username"),
        (None, "rogue-ca.crt", r"TLS.*certificate verify failed.*mqtt\.tls\.ca_file"),
    ],
    ids=["wrong password", "untrusted authority"],
)
def test_a_login_or_tls_problem_is_one_line_at_start_naming_it(
    secure: Secure, tmp_path: Path, password: str | None, ca: str, said: str
) -> None:
    done = start_remote_process(secure, tmp_path, password, ca)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert re.search(said, lines[0]), lines[0]
    assert lines[0].startswith("rotor-bridge remote: cannot reach the station's broker at ")
    assert "Traceback" not in done.stderr and PASSWORDS[OPERATOR_USER] not in done.stderr


def test_the_in_process_start_error_says_the_same(secure: Secure) -> None:
    s = remote_settings(secure, free_port())
    s.mqtt.password = SecretStr("not-the-password")
    with pytest.raises(StartError, match=r"refused the login"):
        Remote(s).start()


def test_anonymous_clients_are_turned_away(secure: Secure) -> None:
    """Without a login nothing is read: the station's state stays between its users."""
    c = paho.Client(CallbackAPIVersion.VERSION2, client_id="anon", protocol=paho.MQTTv5)
    codes: list[Any] = []
    c.on_connect = lambda cl, ud, fl, rc, pr: codes.append(rc)
    c.tls_set(ca_certs=str(secure.pki.path("ca.crt")))
    c.connect("127.0.0.1", secure.broker.port)
    c.loop_start()
    try:
        wait_until(lambda: codes, 10, "the broker's answer")
    finally:
        c.loop_stop()
    assert codes[0].is_failure, codes
