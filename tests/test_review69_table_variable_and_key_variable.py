"""Review 69: 2bfa58c0 refuses two variables of which "the first sets a table whole and the
second a key in it", saying "which the bridge took would depend on their order". For a table
of the top (``[mqtt]``, ``[web]``...) it does not: pydantic-settings reads the table's JSON and
lays the key's variable over it, in either order, and the bridge took both (the key's value
for that key, the JSON for the others). deploy/docker/compose.yaml sets
``ROTOR_BRIDGE_MQTT__HOST`` and ``__PORT`` for everyone; a user who adds the rest of ``[mqtt]``
as one ``ROTOR_BRIDGE_MQTT`` JSON variable had a bridge that started before the change and is
refused after it, exit 2, for an order that never mattered."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support import cli
from tests.test_review69_container_variables import one_rotor_config


def test_a_table_in_json_beside_a_variable_of_one_of_its_keys_is_both(tmp_path: Path) -> None:
    config = one_rotor_config(tmp_path)
    env = {  # compose.yaml's two, and the rest of [mqtt] in one variable
        "ROTOR_BRIDGE_MQTT__HOST": "192.168.1.10",
        "ROTOR_BRIDGE_MQTT__PORT": "1884",
        "ROTOR_BRIDGE_MQTT": '{"base_topic": "shack", "client_id": "rotor-bridge-docker"}',
    }
    out = cli("check-config", "-c", str(config), env=env)
    assert out.returncode == 0, out.stderr
    assert "broker: 192.168.1.10:1884," in out.stdout, out.stdout
    assert "client id rotor-bridge-docker" in out.stdout, out.stdout
    assert "topic shack;" in out.stdout, out.stdout


@pytest.mark.parametrize("json_first", [True, False], ids=["JSON first", "key first"])
def test_the_key_variable_is_the_value_whatever_the_order(tmp_path: Path, json_first: bool) -> None:
    """Where the table's JSON sets the key too, the bridge takes the key's own variable, in
    either order of the environment: the one result the refusal was there to make sure of."""
    config = one_rotor_config(tmp_path)
    table = ("ROTOR_BRIDGE_MQTT", '{"host": "10.0.0.1", "port": 1885, "base_topic": "shack"}')
    key = ("ROTOR_BRIDGE_MQTT__HOST", "192.168.1.10")
    out = cli(
        "check-config", "-c", str(config), env=dict([table, key] if json_first else [key, table])
    )
    assert out.returncode == 0, out.stderr
    assert "broker: 192.168.1.10:1885," in out.stdout, out.stdout
    assert "topic shack;" in out.stdout, out.stdout


def test_a_table_below_the_top_in_json_beside_a_variable_of_its_key_is_still_refused(
    tmp_path: Path,
) -> None:
    """``[mqtt.tls]`` is laid in the environment's order (pydantic-settings' explode_env_vars):
    there the order decides, and the two stay refused (2bfa58c0's case)."""
    config = one_rotor_config(tmp_path)
    env = {
        "ROTOR_BRIDGE_MQTT__TLS": '{"ca_file": "/etc/ssl/a.pem"}',
        "ROTOR_BRIDGE_MQTT__TLS__CA_FILE": "/etc/ssl/b.pem",
    }
    out = cli("check-config", "-c", str(config), env=env)
    assert out.returncode == 2, out.stdout
    assert (
        "ROTOR_BRIDGE_MQTT__TLS, ROTOR_BRIDGE_MQTT__TLS__CA_FILE: the first sets a table whole"
        in out.stderr
    ), out.stderr
