"""Attack 12: a group's key set from the environment as a rotator's is
(``ROTOR_BRIDGE_ROTATORS__TOWER__PORT`` works; ``ROTOR_BRIDGE_GROUPS__STACK__OFFSETS`` or
``ROTOR_BRIDGE_GROUPS__0__ID`` looks the same) is read by pydantic-settings as a table that
replaces the file's ``[[groups]]`` list, and refused as "groups: Input should be a valid list":
no variable named (settings/config.py rule 4 names one for a rotator's key; errors name
the variable that set a value), so the operator looks at the file's [[groups]], which is a
valid list, and the bridge does not start."""

from __future__ import annotations

import os

import pytest

from bridge.settings import ConfigError, settings_from

FILE = {
    "rotators": [
        {"id": "upper", "model": "rotorez", "port": "/dev/ttyUSB0"},
        {"id": "lower", "model": "rotorez", "port": "/dev/ttyUSB1"},
    ],
    "groups": [{"id": "stack", "rotators": ["upper", "lower"]}],
}


@pytest.mark.parametrize(
    ("variable", "value"),
    [
        ("ROTOR_BRIDGE_GROUPS__STACK__OFFSETS", '{"lower": 180}'),
        ("ROTOR_BRIDGE_GROUPS__0__ID", "stack"),
        ("ROTOR_BRIDGE_GROUPS", '[{"id": "stack", "rotators": ["upper", "lower"]}]'),
    ],
)
def test_a_groups_key_from_the_environment_is_taken_or_refused_naming_the_variable(
    monkeypatch: pytest.MonkeyPatch, variable: str, value: str
) -> None:
    """settings/config.py rule 4: groups are the file's alone (docs/configuration.md), so
    such a variable is refused naming it."""
    monkeypatch.setenv(variable, value)
    try:
        s = settings_from({k: list(v) for k, v in FILE.items()}, os.environ)
    except ConfigError as refused:
        assert variable in str(refused), str(refused)  # said where the value came from
    else:
        assert s.groups[0].offsets == {"lower": 180.0}  # or taken, as a rotator's key is
