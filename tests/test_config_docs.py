"""The configuration as the user reads about it: docs/configuration.md is what the settings say,
config/example.toml and every TOML example in the docs load through the real settings.

Convention for the docs' examples: a ```toml block with a ``[[rotators]]`` table is a whole
file; a ```toml block without one is merged on top of BASE (one Rotor-EZ); a block fenced
otherwise (```toml-fragment, ```ini ...) is not loaded. Files the examples name (TLS, password)
are on the reader's machine: they are not opened (files_unread); serial ports never are while
loading.
"""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from unittest import mock

import pytest
from pydantic import BaseModel, ValidationError

from bridge.config_doc import COMMAND, render
from bridge.remote.settings import RemoteSettings
from bridge.settings import (
    ConfigError,
    DxClusterSettings,
    GroupSettings,
    HomeAssistantSettings,
    MqttSettings,
    RotatorSettings,
    Settings,
    StationSettings,
    TlsSettings,
    TrackingSettings,
    WebSettings,
    WsjtxSettings,
    settings_from,
)
from bridge.settings import mqtt as settings_mqtt
from bridge.settings import web as settings_web
from bridge.settings.rotator import AxisSettings
from tests.support import ROOT

DOC = ROOT / "docs" / "configuration.md"
EXAMPLE = ROOT / "config" / "example.toml"
BASE = '[[rotators]]\nid = "hf"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'


@contextlib.contextmanager
def files_unread() -> Iterator[None]:
    """The documentation's examples name files on the reader's machine (certificates, a password
    file): loaded without opening them, the pairing of cert_file and key_file still judged."""
    real = settings_mqtt.check_tls_files

    def pairing_only(ca: Path | None, cert: Path | None, key: Path | None) -> None:
        if (cert is None) != (key is None):
            real(ca, cert, key)  # raises on the pairing before it opens anything

    with (
        mock.patch.object(settings_mqtt, "check_tls_files", pairing_only),
        mock.patch.object(settings_mqtt, "read_password_file", lambda path: "s3cret"),
        mock.patch.object(settings_web, "read_password_file", lambda path: "long enough"),
    ):
        yield


FENCE = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```\s*$", re.M | re.S)


def test_the_committed_reference_is_what_the_settings_say() -> None:
    expected = render()
    if not DOC.exists() or DOC.read_text() != expected:
        pytest.fail(
            f"docs/configuration.md differs from what the settings say: run "
            f".venv/bin/python {COMMAND} and commit the result"
        )


def test_the_script_writes_the_reference_and_checks_it() -> None:
    out = subprocess.run(
        [sys.executable, str(ROOT / COMMAND), "--check"], capture_output=True, text=True
    )
    assert (out.returncode, out.stdout) == (0, ""), out.stdout + out.stderr


def is_table(annotation: Any) -> bool:
    """A table or an array of tables: a settings model, or a list of them."""
    return any(
        isinstance(t, type) and issubclass(t, BaseModel)
        for t in (annotation, *getattr(annotation, "__args__", ()))
    )


def all_models() -> list[type[BaseModel]]:
    found: list[type[BaseModel]] = []

    def walk(model: type[BaseModel]) -> None:
        found.append(model)
        for field in model.model_fields.values():
            for inner in (field.annotation, *getattr(field.annotation, "__args__", ())):
                if isinstance(inner, type) and issubclass(inner, BaseModel):
                    walk(inner)

    walk(Settings)
    return found


@pytest.mark.parametrize("model", all_models(), ids=lambda m: m.__name__)
def test_every_key_says_what_it_means_and_what_leaving_it_out_does(
    model: type[BaseModel],
) -> None:
    for name, field in model.model_fields.items():
        assert field.description and len(field.description.split()) >= 3, (model, name)
        extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
        if field.default is None or field.default_factory is not None:
            assert extra.get("unset") or is_table(field.annotation), (
                f"{model.__name__}.{name}: say what leaving it out does (unset)"
            )
        if not is_table(field.annotation):
            assert field.examples or field.default is not None, f"{model.__name__}.{name}"
            assert f"**`{name}`**" in render(), name


# the keys whose example needs another key beside it to make sense
COMPANIONS: dict[str, dict[str, Any]] = {
    "latitude_deg": {"longitude_deg": 13.4},
    "longitude_deg": {"latitude_deg": 52.5},
    "ca_file": {"enabled": True},  # (files without TLS enabled are refused)
    "cert_file": {"key_file": "/etc/rotor-bridge/client.key", "enabled": True},
    "key_file": {"cert_file": "/etc/rotor-bridge/client.crt", "enabled": True},
    "mqtt.password": {"username": "rotor"},  # (a password goes with a user name)
    "mqtt.password_file": {"username": "rotor"},
    "park_el_deg": {"park_az_deg": 0},
    "park_after_idle_s": {"park_az_deg": 0},
    "track_at_los": {"park_az_deg": 0},
    "wind_topic": {"wind_park_above": 60, "park_az_deg": 0},
    "dxcluster.enabled": {"host": "dxc.example.org", "login": "G4ABC", "cty_file": "cty.dat"},
}


TABLES: list[tuple[tuple[str, ...], type[BaseModel]]] = [
    ((), Settings),
    (("mqtt",), MqttSettings),
    (("mqtt", "tls"), TlsSettings),
    (("homeassistant",), HomeAssistantSettings),
    (("station",), StationSettings),
    (("tracking",), TrackingSettings),
    (("web",), WebSettings),
    (("wsjtx",), WsjtxSettings),
    (("dxcluster",), DxClusterSettings),
    (("rotators",), RotatorSettings),
    (("groups",), GroupSettings),
    (("rotators", "azimuth"), AxisSettings),
]


def example_documents() -> list[tuple[str, dict[str, Any]]]:
    """One document per key: its documented example in its table, on an az/el rotator."""
    assert {m for _, m in TABLES} == set(all_models())
    docs = []
    for place, model in TABLES:
        for name, field in model.model_fields.items():
            if is_table(field.annotation):
                continue  # documented key by key
            value = field.examples[0] if field.examples else field.default
            dotted = ".".join((*place, name))
            keys = {name: value, **COMPANIONS.get(dotted, COMPANIONS.get(name, {}))}
            doc: dict[str, Any] = {"rotators": [{"id": "hf", "model": "md01", "port": "/x"}]}
            if model is AxisSettings:  # a composite rotator's table
                box = {"model": "rt21", "port": "/x", **keys}
                el = {"model": "gs232b", "port": "/y"}
                docs.append((dotted, {"rotators": [{"id": "hf", "azimuth": box, "elevation": el}]}))
                continue
            target = doc["rotators"][0] if place == ("rotators",) else doc
            if place == ("groups",):  # its examples name two rotators, upper and lower
                doc["rotators"] = [
                    {"id": rid, "model": "rotorez", "port": f"/{rid}"} for rid in ("upper", "lower")
                ]
                target = {"id": "stack", "rotators": ["upper", "lower"]}
                doc["groups"] = [target]
            for part in place if place not in (("rotators",), ("groups",)) else ():
                target = target.setdefault(part, {})
            target.update(keys)
            docs.append((".".join((*place, name)), doc))
    return docs


@pytest.mark.parametrize(
    ("key", "doc"), example_documents(), ids=[k for k, _ in example_documents()]
)
def test_every_documented_example_value_is_valid(key: str, doc: dict[str, Any]) -> None:
    with files_unread():
        settings_from(doc, environ={})


# -- config/example.toml -------------------------------------------------------------------------
def test_the_example_configuration_loads_and_points_to_the_reference() -> None:
    text = EXAMPLE.read_text()
    settings = settings_from(tomllib.loads(text), environ={}, path=EXAMPLE)
    assert settings.rotators[0].model == "rotorez"
    assert "docs/configuration.md" in text
    keys = re.findall(r"^#? ?([a-z_]+) = ", text, re.M)
    assert len(keys) <= 22, keys  # the keys people change (a group too); the rest: the reference


def test_the_example_lines_are_valid_when_uncommented() -> None:
    """A user uncomments what they need: every commented key and table loads as written."""
    text = re.sub(r"^# ((?:[a-z_]+ = |\[))", r"\1", EXAMPLE.read_text(), flags=re.M)
    with files_unread():
        settings = settings_from(tomllib.loads(text), environ={})
    tower, yagi = settings.rotators
    assert settings.station.position is not None and settings.mqtt.username == "rotor"
    assert (tower.rotctld_port, tower.az_offset_deg, tower.park_az_deg) == (4533, 180, 0)
    assert yagi.model == "rot2prog"
    assert [(g.id, g.rotators) for g in settings.groups] == [("both", ["tower", "yagi"])]


def test_what_the_example_says_about_the_client_id_is_true() -> None:
    settings = settings_from(tomllib.loads(EXAMPLE.read_text()), environ={})
    client_id = settings.mqtt.effective_client_id()
    assert re.fullmatch(r"rotor-([a-z0-9-]{1,10}-)?[0-9a-f]{6}", client_id), client_id
    assert "rotor-<host>-<6 hex digits>" in EXAMPLE.read_text()


# -- the TOML examples in README.md and docs/ ----------------------------------------------------
def toml_blocks() -> list[tuple[str, str]]:
    found = []
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text()
        for match in FENCE.finditer(text):
            if match.group(1) == "toml":
                line = text[: match.start()].count("\n") + 1
                found.append((f"{path.relative_to(ROOT)}:{line}", match.group(2)))
    return found


def merge(base: dict[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


def test_the_docs_have_toml_examples() -> None:
    assert any(where.startswith("docs/configuration.md") for where, _ in BLOCKS)


BLOCKS = toml_blocks()


@pytest.mark.parametrize(("where", "block"), BLOCKS, ids=[w for w, _ in BLOCKS])
def test_every_toml_example_in_the_docs_loads(where: str, block: str) -> None:
    try:
        doc = tomllib.loads(block)
    except tomllib.TOMLDecodeError as exc:
        pytest.fail(f"{where}: not TOML ({exc}); fence it as ```toml-fragment if it is a part")
    if "endpoints" in doc:  # a remote.toml (docs/remote.md): the remote's own settings
        try:
            with files_unread():
                RemoteSettings(**doc)
        except ValidationError as exc:
            pytest.fail(f"{where}: not a remote.toml the remote takes: {exc}")
        return
    if "rotators" not in doc:
        doc = merge(tomllib.loads(BASE), doc)
    try:
        with files_unread():
            settings_from(doc, environ={})
    except ConfigError as exc:
        pytest.fail(
            f"{where}: {exc}\n(a block with [[rotators]] is a whole file; one without is added "
            "to BASE; a part of a file is fenced as ```toml-fragment)"
        )
