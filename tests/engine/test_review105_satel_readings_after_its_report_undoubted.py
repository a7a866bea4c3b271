"""Review 105: a SatEL's readings after its slew's report, while the rotor settles, are never
doubted: one flipped bit is published as the bearing, past a configured limit, and taken.

controller.py rule 9 doubts a turning rotor's reading that is further from the last taken than
the rotor can have turned (``_doubts_turning``: "a flipped digit mid-turn was published for
one poll on seven models"), and says "a silent controller's report after its slew is not
doubted". ``_doubts`` goes further: for a model that does not report while moving
(``reports_while_moving`` False: the SatEL) it takes every reading while the motion is MOVING
or a target is out, not the report alone. After the report the bridge polls the SatEL at the
moving rate until the rotor is seen still (about two seconds, ten answers); one flipped bit in
any of them (``Azimuth = 200`` read ``Azimuth = 280``, the ``0`` 0x30 read as ``8`` 0x38) is
published as the bearing, 80 degrees off and past ``az_max_deg`` 270, with nothing said, and
fed to the motion machine as a movement of 160 degrees there and back.

Now only the report itself goes undoubted; the answers after it are doubted as a turning rotor's
(``_doubts_turning``).

In virtual time: the emulated SatEL (as built: 10-degree steps) at rest at 150, sent to 200;
the answer after its report reaches the host with its azimuth's tens digit flipped.
"""

from __future__ import annotations

from collections.abc import Callable

from bridge.core.model import MotionState
from tests.engine.virtual import VirtualRotator

Rig = Callable[..., VirtualRotator]
REPORT = b"Azimuth = 200"
ONLINE_S = 30.0  # the SatEL's connect and first readings (virtual time)
WATCH_S = 30.0  # the slew of 50 degrees at 8 deg/s and the settle after it (virtual time)


def second_report_flipped() -> Callable[[bytes, float], bytes]:
    """Line by line (each at its last byte): the first azimuth line at 200 as sent, the second
    with its tens digit flipped (280); the rest as sent."""
    buf = bytearray()
    seen = [0]

    def flip(data: bytes, now: float) -> bytes:
        buf.extend(data)
        out = b""
        while b"\n" in buf:
            cut = buf.index(b"\n") + 1
            line = bytes(buf[:cut])
            del buf[:cut]
            if line.startswith(REPORT):
                seen[0] += 1
                if seen[0] == 2:
                    line = line.replace(REPORT, b"Azimuth = 280", 1)
            out += line
        return out

    return flip


def test_a_flipped_bit_in_a_satel_reading_after_its_report_is_never_published(rig: Rig) -> None:
    v = rig(
        "satel",
        emulator={"start_az_deg": 150.0, "start_el_deg": 45.0, "step_deg": 10},
        settings={"az_max_deg": 270.0},
    )
    v.run_until(lambda h: h.status.available and h.state is MotionState.IDLE, ONLINE_S, "online")
    v.to_host = second_report_flipped()
    t = v.now
    v.target(200.0, 45.0)
    v.run_for(WATCH_S)
    assert v.truth().az_deg == 200.0 and v.state is MotionState.IDLE
    shown = sorted({s.bearing_deg for s in v.published(since=t) if not s.estimated} - {None})
    assert max(shown) <= 205.0, shown
