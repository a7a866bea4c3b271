"""SatEL: a new target during a long slew. Measures stop-and-redirect (what the bridge does)
against holding the target for the after-move report (the alternative), end to end through
mosquitto, the bridge and the SatEL emulator at its default speeds (8 deg/s az, 4 deg/s el).

    .venv/bin/python -m benchmarks.satel_redirect

Scenario: slew 0/0 -> 300/60, five seconds later ask for 100/20. Holding would finish the first
slew and then travel back; the time for that is computed from the emulator's speeds (the bridge
does not implement holding), the redirect is measured.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from bridge import emulators
from bridge.app import App
from bridge.settings import Settings
from tests.support import Probe
from tests.support.mosquitto import Mosquitto

AZ_SPEED, EL_SPEED = 8.0, 4.0


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    broker = Mosquitto(tmp / "broker").start()
    emu = emulators.start(
        "satel",
        link=str(tmp / "tty"),
        az_speed_deg_s=AZ_SPEED,
        el_speed_deg_s=EL_SPEED,
        corrupt_on_misuse=True,
    )
    settings = Settings(
        mqtt={"port": broker.port},
        rotators=[{"id": "sat", "model": "satel", "port": str(tmp / "tty")}],
        state_file=tmp / "state.json",
    )
    app = App(settings)
    app.start()
    probe = Probe(broker.port, "rotor/#")
    try:
        probe.wait_value("rotor/state", "idle", timeout_s=20)
        probe.publish("rotor/target", "300 60")
        emu.wait_for(lambda s: s.slewing, 5)
        time.sleep(5.0)  # part of the scenario: the operator changes their mind 5 s in
        t0 = time.monotonic()
        at = emu.state()
        probe.publish("rotor/target", "100 20")
        emu.wait_for(
            lambda s: abs(s.az_deg - 100) <= 1 and abs(s.el_deg - 20) <= 1 and not s.is_moving, 120
        )
        redirect_s = time.monotonic() - t0
        rest_of_first = max((300 - at.az_deg) / AZ_SPEED, (60 - at.el_deg) / EL_SPEED)
        back = max((300 - 100) / AZ_SPEED, (60 - 20) / EL_SPEED)
        print(f"second target given at az {at.az_deg:.0f} el {at.el_deg:.0f}")
        print(f"stop and redirect (measured):           {redirect_s:5.1f} s to 100/20")
        print(f"hold for the after-move report (speeds): {rest_of_first + back:5.1f} s to 100/20")
        print(f"misuse recorded by the emulator: {len(emu.device.misuse_frames())}")
    finally:
        probe.close()
        app.stop()
        emu.close()
        broker.stop()


if __name__ == "__main__":
    main()
