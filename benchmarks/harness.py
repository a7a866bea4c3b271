"""The benchmarks' own plumbing: processes that are always cleaned up, a private broker, the bridge
as a real service process (tests.support's BridgeProcess, started through a Scope), an MQTT
recorder.

Rules:
1. Every process a benchmark starts goes through a Scope (spawn), which ends it in reverse order
   on leaving the `with` block, whatever happened (exception, Ctrl-C, SIGTERM turned into
   KeyboardInterrupt by __main__). Children also get PR_SET_PDEATHSIG, so they die with us even
   if we are killed outright; the emulator host also exits when its stdin closes. (The signal
   follows the spawning *thread*: a thread that spawns must outlive its Scope, as the pool
   threads of the parallel rows do.)
2. The bridge under test runs as its own process (`python -m bridge run -c FILE`), so its CPU,
   memory and GIL are its own; emulators run in this process (their frame log is the ground
   truth, stamped on time.monotonic, the same clock as ours) or in the emulator host.
3. Nothing here runs bridge code except the emulators (and ModelSpec data for frame sizes;
   tests.support's rig brings in the bridge's modules for its in-process mode, unused here):
   what is measured is the service as a user runs it.
4. What the tests have too comes from them (tests.support: waiting with a deadline, the MQTT
   probe, the bridge's process, environment and configuration, the rig, and demo/mosquitto.py: a
   free port, the mosquitto executable), not a copy of it. `python -m benchmarks` runs from the
   top of the checkout, so `tests` is importable; the broker here is its own start (rule 1, and
   no -v log per message).
5. ``hardware_first()`` (as root) raises this process's priority above everything else here:
   it stands for the controllers on the wire and the operator's own machine, which on a station
   do not wait for a core behind the bridge, the broker or a load, and it stamps the frames the
   latency ends at. Every process it spawns starts at the machine's usual priority again, but
   for one that also stands for hardware (the emulator host: ``spawn(..., hardware=True)``).
6. ``instrument_first()`` (as root) puts every thread this process has at that moment in the
   real-time class (SCHED_FIFO, priority INSTRUMENT_RT): the controllers' emulators and paced
   lines that carry and stamp a measured frame, the publisher's network thread, the probes, and
   every thread that may hold the interpreter lock one of those waits for. A controller's
   microcontroller and UART never wait for a core; a nice value only weighs a thread against
   the others, and under a load a nice -10 thread still waited for one for milliseconds behind
   nice-0 ones (and so did every thread of this process waiting for the lock it held). Only
   threads that sleep until a byte, a message or a deadline run here (one that spun would hold
   a core; the kernel keeps 5 % of each second for the others). Nothing started later inherits
   it (SCHED_RESET_ON_FORK): a process spawned then starts at the usual priority (rule 5's
   hardware at HARDWARE_NICE again), a thread started then at nice 0; call it again once a new
   instrument is up.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import paho.mqtt.client as paho

from tests.support import BridgeProcess, Probe, bridge_env
from tests.support import wait_until as _wait_until
from tests.support.mosquitto import answers, find_mosquitto, free_port
from tests.support.process import bridge_config

REPO = Path(__file__).resolve().parent.parent
PYTHON = sys.executable
_PR_SET_PDEATHSIG = 1


class BenchError(RuntimeError):
    """A measurement could not be made (a process died, a deadline passed)."""


#: set when the run is being abandoned (Ctrl-C, a failed parallel row): loops stop early
ABORT = threading.Event()


def check_abort() -> None:
    if ABORT.is_set():
        raise BenchError("aborted")


# -- processes ----------------------------------------------------------------------------------
USUAL_NICE = os.getpriority(os.PRIO_PROCESS, 0)  # rule 5: before hardware_first()
HARDWARE_NICE = -10


def hardware_first() -> bool:
    """Rule 5, for this thread and the threads it starts from now on (call it first thing);
    False where that is not allowed (not root): then everything shares one priority."""
    try:
        os.setpriority(os.PRIO_PROCESS, 0, HARDWARE_NICE)
    except OSError:
        return False
    return True


INSTRUMENT_RT = 1  # rule 6: the lowest real-time priority, above every ordinary thread
_INSTRUMENT_RAISED = False  # rule 6 done: a hardware child takes HARDWARE_NICE again


def instrument_first() -> bool:
    """Rule 6 for every thread of this process; False where that is not allowed (not root, no
    real-time class here): they keep their priority then."""
    tids = (
        [int(t) for t in os.listdir("/proc/self/task")] if os.path.isdir("/proc/self/task") else []
    )
    try:
        policy = os.SCHED_FIFO | os.SCHED_RESET_ON_FORK
        for tid in tids:
            with contextlib.suppress(ProcessLookupError):  # a thread that ended meanwhile
                os.sched_setscheduler(tid, policy, os.sched_param(INSTRUMENT_RT))
    except (OSError, AttributeError):
        for tid in tids:  # all or none: a figure taken with some raised compares with neither
            with contextlib.suppress(OSError, AttributeError):
                os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
        return False
    global _INSTRUMENT_RAISED  # noqa: PLW0603 (read by the children's preexec)
    _INSTRUMENT_RAISED = bool(tids)
    return _INSTRUMENT_RAISED


def _die_with_parent() -> None:  # runs in the child between fork and exec
    if _INSTRUMENT_RAISED and os.getpriority(os.PRIO_PROCESS, 0) > HARDWARE_NICE:  # rule 6
        with contextlib.suppress(OSError):  # reset it to nice 0: rule 5's again
            os.setpriority(os.PRIO_PROCESS, 0, HARDWARE_NICE)
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def _usual_child() -> None:  # rule 5: a child that is not hardware
    _die_with_parent()
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, USUAL_NICE)


def child_env() -> dict[str, str]:
    env = bridge_env()
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env


def stop_process(proc: subprocess.Popen[Any], timeout_s: float = 5.0) -> None:
    if proc.poll() is not None:
        return
    with contextlib.suppress(ProcessLookupError):
        proc.terminate()
    try:
        proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        proc.wait(5)


class Scope(contextlib.ExitStack):
    """An ExitStack that also spawns processes and always ends them (rule 1)."""

    def __init__(self, workdir: Path) -> None:
        super().__init__()
        self.workdir = workdir
        self.processes: list[subprocess.Popen[bytes]] = []
        workdir.mkdir(parents=True, exist_ok=True)

    def spawn(
        self,
        argv: Sequence[str],
        *,
        log_name: str,
        stdin: int | None = subprocess.DEVNULL,
        stdout: int | None = None,
        cwd: Path = REPO,
        env: dict[str, str] | None = None,
        hardware: bool = False,
    ) -> subprocess.Popen[bytes]:
        """``env``: the child's whole environment (default: this checkout's, child_env)."""
        log = open(self.workdir / log_name, "ab")  # noqa: SIM115 (closed by the stack)
        self.callback(log.close)
        proc = subprocess.Popen(
            list(argv),
            stdin=stdin,
            stdout=log if stdout is None else stdout,
            stderr=log,
            cwd=cwd,
            env=child_env() if env is None else env,
            preexec_fn=_die_with_parent if hardware else _usual_child,
        )
        self.callback(stop_process, proc)
        self.processes.append(proc)
        return proc

    def spawner(self, argv: list[str], log: Path) -> subprocess.Popen[bytes]:
        """``spawn`` as tests.support's BridgeProcess and Rig call it (``log`` in this scope)."""
        return self.spawn(argv, log_name=str(log.relative_to(self.workdir)))


#: tests.support's wait_until(predicate, timeout_s, what, interval_s), raising BenchError
wait_until = functools.partial(_wait_until, error=BenchError)


def check_alive(proc: subprocess.Popen[Any], name: str, log: Path | None = None) -> None:
    if proc.poll() is not None:
        tail = log.read_text(errors="replace")[-1500:] if log and log.exists() else ""
        raise BenchError(f"{name} exited with status {proc.returncode}\n{tail}")


# -- broker -------------------------------------------------------------------------------------
def start_broker(scope: Scope, extra_conf: str = "") -> int:
    """A private mosquitto with its default limits, on a free loopback port; returns the port."""
    port = free_port()
    conf = scope.workdir / "mosquitto.conf"
    conf.write_text(
        f"listener {port} 127.0.0.1\npersistence false\nallow_anonymous true\n{extra_conf}"
    )
    exe = find_mosquitto()
    if exe is None:
        raise BenchError("mosquitto is not installed (Debian: sudo apt-get install mosquitto)")
    proc = scope.spawn([exe, "-c", str(conf)], log_name="mosquitto.log")

    def listening() -> bool:
        check_alive(proc, "mosquitto", scope.workdir / "mosquitto.log")
        return answers("127.0.0.1", port, 0.2)

    try:
        wait_until(listening, 10, "mosquitto to listen")
    except BenchError:
        log = scope.workdir / "mosquitto.log"
        raise BenchError(f"mosquitto did not listen on {port}: {log.read_text()[-500:]}") from None
    return port


# -- the bridge as a service process ------------------------------------------------------------
def start_bridge(
    scope: Scope,
    broker_port: int,
    rotators: list[dict[str, Any]],
    *,
    homeassistant: bool = True,
    log_level: str = "INFO",
    name: str = "bridge",
    sections: dict[str, Any] | None = None,
    mqtt: dict[str, Any] | None = None,
) -> BridgeProcess:
    """tests.support's BridgeProcess, started through ``scope`` (rule 1), its ``check`` raising
    BenchError. ``sections``: more of the configuration file (e.g. ``station``, ``tracking``);
    ``mqtt``: more of its ``[mqtt]`` table."""
    config = bridge_config(
        scope.workdir,
        broker_port,
        rotators,
        client_id=f"bench-{name}-{os.getpid()}",
        mqtt=mqtt,
        sections={"homeassistant": {"enabled": homeassistant}, **(sections or {})},
        state_name=f"{name}-state.json",
    )
    bridge = BridgeProcess(
        scope.workdir, config, log_level=log_level, name=name, spawn=scope.spawner, error=BenchError
    )
    return bridge.start()


# -- MQTT ---------------------------------------------------------------------------------------
class Mqtt(Probe):
    """The recording client: tests.support's Probe (every message under its filters, stamped on
    arrival, TCP_NODELAY so its PUBACKs add no Nagle delay of their own), whose waits raise
    BenchError and whose publish does not wait for the broker."""

    timeout_error = BenchError

    def __init__(
        self,
        port: int,
        filters: Iterable[str] = ("#",),
        *,
        name: str = "bench",
        max_inflight: int = 20,
    ) -> None:
        client_id = f"{name}-{os.getpid()}-{id(self)}"
        super().__init__(
            port, "|".join(filters), client_id, max_inflight=max_inflight, keepalive_s=30
        )

    def publish(  # type: ignore[override]
        self, topic: str, payload: str | bytes, qos: int = 1
    ) -> paho.MQTTMessageInfo:
        return self.client.publish(topic, payload, qos=qos, retain=False)

    def wait_all(self, topics: Iterable[str], value: str, timeout_s: float) -> None:
        """Until the latest message on each topic carries `value`."""
        wanted = list(topics)

        def done() -> bool:
            return all((m := self.last(t)) is not None and m.text == value for t in wanted)

        wait_until(done, timeout_s, f"{len(wanted)} topics = {value}", 0.02)
