"""Review 39, Easycomm: a SatNOGS controller holding its rotor at north says an azimuth a hair
below 0 (``AZ-0.1``), and the bridge throws that reading away.

The SatNOGS DC-motor controller reads its azimuth from an AS5601 encoder, unwrapped across
turns and less the offset taken at the home switch (satnogs-rotator-firmware
libraries/as5601.h ``get_pos``: ``real_pos = ((raw_pos + 360 * _n) / _enc_ratio) -
_angle_offset``), so at home it reads 0 give or take the encoder's last bit, and its PID stops
anywhere within ``POSITION_DEADZONE`` 0.2 of its setpoint (dc_motor_controller.ino): turned
back to north it may come to rest at -0.1, and it answers ``AZ EL`` with
``String(control_az.input, 1)``, ``AZ-0.1 EL0.0`` (libraries/easycomm.h). Hamlib's own
Easycomm back end, the judge of our emulator, reads that line as it is
(rotators/easycomm/easycomm.c at 4.5.4 line 145, ``sscanf(ackbuf, "AZ%f EL%f", az, el)``;
at its newest, lines 153 and 173, ``"AZ%f"`` and ``"EL%f"``; no range check either way),
and the project's protocol sheet (/work/shared/protocols/more-controllers.md, Easycomm
section) names no range that excludes it. The codec spoils every such reply (easycomm.py
rule 2: azimuth outside 0..360), so a SatNOGS rotator parked at north gives no reading at
all, poll after poll: the user sees the rotator go offline while it stands where it was sent.
"""

from __future__ import annotations

import pytest

from bridge.protocols.base import PositionReply
from bridge.protocols.easycomm import EasycommCodec


def _north_apart(az: float) -> float:
    a = az % 360.0
    return min(a, 360.0 - a)


@pytest.mark.parametrize("elevation", [True, False], ids=["azel", "az"])
def test_a_satnogs_at_rest_just_below_north_is_read_at_north(elevation: bool) -> None:
    codec = EasycommCodec(3, elevation=elevation)
    assert codec.encode_query() == b"AZ EL\n"
    replies = codec.feed(b"AZ-0.1 EL0.0\n")
    readings = [r for r in replies if isinstance(r, PositionReply)]
    assert len(readings) == 1, replies
    assert _north_apart(readings[0].az_deg) <= 0.1 + 1e-9
    if elevation:
        assert readings[0].el_deg == 0.0


def test_a_satnogs_at_rest_just_past_360_is_read_at_360() -> None:
    codec = EasycommCodec(3)
    codec.encode_query()
    readings = [r for r in codec.feed(b"AZ360.1 EL0.0\n") if isinstance(r, PositionReply)]
    assert [(r.az_deg, r.el_deg) for r in readings] == [(360.0, 0.0)]
