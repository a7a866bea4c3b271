"""gs232_port and easycomm_port in the configuration: unique among the TCP listeners and the
PstRotator ports, warned about off loopback, and shown by check-config."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.settings import ConfigError, load_settings
from bridge.settings.report import config_warnings
from tests.support import cli


def write(tmp_path: Path, rotators: list[str], extra: str = "") -> Path:
    text = extra + "".join(
        f'[[rotators]]\nid = "r{i}"\nmodel = "rotorez"\nport = "{tmp_path}/tty{i}"\n{keys}\n'
        for i, keys in enumerate(rotators)
    )
    for i in range(len(rotators)):
        (tmp_path / f"tty{i}").write_text("")  # a port that exists: no warning about it
    path = tmp_path / "config.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("rotators", "extra", "said"),
    [
        (["gs232_port = 4533\nrotctld_port = 4533"], "", "rotators[0].gs232_port 4533 is also "),
        (["easycomm_port = 4536", "gs232_port = 4536"], "", "rotators[0].easycomm_port 4536"),
        (["rotctld_port = 4535", "gs232_port = 4535"], "", "rotators[1].gs232_port 4535 is al"),
        (["gs232_port = 12000\npst_udp_port = 12000"], "", "is also rotators[0].pst_udp_port"),
        (["easycomm_port = 8080"], "[web]\nenabled = true\nport = 8080\n", "is also web.port"),
        (["dcu1_port = 4536\neasycomm_port = 4536"], "", "rotators[0].easycomm_port 4536 is"),
        (["rotctld_port = 4537", "dcu1_port = 4537"], "", "rotators[1].dcu1_port 4537 is also"),
    ],
)
def test_a_port_given_twice_is_refused(
    tmp_path: Path, rotators: list[str], extra: str, said: str
) -> None:
    with pytest.raises(ConfigError) as caught:
        load_settings(write(tmp_path, rotators, extra), environ={})
    assert said in str(caught.value)


def test_distinct_ports_load(tmp_path: Path) -> None:
    keys = ["rotctld_port = 4533\ngs232_port = 4535\neasycomm_port = 4536", "gs232_port = 4537"]
    s = load_settings(write(tmp_path, keys), environ={})
    assert [(r.gs232_port, r.easycomm_port) for r in s.rotators] == [(4535, 4536), (4537, None)]
    assert s.rotators[0].gs232_bind == s.rotators[0].easycomm_bind == "127.0.0.1"
    assert config_warnings(s) == []


def test_a_port_off_loopback_is_warned_about(tmp_path: Path) -> None:
    keys = 'gs232_port = 4535\ngs232_bind = "0.0.0.0"\neasycomm_port = 4536\neasycomm_bind = "::"'
    warnings = config_warnings(load_settings(write(tmp_path, [keys]), environ={}))
    assert warnings == [
        "rotators[0].gs232_bind: 0.0.0.0 is not a loopback address: gs232 has no "
        "authentication, anyone who can reach port 4535 there can turn the antenna",
        "rotators[0].easycomm_bind: :: is not a loopback address: easycomm has no "
        "authentication, anyone who can reach port 4536 there can turn the antenna",
    ]


def test_check_config_lists_them(tmp_path: Path) -> None:
    path = write(tmp_path, ["rotctld_port = 4533\ngs232_port = 4535\neasycomm_port = 4536"])
    out = cli("check-config", "-c", str(path))
    assert out.returncode == 0, out.stderr
    assert (
        "rotctld on 127.0.0.1:4533; GS-232B on 127.0.0.1:4535; Easycomm II on 127.0.0.1:4536"
        in out.stdout
    )


@pytest.mark.parametrize(
    ("rotators", "said"),
    [
        (['gs232_pty = "/tmp/x"\neasycomm_pty = "/tmp/x"'], "rotators[0].easycomm_pty /tmp/x is"),
        (['gs232_pty = "/tmp/x"', 'gs232_pty = "/tmp/../tmp/x"'], "also rotators[0].gs232_pty"),
        (['gs232_pty = "/tmp/x"', 'dcu1_pty = "/tmp/x"'], "rotators[1].dcu1_pty /tmp/x is also"),
    ],
)
def test_a_pty_path_given_twice_is_refused(tmp_path: Path, rotators: list[str], said: str) -> None:
    with pytest.raises(ConfigError, match=said.replace(".", r"\.").replace("[", r"\[")):
        load_settings(write(tmp_path, rotators), environ={})


def test_check_config_shows_the_ptys(tmp_path: Path) -> None:
    path = write(tmp_path, ['gs232_pty = "/tmp/rotor-gs232"\neasycomm_pty = "/tmp/rotor-ec"'])
    out = cli("check-config", "-c", str(path)).stdout
    assert "GS-232B on a pty at /tmp/rotor-gs232; Easycomm II on a pty at /tmp/rotor-ec" in out


def test_check_config_shows_the_dcu1_endpoints_and_the_gs232_replies(tmp_path: Path) -> None:
    keys = 'gs232_port = 4535\ngs232_replies = "A"\ndcu1_port = 4537\ndcu1_pty = "/tmp/rotor-dcu1"'
    out = cli("check-config", "-c", str(write(tmp_path, [keys]))).stdout
    assert (
        "GS-232A on 127.0.0.1:4535; DCU-1 on 127.0.0.1:4537; DCU-1 on a pty at /tmp/rotor-dcu1"
        in out
    )


def test_a_dcu1_port_off_loopback_is_warned_about(tmp_path: Path) -> None:
    keys = 'dcu1_port = 4537\ndcu1_bind = "0.0.0.0"'
    assert config_warnings(load_settings(write(tmp_path, [keys]), environ={})) == [
        "rotators[0].dcu1_bind: 0.0.0.0 is not a loopback address: dcu1 has no "
        "authentication, anyone who can reach port 4537 there can turn the antenna",
    ]


def test_gs232_replies_are_a_or_b(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="gs232_replies"):
        load_settings(write(tmp_path, ['gs232_replies = "C"']), environ={})


def test_check_config_shows_a_pty_written_in_the_home_folder_where_its_link_goes(
    tmp_path: Path,
) -> None:
    """settings/base.py rule 7 for a pty's link: shown where the start makes it, not '~/...'."""
    path = write(tmp_path, ['gs232_pty = "~/rotor-gs232"'])
    out = cli("check-config", "-c", str(path), env={"HOME": str(tmp_path)})
    assert f"GS-232B on a pty at {tmp_path}/rotor-gs232" in out.stdout, out.stdout + out.stderr


def test_a_pty_of_a_user_this_system_has_not_is_refused_naming_the_key(tmp_path: Path) -> None:
    """Not a link made under a folder named '~no-such-user-rb' of the working directory."""
    with pytest.raises(ConfigError, match=r"rotators\[0\]\.dcu1_pty: ~no-such-user-rb names no"):
        load_settings(write(tmp_path, ['dcu1_pty = "~no-such-user-rb/dcu1"']), environ={})
