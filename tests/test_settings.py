from __future__ import annotations

import json
import os
import pwd
import subprocess
from pathlib import Path
from typing import Any

import pytest

from bridge.core.model import Target
from bridge.protocols import REGISTRY
from bridge.settings import ConfigError, RotatorSettings, files, load_settings, settings_from
from bridge.settings.report import config_warnings, masked
from tests.dxcluster.cty_sample import CTY_DAT
from tests.support import ROOT, cli, run_cli

MINIMAL = """
[mqtt]
host = "127.0.0.1"
port = 1883
base_topic = "rotor"

[[rotators]]
id = "tower"
name = "Tower"
model = "rotorez"
port = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"
brake_delay_s = 5
"""


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "c.toml"
    p.write_text(text)
    return p


def test_the_issue_minimal_file_works_as_written(tmp_path: Path) -> None:
    s = load_settings(write(tmp_path, MINIMAL))
    r = s.rotators[0]
    assert (r.id, r.model, r.effective_baud, r.effective_brake_delay_s) == (
        "tower",
        "rotorez",
        4800,
        5,
    )
    assert s.rotator_topic(r) == "rotor"


def test_model_defaults_and_topics_for_several_rotators(tmp_path: Path) -> None:
    text = MINIMAL.replace("brake_delay_s = 5\n", "") + (
        '[[rotators]]\nid = "yagi"\nmodel = "rotorcard"\nport = "/dev/ttyUSB1"\n'
        '[[rotators]]\nid = "dcu"\nmodel = "dcu1"\nport = "/dev/ttyUSB2"\n'
    )
    s = load_settings(write(tmp_path, text))
    assert [s.rotator_topic(r) for r in s.rotators] == ["rotor/tower", "rotor/yagi", "rotor/dcu"]
    assert [r.effective_brake_delay_s for r in s.rotators] == [5, 0, 5]


def test_rotor_speeds_default_to_the_model_and_reach_the_engine(tmp_path: Path) -> None:
    from bridge.app import worker_config

    text = MINIMAL.replace('model = "rotorez"', 'model = "satel"').replace(
        "brake_delay_s = 5", "az_speed_deg_s = 4.5"
    )
    r = load_settings(write(tmp_path, text)).rotators[0]
    assert r.effective_speeds_deg_s == (4.5, 2.5)  # el: the model's (a G-5500)
    cfg = worker_config(r)
    assert (cfg.az_speed_deg_s, cfg.el_speed_deg_s, cfg.motion.nominal_speed_deg_s) == (
        4.5,
        2.5,
        4.5,
    )


def test_environment_overrides_the_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__HOST", "broker.lan")
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__USERNAME", "rotor")
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__PASSWORD", "hunter2")
    monkeypatch.setenv("ROTOR_BRIDGE_ROTATORS__TOWER__PORT", "/dev/ttyUSB7")
    monkeypatch.setenv("ROTOR_BRIDGE_ROTATORS__TOWER__IDLE_POLL_INTERVAL_S", "5")
    s = load_settings(write(tmp_path, MINIMAL))
    assert s.mqtt.host == "broker.lan" and s.mqtt.port == 1883
    assert s.rotators[0].port == "/dev/ttyUSB7" and s.rotators[0].idle_poll_interval_s == 5
    shown = json.dumps(masked(s))
    assert "hunter2" not in shown and "********" in shown


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (('model = "rotorez"', 'model = "yaesu"'), "rotators[0].model"),
        (("port = 1883", "port = 99999"), "mqtt.port"),
        (('id = "tower"', 'id = "Tower Rotor"'), "rotators[0].id"),
        (("brake_delay_s = 5", "brake_delay_s = -1"), "rotators[0].brake_delay_s"),
        (("brake_delay_s = 5", "brake_delay_s = 5\nbrake_delay = 5"), "rotators[0].brake_delay"),
        (("brake_delay_s = 5", "az_max_deg = 400"), "rotators[0]"),
        (('base_topic = "rotor"', 'base_topic = "rotor/#"'), "mqtt.base_topic"),
        (("brake_delay_s = 5", "az_speed_deg_s = 0"), "rotators[0].az_speed_deg_s"),
        (("brake_delay_s = 5", "az_speed_deg_s = 0.05"), "rotators[0].az_speed_deg_s"),
        (("brake_delay_s = 5", "el_speed_deg_s = 3"), "rotators[0]"),  # no elevation axis
    ],
)
def test_bad_values_name_the_field(tmp_path: Path, change: tuple[str, str], field: str) -> None:
    with pytest.raises(ConfigError) as exc:
        load_settings(write(tmp_path, MINIMAL.replace(*change)))
    assert f"{field}:" in str(exc.value) or f"{field}." in str(exc.value)


@pytest.mark.parametrize(
    ("variable", "said"),
    [
        ("ROTOR_BRIDGE_MQTT__PASSWORD", "mqtt.password (from ROTOR_BRIDGE_MQTT__PASSWORD): empty"),
        ("ROTOR_BRIDGE_MQTT__USERNAME", "mqtt.username (from ROTOR_BRIDGE_MQTT__USERNAME): empty"),
    ],
)
def test_an_empty_user_name_or_password_is_refused_naming_it(
    tmp_path: Path, variable: str, said: str
) -> None:
    """An attack pass: ``ROTOR_BRIDGE_MQTT__PASSWORD=${MQTT_PASSWORD}`` with the variable unset
    (docker compose) passed check-config as "user rotor, a password", and the bridge logged in
    with no password; the broker's "Not authorized" named no key. The file's ``""`` alike."""
    text = MINIMAL.replace(
        'base_topic = "rotor"', 'base_topic = "rotor"\nusername = "rotor"\npassword = "x"'
    )
    out = cli("check-config", "-c", str(write(tmp_path, text)), env={variable: ""})
    assert out.returncode == 2 and said in out.stderr, out.stdout + out.stderr
    key = variable.removeprefix("ROTOR_BRIDGE_MQTT__").lower()
    given = {"username": 'username = "rotor"', "password": 'password = "x"'}[key]
    with pytest.raises(ConfigError, match=f"mqtt.{key}: empty"):
        load_settings(write(tmp_path, text.replace(given, f'{key} = ""')), {})


def test_a_file_the_bridge_writes_is_no_file_the_configuration_reads(tmp_path: Path) -> None:
    """An attack pass: state_file naming the configuration file passed check-config, and the
    bridge's first lock OFF replaced the configuration with its state (the next start: "not
    valid TOML"); naming the password file, the password went the same way."""
    pw = tmp_path / "pw"
    pw.write_text("s3cret\n")
    pw.chmod(0o600)
    path = tmp_path / "c.toml"
    logins = f'base_topic = "rotor"\nusername = "u"\npassword_file = "{pw}"'
    text = MINIMAL.replace('base_topic = "rotor"', logins)
    cases = [
        (f'state_file = "{path}"', f"state_file: {path} is the configuration file itself"),
        (f'audit_file = "{tmp_path}/./c.toml"', "audit_file: "),
        (f'state_file = "{pw}"', f"state_file {pw} is also mqtt.password_file: the bridge"),
        (
            f'state_file = "{tmp_path}/s.json"\naudit_file = "{tmp_path}/s.json"',
            f"state_file {tmp_path}/s.json is also audit_file",
        ),
    ]
    for first, said in cases:
        path.write_text(f"{first}\n{text}")
        out = cli("check-config", "-c", str(path))
        assert out.returncode == 2 and said in out.stderr, out.stdout + out.stderr
        assert "give it a file of its own" in out.stderr and "s3cret" not in out.stderr
    path.write_text(f'state_file = "{tmp_path}/s.json"\naudit_file = "{tmp_path}/a.jsonl"\n{text}')
    assert cli("check-config", "-c", str(path)).returncode == 0
    secret = tmp_path / "console-secret"  # where the console keeps its own (app.py)
    secret.write_text("a console password\n")
    secret.chmod(0o600)
    path.write_text(
        f'state_file = "{tmp_path}/s.json"\n{text}\n[web]\npassword_file = "{secret}"\n'
    )
    out = cli("check-config", "-c", str(path))
    assert (
        out.returncode == 2
        and (
            f"the console's secret kept beside state_file {secret} is also web.password_file: the "
            "bridge writes there, and would overwrite it; name that file otherwise"
        )
        in out.stderr
    ), out.stderr


def _rotator(port: Path, more: str = "") -> str:
    return f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{port}"\n{more}'


def test_a_file_the_bridge_writes_is_no_serial_port_nor_device(tmp_path: Path) -> None:
    """Attack 28 (rule 6): audit_file naming the rotator's port (by any name: links followed)
    passed check-config and every audit line went down the controller's line; a serial line
    or a terminal's device is no file to write either (/dev/null and /dev/full are: the disk
    full test writes to the latter). The refusal names the key."""
    tty = tmp_path / "ttyUSB0"
    tty.symlink_to("/dev/null")  # (a device: a serial adapter's, to the settings)
    by_id = tmp_path / "usb-FTDI_A1B2C3-if00-port0"
    by_id.symlink_to(tty)
    state = f'state_file = "{tmp_path / "state.json"}"\n'
    cases = [
        (f'audit_file = "{by_id}"\n{state}', "audit_file", "rotators[0].port"),
        (f'audit_file = "{tty}"\n{state}', "audit_file", "rotators[0].port"),
        (f'state_file = "{tty}"\n', "state_file", "rotators[0].port"),
        (f'audit_file = "/dev/ptmx"\n{state}', "audit_file", "is a serial line or terminal"),
    ]
    for top, key, said in cases:
        port = tmp_path / "ttyUSB9" if "serial line" in said else by_id  # (a port of its own)
        cfg = write(tmp_path, top + _rotator(port))
        with pytest.raises(ConfigError) as caught:
            load_settings(cfg, environ={})
        assert f"{key} " in str(caught.value) and said in str(caught.value), caught.value
    for sink in ("/dev/null", "/dev/full"):
        cfg = write(tmp_path, f'audit_file = "{sink}"\n{state}' + _rotator(tmp_path / "ttyUSB9"))
        assert str(load_settings(cfg, environ={}).audit_file) == sink
    composite = (
        f'{state}audit_file = "{tty}"\n[[rotators]]\nid = "t"\n'
        'azimuth = { model = "rt21", port = "/dev/ttyUSB7" }\n'
        f'elevation = {{ model = "gs232b", port = "{by_id}" }}\nel_max_deg = 90\n'
    )
    with pytest.raises(ConfigError, match=r"audit_file .* is also rotators\[0\]\.elevation\.port"):
        load_settings(write(tmp_path, composite), environ={})


def test_the_processs_own_output_is_judged_by_its_name(tmp_path: Path) -> None:
    """Review 87 (rule 6): audit_file = /dev/stdout was judged by where the checking process's
    stdout went (a terminal: "a character device"); by its name, it is the bridge's own output
    (runtime/audit.py rule 11), and no other written file may be one: a state file is read back,
    and a pty's link would replace the system's /dev/stdout."""
    state = f'state_file = "{tmp_path / "state.json"}"\n'
    for name in ("/dev/stdout", "/dev/stderr", "/dev/fd/1", "/proc/self/fd/2"):
        cfg = write(tmp_path, f'{state}audit_file = "{name}"\n' + _rotator(tmp_path / "ttyUSB0"))
        assert str(load_settings(cfg, environ={}).audit_file) == name
    out = cli("check-config", "-c", str(cfg))  # (the last: /proc/self/fd/2)
    assert "audit file: /proc/self/fd/2 (the bridge's own output, never rotated)" in out.stdout
    for top, key in [
        ('state_file = "/dev/stdout"\n', "state_file"),
        (state, "rotators[0].gs232_pty"),
    ]:
        pty = 'gs232_pty = "/dev/stdout"\n' if "pty" in key else ""
        with pytest.raises(ConfigError) as caught:
            load_settings(write(tmp_path, top + _rotator(tmp_path / "ttyUSB0", pty)), environ={})
        said = f"{key} /dev/stdout names one of the process's own descriptors, not a file"
        assert said in str(caught.value), caught.value


@pytest.mark.parametrize("key", ["gs232_pty", "easycomm_pty", "dcu1_pty"])
def test_a_ptys_link_is_no_port_nor_file_the_bridge_writes(tmp_path: Path, key: str) -> None:
    """Attack 28 (rule 6): a pty's link replaces what is at its path: at a rotator's port (by
    any name) the rotator opened the bridge's own pty; at the state or audit file, another
    pty's path (through a folder's link), or the configuration file, it is refused by key."""
    tty = tmp_path / "ttyUSB0"
    tty.symlink_to("/dev/null")
    by_id = tmp_path / "by-id"
    by_id.symlink_to(tty)
    (tmp_path / "run").mkdir()
    (tmp_path / "run-link").symlink_to(tmp_path / "run")
    state = tmp_path / "state.json"
    top = f'state_file = "{state}"\n'
    cases = [
        (top, f'{key} = "{by_id}"', "rotators[0].port"),
        (top, f'{key} = "{tty}"', "rotators[0].port"),  # the device under its other name
        (top, f'{key} = "{state}"', "state_file"),
        (f'{top}audit_file = "{tmp_path / "a.jsonl"}"\n', f'{key} = "{tmp_path}/a.jsonl"', "audit"),
        (top, f'{key} = "{tmp_path / "c.toml"}"', "the configuration file itself"),
    ]
    other = "dcu1_pty" if key != "dcu1_pty" else "gs232_pty"
    cases.append((top, f'{key} = "{tmp_path}/run/p"\n{other} = "{tmp_path}/run-link/p"', "is also"))
    for head, pty, said in cases:
        cfg = write(tmp_path, head + _rotator(by_id, pty + "\n"))
        with pytest.raises(ConfigError) as caught:
            load_settings(cfg, environ={})
        assert key in str(caught.value) and said in str(caught.value), caught.value
    # a crashed run's link left at the pty's path points at a device: its own, not refused
    leftover = tmp_path / "run" / "gs"
    leftover.symlink_to("/dev/null")
    cfg = write(
        tmp_path,
        f'{top}audit_file = "{tmp_path / "a.jsonl"}"\n'
        + _rotator(tmp_path / "nonesuch", f'{key} = "{leftover}"\n'),
    )
    assert getattr(load_settings(cfg, environ={}).rotators[0], key) == str(leftover)


@pytest.mark.parametrize(
    ("reader", "holder"),
    [
        ("tracking.tle_file", "mqtt.password_file"),
        ("tracking.tle_file", "web.password_file"),
        ("tracking.tle_file", "the console's secret kept beside state_file"),
        ("dxcluster.cty_file", "mqtt.password_file"),
        ("dxcluster.cty_file", "the configuration file"),
        ("tracking.tle_file", "the configuration file"),
    ],
)
def test_a_secret_s_file_is_read_as_nothing_else(tmp_path: Path, reader: str, holder: str) -> None:
    """Settings rule 7 (attack 18): tracking.tle_file naming the MQTT password file passed
    check-config, and the start's TLE reader logged the password at WARNING. The console's
    secret is one whether or not the console has a password now (an earlier run left it);
    the configuration file may hold mqtt.password."""
    secret = "Wr1tten-0nly-1n-the-password-file"
    files = {name: tmp_path / name for name in ("mqtt-pw", "web-pw", "console-secret")}
    for path in files.values():
        path.write_text(secret + "\n")
        path.chmod(0o600)
    path = tmp_path / "c.toml"
    given = {
        "mqtt.password_file": files["mqtt-pw"],
        "web.password_file": files["web-pw"],
        "the console's secret kept beside state_file": files["console-secret"],
        "the configuration file": path,
    }[holder]
    table, key = reader.split(".")
    logins = f'base_topic = "rotor"\nusername = "u"\npassword_file = "{files["mqtt-pw"]}"'
    text = (
        f'state_file = "{tmp_path}/state.json"\n'
        + MINIMAL.replace('base_topic = "rotor"', logins)
        + (f'\n[web]\npassword_file = "{files["web-pw"]}"\n' if "web" in holder else "")
        + f'\n[{table}]\n{key} = "{given}"\n'
        + ('enabled = true\nhost = "dx.example"\nlogin = "G4ABC"\n' if table == "dxcluster" else "")
    )
    path.write_text(text)
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 2 and "config OK" not in out.stdout, out.stdout + out.stderr
    assert f"{reader} {given} is also {holder}: a secret's file" in out.stderr, out.stderr
    assert secret not in out.stdout + out.stderr
    (tmp_path / "other").write_text(CTY_DAT)  # (a cty file; a TLE file of no satellite)
    path.write_text(text.replace(f'{key} = "{given}"', f'{key} = "{tmp_path}/other"'))
    out = cli("check-config", "-c", str(path))  # (its own file: OK)
    assert out.returncode == 0 and "config OK" in out.stdout, out.stdout + out.stderr


@pytest.mark.parametrize(
    "key",
    ["STATE_FILE", "AUDIT_FILE", "MQTT__PASSWORD_FILE", "WEB__PASSWORD_FILE", "TRACKING__TLE_FILE"],
)
def test_a_path_given_empty_is_refused_naming_it(tmp_path: Path, key: str) -> None:
    """An attack pass: an empty path (``ROTOR_BRIDGE_AUDIT_FILE=${AUDIT}`` with the variable
    unset) was read as '.', the current folder: the audit file passed check-config and lost
    every line at run, a password file was "not a file"."""
    variable = f"ROTOR_BRIDGE_{key}"
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL)), env={variable: ""})
    name = key.lower().replace("__", ".")
    assert out.returncode == 2, out.stdout + out.stderr
    assert f"{name} (from {variable}): empty: name a file, or leave the key out" in out.stderr


def test_an_audit_file_that_is_a_folder_is_refused(tmp_path: Path) -> None:
    out = cli("check-config", "-c", str(write(tmp_path, f'audit_file = "{tmp_path}"\n' + MINIMAL)))
    assert out.returncode == 2, out.stdout + out.stderr
    assert f"audit_file: {tmp_path} is a folder: name a file in it ({tmp_path}/audit.jsonl)" in (
        out.stderr
    )


def test_world_readable_password_file_is_refused(tmp_path: Path) -> None:
    pw = tmp_path / "pw"
    pw.write_text("s3cret\n")
    os.chmod(pw, 0o644)
    text = MINIMAL.replace(
        'base_topic = "rotor"', f'base_topic = "rotor"\nusername = "u"\npassword_file = "{pw}"'
    )
    with pytest.raises(ConfigError, match="readable by every user"):
        load_settings(write(tmp_path, text))
    os.chmod(pw, 0o600)
    s = load_settings(write(tmp_path, text))
    assert s.mqtt.password is not None and s.mqtt.password.get_secret_value() == "s3cret"
    assert "s3cret" not in json.dumps(masked(s))


def test_a_password_file_this_user_may_not_read_says_who_and_what_to_do(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """check-config run by hand, as oneself, on the service's file (root:rotor-bridge, 640)
    said "Permission denied" alone. (Tests run as root, who may read any file: the refusal
    is made by hand, as the kernel makes it for another user.)"""
    pw = tmp_path / "pw"
    pw.write_text("s3cret\n")
    os.chmod(pw, 0o640)
    text = MINIMAL.replace(
        'base_topic = "rotor"', f'base_topic = "rotor"\nusername = "u"\npassword_file = "{pw}"'
    )
    real_open = os.open

    def refused(path: Any, flags: int, *args: Any) -> int:
        if str(path) == str(pw):
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(files.os, "open", refused)
    with pytest.raises(ConfigError) as exc:
        load_settings(write(tmp_path, text))
    who = pwd.getpwuid(os.getuid()).pw_name
    said = str(exc.value)
    assert f"password_file {pw}: Permission denied for user {who}; run rotor-bridge as" in said
    assert "sudo" in said and "s3cret" not in said


def test_check_config_prints_effective_settings_with_secrets_masked(tmp_path: Path) -> None:
    text = MINIMAL.replace(
        'base_topic = "rotor"', 'base_topic = "rotor"\nusername = "u"\npassword = "topsecret"'
    )
    path = write(tmp_path, text)
    out = cli("check-config", "--full", "-c", str(path))
    assert out.returncode == 0, out.stderr
    doc = full_values(out.stdout)
    assert doc["mqtt"]["password"] == "********" and "topsecret" not in out.stdout + out.stderr
    assert doc["rotators"][0]["baud"] == 4800 and doc["rotators"][0]["topic"] == "rotor"
    assert out.stdout.splitlines()[-1] == f"config OK: {path}"


def full_values(stdout: str) -> dict:
    """The JSON document ``check-config --full`` prints between the summary and the last line."""
    lines = stdout.splitlines()
    start, end = lines.index("{"), len(lines) - lines[::-1].index("}")
    return json.loads("\n".join(lines[start:end]))


def test_bad_file_exits_2_with_one_message(tmp_path: Path) -> None:
    out = run_cli("run", "-c", str(write(tmp_path, MINIMAL.replace("rotorez", "rotorz"))))
    assert out.returncode == 2
    assert "rotators[0].model: unknown model 'rotorz'" in out.stderr
    assert "Traceback" not in out.stderr
    out = cli("check-config", "-c", str(tmp_path / "missing.toml"))
    assert out.returncode == 2 and "not found" in out.stderr
    out = cli("check-config", "-c", str(write(tmp_path, "[mqtt\n")))
    assert out.returncode == 2 and "not valid TOML" in out.stderr
    deep = write(tmp_path, "a = " + "[" * 5000 + "1" + "]" * 5000 + "\n")  # past the parser's depth
    out = cli("check-config", "-c", str(deep))
    assert out.returncode == 2 and "nested too deep" in out.stderr
    assert "Traceback" not in out.stderr


# -- check-config: the values in effect, and warnings for what is legal but probably wrong ------
NOT_APPLICABLE = {"rotctld_port", "park_az_deg", "park_el_deg", "pst_udp_port", "n1mm_rotor_name"}
NOT_APPLICABLE |= {"gs232_port", "easycomm_port"}
NOT_APPLICABLE |= {"wind_topic", "wind_park_above", "wind_release_below", "wind_park_az_deg"}
NOT_APPLICABLE |= {"gs232_pty", "easycomm_pty", "dcu1_port", "dcu1_pty"}
NOT_APPLICABLE |= {"azimuth", "elevation"}  # one controller, no composite's tables
AZ_ONLY_NULLS = {"el_min_deg", "el_max_deg", "el_speed_deg_s"}  # no elevation axis


@pytest.mark.parametrize("model", sorted(REGISTRY))
def test_check_config_shows_the_model_defaults_in_effect(tmp_path: Path, model: str) -> None:
    text = f'[[rotators]]\nid = "tower"\nmodel = "{model}"\nport = "/dev/ttyUSB0"\n'
    s = load_settings(write(tmp_path, text), environ={})
    from bridge.app import worker_config

    spec = REGISTRY[model]
    r = masked(s)["rotators"][0]
    used = worker_config(s.rotators[0])  # what the bridge runs with
    expected = {
        "name": "tower",
        "topic": "rotor",
        "baud": spec.baud,
        "brake_delay_s": spec.brake_delay_s,
        "noise_deg": spec.noise_deg,
        "az_speed_deg_s": spec.nominal_speed_deg_s,
        "az_min_deg": spec.az_min_deg,
        "az_max_deg": spec.az_max_deg,
    }
    assert (used.baud, used.motion.brake_delay_s, used.motion.noise_deg) == (
        r["baud"],
        r["brake_delay_s"],
        r["noise_deg"],
    )
    assert (used.idle_poll_interval_s, used.moving_poll_interval_s, used.silence_timeout_s) == (
        r["idle_poll_interval_s"],
        r["moving_poll_interval_s"],
        r["silence_timeout_s"],
    )
    assert used.az_speed_deg_s == r["az_speed_deg_s"]
    assert r["unasked_moves"] == used.unasked_moves == spec.unasked_moves
    easycomm = model.startswith("easycomm")  # every one asks AZ EL (easycomm.py rule 8)
    rotorez = model in ("rotorez", "rotorcard")
    stops = easycomm or model in ("satel", "rc2800", "rc2800-az")  # (the SatEL's frames near
    assert used.unasked_moves == (  # jogs, the RC2800's poll a stray digit from a target)
        "stop" if stops else "after-stop" if rotorez else "follow"
    )  # (controller.py rule 10)
    assert used.tracking.step_deg == r["track_step_deg"] == r["tolerance_deg"]  # the default
    if spec.has_elevation:
        assert used.el_speed_deg_s == r["el_speed_deg_s"]
        expected |= {
            "el_speed_deg_s": spec.nominal_el_speed_deg_s,
            "el_min_deg": spec.el_min_deg,
            "el_max_deg": spec.el_max_deg,
        }
    assert {k: r[k] for k in expected} == expected
    nulls = {k for k, v in r.items() if v is None}
    assert nulls == NOT_APPLICABLE | (set() if spec.has_elevation else AZ_ONLY_NULLS)
    shown = masked(s)
    assert shown["mqtt"]["client_id"] == s.mqtt.effective_client_id() and shown["state_file"]


def test_check_config_shows_what_the_pointing_settings_mean(tmp_path: Path) -> None:
    text = (
        '[station]\nlocator = "JO62qm"\n'
        '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'
        "az_offset_deg = 180\npresets = { JA = 330 }\npark_az_deg = 0\n"
        '[[rotators]]\nid = "sky"\nmodel = "rot2prog"\nport = "/dev/ttyUSB1"\n'
        "az_offset_deg = 90\n"
    )
    doc, warnings = check_config(write(tmp_path, text))
    assert all("does not exist" in w or "is numbered" in w for w in warnings), warnings
    lat, lon = doc["station"]["position_deg"]  # the square's centre, to check on a map
    assert (lat, lon) == (pytest.approx(52.521, abs=1e-3), pytest.approx(13.375, abs=1e-3))
    tower, sky = doc["rotators"]
    assert list(tower)[:4] == ["id", "name", "model", "port"]
    assert (tower["az_offset_deg"], tower["presets"], tower["park_az_deg"]) == (180, {"JA": 330}, 0)
    assert tower["az_targets_deg"] == [0, 360]  # a scale that wraps: every bearing
    assert sky["az_targets_deg"] == [-90, 630]  # the SPID's -180..540 seen through +90


def check_config(path: Path, **env: str) -> tuple[dict, list[str]]:
    """``rotor-bridge check-config --full``: (the printed settings, the warnings)."""
    out = cli("check-config", "--full", "-c", str(path), env=env)
    assert out.returncode == 0, out.stderr  # warnings never fail it
    assert out.stderr == "" and out.stdout.splitlines()[-1] == f"config OK: {path}"
    warned = [line for line in out.stdout.splitlines() if line.startswith("warning: ")]
    return full_values(out.stdout), [line.removeprefix("warning: ") for line in warned]


def test_check_config_warns_about_what_is_legal_but_probably_wrong(tmp_path: Path) -> None:
    missing = tmp_path / "serial" / "by-id" / "usb-gone"
    text = (
        '[mqtt]\nusername = "u"\npassword = "inline-S3cret"\n'
        f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{missing}"\n'
        'rotctld_port = 4533\nrotctld_bind = "0.0.0.0"\n'
    )
    doc, warnings = check_config(write(tmp_path, text))
    assert doc["mqtt"]["password"] == "********" and doc["rotators"][0]["port"] == str(missing)
    assert len(warnings) == 3, warnings
    password, port, bind = warnings
    assert password.startswith("mqtt.password is written in the configuration file")
    assert "mqtt.password_file" in password and "inline-S3cret" not in password
    assert port.startswith(f"rotators[0].port: {missing} does not exist now"), port
    assert bind.startswith("rotators[0].rotctld_bind: 0.0.0.0 is not a loopback address"), bind
    assert "4533" in bind and "turn the antenna" in bind


def test_check_config_is_quiet_about_a_sound_configuration(tmp_path: Path) -> None:
    device = tmp_path / "ttyUSB0"  # a path that exists, as a plugged-in adapter's does
    device.write_text("")
    pw = tmp_path / "pw"
    pw.write_text("file-S3cret\n")
    os.chmod(pw, 0o640)
    text = (
        f'[mqtt]\nusername = "u"\npassword_file = "{pw}"\n'
        f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{device}"\n'
        'rotctld_port = 4533\nrotctld_bind = "127.0.0.1"\n'
    )
    doc, warnings = check_config(write(tmp_path, text))
    assert warnings == [] and doc["mqtt"]["password"] == "********"
    # a password from the environment is not written in the file: no warning either
    text = text.replace(f'password_file = "{pw}"', "")
    doc, warnings = check_config(write(tmp_path, text), ROTOR_BRIDGE_MQTT__PASSWORD="env-S3cret")
    assert warnings == [] and doc["mqtt"]["password"] == "********"


@pytest.mark.parametrize(
    ("bind", "warned"),
    [
        ("127.0.0.1", False),
        ("127.0.1.1", False),
        ("::1", False),
        ("localhost", False),
        ("0.0.0.0", True),
        ("::", True),
        ("192.168.1.20", True),
        ("shack-pi.lan", True),
    ],
)
def test_only_a_rotctld_port_off_loopback_is_warned_about(
    tmp_path: Path, bind: str, warned: bool
) -> None:
    text = (
        f'[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "{tmp_path}"\n'
        f'rotctld_port = 4533\nrotctld_bind = "{bind}"\n'
    )
    s = load_settings(write(tmp_path, text), environ={})
    assert [w for w in config_warnings(s) if "rotctld_bind" in w] == (
        [f"rotators[0].rotctld_bind: {bind} is not a loopback address: rotctld has no "
         "authentication, anyone who can reach port 4533 there can turn the antenna"]
        if warned else []
    )  # fmt: skip
    without_port = text.replace("rotctld_port = 4533\n", "")
    assert config_warnings(load_settings(write(tmp_path, without_port), environ={})) == []


# -- idle polling and silence: derived from the model's line unless set --------------------------
@pytest.mark.parametrize("model", sorted(REGISTRY))
def test_idle_polls_default_to_at_most_5_percent_of_the_line_and_reach_the_engine(
    tmp_path: Path, model: str
) -> None:
    from bridge.app import worker_config

    text = f'[[rotators]]\nid = "tower"\nmodel = "{model}"\nport = "/dev/ttyUSB0"\n'
    r = load_settings(write(tmp_path, text), environ={}).rotators[0]
    spec = REGISTRY[model]
    idle_s = r.effective_idle_poll_interval_s
    assert idle_s >= 1.0 and spec.exchange_time_s(r.effective_baud) / idle_s <= 0.05
    silence_s = r.effective_silence_timeout_s
    assert silence_s >= max(3.0, 2 * idle_s + spec.reply_timeout_s)  # one lost reply is no outage
    cfg = worker_config(r)
    assert (cfg.idle_poll_interval_s, cfg.silence_timeout_s) == (idle_s, silence_s)


def test_the_slow_lines_poll_rarely_and_wait_longer_before_calling_it_silence(
    tmp_path: Path,
) -> None:
    text = "".join(
        f'[[rotators]]\nid = "{model}"\nmodel = "{model}"\nport = "/dev/ttyUSB{i}"\n{extra}'
        for i, (model, extra) in enumerate(
            [("rot2prog", ""), ("satel", ""), ("rotorez", ""), ("md01", "baud = 600\n")]
        )
    )
    rotators = load_settings(write(tmp_path, text), environ={}).rotators
    shown = [(r.effective_idle_poll_interval_s, r.effective_silence_timeout_s) for r in rotators]
    # an MD-01 set to 600 baud polls like a Rot2Prog
    assert shown == [(9.3, 19.4), (3.9, 9.8), (1.0, 3.0), (9.3, 19.0)]


def test_idle_poll_and_silence_set_by_the_user_are_kept(tmp_path: Path) -> None:
    text = MINIMAL.replace('model = "rotorez"', 'model = "rot2prog"') + (
        "idle_poll_interval_s = 2\nsilence_timeout_s = 4\n"
    )
    r = load_settings(write(tmp_path, text), environ={}).rotators[0]
    assert (r.effective_idle_poll_interval_s, r.effective_silence_timeout_s) == (2, 4)
    text = MINIMAL + "idle_poll_interval_s = 5\n"
    r = load_settings(write(tmp_path, text), environ={}).rotators[0]
    assert r.effective_silence_timeout_s == 10.3  # two 5 s polls and a 0.25 s reply time


@pytest.mark.parametrize(
    "extra",
    [
        "silence_timeout_s = 3\n",  # a Rot2Prog is asked every 9.3 s by default
        "idle_poll_interval_s = 2\nsilence_timeout_s = 2\n",
    ],
)
def test_a_silence_timeout_shorter_than_the_idle_poll_is_refused(
    tmp_path: Path, extra: str
) -> None:
    text = MINIMAL.replace('model = "rotorez"', 'model = "rot2prog"') + extra
    with pytest.raises(ConfigError, match=r"rotators\[0\].*silence_timeout_s .* idle poll"):
        load_settings(write(tmp_path, text), environ={})


@pytest.mark.parametrize("baud", [0, 96, 299, 4_000_001, 2**31, 10**30])
def test_a_line_rate_no_controller_is_set_to_is_refused_naming_the_field(
    tmp_path: Path, baud: int
) -> None:
    """Rule 2: a typo (96 for 9600) said when read, not an offline rotator (2**31 cannot be
    opened) or polls minutes apart."""
    text = MINIMAL + f"baud = {baud}\n"
    with pytest.raises(ConfigError, match=r"rotators\[0\].*baud"):
        load_settings(write(tmp_path, text), environ={})


@pytest.mark.parametrize("baud", [300, 600, 4800, 460800, 4_000_000])
def test_the_line_rates_controllers_are_set_to_are_taken(tmp_path: Path, baud: int) -> None:
    settings = load_settings(write(tmp_path, MINIMAL + f"baud = {baud}\n"), environ={})
    assert settings.rotators[0].effective_baud == baud


@pytest.mark.parametrize(
    ("given", "used"), [(180, 180), (-180, 180), (360, 0), (270, -90), (-90, -90), (-360, 0)]
)
def test_an_offset_is_kept_within_one_turn(given: float, used: float) -> None:
    r = RotatorSettings(id="sky", model="rot2prog", port="/dev/ttyUSB0", az_offset_deg=given)
    assert r.az_offset_deg == used
    assert r.pointing.target_range() == ((-180 + used, 540 + used) if used else (-180, 540))


@pytest.mark.parametrize("offset", [0.3, 90.1, -179.9, 180.0, 12.345])
def test_an_offset_within_one_turn_is_kept_exactly(offset: float) -> None:
    """Cold review: folding by arithmetic turned 0.3 into 0.30000000000001137, and a target a
    hair inside a limit was refused."""
    r = RotatorSettings(id="sky", model="rot2prog", port="/dev/ttyUSB0", az_offset_deg=offset)
    assert r.az_offset_deg == offset
    assert RotatorSettings(
        id="sky",
        model="rot2prog",
        port="/dev/ttyUSB0",
        az_offset_deg=offset - 360 if offset > 0 else offset + 360,
    ).az_offset_deg == pytest.approx(offset, abs=1e-12)


def test_a_target_at_the_lowest_true_bearing_is_taken_with_a_fractional_offset() -> None:
    r = RotatorSettings(id="sky", model="rot2prog", port="/dev/ttyUSB0", az_offset_deg=90.1)
    lo, _ = r.pointing.target_range()
    assert lo == -89.9
    assert r.pointing.judge(Target(-89.9, 0), None).az_deg == -180  # raw: the lower stop


TWO = (
    '[[rotators]]\nid = "a"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n{a}\n'
    '[[rotators]]\nid = "b"\nmodel = "rot2prog"\nport = "/dev/ttyUSB1"\n{b}\n'
)


@pytest.mark.parametrize(
    ("a", "b", "message"),
    [
        (
            "pst_udp_port = 12000",
            "pst_udp_port = 12000",
            r"rotators\[1\].pst_udp_port 12000 is also rotators\[0\].pst_udp_port",
        ),
        ('n1mm_rotor_name = "T"', 'n1mm_rotor_name = "T"', "n1mm_rotor_name 'T' on one N1MM"),
        (
            "pst_udp_port = 12040",
            'n1mm_rotor_name = "T"',
            r"rotators\[1\].n1mm_udp_port 12040 is also rotators\[0\].pst_udp_port",
        ),
        (  # one rotator's own two ports (an attack pass: "two rotators share one ...")
            'pst_udp_port = 12040\nn1mm_rotor_name = "T"',
            "",
            r"rotators\[0\].n1mm_udp_port 12040 is also rotators\[0\].pst_udp_port",
        ),
        (
            'topic = "rotor/x"',
            'topic = "rotor/x"',
            "rotators 'a' and 'b' share the topic 'rotor/x'",
        ),
        ('n1mm_report_to = "13010"', "", r"rotators\[0\].*n1mm_report_to.*host:port"),
        ('n1mm_rotor_name = " T"', "", r"rotators\[0\].*n1mm_rotor_name"),
        # an attack pass: every N1MM datagram naming it is not ASCII, dropped unread
        # (loggers/datagrams.py rule 1), its STOP too: N1MM's stop never stopped that rotator
        ('n1mm_rotor_name = "Süd"', "", r"rotators\[0\].*n1mm_rotor_name.*ASCII"),
        ("pst_udp_port = 65535", "", r"rotators\[0\].*pst_udp_port"),  # its reply port is +1
    ],
)
def test_logger_endpoints_that_cannot_work_are_refused_naming_the_field(
    tmp_path: Path, a: str, b: str, message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        load_settings(write(tmp_path, TWO.format(a=a, b=b)), environ={})


def test_two_rotators_may_share_the_n1mm_port_by_name(tmp_path: Path) -> None:
    text = TWO.format(a='n1mm_rotor_name = "Tower"', b='n1mm_rotor_name = "Sky"')
    s = load_settings(write(tmp_path, text), environ={})
    assert [r.n1mm_udp_port for r in s.rotators] == [12040, 12040]


def test_a_logger_port_off_loopback_is_warned_about(tmp_path: Path) -> None:
    text = TWO.format(a='pst_udp_port = 12000\npst_udp_bind = "0.0.0.0"', b="")
    _doc, warnings = check_config(write(tmp_path, text))
    assert any(
        w.startswith("rotators[0].pst_udp_bind: 0.0.0.0 is not a loopback address")
        for w in warnings
    ), warnings


def test_n1mm_reports_to_another_machine_need_a_bind_that_can_reach_it(tmp_path: Path) -> None:
    """Reports leave from the N1MM port's own socket (interfaces/loggers/server.py rule 6): one
    bound to loopback cannot reach another PC, and N1MM's rotor display would never move."""
    base = 'n1mm_rotor_name = "Tower"\nn1mm_report_to = "192.168.1.20:13010"\n'
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL + base), environ={})
    assert "n1mm_udp_bind" in str(err.value) and "n1mm_report_to" in str(err.value)
    ok = load_settings(write(tmp_path, MINIMAL + base + 'n1mm_udp_bind = "0.0.0.0"\n'), environ={})
    assert ok.rotators[0].n1mm_report_address == ("192.168.1.20", 13010)


# -- check-config's summary: what a user checks first -------------------------------------------
def test_check_config_summarises_rotators_broker_and_what_is_on(tmp_path: Path) -> None:
    device = tmp_path / "ttyUSB0"
    device.write_text("")
    missing = tmp_path / "ttyUSB9"
    text = (
        '[mqtt]\nhost = "broker.lan"\nusername = "u"\npassword = "sum-S3cret"\n'
        '[station]\nlocator = "JO62qm"\n'
        f'[[rotators]]\nid = "tower"\nname = "Tower"\nmodel = "rotorez"\nport = "{device}"\n'
        'rotctld_port = 4533\npst_udp_port = 12000\nn1mm_rotor_name = "Tower"\n'
        f'[[rotators]]\nid = "sky"\nmodel = "rot2prog"\nport = "{missing}"\naz_offset_deg = 90\n'
    )
    path = write(tmp_path, text)
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 0 and out.stderr == "", out.stderr
    lines = out.stdout.splitlines()
    said = "\n".join(lines)
    assert f"tower (Tower): Rotor-EZ (rotorez) on {device} (found)" in said
    assert f"sky: Rot2Prog (rot2prog) on {missing} (NOT FOUND)" in said
    assert "rotctld on 127.0.0.1:4533" in said and "PstRotator UDP on 127.0.0.1:12000" in said
    assert "N1MM 'Tower' on 127.0.0.1:12040" in said and "takes bearings -90..630" in said
    assert "takes bearings -90..630; elevations -20..210" in said  # (the Rot2Prog's own)
    assert said.count("elevations") == 1  # (the Rotor-EZ has none)
    assert "broker: broker.lan:1883, MQTT 5, else 3.1.1, no TLS, user u, a password" in said
    assert "home assistant: on (discovery prefix homeassistant)" in said
    assert "station: locator JO62qm, latitude 52.5208, longitude 13.3750" in said
    assert "tracking: the sun and the moon; no TLE file" in said
    assert any(line.startswith(f"warning: rotators[1].port: {missing}") for line in lines)
    assert "sum-S3cret" not in said and "{" not in said  # every value only with --full
    assert lines[-1] == f"config OK: {path}"


def test_a_port_the_kernel_numbers_is_warned_about(tmp_path: Path) -> None:
    # Two Rotor-EZs on /dev/ttyUSB0 and /dev/ttyUSB1 answer alike: once the adapters come up
    # the other way round (a reboot, a re-plug), each rotator's commands turn the other
    # antenna, and nothing on the line says so.
    text = (
        '[[rotators]]\nid = "high"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'
        '[[rotators]]\nid = "low"\nmodel = "rotorez"\nport = "/dev/ttyACM1"\n'
    )
    warned = [w for w in config_warnings(load_settings(write(tmp_path, text), environ={}))]
    for i, port in enumerate(["/dev/ttyUSB0", "/dev/ttyACM1"]):
        assert (
            f"rotators[{i}].port: {port} is numbered in the order the adapters appear: after a "
            "re-plug or a reboot it can name another adapter (another rotator's controller, a "
            "radio), or none; name the adapter by its /dev/serial/by-id/ path (`rotor-bridge "
            "ports`)"
        ) in warned, warned
    stable = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0"
    text = text.replace("/dev/ttyUSB0", stable).replace("/dev/ttyACM1", "/dev/rotor-low")
    warned = config_warnings(load_settings(write(tmp_path, text), environ={}))
    assert not [w for w in warned if "numbered" in w], warned


@pytest.mark.parametrize("name", ["example.toml", "band-map.toml", "two-boxes.toml"])
def test_the_example_configurations_name_adapters_by_a_stable_path(name: str) -> None:
    s = load_settings(ROOT / "config" / name, environ={})
    assert not [w for w in config_warnings(s) if "numbered" in w]


def test_check_config_names_the_gap_an_offset_puts_in_narrowed_limits(tmp_path: Path) -> None:
    # limits 20..340 on a scale that wraps, offset 180: true 160..200 is refused, not 0 or 360
    text = (
        f'[[rotators]]\nid = "hf"\nmodel = "rotorez"\nport = "{tmp_path / "tty"}"\n'
        "az_offset_deg = 180\naz_min_deg = 20\naz_max_deg = 340\n"
    )
    out = cli("check-config", "-c", str(write(tmp_path, text)))
    assert out.returncode == 0, out.stderr
    assert "takes bearings 0..360 except 160..200" in out.stdout, out.stdout


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (("[[rotators]]", "[[rotator]]"), "unknown table [[rotator]]: did you mean [[rotators]]?"),
        (("[[rotators]]", "[rotator]"), "unknown table [rotator]: did you mean [[rotators]]?"),
        (("[mqtt]", "[mqt]"), "unknown table [mqt]: did you mean [mqtt]?"),
        (("brake_delay_s", "brake_delay"), "rotators[0].brake_delay: unknown key: did you mean "),
        (("host =", "hots ="), "mqtt.hots: unknown key: did you mean host?"),
        (("[mqtt]", "colour = 1\n[mqtt]"), "colour: unknown key (typo?)"),
        (("[mqtt]", "[radio]"), "unknown table [radio] (the tables here: [mqtt], [homeass"),
    ],
)
def test_an_unknown_table_or_key_names_the_nearest_known_one(
    tmp_path: Path, change: tuple[str, str], said: str
) -> None:
    text = MINIMAL.replace(*change)
    out = cli("check-config", "-c", str(write(tmp_path, text)))
    assert out.returncode == 2 and out.stdout == "", out
    assert said in out.stderr, out.stderr
    assert "no rotators configured" not in out.stderr and "Field required" not in out.stderr


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (
            ("[[rotators]]", "[rotators]"),
            "rotators: written [rotators], one table; write [[rotators]], with two brackets",
        ),
        (("[mqtt]", "[[mqtt]]"), "mqtt: written [[mqtt]], a list of tables; write [mqtt], with"),
    ],
)
def test_a_table_with_the_wrong_brackets_says_which_to_write(
    tmp_path: Path, change: tuple[str, str], said: str
) -> None:
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL.replace(*change))))
    assert out.returncode == 2 and out.stdout == "", out
    assert said in out.stderr, out.stderr
    assert "valid list" not in out.stderr and "MqttSettings" not in out.stderr


def test_check_config_by_hand_says_the_state_file_and_client_id_the_service_will_use(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from bridge.settings import report

    monkeypatch.delenv("STATE_DIRECTORY", raising=False)
    monkeypatch.setattr(report, "CONTAINER_MARKS", ())  # as on a host (the tests may not be)
    path = str(write(tmp_path, MINIMAL))
    by_hand = cli("check-config", "-c", path, env={"HOME": str(tmp_path)})
    service = cli("check-config", "-c", path, env={"STATE_DIRECTORY": "/var/lib/rotor-bridge"})
    assert by_hand.returncode == 0 and service.returncode == 0, (by_hand, service)
    lines = {ln.split(":")[0]: ln for ln in service.stdout.splitlines()}
    assert lines["state file"] == "state file: /var/lib/rotor-bridge/state.json"
    service_id = lines["broker"].rsplit("client id ", 1)[1]
    home_file = tmp_path / ".local" / "state" / "rotor-bridge" / "state.json"
    assert f"state file: {home_file} (run by hand as " in by_hand.stdout, by_hand.stdout
    assert "; under the systemd unit /var/lib/rotor-bridge/state.json)" in by_hand.stdout
    assert f" (under the systemd unit {service_id})\n" in by_hand.stdout, by_hand.stdout


def test_check_config_on_macos_says_nothing_of_a_systemd_unit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rule 6 is for Linux: a Mac has no systemd, and its summary named a unit's state file and
    client id that user will never have."""
    import sys

    from bridge.settings import report

    monkeypatch.delenv("STATE_DIRECTORY", raising=False)
    settings = load_settings(write(tmp_path, MINIMAL), environ={})
    monkeypatch.setattr(report, "CONTAINER_MARKS", ())  # as on a host (the tests may not be)
    monkeypatch.setattr(sys, "platform", "darwin")
    lines = "\n".join(report.summary(settings))
    assert f"state file: {settings.state_file}\n" in lines + "\n", lines
    assert "systemd" not in lines, lines


def unopenable_port(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str) -> Path:
    """A serial port (a file, mode 0660) that check-config finds this user may not open, as a
    user outside its group would find it (the tests may run as root, who may open all)."""
    from bridge.settings import report

    port = tmp_path / name
    port.touch()
    port.chmod(0o660)
    real_access = os.access
    monkeypatch.setattr(
        report.os, "access", lambda p, mode: str(p) != str(port) and real_access(p, mode)
    )
    return port


def check_config_on(tmp_path: Path, port: Path) -> subprocess.CompletedProcess[str]:
    """``check-config`` of a configuration whose one rotator is on ``port``: it ends well."""
    text = MINIMAL.replace(
        "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A1B2C3-if00-port0", str(port)
    )
    out = cli("check-config", "-c", str(write(tmp_path, text)), env={"HOME": str(tmp_path)})
    assert out.returncode == 0, out
    return out


def test_check_config_warns_of_a_port_this_user_may_not_open_and_names_the_group(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import getpass
    import grp

    from bridge.settings import report

    port = unopenable_port(tmp_path, monkeypatch, "ttyUSB-by-id")
    group = grp.getgrgid(port.stat().st_gid).gr_name
    monkeypatch.setattr(report, "CONTAINER_MARKS", ())  # as on a host (the tests may not be)
    out = check_config_on(tmp_path, port)
    user = getpass.getuser()
    assert (
        f"warning: rotators[0].port: {port} cannot be opened by {user}: run by hand, the bridge "
        f"keeps trying and says 'no permission'; add {user} to group {group} "
        f"(`sudo usermod -aG {group} {user}`, then log in again)"
    ) in out.stdout, out.stdout


def test_check_config_tells_a_user_already_in_the_ports_group_to_log_in_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Added to the port's group (usermod) but not logged in again since: this login has not
    the group yet. It told them to add themselves to the group they are already in."""
    import getpass
    import grp

    from bridge.settings import report

    port = unopenable_port(tmp_path, monkeypatch, "ttyUSB-by-id")
    gid = port.stat().st_gid  # this user's own group: the user is in it
    group = grp.getgrgid(gid).gr_name
    monkeypatch.setattr(report, "CONTAINER_MARKS", ())  # as on a host (the tests may not be)
    monkeypatch.setattr(report.os, "getgroups", lambda: [g for g in [gid + 1] if g != gid])
    monkeypatch.setattr(report.os, "getegid", lambda: gid + 1)
    out = check_config_on(tmp_path, port)
    user = getpass.getuser()
    assert (
        f"warning: rotators[0].port: {port} cannot be opened by {user}: run by hand, the bridge "
        f"keeps trying and says 'no permission'; {user} is in group {group}, but not this "
        f"login, from before: log out and in again (or run `newgrp {group}`)"
    ) in out.stdout, out.stdout
    assert "usermod" not in out.stdout


def test_check_config_in_a_container_names_the_ports_group_number_for_group_add(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """In Docker the port keeps the host's group number, and a container has no login nor a
    systemd unit: it was told to usermod and log in again, and that the unit's user is in
    dialout. What helps is that number in compose's group_add."""
    from bridge.settings import report

    monkeypatch.delenv("STATE_DIRECTORY", raising=False)  # (an image without the Dockerfile's)

    port = unopenable_port(tmp_path, monkeypatch, "rotor")
    gid = port.stat().st_gid
    mark = tmp_path / ".dockerenv"
    mark.touch()
    monkeypatch.setattr(report, "CONTAINER_MARKS", (str(mark),), raising=False)
    out = check_config_on(tmp_path, port)
    assert (
        f"'no permission'; in this container: give it the port's group, number {gid} on the "
        f"host, in compose's group_add (docker run --group-add {gid})"
    ) in out.stdout, out.stdout
    assert "usermod" not in out.stdout and "systemd" not in out.stdout


def test_check_config_as_a_user_id_without_a_name_warns_and_ends_well(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``docker run --user 1000``: a user id the image's passwd does not name, no USER in the
    environment. A port it may not open ended check-config in a KeyError traceback (getpass);
    it names the user by its number."""
    import pwd

    from bridge.settings import report

    port = unopenable_port(tmp_path, monkeypatch, "rotor")
    mark = tmp_path / ".dockerenv"
    mark.touch()
    monkeypatch.setattr(report, "CONTAINER_MARKS", (str(mark),))
    for name in ("LOGNAME", "USER", "LNAME", "USERNAME"):
        monkeypatch.delenv(name, raising=False)

    def nameless(uid: int) -> Any:
        raise KeyError(f"getpwuid(): uid not found: {uid}")

    monkeypatch.setattr(pwd, "getpwuid", nameless)
    out = check_config_on(tmp_path, port)
    assert f"{port} cannot be opened by uid {os.getuid()}: " in out.stdout, out.stdout


def test_a_file_without_rotators_says_what_to_add_not_to_pass_config(tmp_path: Path) -> None:
    path = write(tmp_path, '[mqtt]\nhost = "broker.lan"\n')
    with pytest.raises(ConfigError) as exc:
        load_settings(path, environ={})
    assert str(exc.value).startswith(f"no rotators configured in {path}: add a [[rotators]]")
    assert "--config" not in str(exc.value)


def test_an_unknown_key_set_in_the_environment_names_its_variable(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The file has no such key: without the variable's name the user looks for it in vain."""
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__HOTS", "broker.lan")
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL))
    assert "mqtt.hots (from ROTOR_BRIDGE_MQTT__HOTS): unknown key: did you mean host?" in str(
        err.value
    )
    monkeypatch.delenv("ROTOR_BRIDGE_MQTT__HOTS")
    environ = {"ROTOR_BRIDGE_ROTATORS__TOWER__BAUDRATE": "9600"}
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL), environ)
    assert "rotators[0].baudrate (from ROTOR_BRIDGE_ROTATORS__TOWER__BAUDRATE): unknown key" in str(
        err.value
    )


@pytest.mark.parametrize(
    ("host", "said"),
    [
        ("mqtt://broker.lan:1883", "not a URL"),
        ("broker.lan:1883", "without its port"),
        ("x" * 64 + ".lan", "is no host name"),
        ("broker..lan", "is no host name"),
        ("[::1]:1883", "without brackets"),  # (a review)
        ("[::1]", "without brackets"),
    ],
)
def test_a_broker_host_that_can_never_connect_is_refused_naming_the_key(
    tmp_path: Path, host: str, said: str
) -> None:
    """An attack pass: a URL passed check-config ("config OK", then "Name or service not
    known" at every retry, naming no key); a label over 63 characters logged a traceback at
    every retry."""
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL.replace('"127.0.0.1"', f'"{host}"')))
    assert "mqtt.host" in str(err.value) and said in str(err.value)
    for fine in ("broker.lan", "broker.lan.", "192.168.1.2", "::1", "fe80::1%eth0"):
        load_settings(write(tmp_path, MINIMAL.replace('"127.0.0.1"', f'"{fine}"')))


@pytest.mark.parametrize(
    ("key", "value", "said"),
    [
        ("rotctld_bind", "shack-pc.lan:Sekr1tPW@127.0.0.1", "not a URL with a login"),
        ("gs232_bind", "x y", "a host name or address, got 'x y'"),
        ("easycomm_bind", "127.0.0.1:4536", "without its port: '127.0.0.1:4536' (easycomm_port)"),
        ("dcu1_bind", "tcp://0.0.0.0", "not a URL"),
        ("pst_udp_bind", "not an address", "a host name or address, got"),
        ("n1mm_udp_bind", "[::1]", "without brackets"),
    ],
)
def test_an_address_to_listen_on_that_can_never_be_is_refused_naming_the_key(
    tmp_path: Path, key: str, value: str, said: str
) -> None:
    """An attack pass: check-config said "config OK" for these, and ``run`` then stopped with
    "cannot listen on shack-pc.lan:Sekr1tPW@127.0.0.1:14600: Name or service not known", a line
    that named no key and quoted what came before the '@'."""
    path = write(tmp_path, MINIMAL + f'{key} = "{value}"\n')
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 2 and "Sekr1tPW" not in out.stdout + out.stderr
    assert f"rotators[0].{key}: " in out.stderr and said in out.stderr, out.stderr
    for fine in ("", "0.0.0.0", "::", "::1", "localhost", "shack-pc.lan"):
        load_settings(write(tmp_path, MINIMAL + f'{key} = "{fine}"\n'))


@pytest.mark.parametrize(
    "host",
    [
        "mqtt://rotor:Sekr1tPW@broker.lan:1883",
        "rotor:Sekr1tPW@broker.lan",
        "mqtts://rotor:Sekr1tPW@broker.lan",
        "rotor:Sekr1tPW @broker.lan",
    ],
)
def test_a_broker_url_with_its_login_is_refused_without_the_password(
    tmp_path: Path, host: str
) -> None:
    """An attack pass: a broker written as a URL with its login, in the file or the
    environment, was refused with the whole value quoted ("not a URL: 'mqtt://rotor:...'"), the
    password on the terminal and in the journal."""
    path = write(tmp_path, MINIMAL.replace('"127.0.0.1"', f'"{host}"'))
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 2 and "Sekr1tPW" not in out.stdout + out.stderr
    assert "mqtt.host: a host name or address, not a URL with a login" in out.stderr
    assert "mqtt.username and mqtt.password_file" in out.stderr
    out = cli(
        "check-config", "-c", str(write(tmp_path, MINIMAL)), env={"ROTOR_BRIDGE_MQTT__HOST": host}
    )
    assert out.returncode == 2 and "Sekr1tPW" not in out.stdout + out.stderr
    assert (
        "mqtt.host (from ROTOR_BRIDGE_MQTT__HOST): a host name or address, not a URL" in out.stderr
    )


@pytest.mark.parametrize(
    "variable",
    [
        "ROTOR_BRIDGE_WEB__HOST_NAMES=shack.example.org",
        "ROTOR_BRIDGE_DXCLUSTER__BANDS=20m",
        "ROTOR_BRIDGE_MQTT__TLS=on",
    ],
)
def test_a_list_or_table_set_from_the_environment_not_in_json_names_its_variable(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, variable: str
) -> None:
    """An attack pass: these ended check-config and run in a 58-line traceback that named
    neither the variable nor the key."""
    name, value = variable.split("=")
    monkeypatch.setenv(name, value)
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__HOST", "broker.lan")  # (plain: not named)
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL))
    assert str(err.value).startswith(f"{name}: a list or a table is set from the environment")


@pytest.mark.parametrize(
    ("model", "said"),
    [
        ("rotor-ez", "did you mean rotorez?"),
        ("RotorEZ", "did you mean rotorez?"),
        ("rot2prg", "did you mean rot2prog?"),
        ("yaesu", "with Idiom Press's RotorCard fitted is rotorcard"),
        ("Yaesu G-800DXA", "with Idiom Press's RotorCard fitted is rotorcard"),
        ("yaesu", "through a GS-232A or GS-232B box is gs232a or gs232b"),
        ("K3NG", "speaks GS-232: gs232b"),
        ("satnogs", "speaks Easycomm: easycomm2"),
        ("hy-gain", "with Idiom Press's Rotor-EZ is rotorez; Hy-Gain's own DCU-1 is dcu1"),
        ("hygain", "with Idiom Press's Rotor-EZ is rotorez; Hy-Gain's own DCU-1 is dcu1"),
        ("spid", "rot2prog, rot1prog (azimuth only) or md01"),
        ("ve5fp", "is satel"),
        ("Green Heron", "RT-21 is rt21"),
        ("rt-21", "did you mean rt21?"),
        ("Prosistel PST-61D", "D box is prosistel (azimuth) or prosistel-el (elevation; "),
        ("Prosistel D elevation", "prosistel-el-a if it answers as unit A"),
        ("Combi-Track", "Combi-Track is prosistel-combi"),
        ("M2", "RC2800 is rc2800 (az/el) or rc2800-az"),
    ],
)
def test_an_unknown_model_names_the_nearest_model_or_the_one_for_its_maker(
    tmp_path: Path, model: str, said: str
) -> None:
    """As a key typo names the key meant: a user who wrote the box's maker or misspelt the
    model learns which name to write, on the one line that names the field."""
    text = MINIMAL.replace('model = "rotorez"', f"model = {model!r}".replace("'", '"'))
    with pytest.raises(ConfigError) as exc:
        load_settings(write(tmp_path, text), environ={})
    (line,) = [ln.strip() for ln in str(exc.value).splitlines() if "model" in ln]
    assert line.startswith(f"rotators[0].model: unknown model {model!r}; ") and said in line, line
    assert line.endswith(" known models: " + ", ".join(sorted(REGISTRY))), line


def test_an_unknown_model_like_none_is_listed_without_a_guess(tmp_path: Path) -> None:
    text = MINIMAL.replace('model = "rotorez"', 'model = "xyzzy"')
    with pytest.raises(ConfigError) as exc:
        load_settings(write(tmp_path, text), environ={})
    assert "rotators[0].model: unknown model 'xyzzy'; known models: dcu1, " in str(exc.value)


@pytest.mark.parametrize(
    "kind", ["FIFO", "directory", "file under a file", "link for its lock", "FIFO for its lock"]
)
def test_check_config_refuses_a_state_file_the_start_would_refuse(
    tmp_path: Path, kind: str
) -> None:
    """check-config said "config OK" and run then stopped with exit 2: it tries the state
    file as the start does (tests/faults/test_config.py has the start's line), writing
    nothing. So for the installation's lock beside it (state_store.py rule 7: a review,
    the start refused a link or a FIFO there, check-config said "config OK")."""
    state_file = tmp_path / "state" / "state.json"
    state_file.parent.mkdir()
    lock = tmp_path / "state" / "state.json.lock"
    if kind.endswith("for its lock"):
        state_file.write_text('{"rotators": {}}')
        if kind.startswith("link"):
            lock.symlink_to(tmp_path / "audit.log")
            said = f"{lock} is a symbolic link, not a file of its own"
        else:
            os.mkfifo(lock)
            said = f"{lock} is not a regular file"
    elif kind == "FIFO":
        os.mkfifo(state_file)
        said = "it is a FIFO, not a regular file"
    elif kind == "directory":
        state_file.mkdir()
        said = "it is a directory, not a regular file"
    else:
        (tmp_path / "state" / "a-file").write_text("")
        state_file = tmp_path / "state" / "a-file" / "rotor" / "state.json"
        said = f"Not a directory ({state_file})"
    text = f"state_file = {str(state_file)!r}\n".replace("'", '"') + MINIMAL
    # a process of its own: a FIFO opened for writing would block a check-config in this one
    # for ever, where the process's deadline says so
    out = run_cli("check-config", "-c", str(write(tmp_path, text)), timeout_s=20)
    assert out.returncode == 2 and out.stdout == "", out
    assert out.stderr == f"rotor-bridge: state_file {state_file} cannot be written: {said}\n"
    beside = ["state.json.lock"] if kind.endswith("for its lock") else []
    assert sorted(p.name for p in (tmp_path / "state").iterdir()) == [
        "a-file" if kind == "file under a file" else "state.json",
        *beside,
    ]
    assert not (tmp_path / "audit.log").exists()  # (nothing made through the link)


def test_check_config_writes_no_state_file_and_warns_of_a_directory_it_cannot_write(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The service may run as another user than check-config, so a directory closed to this
    one is a warning, not an error; and checking writes nothing (no directory either)."""
    state_file = tmp_path / "state" / "rotor" / "state.json"
    text = f"state_file = {str(state_file)!r}\n".replace("'", '"') + MINIMAL
    out = cli("check-config", "-c", str(write(tmp_path, text)))
    assert out.returncode == 0 and "warning: state_file" not in out.stdout, out
    assert not (tmp_path / "state").exists()
    s = load_settings(write(tmp_path, text), environ={})
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != tmp_path)  # as non-root
    (warning,) = [w for w in config_warnings(s) if w.startswith("state_file")]
    assert warning.startswith(f"state_file: {tmp_path} cannot be written by "), warning


# -- what passed check-config and then crashed or misbehaved (an attack pass) -----------------


def refusal(data: dict[str, Any]) -> str:
    """The configuration error ``data`` (a TOML document, no environment) is refused with."""
    with pytest.raises(ConfigError) as err:
        settings_from(data, {})
    return str(err.value)


def document(rotator: dict[str, Any] | None = None, **mqtt: Any) -> dict[str, Any]:
    tower = {"id": "tower", "model": "rotorez", "port": "/dev/ttyUSB0", **(rotator or {})}
    return {"mqtt": {"host": "127.0.0.1", **mqtt}, "rotators": [tower]}


@pytest.mark.parametrize(
    ("variable", "key"),
    [
        ("ROTOR_BRIDGE_MQTT__PASSWORD", "mqtt.password"),
        ("ROTOR_BRIDGE_MQTT__USERNAME", "mqtt.username"),
        ("ROTOR_BRIDGE_MQTT__BASE_TOPIC", "mqtt.base_topic"),
        ("ROTOR_BRIDGE_MQTT__CLIENT_ID", "mqtt.client_id"),
        ("ROTOR_BRIDGE_ROTATORS__TOWER__NAME", "rotators[0].name"),
        ("ROTOR_BRIDGE_ROTATORS__TOWER__ROTCTLD_BIND", "rotators[0].rotctld_bind"),
        ("ROTOR_BRIDGE_ROTATORS__TOWER__PORT", "rotators[0].port"),
        ("ROTOR_BRIDGE_STATE_FILE", "state_file"),
        ("ROTOR_BRIDGE_MQTT__TLS__CA_FILE", "mqtt.tls.ca_file"),
    ],
)
def test_a_value_from_the_environment_that_is_not_utf8_is_refused_naming_its_key(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, variable: str, key: str
) -> None:
    """os.environ holds a byte that is not UTF-8 as a lone surrogate (settings/base.py rule
    3): check-config said "config OK", then run ended in a traceback where the MQTT client
    encoded the password, the user name, the client id or a topic, or where a bind address was
    looked up; a rotator's name broke its Home Assistant discovery; a path named in an error
    ended check-config in one. Never the value."""
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__USERNAME", "rotor")
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__TLS__ENABLED", "true")
    monkeypatch.setenv(variable, "s3cret\udcff")  # what os.environ holds for b"s3cret\xff"
    with pytest.raises(ConfigError) as err:
        load_settings(write(tmp_path, MINIMAL))
    assert f"{key} (from {variable}): must be UTF-8 text: set it again, in UTF-8" in str(err.value)
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL)), env={variable: "s3cret\udcff"})
    assert out.returncode == 2 and out.stdout == "", out
    assert variable in out.stderr and "s3cret" not in out.stderr and "Traceback" not in out.stderr


def test_the_config_files_own_path_and_the_home_folder_need_not_be_utf8(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No keys: the bridge opens them (the home folder's state file path is hashed into the
    default client id as bytes: a home folder not in UTF-8 ended check-config in a traceback)."""
    folder = tmp_path / "d\udce9"
    folder.mkdir()
    monkeypatch.setenv("HOME", str(folder))
    monkeypatch.setenv("ROTOR_BRIDGE_CONFIG", str(write(folder, MINIMAL)))
    settings = load_settings(None)
    assert settings.mqtt.effective_client_id().startswith("rotor-")


@pytest.mark.parametrize("topic", ["rb\u0001x", "rb\nx", "rb\tx", "rb\u007fx", "rb\u0085x"])
def test_a_topic_with_a_control_character_is_refused_naming_the_key(topic: str) -> None:
    """mosquitto drops a CONNECT whose will topic (under the base topic) holds one ("Malformed
    UTF-8"): the bridge blamed the broker's access rules, fell back to MQTT 3.1.1 and never
    connected."""
    said = ", which MQTT does not carry (a control character, a lone surrogate or a non-character)"
    assert f"mqtt.base_topic: holds U+{ord(topic[2]):04X}{said}" in refusal(
        document(base_topic=topic)
    )
    assert f"rotators[0].topic: holds U+{ord(topic[2]):04X}" in refusal(document({"topic": topic}))
    ha = {**document(), "homeassistant": {"discovery_prefix": topic}}
    assert "homeassistant.discovery_prefix: holds U+" in refusal(ha)
    ha = {**document(), "homeassistant": {"status_topic": topic}}
    assert "homeassistant.status_topic: holds U+" in refusal(ha)
    wind = {"wind_topic": topic, "wind_park_above": 60, "park_az_deg": 0}
    assert "rotators[0]: wind_topic: one topic, without wildcards" in refusal(document(wind))


def test_a_topic_the_bridge_publishes_under_does_not_start_with_a_dollar() -> None:
    """$SYS and the like are the broker's: it takes no message from a client there."""
    said = "must not start with '$': the broker keeps those topics for itself"
    assert f"mqtt.base_topic: {said}" in refusal(document(base_topic="$rotor"))
    assert f"rotators[0].topic: {said}" in refusal(document({"topic": "$shack/tower"}))
    ha = {**document(), "homeassistant": {"discovery_prefix": "$ha"}}
    assert f"homeassistant.discovery_prefix: {said}" in refusal(ha)
    # Home Assistant's status topic is Home Assistant's: the bridge only listens there
    ha = {**document(), "homeassistant": {"status_topic": "$ha/status"}}
    assert settings_from(ha, {}).homeassistant.status_topic == "$ha/status"
    assert settings_from(document(base_topic="shack/$rotor"), {}).mqtt.base_topic == "shack/$rotor"


def test_a_topic_the_bridge_publishes_under_has_at_most_32_levels() -> None:
    """Brokers drop a client (mosquitto, past some 200 levels) or die (aedes, past 100) for a
    subscription deeper than they take; the bridge adds levels under its own (review 102)."""
    deep = "/".join(["a"] * 33)
    said = "has 33 levels, at most 32"
    assert f"mqtt.base_topic: {said}" in refusal(document(base_topic=deep))
    assert f"rotators[0].topic: {said}" in refusal(document({"topic": deep}))
    ok = "/".join(["a"] * 32)
    assert settings_from(document(base_topic=ok), {}).mqtt.base_topic == ok


@pytest.mark.parametrize(
    ("key", "most"),
    [("client_id", 65530), ("username", 65535), ("password", 65535), ("base_topic", 64511)],
)
def test_an_mqtt_string_longer_than_mqtt_allows_is_refused_naming_the_key(
    key: str, most: int
) -> None:
    """MQTT's strings are at most 65535 bytes: a longer client id or base topic passed, and run
    logged a struct.error traceback at every connection attempt, never connecting. The base
    topic keeps room for the levels the bridge adds, the client id for the stop lane's
    "-stop"; the length is counted in UTF-8, and the value is never quoted."""
    fine = {"username": "rotor", key: "é" * (most // 2)}
    off = {"homeassistant": {"enabled": False}}  # (its discovery prefix: below)
    assert settings_from({**document(**fine), **off}, {}).mqtt.username is not None
    text = refusal({**document(**{**fine, key: "é" * (most // 2) + "ab"}), **off})
    assert f"mqtt.{key}: a " in text and f"is at most {most} bytes in UTF-8" in text, text
    assert "éé" not in text
    ha = {**document(base_topic="r" * 40_000), "homeassistant": {"discovery_prefix": "h" * 30_000}}
    assert "mqtt.base_topic and homeassistant.discovery_prefix are together at most" in refusal(ha)
    settings_from({**ha, "homeassistant": {**ha["homeassistant"], "enabled": False}}, {})


def test_a_password_file_longer_than_mqtt_allows_is_refused_unquoted(tmp_path: Path) -> None:
    pw = tmp_path / "pw"
    pw.write_text("x" * 70_000 + "\n")
    os.chmod(pw, 0o600)
    text = refusal(document(username="rotor", password_file=str(pw)))
    assert f"mqtt: password_file {pw}: a password is at most 65535 bytes" in text
    assert "xxx" not in text


@pytest.mark.parametrize(
    ("table", "key"),
    [
        ("mqtt", "port"),
        ("mqtt", "keepalive_s"),
        ("web", "port"),
        ("homeassistant", "birth_delay_s"),
        ("rotators", "park_az_deg"),
        ("rotators", "az_max_deg"),
        ("rotators", "rotctld_port"),
        ("rotators", "baud"),
        ("rotators", "presets"),
        ("rotators", "keep_out"),
        (None, "audit_max_bytes"),
    ],
)
def test_a_boolean_where_a_number_belongs_is_refused_naming_the_key(
    table: str | None, key: str
) -> None:
    """pydantic reads true as 1: `port = true` connected to port 1, `park_az_deg = true`
    parked the antenna at 1 degree, `az_max_deg = true` limited it to 0..1."""
    value: Any = {"presets": {"EU": True}, "keep_out": [[True, 20]]}.get(key, True)
    data = document()
    if table == "rotators":
        data["rotators"][0][key] = value
        where = f"rotators[0].{key}"
    elif table is not None:
        data.setdefault(table, {})[key] = value
        where = f"{table}.{key}"
    else:
        data[key] = value
        where = key
    assert f"{where}: must be a number, not true or false" in refusal(data)


def test_a_number_from_the_environment_is_still_read_as_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__PORT", "8883")
    monkeypatch.setenv("ROTOR_BRIDGE_ROTATORS__TOWER__PARK_AZ_DEG", "180")
    s = settings_from(document(), os.environ)
    assert (s.mqtt.port, s.rotators[0].park_az_deg) == (8883, 180.0)
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__PORT", "true")
    with pytest.raises(ConfigError, match=r"mqtt\.port \(from ROTOR_BRIDGE_MQTT__PORT\)"):
        settings_from(document(), os.environ)


@pytest.mark.parametrize("name", ["Tab\tName", "EU\n", "JA\u0085", "X\ufdd0"])
def test_a_preset_name_no_command_could_pick_is_refused_naming_it(name: str) -> None:
    """R/preset refuses a name MQTT does not carry (payloads.parse_name, core/text.py): Home
    Assistant's select offered it, and every pick of it was refused."""
    text = refusal(document({"presets": {name: 90}}))
    assert f"rotators[0]: presets: name {name!r} holds U+" in text, text


@pytest.mark.parametrize("value", [[], [45], [45, 10, 0]])
def test_a_preset_list_not_of_two_numbers_is_refused_naming_it(value: list[int]) -> None:
    """An attack pass: ``presets = { EU = [] }`` ended check-config and run in an IndexError
    traceback (the judge's terms were made of it before it was judged), and ``[45]`` on an
    az/el model was said to need a rotator with elevation."""
    text = refusal(document({"model": "gs232b", "presets": {"EU": value}}))
    expected = f"rotators[0].presets: 'EU': [azimuth, elevation] is two numbers, not {len(value)}"
    assert expected in text, text


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("Tower\\nconfig OK: forged\\u001b[31m", "rotators[0].name: holds U+000A, which MQTT"),
        ("\\u001b[2J", "rotators[0].name: holds U+001B, which MQTT"),
        (" ", "rotators[0].name: must be 1..64 characters without blanks at either end"),
        ("x" * 65, "rotators[0].name: must be 1..64 characters without blanks at either end"),
    ],
)
def test_a_rotator_name_no_one_could_read_is_refused_naming_it(
    tmp_path: Path, name: str, said: str
) -> None:
    """settings/base.py rule 5, an attack pass: any text was taken as a rotator's name, and
    check-config printed a name holding a line break and a terminal's escape sequence in its
    summary, a forged line of its own and the terminal turned red; a blank one gave Home
    Assistant a device with no name."""
    text = MINIMAL.replace('name = "Tower"', f'name = "{name}"')
    out = cli("check-config", "-c", str(write(tmp_path, text)))
    assert out.returncode == 2 and said in out.stderr, out.stdout + out.stderr
    assert "forged" not in out.stdout and "\x1b" not in out.stdout + out.stderr


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        (
            'port = "/dev/serial',
            'port = "/dev/ttyX\\nconfig OK: forged\\u001b[31m/dev/serial',
            "rotators[0].port",
        ),
        ("[mqtt]", 'state_file = "/tmp/st\\nconfig OK: forged.json"\n[mqtt]', "state_file"),
        (
            "brake_delay_s = 5",
            'brake_delay_s = 5\nrotctld_port = 4533\nrotctld_bind = "::1\\nconfig OK: forged"',
            "rotators[0].rotctld_bind",
        ),
        (
            "brake_delay_s = 5",
            'brake_delay_s = 5\ngs232_pty = "/tmp/gs\\nconfig OK: forged"',
            "rotators[0].gs232_pty",
        ),
    ],
)
def test_a_path_or_an_address_holding_a_control_character_is_refused_naming_it(
    tmp_path: Path, old: str, new: str, key: str
) -> None:
    """settings/base.py rule 6, an attack pass: a serial port named with a line break and a
    terminal's escape sequence passed, and check-config's report and its warning that the port
    was not found each printed a forged line 'config OK: forged', the terminal turned red; a
    pty's path and a bind address, in check-config's summary, likewise."""
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL.replace(old, new, 1))))
    said = f"{key}: holds U+000A, a control character or a non-character"
    assert out.returncode == 2 and said in out.stderr, out.stdout + out.stderr
    assert "\nconfig OK: forged" not in out.stdout + out.stderr


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ('host = "127.0.0.1"', f'host = "{"x" * 70_000}"', "mqtt.host"),
        ("[mqtt]", f'state_file = "/tmp/{"s" * 70_000}"\n[mqtt]', "state_file"),
    ],
)
def test_a_value_of_70000_characters_is_refused_in_short_lines(
    tmp_path: Path, old: str, new: str, key: str
) -> None:
    """An attack pass: a validator quotes the value it refuses, and check-config printed an
    mqtt.host of 70,000 characters whole (a state_file as long twice) to the terminal and the
    journal. Each line of the error is cut short; the key is still named."""
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL.replace(old, new, 1))))
    assert out.returncode == 2 and f"{key}" in out.stderr, out.stderr[:300]
    assert len(out.stderr) < 3000 and "characters not shown)..." in out.stderr, len(out.stderr)


def test_a_park_elevation_out_of_the_limits_is_refused_naming_park_el_deg() -> None:
    """An attack pass: ``park_el_deg = -1`` was refused as ``park_az_deg: elevation -1 outside
    the limits``, naming the key that was right."""
    text = refusal(document({"model": "gs232b", "park_az_deg": 0, "park_el_deg": -1}))
    assert "rotators[0]: park_az_deg, park_el_deg: elevation -1 outside" in text, text


@pytest.mark.parametrize("name", ["شمال\u200cغرب", "my\u00a0shack", "\U0001fae8 Ham"])
def test_a_preset_name_in_any_script_is_taken_and_picked(name: str) -> None:
    """A zero-width non-joiner (Persian), a no-break space, a character newer than Python's
    tables: str.isprintable refused each (a review); the settings, R/preset and the console
    share core/text.py's rule."""
    from bridge.interfaces.mqtt.payloads import parse_name

    settings = settings_from(document({"presets": {name: 90}, "topic": f"rotor/{name}"}), {})
    assert name in settings.rotators[0].presets
    assert parse_name(name.encode(), "preset") == name


@pytest.mark.parametrize(
    ("port", "said"),
    [
        ("", "must name the serial port"),
        ("   ", "must name the serial port"),
        ("/dev/ttyUSB0\x00", "must not hold a NUL byte"),
    ],
)
def test_a_port_that_names_no_serial_port_is_refused_naming_the_key(port: str, said: str) -> None:
    """An empty port passed and the bridge tried to open it for ever; a NUL byte ended the
    check of the ports in "configuration: embedded null byte", naming no key."""
    assert f"rotators[0].port: {said}" in refusal(document({"port": port}))


@pytest.mark.parametrize("login", [{"password": "s3cret-pw"}, {"password_file": "pw"}])
def test_a_password_without_a_username_is_refused(tmp_path: Path, login: dict[str, str]) -> None:
    """The MQTT client logs in only with a user name: a password without one went unused, and
    check-config said "no login"."""
    if "password_file" in login:
        (tmp_path / "pw").write_text("s3cret-pw\n")
        os.chmod(tmp_path / "pw", 0o600)
        login = {"password_file": str(tmp_path / "pw")}
    key = next(iter(login))
    text = refusal(document(**login))
    assert f"mqtt.{key}: needs mqtt.username" in text and "s3cret" not in text, text
    assert settings_from(document(username="rotor", **login), {}).mqtt.password is not None


@pytest.mark.parametrize(
    ("where", "key"),
    [
        ({"state_file": "/tmp/a\x00b"}, "state_file"),
        ({"audit_file": "/tmp/a\x00b"}, "audit_file"),
        ({"mqtt": {"host": "h", "username": "u", "password_file": "/a\x00"}}, "mqtt.password_file"),
        ({"tracking": {"tle_file": "/tmp/a\x00b"}}, "tracking.tle_file"),
        (
            {"rotators": [{"id": "t", "model": "rotorez", "port": "/p", "gs232_pty": "/x\x00"}]},
            "rotators[0].gs232_pty",
        ),
    ],
)
def test_a_nul_byte_in_any_path_is_refused_naming_its_key(where: dict[str, Any], key: str) -> None:
    """A state file's ended check-config in a traceback, a password file's named no key, and an
    audit file's, a TLE file's and a pty's were "config OK" (a review; settings/base.py rule 3)."""
    assert f"{key}: must not hold a NUL byte" in refusal({**document(), **where})


@pytest.mark.parametrize("key", ["client_id", "username"])
def test_a_client_id_or_user_name_mqtt_does_not_carry_is_refused(key: str) -> None:
    """mosquitto closes such a CONNECT, and the bridge blamed the broker's access rules."""
    for value in ("rb\x01", "rb\ufdd0"):
        assert f"mqtt.{key}: a " in refusal(document(**{"username": "u", key: value}))


def test_a_rotators_list_or_table_from_the_environment_is_json() -> None:
    """docs/configuration.md: a list or a table is set from the environment in JSON; a
    rotator's was handed on as its text and refused as no table (a review)."""
    env = {
        "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS": '{"home": 10, "eu": 45}',
        "ROTOR_BRIDGE_ROTATORS__TOWER__KEEP_OUT": "[[100, 120]]",
    }
    settings = settings_from(document(), env)
    assert settings.rotators[0].presets == {"home": 10, "eu": 45}
    assert settings.rotators[0].keep_out == [(100, 120)]
    with pytest.raises(ConfigError) as err:
        settings_from(document(), {"ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS": "home=10"})
    assert str(err.value).startswith("ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS: a list or a table")


@pytest.mark.parametrize(
    ("variable", "hint"),
    [
        ("ROTOR_BRIDGE_MQTT_HOST=broker.lan", "did you mean ROTOR_BRIDGE_MQTT__HOST?"),
        ("ROTOR_BRIDGE_ROTATOR__TOWER__PORT=/dev/ttyUSB9", "did you mean ROTOR_BRIDGE_ROTATORS__"),
        # (a review: the rotators' own variables were dropped as silently, the file's port used)
        ("ROTOR_BRIDGE_ROTATORS__TOWER_PORT=/dev/ttyUSB9", "ROTATORS__TOWER__PORT?"),
        ("ROTOR_BRIDGE_ROTATORS__TOWER=/dev/ttyUSB9", "ROTATORS__<ID>__<KEY>"),
        ("ROTOR_BRIDGE_LOGLEVEL=DEBUG", "did you mean ROTOR_BRIDGE_LOG_LEVEL?"),
        ("rotor_bridge_statefile=/tmp/s.json", "did you mean ROTOR_BRIDGE_STATE_FILE?"),
    ],
)
def test_a_variable_of_the_bridge_that_names_no_key_is_refused_naming_it(
    tmp_path: Path, variable: str, hint: str
) -> None:
    """An attack pass: a variable whose first word is no key of the file's top (one ``_``
    where tables take ``__``, ``ROTATOR`` for ``ROTATORS``) was dropped without a word:
    check-config said "config OK" and the bridge went to the file's broker, or opened the
    file's port, while the user thought it changed. A typo must not silently do nothing."""
    name, value = variable.split("=")
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL)), env={name: value})
    assert out.returncode == 2, out
    assert "config OK" not in out.stdout
    assert f"{name}: " in out.stderr and "unknown" in out.stderr and hint in out.stderr, out
    path = str(write(tmp_path, MINIMAL))
    good = {"ROTOR_BRIDGE_MQTT__HOST": "broker.lan", "rotor_bridge_log_level": "DEBUG"}
    assert cli("check-config", env={"ROTOR_BRIDGE_CONFIG": path, **good}).returncode == 0


def test_a_variable_for_an_id_with_a_dash_written_with_underscores_says_how_to_spell_it(
    tmp_path: Path,
) -> None:
    """A shell's export and systemd's Environment= take no '-' in a name, so a rotator
    ``tower-2`` is set as ``ROTOR_BRIDGE_ROTATORS__TOWER-2__PORT`` (env(1) takes it) or in the
    file. A review: ``TOWER_2`` was only "no rotator with id 'tower_2'"."""
    config = write(tmp_path, MINIMAL.replace('id = "tower"', 'id = "tower-2"'))
    out = cli("check-config", "-c", str(config), env={"ROTOR_BRIDGE_ROTATORS__TOWER_2__PORT": "/x"})
    assert out.returncode == 2, out
    assert "no rotator with id 'tower_2'" in out.stderr, out.stderr
    assert "ROTOR_BRIDGE_ROTATORS__TOWER-2__PORT" in out.stderr and "env(1)" in out.stderr
    dashed = {"ROTOR_BRIDGE_ROTATORS__TOWER-2__PORT": str(tmp_path / "tty")}
    out = cli("check-config", "--full", "-c", str(config), env=dashed)
    assert out.returncode == 0, out.stderr
    assert json.dumps(str(tmp_path / "tty")) in out.stdout


@pytest.mark.parametrize("rid", ["a__b", "tower_"])
def test_a_rotator_whose_id_holds_the_delimiter_is_set_from_the_environment(
    tmp_path: Path, rid: str
) -> None:
    """The file's ids are looked for whole: ``a__b`` was read as id ``a`` and key ``b__port``
    ("no rotator with id 'a'"), so such a rotator could not be set from the environment."""
    config = write(tmp_path, MINIMAL.replace('id = "tower"', f'id = "{rid}"'))
    env = {f"ROTOR_BRIDGE_ROTATORS__{rid.upper()}__PORT": str(tmp_path / "tty")}
    out = cli("check-config", "--full", "-c", str(config), env=env)
    assert out.returncode == 0, out.stderr
    assert json.dumps(str(tmp_path / "tty")) in out.stdout


def test_a_variable_two_rotators_ids_both_fit_is_refused_naming_both(tmp_path: Path) -> None:
    """``ROTOR_BRIDGE_ROTATORS__SKY__AZIMUTH__PORT`` is ``sky``'s azimuth box's port and
    ``sky__azimuth``'s port: which cannot be told."""
    second = MINIMAL[MINIMAL.index("[[rotators]]") :].replace('id = "tower"', 'id = "sky__azimuth"')
    text = MINIMAL.replace('id = "tower"', 'id = "sky"') + second.replace("A1B2C3", "D4E5F6")
    env = {"ROTOR_BRIDGE_ROTATORS__SKY__AZIMUTH__PORT": str(tmp_path / "tty")}
    out = cli("check-config", "-c", str(write(tmp_path, text)), env=env)
    assert out.returncode == 2, out
    assert "rotator 'sky''s azimuth.port and rotator 'sky__azimuth''s port" in out.stderr, out


@pytest.mark.parametrize(
    ("first", "second", "why"),
    [
        ("ROTOR_BRIDGE_MQTT__HOST", "rotor_bridge_mqtt__host", "both set one key"),
        (
            "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU",
            "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__eu",
            "both set one key",
        ),
        # (a table below the top: pydantic-settings lays the two in their order; one of the
        # top, ROTOR_BRIDGE_MQTT, takes its key's variable over its JSON in either: review 69)
        ("ROTOR_BRIDGE_MQTT__TLS", "ROTOR_BRIDGE_MQTT__TLS__CA_FILE", "sets a table whole"),
        (
            "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS",
            "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS__EU",
            "sets a table whole",
        ),
    ],
)
def test_two_variables_that_set_one_key_are_refused_naming_both(
    tmp_path: Path, first: str, second: str, why: str
) -> None:
    """settings rule 4. An attack pass: the bridge took one of the two as their order in the
    environment decided, without a word (mqtt.host was a or b as the two were listed)."""
    values = {
        "ROTOR_BRIDGE_MQTT__TLS": '{"ca_file": "/etc/ssl/a.pem"}',
        "ROTOR_BRIDGE_ROTATORS__TOWER__PRESETS": '{"JA": 330}',
    }
    for env in ({first: values.get(first, "10"), second: "20"}, {second: "20", first: "10"}):
        env = {k: values.get(k, v) for k, v in env.items()}
        out = cli("check-config", "-c", str(write(tmp_path, MINIMAL)), env=env)
        assert out.returncode == 2, out
        said = [line for line in out.stderr.splitlines() if line.strip()]
        assert len(said) == 1 and f"{first}, {second}: " in said[0] and why in said[0], said


def test_the_configuration_files_variable_in_small_letters_is_refused_naming_it(
    tmp_path: Path,
) -> None:
    """The bridge reads ``ROTOR_BRIDGE_CONFIG`` as spelt, and every other variable in any case:
    ``rotor_bridge_config`` was "no configuration file given ... or set ROTOR_BRIDGE_CONFIG"."""
    out = cli("check-config", env={"rotor_bridge_config": str(write(tmp_path, MINIMAL))})
    assert out.returncode == 2, out
    assert "rotor_bridge_config: " in out.stderr and "spelt ROTOR_BRIDGE_CONFIG" in out.stderr


@pytest.mark.parametrize(
    ("variable", "itself"),
    [
        ("ROTOR_BRIDGE_CONFIG__X", "set ROTOR_BRIDGE_CONFIG itself"),
        ("ROTOR_BRIDGE_LOG_LEVEL__X", "set ROTOR_BRIDGE_LOG_LEVEL itself"),
        ("rotor_bridge_state_file__x", "set rotor_bridge_state_file itself"),
        ("ROTOR_BRIDGE_MQTT__HOST__X", "set ROTOR_BRIDGE_MQTT__HOST itself"),
        ("ROTOR_BRIDGE_WEB__HOST_NAMES__X", "set ROTOR_BRIDGE_WEB__HOST_NAMES itself"),
        ("ROTOR_BRIDGE_ROTATORS__TOWER__PORT__X", "set ROTOR_BRIDGE_ROTATORS__TOWER__PORT itself"),
    ],
)
def test_a_variable_under_a_key_that_is_one_value_is_refused_naming_it(
    tmp_path: Path, variable: str, itself: str
) -> None:
    """settings rule 4: a key that is one value has no key under it. An attack pass:
    ``ROTOR_BRIDGE_CONFIG__X`` and ``ROTOR_BRIDGE_LOG_LEVEL__X`` were dropped without a word
    ("config OK") while other variables that name no key were refused, and one under
    ``mqtt.host`` was "Input should be a valid string", naming no variable."""
    out = cli("check-config", "-c", str(write(tmp_path, MINIMAL)), env={variable: "DEBUG"})
    assert out.returncode == 2, out
    assert "config OK" not in out.stdout
    said = [line for line in out.stderr.splitlines() if line.strip()]
    assert len(said) == 1 and said[0].startswith(f"rotor-bridge: {variable}: "), out.stderr
    assert itself in said[0], out.stderr


@pytest.mark.parametrize(
    ("topic", "under"),
    [
        ("rotor/bearing", "rotor, rotator 'tower''s"),
        ("rotor", "rotor, rotator 'tower''s"),
        ("shack/tower/status", "shack/tower, rotator 'tower''s"),
    ],
)
def test_a_wind_topic_of_the_bridges_own_is_refused_naming_the_key(topic: str, under: str) -> None:
    """settings/wind.py rule 3: no weather station publishes there (an attack pass: taken
    without a word, the wind was silent for good)."""
    wind = {"wind_topic": topic, "wind_park_above": 60, "park_az_deg": 0}
    rotator = {**wind, "topic": "shack/tower"} if topic.startswith("shack") else wind
    assert (
        f"rotators[0].wind_topic: {topic} is one of the bridge's own topics (under {under}): "
        "give the weather station's topic"
    ) in refusal(document(rotator))
    two = {**document(wind), "rotators": [{**document(wind)["rotators"][0]}]}
    two["rotators"].append({"id": "dish", "model": "rotorez", "port": "/dev/ttyUSB1"})
    two["rotators"][0]["wind_topic"] = "rotor/bridge/state"
    assert "(under rotor/bridge, the bridge's)" in refusal(two)
    two["rotators"][0]["wind_topic"] = "rotor/dish/status"
    assert "(under rotor/dish, rotator 'dish''s)" in refusal(two)
    two["rotators"][0]["wind_topic"] = "rotor/weather/wind"  # under the base topic, no one's
    settings_from(two, {})


@pytest.mark.parametrize("topic", ["rotor/weather/wind", "rotor/wind_kmh", "shack/anemometer"])
def test_a_wind_topic_beside_a_lone_rotators_words_is_taken(topic: str) -> None:
    """settings/wind.py rule 3, a review: a lone rotator's topic is the base topic, and a
    station's topic beside its words (under the base topic, no one's, as with two rotators)
    was refused as the rotator's own; a rotator's own word there is still refused."""
    wind = {"wind_topic": topic, "wind_park_above": 60, "park_az_deg": 0}
    rotator = {**wind, "topic": "shack"} if topic.startswith("shack") else wind
    settings = settings_from(document(rotator), {})
    assert settings.rotators[0].wind_topic == topic
    root = topic.split("/")[0]
    rotator["wind_topic"] = f"{root}/status"
    assert f"(under {root}, rotator 'tower''s)" in refusal(document(rotator))


def test_a_configuration_file_where_the_console_keeps_its_secret_is_refused(
    tmp_path: Path,
) -> None:
    """Settings rule 6, a review: the console's secret beside the state file is a file the
    bridge writes, and the configuration file is none of those; a configuration file named
    console-secret in the state file's folder passed check-config, and the console took the
    configuration (readable by more than the service, often) as its login secret."""
    pw = tmp_path / "console-password"
    pw.write_text("a console password\n")
    pw.chmod(0o600)
    path = tmp_path / "console-secret"
    path.write_text(f'state_file = "{tmp_path}/s.json"\n{MINIMAL}\n[web]\npassword_file = "{pw}"\n')
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 2, out.stdout + out.stderr
    assert (
        f"the console's secret kept beside state_file: {path} is the configuration file itself"
    ) in out.stderr


def test_one_n1mm_port_bound_to_two_addresses_is_refused_naming_the_field(tmp_path: Path) -> None:
    """interfaces/loggers/server.py rule 10 (a cold review): with the port the bridge's alone,
    one rotator on 0.0.0.0:12040 and another on 127.0.0.1:12040 passed check-config and the
    start then failed, blaming another program."""
    text = TWO.format(
        a='n1mm_rotor_name = "Tower"\nn1mm_udp_bind = "0.0.0.0"', b='n1mm_rotor_name = "Sky"'
    )
    with pytest.raises(ConfigError, match="n1mm_udp_port 12040 is bound to 0.0.0.0 and 127.0.0.1"):
        load_settings(write(tmp_path, text), environ={})


def test_a_path_beginning_with_a_tilde_is_in_the_home_folder_for_every_path_key(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """settings/base.py rule 7 (attack 18: state_file '~/...' was a folder named '~' under the
    working directory; password_file '~/...' was 'no such file')."""
    home = tmp_path / "home"
    home.mkdir()
    pw = home / "pw"
    pw.write_text("s3cret\n")
    os.chmod(pw, 0o600)
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(tmp_path)
    text = MINIMAL.replace(
        'base_topic = "rotor"', 'base_topic = "rotor"\nusername = "u"\npassword_file = "~/pw"'
    )
    s = load_settings(write(tmp_path, 'state_file = "~/s.json"\naudit_file = "~/a.jsonl"\n' + text))
    assert (s.state_file, s.audit_file, s.mqtt.password_file) == (
        home / "s.json",
        home / "a.jsonl",
        pw,
    )
    assert s.mqtt.password is not None and s.mqtt.password.get_secret_value() == "s3cret"
    out = cli(
        "check-config", "-c", str(write(tmp_path, 'state_file = "~nosuchuser9/s.json"\n' + MINIMAL))
    )
    assert out.returncode == 2, out.stdout + out.stderr
    assert "state_file: ~nosuchuser9 names no user on this system" in out.stderr
