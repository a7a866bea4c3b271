"""Review 69: a ``ROTOR_BRIDGE_`` variable that names no key is refused (settings rule 4), but
a container platform sets such variables without being asked. Kubernetes gives every pod the
"service links" of each Service in its namespace (enableServiceLinks is on by default): for a
Service named ``rotor-bridge`` (the console's port put behind one, the name anyone would give
it) that is ``ROTOR_BRIDGE_SERVICE_HOST``, ``ROTOR_BRIDGE_PORT=tcp://...`` and the like, in the
bridge's own pod. The bridge then refuses to start, "ROTOR_BRIDGE_PORT: unknown key 'port'",
exit 2, and the pod restarts into the same line for ever; nothing the user wrote is wrong.
(Rule 4 predates helper-593's changes; its walk of the variables is where they are read.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import cli, to_toml

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


@pytest.mark.xfail(
    strict=True,
    reason="review 69: in a Kubernetes pod beside a Service named rotor-bridge the bridge "
    "refuses to start: 'ROTOR_BRIDGE_PORT: unknown key', variables the platform set",
)
def test_the_variables_kubernetes_sets_for_a_service_named_rotor_bridge_do_not_stop_its_start(
    tmp_path: Path,
) -> None:
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
    out = cli("check-config", "-c", str(config), env=SERVICE_LINKS)
    assert out.returncode == 0, out.stderr
    assert f"config OK: {config}" in out.stdout, out.stdout
