"""``[wsjtx]`` and ``follow_hold_while_tx`` as a user writes them, through the real loader."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.app import App
from bridge.settings import ConfigError, Settings, load_settings

ROTATOR = '[[rotators]]\nid = "tower"\nmodel = "rotorez"\nport = "/dev/ttyUSB0"\n'


def load(tmp_path: Path, text: str, rotator: str = "") -> Settings:
    path = tmp_path / "c.toml"
    path.write_text(text + ROTATOR + rotator)
    return load_settings(path, environ={})


def refused(tmp_path: Path, text: str) -> str:
    with pytest.raises(ConfigError) as err:
        load(tmp_path, text)
    return str(err.value)


def test_off_on_wsjtxs_own_port_on_loopback_by_default(tmp_path: Path) -> None:
    s = load(tmp_path, "")
    assert (s.wsjtx.enabled, s.wsjtx.port, s.wsjtx.bind, s.wsjtx.multicast_group) == (
        False,
        2237,
        "127.0.0.1",
        None,
    )
    assert s.rotators[0].follow_hold_while_tx is True
    s = load(tmp_path, '[wsjtx]\nenabled = true\nmulticast_group = "239.255.0.1"\n', "")
    assert s.wsjtx.enabled and s.wsjtx.multicast_group == "239.255.0.1"
    s = load(tmp_path, "", "follow_hold_while_tx = false\n")
    assert s.rotators[0].follow_hold_while_tx is False


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('[wsjtx]\nmulticast_group = "192.168.1.5"\n', "wsjtx.multicast_group"),
        ('[wsjtx]\nmulticast_group = "239.255.0"\n', "multicast address"),
        ('[wsjtx]\nbind = "localhost"\n', "wsjtx.bind"),
        ("[wsjtx]\nport = 70000\n", "wsjtx.port"),
        ("[wsjtx]\nenable = true\n", "enabled"),  # a typo: the nearest key suggested
    ],
)
def test_a_bad_wsjtx_table_is_an_error_naming_the_key(tmp_path: Path, text: str, says: str) -> None:
    assert says in refused(tmp_path, text)


def test_a_rotator_can_follow_only_with_the_listener_and_the_station(tmp_path: Path) -> None:
    station = '[station]\nlocator = "JO62qm"\n'
    wsjtx = "[wsjtx]\nenabled = true\nport = 2237\n"
    for text, can in [("", False), (station, False), (wsjtx, False), (station + wsjtx, True)]:
        settings = load(tmp_path, f'state_file = "{tmp_path / "state.json"}"\n' + text)
        app = App(settings)  # built, never started: no socket, no broker, no serial port
        assert [r.can_follow for r in app.rotators] == [can], text


@pytest.mark.parametrize(
    "table",
    [
        '[wsjtx]\nenabled = true\nbind = "0.0.0.0"\n',
        '[wsjtx]\nenabled = true\nbind = "192.168.1.5"\nmulticast_group = "239.255.0.1"\n',
    ],
)
def test_check_config_warns_of_a_wsjtx_port_off_loopback(tmp_path: Path, table: str) -> None:
    """WSJT-X's UDP protocol has no authentication: off loopback, anyone on the network can
    send the Status that a following rotator turns to (a forged grid), as check-config says of
    the loggers' and rotctld's ports."""
    from bridge.settings.report import config_warnings

    (warning,) = [w for w in config_warnings(load(tmp_path, table)) if w.startswith("wsjtx.")]
    assert "wsjtx.bind" in warning and "no authentication" in warning
    quiet = load(tmp_path, '[wsjtx]\nenabled = true\nmulticast_group = "239.255.0.1"\n')
    assert not [w for w in config_warnings(quiet) if w.startswith("wsjtx.")]
    off = load(tmp_path, '[wsjtx]\nbind = "0.0.0.0"\n')
    assert not [w for w in config_warnings(off) if w.startswith("wsjtx.")]
