"""``[dxcluster]`` as a user writes it, through the real loader; a cty file that cannot be
read stops the start with one line naming it."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import App
from bridge.interfaces.dxcluster import DxCluster
from bridge.settings import ConfigError, Settings, load_settings
from tests.dxcluster.cty_sample import CTY_DAT

ROTATOR = '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'


def load(tmp_path: Path, text: str) -> Settings:
    path = tmp_path / "c.toml"
    path.write_text(f'state_file = "{tmp_path / "state.json"}"\n' + text + ROTATOR)
    return load_settings(path, environ={})


def refused(tmp_path: Path, text: str) -> str:
    with pytest.raises(ConfigError) as err:
        load(tmp_path, text)
    return str(err.value)


def test_off_by_default_and_read_when_on(tmp_path: Path) -> None:
    s = load(tmp_path, "")
    assert not s.dxcluster.enabled and s.dxcluster.port == 7300 and s.dxcluster.max_spots == 50
    on = (
        '[dxcluster]\nenabled = true\nhost = "dxc.example.org"\nlogin = "g4abc"\n'
        'cty_file = "cty.dat"\nbands = ["20M", "6m"]\nmax_age_min = 15\n'
    )
    s = load(tmp_path, on)
    assert (s.dxcluster.login, s.dxcluster.bands, s.dxcluster.max_age_min) == (
        "G4ABC",
        ["20m", "6m"],
        15,
    )


@pytest.mark.parametrize(
    ("host", "says"),
    [
        ("telnet://g4abc:Sekr1tPW@dxc.example.org:7300", "not a URL with a login"),
        ("g4abc:Sekr1tPW@dxc.example.org", "not a URL with a login"),
        ("telnet://dxc.example.org", "not a URL: 'telnet://dxc.example.org' (the port is "),
        ("dxc.example.org:7300", "without its port: 'dxc.example.org:7300' (dxcluster.port)"),
        ("dxc..example.org", "is no host name"),
    ],
)
def test_a_host_that_is_no_host_name_is_refused_naming_the_key_and_no_password(
    tmp_path: Path, host: str, says: str
) -> None:
    """An attack pass: any text passed check-config ("config OK", the URL printed whole, its
    password with it), and the client retried it for ever."""
    table = f'[dxcluster]\nenabled = true\nhost = "{host}"\nlogin = "G4ABC"\ncty_file = "c"\n'
    said = refused(tmp_path, table)
    assert "dxcluster.host: " in said and says in said
    assert "Sekr1tPW" not in said
    for fine in ("dxc.example.org", "192.0.2.7", "2001:db8::7"):
        assert load(tmp_path, table.replace(host, fine)).dxcluster.host == fine


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('[dxcluster]\nenabled = true\nlogin = "G4ABC"\ncty_file = "c"\n', "host: needed"),
        ('[dxcluster]\nenabled = true\nhost = "h"\ncty_file = "c"\n', "login: needed"),
        ('[dxcluster]\nenabled = true\nhost = "h"\nlogin = "G4ABC"\n', "cty_file: needed"),
        ('[dxcluster]\nlogin = "G4 ABC"\n', "dxcluster.login"),
        ('[dxcluster]\nbands = ["20m", "11m"]\n', "'11m' is not an amateur band"),
        ("[dxcluster]\nport = 0\n", "dxcluster.port"),
        ("[dxcluster]\nmax_spots = 500\n", "dxcluster.max_spots"),
        ("[dxcluster]\nhots = 1\n", "host"),  # a typo: the nearest key suggested
    ],
)
def test_a_bad_table_is_an_error_naming_the_key(tmp_path: Path, text: str, says: str) -> None:
    assert says in refused(tmp_path, text)


def test_a_missing_or_empty_cty_file_stops_the_start_naming_it(tmp_path: Path) -> None:
    table = '[dxcluster]\nenabled = true\nhost = "127.0.0.1"\nlogin = "G4ABC"\n'
    missing = load(tmp_path, table + f'cty_file = "{tmp_path / "nowhere.dat"}"\n')
    with pytest.raises(ConfigError, match="nowhere.dat cannot be read"):
        App(missing)
    (tmp_path / "junk.dat").write_text("this is no country file\n")
    junk = load(tmp_path, table + f'cty_file = "{tmp_path / "junk.dat"}"\n')
    with pytest.raises(ConfigError, match="junk.dat: no entity"):
        App(junk)
    (tmp_path / "cty.dat").write_text(CTY_DAT)
    good = load(tmp_path, table + f'cty_file = "{tmp_path / "cty.dat"}"\n')
    app = App(good)  # built, never started: no socket, no broker, no serial port
    dx = app.services["dxcluster"]  # the feature's service (features/dxcluster)
    assert isinstance(dx, DxCluster) and dx.book.entity_place("JA1ABC") is not None
