"""Review 69: 3e65c148 made check-config judge the cty file by the start's own reading (an
attack pass: check-config said "(found)" and "config OK" of an error page a failed download
saved, which the start refused). The TLE file, whose reader 39f86c2c reworked in the same
series, is still judged by ``os.path.isfile`` alone: an error page saved as the TLE file is
"(found)" with no warning, while the start reads no satellite in it and logs a bad entry, and
the device or pipe the start calls "no regular file (a device, a pipe or a folder): not read"
is one that "does not exist now" to check-config. A user sets up tracking, is told the file
is found, and every satellite is then "no satellite" at run."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.support import cli, to_toml
from tests.support.sky import synthetic_tle


def _config(tmp_path: Path, tle: Path) -> Path:
    """A configuration that tracks with ``tle`` as its TLE file."""
    config = tmp_path / "bridge.toml"
    config.write_text(
        to_toml(
            {
                "state_file": tmp_path / "state.json",
                "mqtt": {"host": "127.0.0.1"},
                "station": {"locator": "JO01"},
                "tracking": {"tle_file": tle},
                "rotators": [{"id": "tower", "model": "gs232b", "port": "/dev/rotor"}],
            }
        )
    )
    return config


def _html(tmp_path: Path) -> Path:
    page = tmp_path / "amateur.tle"
    page.write_text("<html><body><h1>404 Not Found</h1></body></html>\n")
    return page


def _fifo(tmp_path: Path) -> Path:
    pipe = tmp_path / "amateur.tle"
    os.mkfifo(pipe)
    return pipe


@pytest.mark.parametrize("made", [_html, _fifo], ids=["an error page", "a pipe"])
def test_check_config_says_of_a_tle_file_what_the_start_will_find_in_it(
    tmp_path: Path, made: Callable[[Path], Path]
) -> None:
    tle = made(tmp_path)
    config = _config(tmp_path, tle)
    out = cli("check-config", "-c", str(config))
    warned = [line for line in out.stdout.splitlines() if line.startswith("warning: tracking.")]
    assert warned, out.stdout  # the start's log says it: check-config says it too
    assert "does not exist" not in warned[0], warned[0]  # it exists: it is no TLE file


def _good(tmp_path: Path) -> Path:
    line1, line2 = synthetic_tle(
        "", 1767225600.0, inclination_deg=51.6, raan_deg=0.0, mean_anomaly_deg=0.0, catalog=25544
    )
    tle = tmp_path / "amateur.tle"
    tle.write_text(f"ISS (ZARYA)\n{line1}\n{line2}\n")
    return tle


def test_check_config_says_nothing_against_a_tle_file_the_start_reads_a_satellite_from(
    tmp_path: Path,
) -> None:
    """The other side: a file the start reads whole is '(found)', and no warning names it."""
    tle = _good(tmp_path)
    config = _config(tmp_path, tle)
    out = cli("check-config", "-c", str(config))
    assert out.returncode == 0, out.stderr
    assert f"the satellites in {tle} (found)" in out.stdout, out.stdout
    assert "warning: tracking." not in out.stdout, out.stdout
    assert not out.stderr, out.stderr  # (the reading's log is not check-config's output)
