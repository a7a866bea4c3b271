"""Review 73 (b9b7d920, settings/base.py rule 7 for a rotator's ``port``): a composite
rotator's ``port`` is derived from its two tables' ports, ``<azimuth's>+<elevation's>``, before
either is expanded, and the derived text is then expanded as one path: only its head. An
elevation box written ``~/...`` gives ``/home/.../az+~/el``, which check-config --full prints,
and which no longer loads back (test_composite_settings.py's promise): "port is given with
azimuth/elevation tables", the tables' ports being expanded by then."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.settings import ConfigError, settings_from


def test_a_composite_with_an_elevation_port_in_the_home_folder_loads_as_it_is_printed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))
    boxes = {
        "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
        "elevation": {"model": "gs232b", "port": "~/el"},
    }
    r = settings_from({"rotators": [{"id": "sky", **boxes}]}, environ={}).rotators[0]
    assert r.ports == ["/dev/ttyAZ", str(tmp_path / "el")]  # (each box's, expanded)
    assert r.port == f"/dev/ttyAZ+{tmp_path / 'el'}", r.port  # (observed: /dev/ttyAZ+~/el)
    again = type(r).model_validate(r.model_dump())  # what check-config --full prints loads
    assert (again.model, again.ports) == (r.model, r.ports)


def test_a_box_port_written_in_the_home_folder_and_as_its_path_is_one_port(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One port for both boxes is refused naming the elevation's, however each is written."""
    monkeypatch.setenv("HOME", str(tmp_path))
    boxes = {
        "azimuth": {"model": "rt21", "port": "~/box"},
        "elevation": {"model": "gs232b", "port": str(tmp_path / "box")},
    }
    with pytest.raises(ConfigError) as err:
        settings_from({"rotators": [{"id": "sky", **boxes}]}, environ={})
    assert f"elevation.port: {tmp_path / 'box'} is the azimuth's port too" in str(err.value)
