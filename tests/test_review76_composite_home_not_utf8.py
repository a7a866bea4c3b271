"""Review 76 of b9e5cc7d (settings/base.py rules 3, 6 and 7, ``beyond_home``): a serial port
written ``~/...`` in a home folder whose name is not UTF-8 is now taken, judged as the ``~/...``
it reads as. A composite rotator's elevation box written so is not: the tables' ports are
expanded (7051873c) and joined as ``<azimuth's>+<elevation's>``, and that port of both is
judged whole; only a head in the home folder is exempt, so ``/dev/ttyAZ+/home/h\\xe9/el`` is
refused as not UTF-8, naming ``port``, a key the file does not give. The same box as the
azimuth's (``~/az+/dev/ttyEL``) loads."""

from __future__ import annotations

from pathlib import Path

import pytest

from bridge.settings import settings_from


def test_a_composite_elevation_box_in_a_home_folder_not_in_utf8_is_taken(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    boxes = {
        "azimuth": {"model": "rt21", "port": "/dev/ttyAZ"},
        "elevation": {"model": "gs232b", "port": "~/el"},
    }
    r = settings_from({"rotators": [{"id": "sky", **boxes}]}, environ={}).rotators[0]
    assert r.ports == ["/dev/ttyAZ", str(home / "el")]
    again = type(r).model_validate(r.model_dump())  # what check-config --full prints loads
    assert again.ports == r.ports


def test_a_composite_azimuth_box_in_a_home_folder_not_in_utf8_is_taken(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same box written as the azimuth's: taken (the head of the port of both is exempt)."""
    home = tmp_path / "h\udce9"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    boxes = {
        "azimuth": {"model": "rt21", "port": "~/az"},
        "elevation": {"model": "gs232b", "port": "/dev/ttyEL"},
    }
    r = settings_from({"rotators": [{"id": "sky", **boxes}]}, environ={}).rotators[0]
    assert r.ports == [str(home / "az"), "/dev/ttyEL"]
    again = type(r).model_validate(r.model_dump())
    assert again.ports == r.ports
