"""Review 49: axes.py rule 2 (43b6e7b5) makes a one-axis elevation box's bearing outside the
elevation's scale a MISFIT, told at once on R/error as "no elevation (a pot past its end, or a
box calibrated for an azimuth rotor?)". One reply alone is neither: an RT-21 turning the
elevation of a 0..180 (flip) satellite station at 120 answers ``120.0;``, and one flipped bit
('1' 0x31 and '3' 0x33) makes it ``320.0;``. Before 43b6e7b5 rule 9 told that lone reading as
what it is, "a reading at rest of 0/320 ... was not said again: ignored (line noise?)"; now the
operator is sent to the pot or the box's calibration. In virtual time, two emulated RT-21s."""

from __future__ import annotations

from bridge.protocols.axes import Axis
from tests.engine.virtual import VirtualRotator
from tests.engine.virtual_composite import VirtualComposite


def _next_reply_read_as(box: VirtualRotator, reply: bytes) -> None:
    """The box's next reply (its bytes paced one at a time, through its ``;``) reaches the
    host as ``reply``, once."""
    state = ["waiting"]

    def once(data: bytes, now: float) -> bytes:
        if state[0] == "waiting" and data[:1].isdigit():
            state[0] = "eating"
        if state[0] != "eating":
            return data
        if data.endswith(b";"):
            state[0] = "done"
            return reply
        return b""

    box.to_host = once


def test_one_flipped_bit_past_the_elevation_scale_is_told_as_line_noise() -> None:
    with VirtualComposite("rt21", "rt21", emulators={Axis.ELEVATION: {"start_az_deg": 120.0}}) as v:
        v.run_for(10)
        assert v.status.elevation_deg == 120.0 and v.status.available
        t = v.now
        _next_reply_read_as(v.el, b"320.0;")
        v.run_for(40)
        assert v.status.elevation_deg == 120.0 and v.status.available
        told = [e.message for e in v.el.errors(since=t)]
        assert told, "a glitch at rest went unsaid"
        assert not any("pot past its end" in m or "calibrated" in m for m in told), told
        assert any("line noise" in m for m in told), told
