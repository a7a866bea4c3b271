"""Attack 17 on the DCU-1 endpoint: the DCU-1 / Rotor-EZ protocol has one north. Hamlib's
``-m 401``/``-m 403`` send a bearing as three whole degrees and fold 360 to ``000``
(../shared/protocols/rotor-ez.md: 359.6 and 360 both go out as ``AP1000;``), and ``AI1;``
answers the rotor at 360 as ``;000``: 000 names north, a direction, not an end of a travel.
The endpoint takes it as the bridge's true bearing 0 named (pointing.py rule 2: the
counter-clockwise end), so a Yaesu behind a GS-232 (its 0 and 360 the two ends of its travel)
at 355, asked for north by a DCU-1 program, is sent ``M000`` and turns 355 degrees back
through south, where the same north from a logger (loggers/commands.py ``heading``), or from
the GS-232 port's ``W360`` which Hamlib's ``-m 603`` sends for it, turns it 5 degrees."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration.test_dcu1_endpoint import DCU1
from tests.integration.test_gs232_integration import rotctl
from tests.support import free_port
from tests.support.rig import Rig

pytestmark = pytest.mark.hamlib


def test_a_dcu1_north_turns_a_yaesu_at_355_the_short_way(
    rig: Rig, tmp_path: Path, rotctl_path: str
) -> None:
    port = free_port()
    emu = rig.add("tower", model="gs232b-az", emu={"start_az_deg": 355}, dcu1_port=port)
    rig.start()
    rig.ready("tower")
    rotctl(rotctl_path, DCU1, port, "P", "360", "0")  # Hamlib sends AP1000; then AM1;
    rig.arrived("tower", 0)  # north, on either end of the scale
    assert [f.data for f in emu.frames("move")] == [b"M360"], (
        "the rotor at 355 was sent the far end of its travel for north: a turn of 355 "
        "degrees through south for a bearing 5 degrees away"
    )
