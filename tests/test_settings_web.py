"""``[web]`` and ``beamwidth_deg``: the console's settings as a user writes them, loaded through
the real loader from TOML files, and what check-config says about them."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from bridge.settings import ConfigError, Settings, load_settings
from bridge.settings.report import config_warnings, masked
from tests.support import cli

ROTATOR = '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'
PASSWORD = "correct horse battery"


def load(tmp_path: Path, text: str, **environ: str) -> Settings:
    path = tmp_path / "c.toml"
    path.write_text(text + ROTATOR)
    return load_settings(path, environ=environ)


def refused(tmp_path: Path, text: str) -> str:
    with pytest.raises(ConfigError) as err:
        load(tmp_path, text)
    return str(err.value)


def password_file(tmp_path: Path, text: str, mode: int = 0o600) -> Path:
    path = tmp_path / "web-password"
    path.write_text(text)
    os.chmod(path, mode)
    return path


def test_the_console_is_off_on_loopback_without_a_password_by_default(tmp_path: Path) -> None:
    w = load(tmp_path, "").web
    assert (w.enabled, w.bind, w.port, w.password_file, w.frame_ancestors) == (
        False,
        "127.0.0.1",
        8754,
        None,
        [],
    )
    assert w.password is None


@pytest.mark.parametrize("bind", ["127.0.0.1", "::1", "localhost", "127.0.0.2"])
def test_on_loopback_the_console_needs_no_password(tmp_path: Path, bind: str) -> None:
    w = load(tmp_path, f'[web]\nenabled = true\nbind = "{bind}"\n').web
    assert w.enabled and w.bind == bind and w.password is None


@pytest.mark.parametrize("bind", ["0.0.0.0", "::", "", "192.168.1.5", "shack.lan"])
def test_beyond_loopback_without_a_password_is_an_error_naming_the_risk(
    tmp_path: Path, bind: str
) -> None:
    said = refused(tmp_path, f'[web]\nenabled = true\nbind = "{bind}"\n')
    assert "web.bind" in said and "anyone who can reach that address could turn the antenna" in said
    assert "web.password_file" in said and "reverse proxy" in said
    # the same bind with the console off is no risk
    assert load(tmp_path, f'[web]\nbind = "{bind}"\n').web.bind == bind


def test_the_password_is_read_from_its_file_and_never_shown(tmp_path: Path) -> None:
    path = password_file(tmp_path, PASSWORD + "\n")
    s = load(tmp_path, f'[web]\nenabled = true\nbind = "0.0.0.0"\npassword_file = "{path}"\n')
    assert s.web.password is not None and s.web.password.get_secret_value() == PASSWORD
    assert PASSWORD not in repr(s.web) + str(masked(s)) + s.model_dump_json()
    assert masked(s)["web"]["password_file"] == str(path)


def test_a_password_file_every_user_may_read_is_refused(tmp_path: Path) -> None:
    path = password_file(tmp_path, PASSWORD + "\n", mode=0o644)
    said = refused(tmp_path, f'[web]\nenabled = true\npassword_file = "{path}"\n')
    assert f"password_file {path} is readable by every user" in said and PASSWORD not in said


def test_a_missing_password_file_is_an_error_naming_it(tmp_path: Path) -> None:
    said = refused(tmp_path, f'[web]\npassword_file = "{tmp_path / "nope"}"\n')
    assert f"web: password_file {tmp_path / 'nope'}" in said


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("", "is empty"),
        ("\n", "is empty"),
        ("seven77\n", "shorter than 8 characters"),
        ("first line\nsecond line\n", "more than one line"),
    ],
)
def test_an_empty_short_or_multi_line_password_is_refused(
    tmp_path: Path, text: str, said: str
) -> None:
    path = password_file(tmp_path, text)
    message = refused(tmp_path, f'[web]\nenabled = true\npassword_file = "{path}"\n')
    assert f"web: password_file {path}" in message and said in message
    assert not text.strip() or text.split()[0] not in message  # the password is never quoted


def test_the_password_itself_cannot_be_written_in_the_configuration(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    said = refused(tmp_path, f'[web]\npassword = "{PASSWORD}"\n')
    assert "web.password_file" in said and PASSWORD not in said
    monkeypatch.setenv("ROTOR_BRIDGE_WEB__PASSWORD", PASSWORD)  # nor in the environment
    said = refused(tmp_path, "")
    assert "web.password_file" in said and PASSWORD not in said


def test_frame_ancestors_are_origins(tmp_path: Path) -> None:
    text = (
        '[web]\nframe_ancestors = ["http://homeassistant.local:8123", '
        '"https://ha.example.org/", "http://[fd00::1]:8123", "http://192.168.1.10"]\n'
    )
    assert load(tmp_path, text).web.frame_ancestors == [
        "http://homeassistant.local:8123",
        "https://ha.example.org",  # the address bar's '/' is the same origin
        "http://[fd00::1]:8123",
        "http://192.168.1.10",
    ]


@pytest.mark.parametrize(
    "bad",
    [
        "http://homeassistant.local:8123/lovelace",
        "homeassistant.local:8123",
        "ftp://ha.lan",
        "http://ha.lan:99999",
        "http://ha.lan; script-src *",
        "'self'",
        "*",
        "http://user@ha.lan",
        "http://ha.lan?x=1",
    ],
)
def test_a_frame_ancestor_that_is_no_origin_is_refused_by_name(tmp_path: Path, bad: str) -> None:
    said = refused(tmp_path, f'[web]\nframe_ancestors = ["http://ok.lan", {json.dumps(bad)}]\n')
    assert said.count("\n") == 1 and "web.frame_ancestors" in said
    shown = "an entry holding '@'" if "@" in bad else repr(bad)  # (rule 5: a login is hidden)
    assert shown in said and "scheme://host[:port]" in said


def test_the_environment_overrides_the_web_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ROTOR_BRIDGE_WEB__ENABLED", "true")
    monkeypatch.setenv("ROTOR_BRIDGE_WEB__PORT", "8099")
    monkeypatch.setenv("ROTOR_BRIDGE_WEB__FRAME_ANCESTORS", '["http://ha.lan:8123"]')
    w = load_settings(_file(tmp_path, "[web]\nport = 8000\n")).web
    assert (w.enabled, w.port, w.frame_ancestors) == (True, 8099, ["http://ha.lan:8123"])
    monkeypatch.setenv("ROTOR_BRIDGE_WEB__BIND", "0.0.0.0")  # and is judged like the file
    with pytest.raises(ConfigError, match="web.bind"):
        load_settings(_file(tmp_path, ""))


def _file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "c.toml"
    path.write_text(text + ROTATOR)
    return path


def test_the_console_port_must_not_be_a_rotctld_port(tmp_path: Path) -> None:
    rotctld = ROTATOR + "rotctld_port = 4533\n"
    path = tmp_path / "c.toml"
    path.write_text("[web]\nenabled = true\nport = 4533\n" + rotctld)
    with pytest.raises(ConfigError) as err:
        load_settings(path, environ={})
    assert "web.port 4533 is also rotators[0].rotctld_port" in str(err.value)
    path.write_text("[web]\nport = 4533\n" + rotctld)  # off: no listener to collide with
    assert load_settings(path, environ={}).web.port == 4533


def test_the_beamwidth_defaults_to_60_and_is_an_angle(tmp_path: Path) -> None:
    assert load(tmp_path, "").rotators[0].beamwidth_deg == 60
    path = tmp_path / "c.toml"
    path.write_text(ROTATOR + "beamwidth_deg = 30\n")
    assert load_settings(path, environ={}).rotators[0].beamwidth_deg == 30
    for bad in ("0", "-10", "400"):
        path.write_text(ROTATOR + f"beamwidth_deg = {bad}\n")
        with pytest.raises(ConfigError, match=r"rotators\[0\]\.beamwidth_deg"):
            load_settings(path, environ={})


# -- check-config -------------------------------------------------------------------------------
def test_check_config_says_whether_the_console_is_on_and_where(tmp_path: Path) -> None:
    path = tmp_path / "c.toml"
    path.write_text(ROTATOR)
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 0 and "web console: off" in out.stdout.splitlines(), out

    path.write_text("[web]\nenabled = true\n" + ROTATOR)
    out = cli("check-config", "-c", str(path))
    assert "web console: http://127.0.0.1:8754/, no password" in out.stdout.splitlines(), out
    assert "web.bind" not in out.stdout  # loopback: nothing to warn about

    secret = password_file(tmp_path, PASSWORD + "\n")
    path.write_text(f'[web]\nenabled = true\nbind = "::"\npassword_file = "{secret}"\n' + ROTATOR)
    out = cli("check-config", "--full", "-c", str(path))
    assert out.returncode == 0, out.stderr
    assert "web console: http://[::]:8754/, a password" in out.stdout.splitlines()
    assert PASSWORD not in out.stdout + out.stderr
    assert "warning: web.bind: :: is not a loopback address" in out.stdout


def test_a_console_beyond_loopback_is_warned_about_even_with_a_password(tmp_path: Path) -> None:
    secret = password_file(tmp_path, PASSWORD)
    s = load(tmp_path, f'[web]\nenabled = true\nbind = "0.0.0.0"\npassword_file = "{secret}"\n')
    (warning,) = [w for w in config_warnings(s) if w.startswith("web.")]
    assert warning.startswith("web.bind: 0.0.0.0 is not a loopback address") and "HTTPS" in warning


def test_host_names_are_names_alone(tmp_path: Path) -> None:
    ok = load(tmp_path, '[web]\nenabled = true\nhost_names = ["Shack.Example.org"]\n')
    assert ok.web.host_names == ["shack.example.org"]
    said = refused(tmp_path, '[web]\nhost_names = ["https://shack.example.org/"]\n')
    assert "web.host_names" in said and "not a host name" in said


@pytest.mark.parametrize("key", ["frame_ancestors", "host_names"])
def test_an_origin_or_name_with_a_login_is_refused_without_the_password(
    tmp_path: Path, key: str
) -> None:
    """An attack pass: an address with its login (``https://admin:pw@ha.lan:8123``) was
    refused with the whole value quoted, the password on the terminal and in the journal."""
    for given in ("https://admin:Sekr1tPW@ha.lan:8123", "admin:Sekr1tPW@ha.lan"):
        said = refused(tmp_path, f'[web]\n{key} = ["{given}"]\n')
        assert f"web.{key}: an entry holding '@' (not shown: " in said and "Sekr1tPW" not in said
    said = refused(tmp_path, f'[web]\n{key} = ["ha.lan/x"]\n')
    assert f"web.{key}: 'ha.lan/x' is not " in said  # (nothing to hide: quoted)


def test_a_proxy_with_a_login_and_a_bad_bind_are_refused_without_the_password(
    tmp_path: Path,
) -> None:
    """An attack pass: ``trusted_proxies = ["admin:pw@10.0.0.1"]`` was refused quoting the
    whole value, and ``web.bind`` took any text until the console failed to listen."""
    said = refused(tmp_path, '[web]\ntrusted_proxies = ["admin:Sekr1tPW@10.0.0.1"]\n')
    assert "web.trusted_proxies: an entry holding '@' (not shown: " in said
    assert "Sekr1tPW" not in said
    said = refused(tmp_path, '[web]\nbind = "admin:Sekr1tPW@0.0.0.0"\n')
    assert "web.bind: a host name or address, not a URL with a login" in said
    assert "Sekr1tPW" not in said
    said = refused(tmp_path, '[web]\nbind = "localhost:8080"\n')
    assert "web.bind: a host name or address, without its port: 'localhost:8080' (web.port)" in said


def test_a_trusted_proxy_network_wider_than_one_address_is_warned_about(tmp_path: Path) -> None:
    """An attack pass: the docs say to list only the proxies, but a LAN listed (any host on it
    may then write X-Forwarded-For and be limited and audited as another browser) passed
    check-config without a word."""
    s = load(
        tmp_path,
        '[web]\nenabled = true\ntrusted_proxies = ["127.0.0.1", "::1", "10.0.0.9/32", '
        '"192.168.1.0/24"]\n',
    )
    (warning,) = [w for w in config_warnings(s) if w.startswith("web.trusted_proxies")]
    assert warning.startswith("web.trusted_proxies: 192.168.1.0/24 is a network of 256 addresses")


def test_trusted_proxies_without_host_names_is_warned_about(tmp_path: Path) -> None:
    """A review: behind a proxy reached by a name, a rebinding page's name pointed at the proxy
    and the operator's own counted their failed logins in one bucket (both "another name"),
    and the page's guesses held the operator's right password back."""
    path = password_file(tmp_path, PASSWORD + "\n")
    proxied = f'[web]\nenabled = true\ntrusted_proxies = ["127.0.0.1"]\npassword_file = "{path}"\n'
    (warning,) = [w for w in config_warnings(load(tmp_path, proxied)) if "host_names" in w]
    assert warning.startswith("web.host_names: none listed, with trusted_proxies")
    named = load(tmp_path, proxied + 'host_names = ["shack.example.org"]\n')
    assert not [w for w in config_warnings(named) if "host_names" in w]
    # without a password a name not listed is refused whatever it is: nothing to warn of
    bare = load(tmp_path, '[web]\nenabled = true\ntrusted_proxies = ["127.0.0.1"]\n')
    assert not [w for w in config_warnings(bare) if "host_names" in w]
