"""Attack 23, on a real pty with real mosquitto: a STOP owed across an unplug waits out the
port's reopen back-off once the adapter is back.

docs/reliability.md: "A STOP sent while the adapter is out is the first frame once it is
back." The worker tries the port again only on its back-off (runtime/worker.py rule 1: 0.5 s
doubling to ``reconnect_max_s``, 10 s), whatever it owes the controller: an adapter out for
some 17 s (a USB cable knocked out, found and pushed back in) has the next try up to 10 s
after it is back. A Rotor-EZ that kept its power turns on to its old target all that time,
the STOP pressed, the adapter back: here 8 to 9 s, some 35 degrees at 4 degrees a second.
The stop frame was the first one, as promised, but late by the back-off. Now a stop owed has
the port tried every OWED_RETRY_S (worker.py rule 1), so it goes out within that and one
exchange of the replug.
"""

from __future__ import annotations

import time

from bridge.emulators.rotorez_models import Outcome
from tests.faults.conftest import Rig
from tests.support.waiting import slow, wait_until

OUT_S = 17.0  # how long the adapter stays out: a fault's length, not a deadline
SPEED_DEG_S = 4.0
PROMPT_S = 2.0  # the stop's frame after the replug: a reopen poll and an exchange, at most


def test_a_stop_owed_across_an_unplug_goes_out_promptly_once_the_adapter_is_back(
    rig: Rig,
) -> None:
    emu = rig.add("tower", "rotorez", emu={"start_az_deg": 10, "speed_deg_s": SPEED_DEG_S})
    rig.start()
    rig.ready("tower")
    rig.probe.publish(rig.topic("tower", "target"), "300")
    emu.wait_for(lambda s: s.is_moving and s.az_deg > 15, slow(10))
    t = time.monotonic()
    emu.unplug()
    rig.probe.wait_value(rig.topic("tower", "availability"), "offline", slow(5), after=t)
    rig.probe.publish(rig.topic("tower", "stop"), "STOP")  # while the port is out: owed
    wait_until(lambda: rig.status("tower").stop_owed, 5, "the stop owed")
    time.sleep(OUT_S)  # the adapter out: the fault's length (not a deadline)
    assert emu.state().is_moving  # the controller kept its power and its turn
    logged = len(emu.log())
    emu.replug(power_cycle=False)
    back = time.monotonic()
    stopped = emu.wait_until(
        lambda device, _now: [f for f in device.log[logged:] if f.outcome == Outcome.STOP],
        bool,
        slow(30),
    )
    took_s = stopped[0].time_s - back  # (the emulator's clock is the steady one)
    assert emu.log()[logged].outcome == Outcome.STOP  # the first frame, as promised...
    rest = emu.wait_for(lambda s: not s.is_moving, slow(10))
    assert took_s < slow(PROMPT_S), (  # ...but not once the adapter is back
        f"the owed stop reached the controller {took_s:.1f} s after the adapter was back; "
        f"the rotor turned on to {rest.az_deg:.0f} meanwhile"
    )
