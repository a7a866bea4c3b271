"""Review 76 of b9e5cc7d (settings/base.py rules 3 and 7, ``beyond_home``): a pty's link
written ``~/...`` in a home folder whose name is not UTF-8 is now taken, and check-config says
"GS-232B on a pty at .../h\\udce9/gs232" and "config OK" (test_review69_home_not_utf8.py). The
start does not make it: the pty server claims its path by a hash of its UTF-8 text
(interfaces/ptylines.py rule 1, ``_claimed``: ``self.path.encode()``), which a lone surrogate
has none of, and the App's start ends in a UnicodeEncodeError (run: a traceback, exit 1, which
the systemd unit restarts for ever), where check-config had said the file is good."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.integration.test_gs232_integration import GS232, rotctl
from tests.support.rig import Rig

pytestmark = pytest.mark.hamlib


def test_a_gs232_pty_in_a_home_folder_not_in_utf8_is_linked_and_answers(
    rig: Rig, rotctl_path: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    home = tmp_path / "h\udce9"  # b"h\xe9": a Latin-1 name, as os.environ holds it
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    rig.add("tower", emu={"start_az_deg": 120, "jitter_deg": 0}, gs232_pty="~/gs232")
    rig.start()
    rig.ready("tower")
    link = str(home / "gs232")
    assert os.readlink(link).startswith("/dev/pts/")
    az, el = rotctl(rotctl_path, GS232, link, "p").split()
    assert abs(float(az) - 120) <= 1 and float(el) == 0
