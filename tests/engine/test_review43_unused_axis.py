"""Review 43: the lock fights a turn by itself (stops.py rule 7) at every reading at rest the
doubt does not take (controller.py rule 9), and that doubt covers a composite box's axis that
is never turned (axes.py rule 5). An elevation box whose azimuth, which the rotator takes from
the other box, reads 100, 103, 100... (a worn or floating pot, which
test_composite.py's ``test_a_box_whose_unused_axis_never_reads_the_same_twice_still_turns``
keeps turning) has the lock's stop written to it about once a second for as long as the lock
holds, its polls half as many again, and R/error says every junk interval that a reading
"disagrees with where the locked rotor stands (a hand at the panel, or line noise)": nothing
turns, and no hand can turn an axis the rotator does not have. Before rule 7 the lock wrote
no stop there. The stop belongs to a sign the rotor may be turning; a jitter of the axis the
box never turns is none.
(Fixed: only a reading away on an axis the box turns is a sign, controller.py ``_turned_axis``.)"""

from __future__ import annotations

import itertools

from bridge.protocols.axes import Axis
from tests.engine.test_composite import online
from tests.engine.virtual_composite import VirtualComposite

LOCKS = "the lock's stop sent again"


def test_a_locked_composite_writes_no_stop_for_its_elevation_boxs_unused_azimuth() -> None:
    gs232b = {"start_az_deg": 100.0, "start_el_deg": 10.0}
    with VirtualComposite("rt21", "gs232b", emulators={Axis.ELEVATION: gs232b}) as v:
        box = v.boxes[Axis.ELEVATION]
        device, jitter = box.device, itertools.cycle([0, 3])
        reading = device._reading

        def jittering(text: str) -> bytes:  # its azimuth, which the rotator never uses
            out = reading(text)
            shaken = b"%03d" % (int(out[3:6]) + next(jitter))
            return out[:3] + shaken + out[6:]

        device._reading = jittering
        v.run_until(online, 10, "both boxes answer")
        v.run_for(20)
        v.mailbox.put_lock(True)
        v.mailbox.put_lock_saved(True)
        v._take()
        v.run_for(5)  # (the lock's own stop, to both boxes)
        t = v.now
        v.run_for(120)
        assert v.status.locked
        assert not box.truth().is_moving
        said = [e for b in v.boxes.values() for e in b.errors(since=t) if LOCKS in e.message]
        assert said == []
        assert [w.t for w in box.writes if w.t >= t and w.data == b"S\r"] == []
