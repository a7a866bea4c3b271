"""One RotatorSession wired to one device emulator in-process, in virtual time.

What this is: the proof bench of docs/architecture.md ("decisions are proven in virtual time").
The session (session/session.py) and an emulator (emulators/, a sans-IO Responder written from
the documents, never from our codecs) talk through a simulated serial line; a fake clock jumps
from one thing that can happen to the next, so minutes of rotor time cost milliseconds.

How it drives the session: exactly as runtime/worker.py does (``start``, ``link_up``, then
``commands`` / ``bytes_received`` / ``tick`` when ``next_wakeup`` has passed and nothing else
acted), and it carries out the actions: ``Write`` bytes go on the line to the device,
``Publish`` and ``Report`` are recorded with the virtual time they came at.

Rules:
1. Virtual time only moves forward, to the earliest of: the session's ``next_wakeup``, the
   device's ``next_wakeup`` (a byte of its output due, an arrival, a brake set), the arrival of
   the next byte the host wrote, or the end of the run asked for.
2. The host's bytes are paced like the device's own output: 10 bits a byte at the configured
   baud rate, one after another (``base.PacedLine``); each byte reaches the device when it has
   completely arrived. The device's output is already paced by the device.
3. Faults act on the line, never on either side: a write can be lost or garbled on its way to
   the device (``drop_writes``, ``garble_writes``, ``set_deaf``, ``to_device``), the device's
   output on its way to the host (``set_silent``, ``to_host``, ``glitch_once``, or held back
   by ``delay_output``). Lost writes stay in ``writes`` (marked lost): they are what the bridge
   sent, the device's log is what arrived.
4. A session that asks to be woken at or before the present, again and again, spins the real
   worker's select loop until its clock moves on. Here the clock then moves on by CLOCK_GRAIN_S
   (counted in ``spins``); a spin that lasts SPIN_LIMIT grains raises ``BusyLoop`` instead of
   hanging the test.
5. The sky worker is played here: an ``Ask`` is answered by the same computation
   (``skywork.answer``, or ``answer_sky`` if a test replaces it), handed back ``sky_delay_s``
   of virtual time later (0: at the same instant, as an input of its own), as the real worker
   hands it to the session. Every question asked is kept in ``asked``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from bridge import emulators
from bridge.app import worker_config
from bridge.core.model import MotionState, RotatorStatus, SetOption, SettingValue, Stop, Target
from bridge.emulators.base import LoggedFrame, PacedLine, Responder, RotatorState
from bridge.session.actions import Ask, Audit
from bridge.session.config import FollowConfig, WorkerConfig
from bridge.session.follow import Follow, Heard
from bridge.session.mailbox import Mailbox
from bridge.session.session import Action, OwnTurn, Publish, Report, RotatorSession, Write
from bridge.session.tracking import Track
from bridge.settings import RotatorSettings
from bridge.sky import Body, Sky
from bridge.sky import worker as skywork

WALL_EPOCH_S = 1_750_000_000.0  # the wall clock reads this at virtual time 0
MAX_STEPS_AT_ONE_INSTANT = 20  # bytes, a tick, a command: a few things may share an instant
CLOCK_GRAIN_S = 1e-6  # how far a real monotonic clock has moved by the next loop, at least
SPIN_LIMIT = 1000


class BusyLoop(AssertionError):
    """The session keeps asking to be woken without time passing (rule 4)."""


@dataclass(frozen=True)
class Sent:
    """One frame the session wrote, and whether the line delivered it (rule 3)."""

    t: float
    data: bytes
    lost: bool = False


@dataclass
class _WriteFault:
    data: bytes
    replacement: bytes  # b"" drops the write
    count: int


class VirtualRotator:
    """A rotator under test: the session, its emulated controller, a line and a fake clock."""

    def __init__(
        self,
        model: str,
        *,
        settings: Mapping[str, Any] | None = None,
        emulator: Mapping[str, Any] | None = None,
        options: dict[str, SettingValue] | None = None,
        locked: bool = False,
        stop_owed: bool = False,  # as the state file kept it (runtime/kept.py rule 8)
        connect: bool = True,
        start_s: float = 0.0,
        sky: Sky | None = None,
        wall_epoch_s: float = WALL_EPOCH_S,
        sky_delay_s: float = 0.0,
        follow: FollowConfig | None = None,
        cfg: WorkerConfig | None = None,  # one box of a composite rotator (virtual_composite.py)
        place: Callable[[OwnTurn], int] | None = None,  # the own turns' places (the box's:
        # the composite's mailbox's, as runtime/composite.py rule 10 has it)
        own_places: bool = False,  # the mailbox's own_place, as runtime/worker.py gives it
        # (mailbox.py rule 10b; off by default: a session copied whole would copy the mailbox)
    ) -> None:
        self.now = start_s
        self.wall_epoch_s = wall_epoch_s  # the wall clock at virtual time 0
        rotator = RotatorSettings.model_validate(
            {"id": "v", "model": model, "port": "/dev/ttyVIRTUAL", **(settings or {})}
        )
        self.settings = rotator
        self.cfg = cfg or worker_config(rotator, sky, follow)
        self.device: Responder = emulators.create(model, now=start_s, **(emulator or {}))
        self.mailbox = Mailbox()
        self.session = RotatorSession(
            self.cfg,
            options=options,
            locked=locked,
            stop_owed=stop_owed,
            place=self.mailbox.own_place if own_places else place,
        )
        self.connected = False
        self.writes: list[Sent] = []
        self.statuses: list[tuple[float, RotatorStatus]] = []
        self.events: list[tuple[float, Report]] = []
        self.audited: list[tuple[float, Audit]] = []  # session.py rule 25: the bridge's own moves
        self.to_device: Callable[[bytes, float], bytes] | None = None  # rule 3: custom faults
        self.to_host: Callable[[bytes, float], bytes] | None = None
        self.received: list[tuple[float, bytes]] = []  # device output the host got, by chunk
        self.lost_to_host = 0  # bytes of device output lost on the line
        self._tx = PacedLine(self.cfg.baud)  # host -> device (rule 2)
        self._write_faults: list[_WriteFault] = []
        self._silent = False
        self._deaf = False
        self._delayed_until = -math.inf  # rule 3: the device's output held on the line until then
        self._delayed = b""
        self._steps_at_now = 0
        self._spin_run = 0
        self.spins: list[float] = []  # when the loop turned with nothing to do (rule 4)
        self.sky_delay_s = sky_delay_s  # rule 5
        self.answer_sky: Callable[[skywork.Question], skywork.Answer] = skywork.answer
        self.asked: list[tuple[float, Ask]] = []
        self._answers: list[tuple[float, int, skywork.Answer]] = []
        self._do(self.session.start(self.now))
        if connect:
            self.link_up()

    def close(self) -> None:
        self.mailbox.close()

    def __enter__(self) -> VirtualRotator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- what a test looks at -----------------------------------------------------------------
    @property
    def status(self) -> RotatorStatus:
        """The last status published."""
        return self.statuses[-1][1]

    @property
    def state(self) -> MotionState:
        return self.status.state

    def truth(self) -> RotatorState:
        """The emulator's ground truth now (no jitter, no rounding)."""
        return self.device.state(self.now)

    def frames(self, *outcomes: str, since: float = float("-inf")) -> list[LoggedFrame]:
        """Frames as the controller understood them (optionally only these outcomes)."""
        wanted = set(outcomes)
        return [
            f for f in self.device.log if f.time_s >= since and (not wanted or f.outcome in wanted)
        ]

    def sent(self, since: float = float("-inf")) -> list[bytes]:
        """What the session wrote (lost writes included), in order."""
        return [w.data for w in self.writes if w.t >= since]

    def errors(self, kind: str | None = None, since: float = float("-inf")) -> list[Report]:
        return [r for t, r in self.events if t >= since and (kind is None or r.kind == kind)]

    def published(self, since: float = float("-inf")) -> list[RotatorStatus]:
        return [s for t, s in self.statuses if t >= since]

    # -- commands (through a real mailbox, taken at once as the worker does) -----------------
    def command(self, *commands: Target | Stop | SetOption) -> None:
        for c in commands:
            self.mailbox.put(c)
        self._take()

    def aim(self, target: Target) -> None:
        """``target`` in true bearings, judged and converted as the Rotator does (pointing.py)."""
        self.command(self.cfg.aim.judge(target, self.session.status.raw_bearing_deg))

    def target(self, az_deg: float | None, el_deg: float | None = None) -> None:
        self.command(Target(az_deg, el_deg))

    def stop(self) -> None:
        self.command(Stop())

    def option(self, name: str, value: SettingValue) -> None:
        """Straight to the session, as the judge hands it on: ``value`` as the declaration
        reads it (the session does not judge; runtime/rotator.py does)."""
        setting = self.cfg.spec.setting(name)
        self.command(SetOption(name, setting.read(value) if setting is not None else value))

    def lock(self, locked: bool, *, saved: bool = True) -> None:
        """A lock word, saved at once (the writer's part, runtime/kept.py rule 2) unless not
        ``saved``."""
        self.mailbox.put_lock(locked)
        if saved:
            self.mailbox.put_lock_saved(locked)
        self._take()

    def track(self, body: Body | None) -> None:
        self.mailbox.put_track(Track(body))
        self._take()

    def follow(self, on: bool, *, long_path: bool = False) -> None:
        self.mailbox.put_follow(Follow(on, long_path))
        self._take()

    def heard(
        self, call: str, grid: str, transmitting: bool = False, dial_hz: int | None = None
    ) -> None:
        """What WSJT-X says, as the listener hands it on (interfaces/wsjtx/server.py)."""
        self.mailbox.put_heard(Heard(call, grid, transmitting, dial_hz=dial_hz))
        self._take()

    def wall(self) -> float:
        """The wall clock (unix seconds) now."""
        return self.wall_epoch_s + self.now

    def _take(self) -> None:
        batch = self.mailbox.take()
        if batch:
            self._do(self.session.commands(batch, self.now))

    # -- the link -------------------------------------------------------------------------------
    def link_up(self) -> None:
        self.connected = True
        self._do(self.session.link_up(self.now, self.wall_epoch_s + self.now))

    def link_down(self, reason: str | None = "virtual port unplugged") -> None:
        self.connected = False
        self._tx.clear()  # whatever was still on its way is lost with the adapter
        self._do(self.session.link_down(reason, self.now))

    # -- faults (rule 3) ------------------------------------------------------------------------
    def drop_writes(self, data: bytes, count: int = 1) -> None:
        """The next ``count`` writes equal to ``data`` are lost on the way to the device."""
        self._write_faults.append(_WriteFault(data, b"", count))

    def garble_writes(self, data: bytes, replacement: bytes, count: int = 1) -> None:
        """The next ``count`` writes equal to ``data`` arrive as ``replacement``."""
        self._write_faults.append(_WriteFault(data, replacement, count))

    def set_silent(self, silent: bool) -> None:
        """Everything the device transmits is lost (it still hears and obeys)."""
        self._silent = silent

    def set_deaf(self, deaf: bool) -> None:
        """Everything the host writes is lost before the device hears it."""
        self._deaf = deaf

    def delay_output(self, seconds: float) -> None:
        """What the device transmits from now for ``seconds`` reaches the host then, all at
        once and in order (a loaded host, a USB adapter that hands the bytes over late)."""
        self._delayed_until = self.now + seconds

    def answer_after(self, seconds: float) -> None:
        """From now on the device starts each answer ``seconds`` after the frame it answers
        (a controller gone slow, a serial server on the network, a slow USB adapter)."""
        self.device._tx.processing_delay_s = seconds  # type: ignore[attr-defined]

    def stopped_with_late_answers(self, poll: bytes, late_s: float) -> float:
        """A STOP (the stop lane's, and the main connection's copy 50 ms later) right after
        ``poll`` went out, the device's output from then on held ``late_s`` (past the poll's
        reply time: its answer, and the next poll's, come late); run until the rotor is idle.
        The time the poll went out."""
        self.run_until(lambda h: h.writes[-1] == Sent(h.now, poll), 5, "a poll just written")
        t = self.now
        self.delay_output(late_s)
        self.stop()
        self.run_for(0.05)
        self.stop()  # the main connection's copy of the lane's STOP
        self.run_until(lambda h: h.state is MotionState.IDLE, 10, "stopped")
        late = [at for at, _ in self.received if at > t][:1]
        assert late and math.isclose(late[0], t + late_s, abs_tol=1e-6), late  # (late)
        return t

    def glitch_once(self, first: bytes, noise: bytes) -> list[float]:
        """``noise`` reaches the host once, just before the next output that is ``first`` alone
        (a reply's first byte: the device's output is paced); the list returned gets the
        instant it did."""
        when: list[float] = []

        def glitch(data: bytes, now: float) -> bytes:
            if when or data != first:
                return data
            when.append(now)
            return noise + data

        self.to_host = glitch
        return when

    def read_once_as(self, first: bytes, reply: bytes) -> list[bytes]:
        """The next reply that begins with ``first`` alone (the device's output is paced, a
        byte at a time) reaches the host as ``reply``, once, through its LF; the list returned
        gets the bytes the device sent meanwhile (a flipped bit in one answer)."""
        sent: list[bytes] = []

        def in_place(data: bytes, now: float) -> bytes:
            if len(sent) > 1 and sent[-1] == b"\n":
                return data
            if sent or data == first:
                sent.append(data)
                return reply if len(sent) == 1 else b""
            return data

        self.to_host = in_place
        return sent

    # -- front panel ----------------------------------------------------------------------------
    def jam(self) -> None:
        self.device.jam(self.now)

    def unjam(self) -> None:
        self.device.unjam(self.now)

    def power_cycle(self) -> None:
        self.device.power_cycle(self.now)

    def press_brake(self) -> bool:
        return self.device.press_brake(self.now)

    def manual_rotate(self, az_deg: float) -> None:
        self.device.manual_rotate(az_deg, self.now)

    # -- time -----------------------------------------------------------------------------------
    def run_for(self, seconds: float) -> None:
        end = self.now + seconds
        while self.now < end:
            self._step(end)

    def pause(self, seconds: float) -> None:
        """The bridge's process held for ``seconds`` (SIGSTOP, a host that stalls): the line
        and the controller go on, what the controller sends waits in the port, and the
        session is not stepped; then it is, as the lines thread wakes (the port's bytes first,
        if any: runtime/worker.py ``serve``)."""
        end, held = self.now + seconds, b""
        while True:
            self.now = max(self.now, min([end, *self._wire_times()]))
            arrived = self._tx.due(self.now)
            if arrived:
                self.device.receive(arrived, self.now)
            out = self.device.due_output(self.now)
            if out and not self._silent and self.connected:
                held += out
            if self.now >= end:
                break
        if held:
            self.received.append((self.now, held))
            self._do(self.session.bytes_received(held, self.now))

    def run_until(
        self, predicate: Callable[[VirtualRotator], object], timeout_s: float, what: str = ""
    ) -> float:
        """Run until ``predicate(self)`` holds (checked after every step: between two things
        that happen, nothing changes); the virtual time it took. AssertionError (with the last
        status and the ground truth) if it does not within ``timeout_s``."""
        start, end = self.now, self.now + timeout_s
        while not predicate(self):
            if self.now >= end:
                raise AssertionError(
                    f"not within {timeout_s:g} s of rotor time: {what or predicate}\n"
                    f"  t={self.now:.3f} status={self.status}\n  truth={self.truth()}\n"
                    f"  last writes={self.sent(since=self.now - 5)}"
                )
            self._step(end)
        return self.now - start

    def run_until_state(self, state: MotionState, timeout_s: float) -> float:
        return self.run_until(lambda h: h.state is state, timeout_s, f"state {state.value}")

    def _wire_times(self) -> list[float]:
        """When the controller or the line next has something to do (none: nothing due)."""
        times = [self.device.next_wakeup(self.now), self._tx.next_due_s()]
        if self._delayed:
            times.append(self._delayed_until)
        return [t for t in times if t is not None]

    def next_time(self, until: float) -> float:
        """The time of the next thing that can happen here, ``until`` at the latest (rule 1)."""
        times = [until]
        if self.connected:
            times.append(self.session.next_wakeup())
        times += self._wire_times()
        times += [due for due, _gen, _answer in self._answers]
        return max(self.now, min(times))

    def _step(self, until: float) -> None:
        times = [until]
        if self.connected:
            times.append(self.session.next_wakeup())
        times += self._wire_times()
        times += [due for due, _gen, _answer in self._answers]
        t = max(self.now, min(times))
        if t > self.now:
            self._steps_at_now = self._spin_run = 0
        else:
            self._steps_at_now += 1
        if self._steps_at_now > MAX_STEPS_AT_ONE_INSTANT:
            t = self.now + CLOCK_GRAIN_S  # rule 4
            self.spins.append(self.now)
            self._spin_run += 1
            self._steps_at_now = 0
            if self._spin_run > SPIN_LIMIT:
                raise BusyLoop(
                    f"no time passes at t={self.now}: session next_wakeup "
                    f"{self.session.next_wakeup()}, status {self.status}"
                )
        self.now = t
        arrived = self._tx.due(t)
        if arrived:
            self.device.receive(arrived, t)
        out = self.device.due_output(t)
        if out and self.to_host is not None:
            out = self.to_host(out, t)
        if t < self._delayed_until:  # rule 3: held on the line
            self._delayed, out = self._delayed + out, b""
        elif self._delayed:
            self._delayed, out = b"", self._delayed + out
        if out and (self._silent or not self.connected):
            self.lost_to_host += len(out)
            out = b""
        acted = False
        while self._answers and self._answers[0][0] <= t:  # rule 5
            _due, generation, answer = self._answers.pop(0)
            self._do(self.session.sky_answer(generation, answer, t))
            acted = True
        if self.connected:
            if out:
                self.received.append((t, out))
                actions = self.session.bytes_received(out, t)
                acted = acted or bool(actions)
                self._do(actions)
            if not acted and t >= self.session.next_wakeup():
                self._do(self.session.tick(t))

    def _do(self, actions: Iterable[Action]) -> None:
        for action in actions:
            if isinstance(action, Write):
                self._write(action.data)
            elif isinstance(action, Publish):
                self.statuses.append((self.now, action.status))
            elif isinstance(action, Report):
                self.events.append((self.now, action))
            elif isinstance(action, Audit):
                self.audited.append((self.now, action))
            elif isinstance(action, Ask):
                self.asked.append((self.now, action))
                answer = self.answer_sky(action.question)
                self._answers.append((self.now + self.sky_delay_s, action.generation, answer))

    def _write(self, data: bytes) -> None:
        assert self.connected, f"the session wrote {data!r} while its link was down"
        wire = data
        for fault in self._write_faults:
            if fault.count > 0 and fault.data == data:
                fault.count -= 1
                wire = fault.replacement
                break
        if self.to_device is not None:
            wire = self.to_device(wire, self.now)
        if self._deaf:
            wire = b""
        self.writes.append(Sent(self.now, data, lost=wire != data))
        if wire:
            self._tx.send(wire, self.now)


def moves(v: VirtualRotator, since: float = float("-inf")) -> list[bytes]:
    """The bearings the device took since ``since``: the frames it logged as a move."""
    return [f.data for f in v.frames("move", since=since)]


def settled_at(az: float, el: float | None = None) -> Callable[[VirtualRotator], bool]:
    """For run_until: the session idle, the rotor still at ``az`` (and ``el``, if named)."""

    def there(v: VirtualRotator) -> bool:
        truth = v.truth()
        return (
            v.state is MotionState.IDLE
            and not truth.is_moving
            and truth.az_deg == az
            and (el is None or truth.el_deg == el)
        )

    return there
