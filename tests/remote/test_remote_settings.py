"""The remote's ``[[endpoints]]`` (remote/settings.py rules 2-4): what each offers, loopback
binds unless set, and a problem named by the key as the file spells it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from bridge.remote.settings import load_remote_settings
from bridge.settings import ConfigError

HEAD = 'operator = "DL1ABC"\n[mqtt]\nhost = "station.example.org"\n'


def load(tmp_path: Path, *endpoints: str) -> object:
    path = tmp_path / "remote.toml"
    path.write_text(HEAD + "".join(f"[[endpoints]]\n{e}\n" for e in endpoints))
    return load_remote_settings(str(path))


def test_every_kind_of_endpoint_binds_loopback_unless_set(tmp_path: Path) -> None:
    s = load(
        tmp_path,
        'rotator = "tower"\ngs232_port = 4534\ngs232_pty = "/tmp/rotor-gs232"\n'
        'pst_udp_port = 12000\neasycomm_port = 4536\neasycomm_bind = "0.0.0.0"',
    )
    (ep,) = s.endpoints  # type: ignore[attr-defined]
    assert ep.rotctld_port is None
    assert [(o.key, o.transport, o.where, o.bind) for o in ep.offers()] == [
        ("gs232_port", "tcp", 4534, "127.0.0.1"),
        ("easycomm_port", "tcp", 4536, "0.0.0.0"),
        ("pst_udp_port", "udp", 12000, "127.0.0.1"),
        ("gs232_pty", "pty", "/tmp/rotor-gs232", ""),
    ]


@pytest.mark.parametrize(
    ("endpoints", "said"),
    [
        (
            ['rotator = "tower"'],
            "endpoints[0] (rotator 'tower') offers nothing: give it one of rotctld_port, ",
        ),
        (
            ['rotator = "a"\nrotctld_port = 4533', 'rotator = "b"\ngs232_port = 4533'],
            "endpoints[1].gs232_port 4533 clashes with endpoints[0].rotctld_port: give it "
            "another port",
        ),
        (
            ['rotator = "a"\nrotctld_port = 4533\neasycomm_port = 4533\neasycomm_bind = "::1"'],
            "endpoints[0].easycomm_port 4533 clashes with endpoints[0].rotctld_port",
        ),
        (
            ['rotator = "a"\npst_udp_port = 12000', 'rotator = "b"\npst_udp_port = 12001'],
            "endpoints[1].pst_udp_port 12001 clashes with endpoints[0].pst_udp_port",
        ),
        (
            [
                'rotator = "a"\ngs232_pty = "/tmp/x"',
                'rotator = "b"\neasycomm_pty = "/tmp/../tmp/x"',
            ],
            "endpoints[1].easycomm_pty /tmp/x clashes with endpoints[0].gs232_pty: give it "
            "another path",
        ),
        (["gs232_prt = 4534"], "endpoints[0].gs232_prt: unknown key: did you mean gs232_port?"),
        (["pst_udp_port = 70000"], "endpoints[0].pst_udp_port"),
        (['gs232_pty = ""'], "endpoints[0].gs232_pty"),
    ],
)
def test_a_problem_names_the_endpoint(tmp_path: Path, endpoints: list[str], said: str) -> None:
    with pytest.raises(ConfigError) as caught:
        load(tmp_path, *endpoints)
    assert said in str(caught.value)


def test_the_acknowledgement_wait_is_a_setting_within_the_expiry(tmp_path: Path) -> None:
    """A link whose round trip is longer than a second (a satellite link) reset on every
    command: the wait is ack_wait_s, and one past the expiry is refused by name."""
    path = tmp_path / "remote.toml"
    path.write_text(HEAD.replace("[mqtt]", "ack_wait_s = 2.5\n[mqtt]") + "[[endpoints]]\n")
    path.write_text(path.read_text() + "rotctld_port = 4533\n")
    assert load_remote_settings(str(path)).ack_wait_s == 2.5
    path.write_text(path.read_text().replace("ack_wait_s = 2.5", "ack_wait_s = 6"))
    with pytest.raises(ConfigError) as caught:
        load_remote_settings(str(path))
    assert "ack_wait_s (6) must not be more than command_expiry_s (5)" in str(caught.value)


@pytest.mark.parametrize(
    ("endpoint", "head", "said"),
    [
        (
            "rotctld_port = true",
            "",
            "endpoints[0].rotctld_port: must be a number, not true or false",
        ),
        ("rotctld_port = 4533", "ack_wait_s = true\n", "ack_wait_s: must be a number"),
    ],
)
def test_a_boolean_where_a_number_goes_is_refused_naming_the_key(
    tmp_path: Path, endpoint: str, head: str, said: str
) -> None:
    """pydantic reads true as 1: an endpoint on port 1, an acknowledgement awaited 1 s."""
    path = tmp_path / "remote.toml"
    path.write_text(head + HEAD + f"[[endpoints]]\n{endpoint}\n")
    with pytest.raises(ConfigError, match=re.escape(said)):
        load_remote_settings(str(path))


@pytest.mark.parametrize("operator", ["K1\x01X", "DL1\x85ABC", "X\ufdd0", "D" * 33])
def test_an_operator_the_station_would_not_take_is_refused(tmp_path: Path, operator: str) -> None:
    """It goes with every command as an MQTT 5 user property: a control character in it got
    the connection dropped by mosquitto, and a name past the station's 32 was ignored there."""
    path = tmp_path / "remote.toml"
    head = HEAD.replace('operator = "DL1ABC"', f"operator = {json.dumps(operator)}")
    path.write_text(head + "[[endpoints]]\nrotctld_port = 4533\n")
    with pytest.raises(ConfigError, match=r"operator: (holds U\+|.* at most 32 char)"):
        load_remote_settings(str(path))


@pytest.mark.parametrize("operator", ["rotctld 192.168.1.20", "MQTT", "auto-park"])
def test_an_interfaces_name_as_the_operator_is_refused(tmp_path: Path, operator: str) -> None:
    """The station ignores such a user property (an interface's name is no operator's:
    runtime/lease.py rule 1): every command would go as plain ``mqtt``, the lease refused."""
    path = tmp_path / "remote.toml"
    head = HEAD.replace('operator = "DL1ABC"', f"operator = {json.dumps(operator)}")
    path.write_text(head + "[[endpoints]]\nrotctld_port = 4533\n")
    with pytest.raises(ConfigError, match=r"operator: .*names an interface"):
        load_remote_settings(str(path))


@pytest.mark.parametrize(
    "operator", ["DL1ABC\u00a0Jo", "\u0645\u062d\u0645\u062f\u200c\u0631\u0636\u0627"]
)
def test_an_operator_mqtt_carries_is_taken_and_the_station_names_it(
    tmp_path: Path, operator: str
) -> None:
    """A no-break space (macOS types one at Option-Space), Persian's zero-width non-joiner:
    str.isprintable refused both, here and at the station (a review; core/text.py)."""
    from bridge.core.model import valid_operator

    path = tmp_path / "remote.toml"
    head = HEAD.replace('operator = "DL1ABC"', f"operator = {json.dumps(operator)}")
    path.write_text(head + "[[endpoints]]\nrotctld_port = 4533\n")
    typed = operator.replace("\u00a0", " ")  # its compatibility form: one operator either way
    assert load_remote_settings(str(path)).operator == typed  # type: ignore[attr-defined]
    assert valid_operator(operator) == typed


def test_a_byte_order_mark_before_the_remotes_file_is_read_past(tmp_path: Path) -> None:
    """Attack 28: the remote's file is edited on Windows (PowerShell 5, old Notepad save a
    byte-order mark); read by the bridge's read_toml, it was refused at line 1, column 1."""
    path = tmp_path / "remote.toml"
    path.write_bytes(b"\xef\xbb\xbf" + (HEAD + "[[endpoints]]\nrotctld_port = 4533\n").encode())
    assert load_remote_settings(str(path)).operator == "DL1ABC"  # type: ignore[attr-defined]


def test_a_byte_the_remotes_file_cannot_decode_is_counted_from_its_start(tmp_path: Path) -> None:
    """The mark dropped after decoding: the byte an error names is the file's own offset."""
    path = tmp_path / "remote.toml"
    path.write_bytes(b"\xef\xbb\xbf# \xff\n" + HEAD.encode())
    with pytest.raises(ConfigError, match=r"is not UTF-8 text \(byte 5\)"):
        load_remote_settings(str(path))


def test_a_ptys_path_takes_no_file_the_remote_reads(tmp_path: Path) -> None:
    """Review 87 (rule 6): a pty's path naming the symlinked password file (a dotfiles folder's
    link), or the remote's own file, passed; the start replaced that link with the pty's, and
    the next start could not read the file. Refused naming the key, by any name the file's links
    go through; /dev/stdout too."""
    (tmp_path / "dotfiles").mkdir()
    real = tmp_path / "dotfiles" / "mqtt-password"
    real.write_text("s3cret\n")
    real.chmod(0o600)
    link = tmp_path / "mqtt-password"
    link.symlink_to(real)
    head = HEAD + f'username = "dl1abc"\npassword_file = "{link}"\n'
    remote = tmp_path / "remote.toml"
    for pty, said in [
        (link, "endpoints[0].gs232_pty"),
        (real, "endpoints[0].gs232_pty"),
        (Path("/dev/stdout"), "names one of the process's own descriptors"),
    ]:
        remote.write_text(head + f'[[endpoints]]\ngs232_pty = "{pty}"\n')
        with pytest.raises(ConfigError) as caught:
            load_remote_settings(str(remote))
        assert said in str(caught.value) and "s3cret" not in str(caught.value), caught.value
    (tmp_path / "dotfiles" / "remote.toml").write_text(
        HEAD + f'[[endpoints]]\ndcu1_pty = "{tmp_path / "remote.toml"}"\n'
    )
    remote.unlink()
    remote.symlink_to(tmp_path / "dotfiles" / "remote.toml")
    with pytest.raises(ConfigError, match=r"endpoints\[0\]\.dcu1_pty: .* configuration file"):
        load_remote_settings(str(remote))
    remote.unlink()  # a leftover pty link at the path is the remote's own: taken
    remote.write_text(head + f'[[endpoints]]\ngs232_pty = "{tmp_path / "gs"}"\n')
    (tmp_path / "gs").symlink_to("/dev/null")
    assert load_remote_settings(str(remote)).endpoints[0].gs232_pty == str(tmp_path / "gs")
