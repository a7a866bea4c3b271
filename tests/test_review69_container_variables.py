"""Review 69: a ``ROTOR_BRIDGE_`` variable that names no key is refused (settings rule 4), but
a container platform sets such variables without being asked. Kubernetes gives every pod the
"service links" of each Service in its namespace (enableServiceLinks is on by default): for a
Service named ``rotor-bridge`` (the console's port put behind one, the name anyone would give
it) that is ``ROTOR_BRIDGE_SERVICE_HOST``, ``ROTOR_BRIDGE_PORT=tcp://...`` and the like, in the
bridge's own pod. The bridge then refuses to start, "ROTOR_BRIDGE_PORT: unknown key 'port'",
exit 2, and the pod restarts into the same line for ever; nothing the user wrote is wrong.
(Rule 4 predates helper-593's changes; its walk of the variables is where they are read.)"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.support import BridgeProcess, bridge_env, cli, to_toml, wait_until
from tests.support.mosquitto import Mosquitto
from tests.support.process import ROOT

# what Kubernetes puts in a pod's environment for a Service "rotor-bridge" with one port, 8754,
# named "web" (the docker-links-style variables and the SERVICE_* ones)
SERVICE_LINKS = {
    "ROTOR_BRIDGE_SERVICE_HOST": "10.96.0.12",
    "ROTOR_BRIDGE_SERVICE_PORT": "8754",
    "ROTOR_BRIDGE_SERVICE_PORT_WEB": "8754",
    "ROTOR_BRIDGE_PORT": "tcp://10.96.0.12:8754",
    "ROTOR_BRIDGE_PORT_8754_TCP": "tcp://10.96.0.12:8754",
    "ROTOR_BRIDGE_PORT_8754_TCP_PROTO": "tcp",
    "ROTOR_BRIDGE_PORT_8754_TCP_PORT": "8754",
    "ROTOR_BRIDGE_PORT_8754_TCP_ADDR": "10.96.0.12",
}


def one_rotor_config(tmp_path: Path) -> Path:
    """A configuration file of one Rotor-EZ and a broker, none of it set by the variables under
    test."""
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": tmp_path / "state.json",
                "mqtt": {"host": "127.0.0.1"},
                "rotators": [{"id": "tower", "model": "rotorez", "port": "/dev/rotor"}],
            }
        )
    )
    return config


def test_the_variables_kubernetes_sets_for_a_service_named_rotor_bridge_do_not_stop_its_start(
    tmp_path: Path,
) -> None:
    config = one_rotor_config(tmp_path)
    out = cli("check-config", "-c", str(config), env=SERVICE_LINKS)
    assert out.returncode == 0, out.stderr
    assert f"config OK: {config}" in out.stdout, out.stdout


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("ROTOR_BRIDGE_PORT", "/dev/ttyUSB0"),  # a rotator's port, set at the wrong level
        ("ROTOR_BRIDGE_SERVICE_HOST", "broker.example.org"),  # no address: no Kubernetes'
        ("ROTOR_BRIDGE_PORT_8754_TCP_PORT", "1883"),  # not the port its name says
        ("ROTOR_BRIDGE_PORT_8754_TCP_HOST", "10.96.0.12"),  # no such variable of Kubernetes
        ("rotor_bridge_port", "tcp://10.96.0.12:8754"),  # Kubernetes spells them in capitals
    ],
)
def test_a_variable_only_like_a_service_link_is_still_refused(
    tmp_path: Path, name: str, value: str
) -> None:
    config = one_rotor_config(tmp_path)
    out = cli("check-config", "-c", str(config), env={**SERVICE_LINKS, name: value})
    assert out.returncode == 2, out.stdout
    assert out.stderr.startswith(f"rotor-bridge: {name}: unknown key"), out.stderr


def test_the_running_bridge_says_once_which_variables_it_ignored(
    tmp_path: Path, broker: Mosquitto
) -> None:
    def spawn(argv: list[str], log_path: Path) -> subprocess.Popen[bytes]:
        with open(log_path, "ab") as log:
            return subprocess.Popen(
                argv, stdout=log, stderr=subprocess.STDOUT, env=bridge_env(SERVICE_LINKS), cwd=ROOT
            )

    bridge = BridgeProcess(
        tmp_path,
        {
            "state_file": str(tmp_path / "state.json"),
            "mqtt": {"host": "127.0.0.1", "port": broker.port},
            "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp_path / "tty")}],
        },
        log_level="INFO",
        spawn=spawn,
    ).start()
    try:
        wait_until(
            lambda: not bridge.alive() or "Kubernetes" in bridge.log(),
            what="the bridge to start and say what it ignored",
        )
        bridge.check()  # started, not refused
    finally:
        if bridge.alive():
            bridge.terminate()
    said = [line for line in bridge.log().splitlines() if "Kubernetes" in line]
    assert len(said) == 1, bridge.log()
    assert " INFO " in said[0], said[0]
    assert all(name in said[0] for name in SERVICE_LINKS), said[0]
