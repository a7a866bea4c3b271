"""Invalid configuration: every bad file or value stops the start with exit code 2 and one
message naming the field; never a traceback, never the password. The CLI is run in-process for
the many cases (same code path: ``main`` raises SystemExit(2) or the test sees the exception)
and as the real process for the exit status itself. Random documents shaped like the real
schema either load or fail that way, nothing else.
"""

from __future__ import annotations

import os
import resource
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bridge.cli import main
from bridge.runtime.state_store import held
from bridge.settings import ConfigError, load_settings
from tests.faults.conftest import Pki
from tests.support import retained_snapshot, run_cli, to_toml
from tests.support.mosquitto import Mosquitto
from tests.support.process import bridge_env
from tests.support.waiting import slow

SECRET = "hunter2-do-not-show"
BASE = """
[mqtt]
host = "127.0.0.1"
port = 1883
username = "u"
password = "hunter2-do-not-show"

[[rotators]]
id = "tower"
model = "rotorez"
port = "/dev/ttyUSB0"
"""


def edit(old: str, new: str) -> str:
    assert old in BASE
    return BASE.replace(old, new, 1)


SPID = '[[rotators]]\nid = "sat"\nmodel = "rot2prog"\nport = "/dev/ttyUSB1"\n'
CASES: list[tuple[str, str | bytes, str]] = [
    ("port not a number", edit("port = 1883", 'port = "abc"'), "mqtt.port"),
    ("port out of range", edit("port = 1883", "port = 70000"), "mqtt.port"),
    ("keepalive too short", edit("port = 1883", "port = 1883\nkeepalive_s = 1"), "keepalive_s"),
    ("protocol 4", edit("port = 1883", 'port = 1883\nprotocol = "4"'), "mqtt.protocol"),
    ("password not text", edit(f'password = "{SECRET}"', "password = 12"), "mqtt.password"),
    ("typo in a key", edit("port = 1883", "port = 1883\npasword = 'x'"), "mqtt.pasword"),
    ("no rotators", BASE.split("[[rotators]]")[0], "no rotators configured"),
    ("empty rotators", BASE.split("[[rotators]]")[0] + "rotators = []\n", "rotators"),
    ("rotators as a table", edit("[[rotators]]", "[rotators]"), "rotators"),
    ("rotator without port", edit('port = "/dev/ttyUSB0"\n', ""), "rotators[0].port"),
    ("unknown model", edit('model = "rotorez"', 'model = "rotorz"'), "rotators[0].model"),
    ("id bridge", edit('id = "tower"', 'id = "bridge"'), "rotators[0].id"),
    ("same id twice", BASE + SPID.replace('"sat"', '"tower"'), "used twice"),
    ("same port twice", BASE + SPID.replace("USB1", "USB0"), "given to two rotators"),
    ("elevation on rotorez", BASE + "el_max_deg = 90\n", "no elevation axis"),
    ("az limit beyond range", BASE + "az_max_deg = 400\n", "azimuth limits"),
    ("nan limit", BASE + "az_min_deg = nan\n", "rotators[0]"),
    ("settle too short", BASE + "settle_s = 0.1\n", "settle_s"),
    ("poll order", BASE + "moving_poll_interval_s = 5\n", "moving_poll_interval_s"),
    ("negative brake", BASE + "brake_delay_s = -1\n", "rotators[0].brake_delay_s"),
    ("park el without az", BASE.replace("rotorez", "rot2prog") + "park_el_deg = 10\n", "park_el"),
    ("rotctld twice", BASE + "rotctld_port = 4533\n" + SPID + "rotctld_port = 4533\n", "rotctld"),
    (
        "ha prefix = base",
        BASE + '[homeassistant]\ndiscovery_prefix = "rotor"\n',
        "discovery_prefix",
    ),
    ("topic wildcard", edit("port = 1883", 'port = 1883\nbase_topic = "a/+"'), "mqtt.base_topic"),
    ("log level", 'log_level = "LOUD"\n' + BASE, "log_level"),
    ("unknown top-level key", "colour = 'blue'\n" + BASE, "colour"),
    ("both password kinds", edit("port = 1883", 'port = 1883\npassword_file = "/x"'), "mqtt"),
    ("password file missing", edit(f'password = "{SECRET}"', 'password_file = "/nope"'), "/nope"),
    (
        "tls cert without key",
        BASE + '[mqtt.tls]\nenabled = true\ncert_file = "/etc/hostname"\n',
        "go together",
    ),  # fmt: skip
    ("tls ca missing", BASE + '[mqtt.tls]\nenabled = true\nca_file = "/nope.crt"\n', "mqtt.tls"),
    ("host empty", edit('host = "127.0.0.1"', 'host = ""'), "mqtt.host"),  # (paho's traceback)
    # the same device under two names; absurd stalls; one UDP port twice (an attack pass)
    (
        "one device two names",
        BASE + SPID.replace("/dev/ttyUSB1", "/dev/../dev/ttyUSB0"),
        "port /dev/../dev/ttyUSB0 is /dev/ttyUSB0 under another name",
    ),
    ("stall before a reading", BASE + "stall_timeout_s = 0.1\n", "stall_timeout_s 0.1 must be"),
    (
        "ids one name to HA",
        BASE
        + SPID.replace('"sat"', '"tow-er"')
        + SPID.replace('"sat"', '"tow_er"').replace("USB1", "USB2"),
        "rotator id 'tow_er' and rotator 'tow-er' are one",
    ),
    (
        "ids one name to HA, a trailing dash",
        BASE + SPID + SPID.replace('"sat"', '"sat-"').replace("USB1", "USB2"),
        "rotator id 'sat-' and rotator 'sat' are one",
    ),
    (
        "wsjtx on the pst port",
        BASE + "pst_udp_port = 12000\n[wsjtx]\nenabled = true\nport = 12000\n",
        "wsjtx.port 12000 is also a pst_udp_port",
    ),
    ("host with a space", edit('host = "127.0.0.1"', 'host = "broker lan"'), "mqtt.host"),
    ("rotator singular", edit("[[rotators]]", "[[rotator]]"), "did you mean [[rotators]]?"),
    ("typo in a table", edit("[mqtt]", "[mqtt_]"), "unknown table [mqtt_]: did you mean [mqtt]?"),
    ("missing key", edit('model = "rotorez"\n', ""), "rotators[0].model: missing"),
    ("not TOML", "[mqtt\nhost = ", "not valid TOML"),
    ("empty file", "", "no rotators configured"),
]


def run_main(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exc:
        main(list(args))
    out = capsys.readouterr()
    return int(exc.value.code or 0), out.out, out.err


@pytest.mark.parametrize(("why", "text", "field"), CASES, ids=[c[0] for c in CASES])
def test_a_bad_file_is_exit_2_and_one_message_naming_the_field(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    why: str,
    text: str | bytes,
    field: str,
) -> None:
    for key in [k for k in os.environ if k.startswith("ROTOR_BRIDGE_")]:
        monkeypatch.delenv(key)
    path = tmp_path / "bad.toml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    for command in ("run", "check-config"):
        code, out, err = run_main(capsys, command, "-c", str(path))
        assert code == 2, (why, out, err)
        assert err.startswith("rotor-bridge: ") and field in err, (why, err)
        assert "Traceback" not in err and SECRET not in out + err, (why, err)
        assert out == ""


def test_bad_environment_values_name_the_variable(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "good.toml"
    path.write_text(BASE)
    monkeypatch.setenv("ROTOR_BRIDGE_ROTATORS__GHOST__PORT", "/dev/ttyUSB9")
    code, _, err = run_main(capsys, "check-config", "-c", str(path))
    assert code == 2 and "ROTOR_BRIDGE_ROTATORS__GHOST__PORT" in err and "ghost" in err
    monkeypatch.delenv("ROTOR_BRIDGE_ROTATORS__GHOST__PORT")
    monkeypatch.setenv("ROTOR_BRIDGE_MQTT__PORT", "eighteen-eighty-three")
    code, _, err = run_main(capsys, "check-config", "-c", str(path))
    assert code == 2 and "mqtt.port (from ROTOR_BRIDGE_MQTT__PORT): " in err and SECRET not in err
    monkeypatch.setenv("ROTOR_BRIDGE_ROTATORS__TOWER__TOLERANCE_DEG", "-3")
    code, _, err = run_main(capsys, "check-config", "-c", str(path))
    assert code == 2 and "rotators[0].tolerance_deg (from ROTOR_BRIDGE_ROTATORS__TOWER__" in err


def test_the_real_process_exits_2_without_a_traceback(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(edit("port = 1883", 'port = "abc"'))
    for command in ("run", "check-config"):
        out = run_cli(command, "-c", str(path))
        assert out.returncode == 2, out
        assert "mqtt.port" in out.stderr and "Traceback" not in out.stderr
        assert SECRET not in out.stdout + out.stderr
    out = run_cli("run", "-c", str(tmp_path))  # a directory, not a file
    assert out.returncode == 2 and "Traceback" not in out.stderr, out


def test_a_file_that_is_not_utf8_is_a_config_error_not_a_crash(tmp_path: Path) -> None:
    """BUG (reported): settings.load_settings catches TOMLDecodeError and OSError, but tomllib
    raises UnicodeDecodeError for bytes that are not UTF-8. A configuration saved in Latin-1
    (an editor's default on some systems; a rotator named "Süd") crashes with a traceback and
    exit status 1, which the systemd unit restarts (it only spares exit code 2): a crash loop."""
    path = tmp_path / "latin1.toml"
    path.write_bytes(
        BASE.replace('id = "tower"', 'id = "tower"\nname = "Mast Süd"').encode("latin-1")
    )
    for command in ("run", "check-config"):
        out = run_cli(command, "-c", str(path))
        assert "Traceback" not in out.stderr, out.stderr[-600:]
        assert out.returncode == 2 and "UTF-8" in out.stderr.upper().replace("UTF8", "UTF-8")


# -- start-up errors: valid settings, but the start cannot work --------------------------------
# Exit code 2 (the systemd unit does not restart it) and one line saying what and why; nothing
# started, nothing published.
def start_up_config(
    tmp: Path, broker_port: int, state_file: Path | None = None, **rotator: Any
) -> Path:
    doc: dict[str, Any] = {
        "state_file": str(state_file or tmp / "state" / "state.json"),
        "mqtt": {"host": "127.0.0.1", "port": broker_port, "username": "u", "password": SECRET},
        "rotators": [{"id": "tower", "model": "rotorez", "port": str(tmp / "tty"), **rotator}],
    }
    path = tmp / "bridge.toml"
    path.write_text(to_toml(doc))
    return path


def the_one_line(out: subprocess.CompletedProcess[str], code: int = 2) -> str:
    """The process failed with exit code 2 (or ``code``) and said why in one line (besides its
    INFO log)."""
    assert out.returncode == code, out
    assert "Traceback" not in out.stderr and SECRET not in out.stdout + out.stderr, out.stderr
    lines = out.stderr.splitlines()
    said = [line for line in lines if line.startswith("rotor-bridge: ")]
    assert len(said) == 1, out.stderr
    assert [line for line in lines if line not in said and " INFO " not in line] == [], lines
    return said[0]


def test_a_rotctld_port_taken_by_another_process_is_exit_2_and_one_line(
    tmp_path: Path, broker: Mosquitto
) -> None:
    holder = socket.create_server(("127.0.0.1", 0))  # the test is the other process
    port = holder.getsockname()[1]
    try:
        out = run_cli("run", "-c", str(start_up_config(tmp_path, broker.port, rotctld_port=port)))
    finally:
        holder.close()
    line = the_one_line(out)
    assert line.startswith(
        f"rotor-bridge: rotctld for rotator 'tower': cannot listen on 127.0.0.1:{port}: "
        "Address already in use"
    ), line
    assert retained_snapshot(broker.port, "#") == {}  # no discovery, no state, no "online"


def test_a_rotctld_address_not_on_this_host_is_one_line_and_exit_1_to_be_retried(
    tmp_path: Path, broker: Mosquitto
) -> None:
    """At boot the interface may not be up yet: exit 1, so systemd starts the bridge again
    (exit 2 is for what only the user can fix: the unit does not restart on it)."""
    config = start_up_config(tmp_path, broker.port, rotctld_port=4533, rotctld_bind="192.0.2.7")
    line = the_one_line(run_cli("run", "-c", str(config)), code=1)
    assert "rotator 'tower'" in line and "192.0.2.7:4533" in line
    assert "Cannot assign requested address" in line


def test_a_state_file_that_cannot_be_written_is_exit_2_and_one_line(
    tmp_path: Path, broker: Mosquitto
) -> None:
    # under a regular file: no directory can be made there, not even by root (a read-only
    # directory would not stop root)
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory\n")
    state_file = blocker / "rotor" / "state.json"
    config = start_up_config(tmp_path, broker.port, state_file=state_file)
    line = the_one_line(run_cli("run", "-c", str(config)))
    assert line.startswith(f"rotor-bridge: state_file {state_file} cannot be written: "), line
    assert "Not a directory" in line
    assert retained_snapshot(broker.port, "#") == {}
    assert blocker.read_text() == "not a directory\n"


@pytest.mark.parametrize(
    "content",
    ['{"rotators": {"tower": {"locked": true}}}', '{"rotators": {"tower": {"locked": "no"}}}'],
    ids=["valid", "malformed"],
)
def test_a_second_run_of_one_installation_is_exit_2_naming_the_first(
    tmp_path: Path, broker: Mosquitto, capsys: pytest.CaptureFixture[str], content: str
) -> None:
    """state_store.py rule 7, an attack pass: the same configuration run twice took turns
    throwing the first off the broker under one client id, and a STOP that reached the one
    that could not open the port was lost without a word. The second now does not start."""
    state_file = tmp_path / "state" / "state.json"
    config = start_up_config(tmp_path, broker.port, state_file=state_file)
    state_file.parent.mkdir()
    state_file.write_text(content)  # (a malformed entry is replaced, locked, by a start)
    before = state_file.stat().st_ino
    with held(state_file):
        code, out, err = run_main(capsys, "run", "-c", str(config))
    # (reviews: the refused one wrote the state file over, and could undo the first's save)
    assert state_file.stat().st_ino == before and state_file.read_text() == content
    assert (code, out) == (2, ""), err
    assert f"another rotor-bridge runs this installation (process {os.getpid()})" in err, err
    assert f"state_file {state_file} is in use" in err and "Traceback" not in err, err
    assert retained_snapshot(broker.port, "#") == {}  # nothing published, nobody thrown off
    with held(state_file):  # let go when the first ended
        pass


def test_a_state_file_whose_content_cannot_be_written_is_exit_2_and_leaves_nothing(
    tmp_path: Path, broker: Mosquitto
) -> None:
    """A full disk lets an empty file be made but not written: the start writes the real content
    (as every later change does), so the failure is found here, not at the first lock."""
    state_file = tmp_path / "state" / "state.json"
    config = start_up_config(tmp_path, broker.port, state_file=state_file)

    def no_file_may_grow() -> None:  # as on a full disk: EFBIG here, ENOSPC there
        resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))

    out = subprocess.run(
        [sys.executable, "-m", "bridge", "run", "-c", str(config)],
        capture_output=True,
        text=True,
        env=bridge_env({"PYTHONDONTWRITEBYTECODE": "1"}),
        timeout=slow(10),
        preexec_fn=no_file_may_grow,
    )
    line = the_one_line(out)
    assert line == f"rotor-bridge: state_file {state_file} cannot be written: File too large"
    # no temporary file left behind (the installation's lock stays: state_store.py rule 7)
    assert [p.name for p in state_file.parent.iterdir()] == ["state.json.lock"]
    assert retained_snapshot(broker.port, "#") == {}


@pytest.mark.parametrize(
    "kind", ["FIFO", "directory", "link to a file that is not there (a volume not mounted yet?)"]
)
def test_a_state_file_that_is_no_regular_file_is_exit_2_naming_it_at_once(
    tmp_path: Path, broker: Mosquitto, kind: str
) -> None:
    """A FIFO at the state file's path held the start forever (reading it waits for a writer),
    and a file written over it would have replaced it: /dev/null by mistake, as root."""
    state_file = tmp_path / "state" / "state.json"
    state_file.parent.mkdir()
    if kind == "FIFO":
        os.mkfifo(state_file)
    elif kind == "directory":
        state_file.mkdir()
    else:  # an attack pass: read as no file (a kept lock lost), and replaced by a new one
        os.symlink(tmp_path / "not-mounted" / "state.json", state_file)
    config = start_up_config(tmp_path, broker.port, state_file=state_file)
    line = the_one_line(run_cli("run", "-c", str(config), timeout_s=10))
    assert line == (
        f"rotor-bridge: state_file {state_file} cannot be written: "
        f"it is a {kind}, not a regular file"
    )
    assert list(state_file.parent.iterdir()) == [state_file]  # nothing written beside it
    kept = {"FIFO": state_file.is_fifo(), "directory": state_file.is_dir()}
    assert kept.get(kind, state_file.is_symlink())  # nor over it
    assert retained_snapshot(broker.port, "#") == {}


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Pki:
    pki = Pki(tmp_path_factory.mktemp("pki"))
    encrypted = pki.path("encrypted.key")
    subprocess.run(
        ["openssl", "pkey", "-in", pki.path("client.key"), "-aes256", "-passout", "pass:x",
         "-out", encrypted],
        check=True, capture_output=True,
    )  # fmt: skip
    pki.path("junk.pem").write_text("this is no certificate\n")
    return pki


TLS_CASES = [  # (why, file settings, what the message says); DIR is the certificates' directory
    ("ca not PEM", {"ca_file": "junk.pem"}, "ca_file DIR/junk.pem holds no PEM certificate"),
    ("ca a directory", {"ca_file": ""}, "ca_file DIR is not a readable file"),
    ("cert not PEM", {"cert_file": "junk.pem", "key_file": "client.key"}, "cert_file DIR/junk.pem"),
    ("key not PEM", {"cert_file": "client.crt", "key_file": "junk.pem"}, "key_file DIR/junk.pem"),
    ("key of another cert", {"cert_file": "client.crt", "key_file": "server.key"}, "and its key"),
    ("key encrypted", {"cert_file": "client.crt", "key_file": "encrypted.key"}, "is encrypted"),
]


@pytest.mark.parametrize(("why", "files", "said"), TLS_CASES, ids=[c[0] for c in TLS_CASES])
def test_tls_files_that_cannot_be_used_are_exit_2_and_one_message(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    pki: Pki,
    why: str,
    files: dict[str, str],
    said: str,
) -> None:
    """Before they were checked, paho raised these at start: a traceback and exit code 1."""
    tls = "".join(f"{key} = {str(pki.dir / name)!r}\n" for key, name in files.items())
    path = tmp_path / "tls.toml"
    path.write_text(BASE + "[mqtt.tls]\nenabled = true\n" + tls)
    for command in ("run", "check-config"):
        code, out, err = run_main(capsys, command, "-c", str(path))
        assert (code, out) == (2, ""), (why, err)
        assert err.startswith("rotor-bridge: invalid configuration:\n  mqtt.tls: "), (why, err)
        assert said.replace("DIR", str(pki.dir)) in err, (why, err)
        assert SECRET not in err and "Traceback" not in err, (why, err)
    out = run_cli("run", "-c", str(path))  # the real process too
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr


def test_the_tls_key_s_file_is_read_as_no_tle_file_but_may_hold_its_certificate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], pki: Pki
) -> None:
    """Settings rule 7 (attack 18): a secret's file is read as nothing else, the TLS key's
    too, named by both keys; a certificate and its key in one PEM file is the pair allowed
    (ssl reads it and quotes neither)."""
    both = tmp_path / "client.pem"
    both.write_text(pki.path("client.crt").read_text() + pki.path("client.key").read_text())
    both.chmod(0o600)
    tls = f"[mqtt.tls]\nenabled = true\ncert_file = {str(both)!r}\nkey_file = {str(both)!r}\n"
    path = tmp_path / "tls.toml"
    path.write_text(BASE + tls)
    assert main(["check-config", "-c", str(path)]) == 0
    assert "config OK" in capsys.readouterr().out
    path.write_text(BASE + tls + f"[tracking]\ntle_file = {str(both)!r}\n")
    code, out, err = run_main(capsys, "check-config", "-c", str(path))
    assert (code, out) == (2, ""), err
    assert f"tracking.tle_file {both} is also mqtt.tls.key_file: a secret's file" in err, err


@pytest.mark.parametrize(
    ("content", "said"),
    [(b"one\ntwo\n", "on one line (it holds several lines)"), (b"\n", "(it holds nothing)"),
     (b"\xff\xfe", "is not UTF-8 text")],
)  # fmt: skip
def test_a_password_file_of_no_one_line_password_is_exit_2_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes, said: str
) -> None:
    """An attack pass: two lines became a password with a line break in it, an empty file
    \"a password\", and a file not UTF-8 a message that named no field."""
    secret = tmp_path / "pw"
    secret.write_bytes(content)
    secret.chmod(0o600)
    path = tmp_path / "pw.toml"
    path.write_text(edit(f'password = "{SECRET}"', f"password_file = {str(secret)!r}"))
    code, out, err = run_main(capsys, "check-config", "-c", str(path))
    assert (code, out) == (2, "") and f"password_file {secret} " in err and said in err, err


@pytest.mark.parametrize(
    ("kind", "said"),
    [
        ("device", "is not a file (a directory or a device): write the password in a file of "
         "its own"),
        ("directory", "is not a file (a directory or a device): write the password in a file "
         "of its own"),
        ("pipe", "must hold the password on one line (it holds nothing)"),
    ],
)  # fmt: skip
def test_a_password_file_that_is_no_file_is_exit_2_naming_it(
    tmp_path: Path, kind: str, said: str
) -> None:
    """An attack pass: password_file = "/dev/zero" ended check-config in a MemoryError
    traceback once it had taken every byte it could hold, and a FIFO nothing wrote to held it
    for ever. A pipe that brings the password (``<(pass show mqtt)``) is still read."""
    secret = {"device": Path("/dev/zero"), "pipe": tmp_path / "fifo", "directory": tmp_path}[kind]
    if kind == "pipe":
        os.mkfifo(secret, 0o600)
    path = tmp_path / "pw.toml"
    path.write_text(edit(f'password = "{SECRET}"', f"password_file = {str(secret)!r}"))

    def little_memory() -> None:  # (the old reading of /dev/zero filled what it was given)
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))

    out = subprocess.run(
        [sys.executable, "-m", "bridge", "check-config", "-c", str(path)],
        capture_output=True,
        text=True,
        env=bridge_env(),
        timeout=slow(20),
        preexec_fn=little_memory,
    )
    assert (out.returncode, out.stdout, out.stderr) == (
        2,
        "",
        f"rotor-bridge: invalid configuration:\n  mqtt: password_file {secret} {said}\n",
    )
    read, write = os.pipe()
    os.write(write, f"{SECRET}\n".encode())
    os.close(write)
    try:
        text = edit(f'password = "{SECRET}"', f"password_file = '/proc/self/fd/{read}'")
        path.write_text(text)
        password = load_settings(path, environ={}).mqtt.password
    finally:
        os.close(read)
    assert password is not None and password.get_secret_value() == SECRET


def test_a_config_file_with_no_end_is_exit_2_and_a_pipe_still_a_config(tmp_path: Path) -> None:
    """An attack pass: ``-c /dev/zero`` (or ``/dev/urandom``) ended check-config in a
    MemoryError traceback once it had taken every byte it could hold."""

    def little_memory() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))

    out = subprocess.run(
        [sys.executable, "-m", "bridge", "check-config", "-c", "/dev/zero"],
        capture_output=True,
        text=True,
        env=bridge_env(),
        timeout=slow(20),
        preexec_fn=little_memory,
    )
    assert the_one_line(out) == (
        "rotor-bridge: config file /dev/zero is larger than 16 MiB: no configuration is (is it "
        "the right file?)"
    )
    config = tmp_path / "c.toml"
    config.write_text(BASE)
    read, write = os.pipe()  # as -c <(...) gives it
    os.write(write, config.read_bytes())
    os.close(write)
    try:
        out = subprocess.run(
            [sys.executable, "-m", "bridge", "check-config", "-c", f"/proc/self/fd/{read}"],
            capture_output=True,
            text=True,
            env=bridge_env(),
            timeout=slow(20),
            pass_fds=(read,),
        )
    finally:
        os.close(read)
    assert out.returncode == 0 and out.stdout.endswith(f"config OK: /proc/self/fd/{read}\n")


@pytest.mark.parametrize("key", ["ca_file", "cert_file", "key_file"])
def test_a_tls_file_that_cannot_be_looked_at_is_exit_2_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], pki: Pki, key: str
) -> None:
    """An attack pass: a TLS file whose name is too long (or in a folder the user may not
    enter) ended check-config in an OSError traceback: only a missing file was said."""
    files = {k: str(pki.dir / n) for k, n in [("cert_file", "client.crt"), ("key_file",
             "client.key"), ("ca_file", "ca.crt")]}  # fmt: skip
    files[key] = str(tmp_path / ("x" * 300))
    table = "".join(f"{k} = {v!r}\n" for k, v in files.items())
    path = tmp_path / "tls.toml"
    path.write_text(BASE + f"[mqtt.tls]\nenabled = true\n{table}")
    code, out, err = run_main(capsys, "check-config", "-c", str(path))
    assert (code, out) == (2, "")
    assert err == (
        f"rotor-bridge: invalid configuration:\n  mqtt.tls: {key} {files[key]}: File name too "
        "long\n"
    )


def test_tls_files_with_tls_not_enabled_are_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], pki: Pki
) -> None:
    """An attack pass: ``[mqtt.tls]`` with its files and port 8883 but ``enabled`` left out
    said "no TLS" and "config OK", and the bridge sent its password in the clear."""
    path = tmp_path / "tls.toml"
    path.write_text(BASE + f"[mqtt.tls]\nca_file = {str(pki.dir / 'ca.crt')!r}\n")
    for command in ("run", "check-config"):
        code, out, err = run_main(capsys, command, "-c", str(path))
        assert (code, out) == (2, ""), err
        assert "mqtt.tls: ca_file given but enabled left out" in err and SECRET not in err, err


def test_check_config_refuses_a_cty_file_the_start_would_stop_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An attack pass: ``[dxcluster]`` with a cty_file that is not there printed "NOT FOUND"
    and then "config OK", where the start stops on it."""
    path = tmp_path / "dx.toml"
    dx = '[dxcluster]\nenabled = true\nhost = "dxc.example.org"\nlogin = "G4ABC"\n'
    path.write_text(BASE + f"{dx}cty_file = {str(tmp_path / 'cty.dat')!r}\n")
    code, out, err = run_main(capsys, "check-config", "-c", str(path))
    assert code == 2 and "config OK" not in out, out
    assert f"dxcluster.cty_file {tmp_path / 'cty.dat'} cannot be read" in err, err


def test_a_key_file_every_user_may_read_is_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], pki: Pki
) -> None:
    """An attack pass: a private key readable by all was taken, where such a password file is
    refused."""
    key = tmp_path / "client.key"
    key.write_bytes(pki.path("client.key").read_bytes())
    key.chmod(0o644)
    crt = pki.dir / "client.crt"
    tls = f"[mqtt.tls]\nenabled = true\ncert_file = {str(crt)!r}\nkey_file = {str(key)!r}\n"
    path = tmp_path / "key.toml"
    path.write_text(BASE + tls)
    code, out, err = run_main(capsys, "check-config", "-c", str(path))
    assert (code, out) == (2, "") and f"key_file {key} is readable by every user" in err, err


# -- random documents shaped like the schema ---------------------------------------------------
SCALARS = st.one_of(
    st.none(),  # left out
    st.booleans(),
    st.integers(-(2**40), 2**40),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=20),
    st.sampled_from(["rotorez", "rot2prog", "satel", "dcu1", "/dev/null", "/etc/hostname", ""]),
)
VALUES = st.one_of(SCALARS, st.lists(SCALARS.filter(lambda v: v is not None), max_size=3))
ROTATOR_KEYS = [
    "id", "name", "model", "port", "baud", "topic", "idle_poll_interval_s",
    "moving_poll_interval_s", "tolerance_deg", "brake_delay_s", "stall_timeout_s", "settle_s",
    "deadband_deg", "noise_deg", "silence_timeout_s", "az_min_deg", "az_max_deg", "el_min_deg",
    "el_max_deg", "rotctld_port", "rotctld_bind", "park_az_deg", "park_el_deg", "bogus",
]  # fmt: skip
MQTT_KEYS = [
    "host", "port", "username", "password", "password_file", "client_id", "keepalive_s",
    "base_topic", "protocol", "bogus",
]  # fmt: skip
TLS_KEYS = ["enabled", "ca_file", "cert_file", "key_file", "insecure"]


def table(keys: list[str]) -> st.SearchStrategy[dict[str, Any]]:
    return st.dictionaries(st.sampled_from(keys), VALUES, max_size=len(keys)).map(
        lambda d: {k: v for k, v in d.items() if v is not None}
    )


def rotator() -> st.SearchStrategy[dict[str, Any]]:
    base = st.fixed_dictionaries(
        {
            "id": st.sampled_from(["tower", "yagi", "Tower", "bridge", "a" * 60]),
            "model": st.sampled_from(["rotorez", "rotorcard", "dcu1", "rot2prog", "md01", "satel"]),
            "port": st.sampled_from(["/dev/ttyUSB0", "/dev/ttyUSB1", ""]),
        }
    )
    return st.tuples(base, table(ROTATOR_KEYS)).map(lambda p: {**p[0], **p[1]})


DOCUMENTS = st.fixed_dictionaries(
    {},
    optional={
        "mqtt": st.tuples(table(MQTT_KEYS), table(TLS_KEYS)).map(
            lambda p: {**p[0], **({"tls": p[1]} if p[1] else {})}
        ),
        "homeassistant": table(["enabled", "discovery_prefix", "status_topic", "birth_delay_s"]),
        "rotators": st.lists(rotator(), max_size=3),
        "log_level": st.sampled_from(["INFO", "debug", "LOUD"]),
        "state_file": st.sampled_from(["/tmp/x/state.json", ""]),
    },
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(doc=DOCUMENTS)
def test_any_document_loads_or_is_a_config_error(tmp_path_factory, doc: dict[str, Any]) -> None:  # noqa: ANN001
    path = tmp_path_factory.mktemp("doc") / "c.toml"
    try:
        path.write_text(to_toml(doc))
    except (TypeError, UnicodeEncodeError):
        return  # not expressible as TOML text
    try:
        load_settings(path, environ={})
    except ConfigError as exc:
        text = str(exc)
        assert text and "Traceback" not in text
        first = text.splitlines()[0]
        assert first.startswith(("invalid configuration", "config file", "no rotators")), text
