"""Real parts for tests (and the benchmarks), one copy of each: import them from here.

- waiting.py: ``wait_until``, waiting on a condition with a deadline, never a bare sleep;
  ``slow``, the one factor (ROTOR_TEST_SLOWDOWN) every deadline of the tests is scaled by
- mqtt.py: ``Probe``, an MQTT client that records what arrives; ``retained_snapshot``
- process.py: the bridge as a user runs it (``BridgeProcess``, ``run_cli``; ``cli`` in this
  process, for check-config), its TOML files;
  the one BridgeProcess of the tests, the fault suite, the soak and the benchmarks
- ports.py: ``free_port``, ``free_udp_port``: loopback ports no other test's sender can take
  before the listener they are handed to binds them
- codecs.py: feeding a sans-IO parser whole, byte by byte, and split (``feed``, ``HOW``)
- mqtt_proxy.py: ``MqttProxy``, a TCP proxy before the broker that knows each connection by
  its client id: one dropped, what one sends held, the SUBACKs counted, every open connection
  made a dead path (``blackhole``), each packet passing seen, changed or lost (``on_packet``);
  where a test places a message at a connection's moment
- rig.py: a broker, emulated controllers on real ptys and the bridge, in-process or as its own
  process (``Rig``): the one rig of the tests, the fault suite (tapped, faster) and the
  benchmarks (real timings, paced lines); imported from there, as it brings the whole bridge in
- tap.py: the serial sniffer on a controller's transmit line and independent parsers of what
  it reports (the ground truth of "a bearing the controller never reported")
- cpu.py: where the suite's CPU goes, each test's CPU-seconds and its children's, recorded
  when ROTOR_TEST_CPU names a file (``python -m tests.support.cpu FILE`` reports them)

A private mosquitto on a free loopback port is demo/mosquitto.py's ``Mosquitto`` (the demo's broker
with a configuration of its own, a crash, a freeze and a restart); the pytest fixtures
``broker``, ``probe`` and ``rig`` are in tests/conftest.py.
"""

from tests.support.codecs import HOW, feed
from tests.support.mosquitto import Mosquitto
from tests.support.mqtt import Message, Probe, retained_snapshot
from tests.support.ports import free_port
from tests.support.process import ROOT, BridgeProcess, bridge_env, cli, run_cli, to_toml
from tests.support.waiting import slow, wait_until

__all__ = [
    "HOW",
    "ROOT",
    "BridgeProcess",
    "Message",
    "Mosquitto",
    "Probe",
    "bridge_env",
    "cli",
    "feed",
    "free_port",
    "retained_snapshot",
    "run_cli",
    "slow",
    "to_toml",
    "wait_until",
]
