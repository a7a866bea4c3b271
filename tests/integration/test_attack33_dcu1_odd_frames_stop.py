"""Attack 33's suspicion: on the DCU-1 TCP front end, ``APnan;`` stopped the rotor but
``AP1nan;`` and ``AP-0;`` sent no stop. docs/rotctld.md: "a ``;`` that ends anything else (a torn
command, ``AP1999;``) stops too, since it may have been meant as one". Asserted on the wire: the
controller gets its stop frame for each, and the turn ends short of its target. (Not
reproduced: each stops, as ``;`` does; with a Rotor-EZ behind the port a stop at rest sends
nothing to the controller, whichever frame carries it.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration.test_dcu1_endpoint import client, start
from tests.support.rig import Rig

ODD = [b"APnan;", b"AP1nan;", b"AP-0;"]


@pytest.mark.parametrize("sender", ["same", "new"])
@pytest.mark.parametrize("frame", ODD, ids=[f.decode() for f in ODD])
def test_an_odd_frame_ended_by_a_semicolon_stops_a_turning_rotor(
    rig: Rig, tmp_path: Path, frame: bytes, sender: str
) -> None:
    """Sent by the program that started the turn, or by a new connection (its first bytes: the
    accept loop's look for a stop, tcplines.py)."""
    port, _ = start(rig, tmp_path)
    emu = rig.emus["tower"]
    with client(port) as program:
        program.send(b"AP1300;AM1;")
        emu.wait_for(lambda s: s.is_moving and s.az_deg > 60, 15)
        stops = len(emu.frames("stop"))
        if sender == "same":
            program.send(frame)
        else:
            with client(port) as other:
                other.send(frame)
        stopped = emu.wait_for(lambda s: not s.is_moving, 5)
        assert stopped.az_deg < 290, f"{frame!r} did not stop the turn"
        assert len(emu.frames("stop")) > stops, f"{frame!r}: no stop frame on the wire"
