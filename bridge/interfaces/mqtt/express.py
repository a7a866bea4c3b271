"""The stop express: a STOP's frame written to the controller by a process of its own.

Every thread of the bridge's process shares one interpreter lock. A stop read by the stop lane
(lane.py) still waits for that lock at each step (the lane's paho thread, the last word, the
mailbox, the serial-lines thread) while anything else holds it: the main connection reading a
backlog of targets, the console, a tracking starting. Bounds and courtesies (lane.py rule 4,
the front ends' budgets) keep those waits short, not absent. So the stop's frame takes a
second path that no work of the bridge's process can hold up: a small child process with its
own interpreter, its own connection to the broker and a copy of each port's descriptor. The
bridge itself is unchanged: the same stop reaches it on the stop lane and the main connection,
and its session decides and writes as before; the express only gets the frame to the wire
first. Both halves live here: ``Express`` in the bridge, ``main`` in the child.

Rules:
1. A process of its own (``python -m bridge.interfaces.mqtt.express``), started by ``Express.start``
   once the main connection is up (as the lane: the broker is known to take the bridge), on a
   thread of its own that then stays to read the child's words (one thread, asleep on a
   socket, awake once a second while the child starts, a word sent to it is unread or a hold
   waits (rules 6 and 8), and woken by each word sent; nothing else wakes it). The
   child imports paho, connection.py, the broker's settings (settings/mqtt.py alone: not the
   package's every table, nor pydantic-settings) and payloads.py (the words of a lock ON),
   nothing of the engine.
2. Its connection is the lane's in all but the client id (``express_client_id``): the same
   broker settings, credentials and TLS (the password handed over the control socket, never
   on the command line), the protocol the main connection settled on, subscribed to the stop
   and lock topics of every rotator, the stop topics of the groups, and its own sync topic
   (rule 8), without the broker's replay of a retained message (lastword.py rule 6). It
   publishes its sync words, nothing else.
3. What it does, and all it does: a message on ``R/stop`` (any payload), a lock ON on
   ``R/lock`` or a message on ``G/stop`` of a group (each member), not a
   replay (under MQTT 3.1.1 a retained flag means "replayed"; the session carries such a
   stop out once, lastword.py rule 6) nor an empty retained message (the deletion of a
   retained one: service.py rule 1), is one ``os.write`` of that rotator's stop frame on its
   copy of the port, at once, if it holds one and may write (rule 8). A tty takes one write
   whole against the serial-lines thread's (one write a frame too, runtime/port.py) unless its
   output buffer is nearly full: then the write takes part of the frame, and the rest is owed
   (rule 9). A tty refuses a write whole while another writer of it is inside its own
   (the serial-lines thread, writing the session's stop that instant): the frame is written as
   soon as the tty takes bytes again, within rule 9's wait. A write that takes nothing for that
   long (a full buffer) or fails (an unplugged adapter) is let go: the session's own stop
   follows. It decides nothing else and changes no state (but for what it alone heard: rule
   11): the session still gets the stop from the lane and the main connection, holds,
   markers and the lock as before, and writes its own stop frame (the controller gets two:
   ModelSpec.stop_anytime says the model takes that). At most one frame a rotator in GAP_S: a
   flood on the stop topic must not fill the port's output buffer (the session's own frames
   would wait behind it, and a full buffer is a lost link, runtime/port.py rule 6); a second
   stop that soon adds nothing the first did not do, and the session's still comes.
4. Only models whose stop frame may go at any moment (``ModelSpec.stop_anytime``) get a copy
   of their port; elsewhere (a SatEL that slews, a SPID that owes replies) the session alone
   writes, as before.
5. Ports (runtime/port.py rule 7): the descriptor of each port opened goes to the express over
   the control socket (SCM_RIGHTS), numbered; before a port is closed the express is told to
   close its copy and says it did, and the closing thread waits for that (DROP_WAIT_S), since a
   copy keeps the tty open and its TIOCEXCL would refuse the reopen (until START_WAIT_S after
   its start while the express has not said a word yet: still starting, not hung). The port
   going is named by its descriptor: a close that runs late, after the rotator's next port was
   handed over (an unplug and replug), leaves that one held (the express closed the old copy
   then). An express that does not answer in time is killed (rule 6) and the port closed all
   the same.
6. Never silent: an express not up within START_WAIT_S of its start (judged once a child: one
   that came up and whose connection then ended waits for its broker, which the main
   connection says; after an outage of over START_WAIT_S it was said at ERROR, and on
   ``B/bridge/info``, as a start that failed: attack 23), one that ends or is killed, one whose
   connection the broker refuses (said until a connection is accepted) or whose subscription it
   denies, one whose client id another client keeps taking over (said until a connection of it
   lasts connection.py's STABLE_S; it backs off TAKEOVER_FIRST_S at most: connection.py rule 7,
   and reconnects otherwise on rule 6's short back-off for a connection that carries stops),
   a frame left half-written (rule 9) and a long hold (rule 8) are said on ``B/bridge/info``
   (``on_problem``); stops then take the stop lane in the bridge's process, as without it. An
   express that ended is started again, RESTART_FIRST_S later, the wait doubling for each end in
   a row up to RESTART_MAX_S (back to the first once one ran for RESTART_STABLE_S); the ports
   open then are handed to it again. A word from it that the bridge cannot read (not JSON, or
   cut at _PACKET) ends that child (killed, said, started again): the reader that died on one
   left every hold unanswered, and no target after a stop went out again, without a word (an
   attack pass; rule 11). So does a word of JSON whose fields are not the ones its ``op`` has
   (one missing, or of another kind): a child is started from the package as it is on disk then,
   so one started again after an upgrade under a running bridge may speak another version's
   words, and the reader died on the first such one as it did on a cut one (a review).
7. Shutdown: ``stop`` closes the control socket; the express closes its copies of the ports
   (a bridge restarted at once finds them free), disconnects and exits on its end of file,
   and is killed after STOP_WAIT_S. It exits too when the bridge's process dies (the
   socket's other end closes with it), and only then: it ignores SIGINT and SIGTERM (a service
   manager or a terminal signals the whole group; the bridge stops its rotators first). From
   the moment the bridge begins to stop (``shutting_down``, before it stops its rotators), an
   express that ends (a service manager's SIGKILL to the group, the out-of-memory killer) is
   said to have ended "as the bridge stops", and is not started again, nor said to be.
8. A late frame never stops a newer move. The express may be descheduled between reading a
   STOP and writing its frame; meanwhile the bridge can carry the same STOP out, read a target
   published just after it and send the move, which the late frame would then stop. So every
   stop or lock ON the bridge carries out from MQTT (halts.py) first puts that rotator's
   targets on a hold of the express's own (session/stops.py rule 5), in the same step, and asks
   the express for a sync word (a number, over the socket). The express publishes a word of
   its own on its sync topic (``B/bridge/fence/express``) and answers the request when it
   reads that word back: the broker had the stop before the word (the bridge had read it
   before asking), so by then the express has read the stop and written its frame or let it
   go; the hold ends with the answer. Nothing is counted: the word orders the two
   connections as the last word's markers do. Each word carries a random mark of its own,
   known to nobody before it is published: a word another client forges from earlier ones
   (it may read the topic) or leaves retained there could otherwise come back before the
   stop and end the hold early; a copy of the real one comes after it. Where it cannot, the
   express writes nothing and answers at once: while its connection is down (a stop it reads later
   comes on a subscription made after the bridge read it: this one will never come), and
   from each connection until a word it published after its last answer given at once came
   back (it says ``up`` then, not at the SUBACK): a broker that drops its words (an ACL) keeps
   it from writing, never holds a target. A connection that ends, an express that dies or is
   not running, answer every request (nothing of it can write any more); no clock ends a
   hold. A word the broker dropped is asked for again (``again``) every RESEND_S while a hold
   waits; the newest WORDS_KEPT words out are kept, older ones forgotten (the newest answers
   every request they answer: a broker that stopped passing them back keeps WORDS_KEPT words
   and their marks, not one a RESEND_S, attack 31; a broker slower than RESEND_S still ends
   the hold with a word it brings back after the next went out), and a hold longer than
   LONG_HOLD_S is said while it lasts, and holds. A stop's
   request is not sent while the last word sent is a request the express has not read yet
   (``_Outbox``: it reads that one after the bridge read this stop, so its answer answers
   both): a flood of stops, carried out on both connections, leaves a request or two unread
   (a resend, or two sent out of order), not one a stop (a few hundred filled the socket
   while the express's reader waited for its core, and a healthy express was killed as
   hung). A socket the express does not
   read (its buffer full, or a word of the bridge's left unread READ_WAIT_S once it has said
   a word; a start is rule 6's, said late and never killed) is a hung express: killed, and
   its end (waited for: nothing of it can write any more) ends the holds, not the clock.
   No send to it ever waits for room (a request, a port handed over or given back): the lock
   they are sent under is the one every MQTT stop's hold takes before the stop is put in.
9. A frame is never left half-written. A write that took part of the frame (or none, refused
   whole while another writer was inside its own: rule 3) is finished by the express as soon as
   the port takes bytes again (it waits for that, for up to FINISH_WAIT_S, after the first write
   of every other rotator's frame of the same stop, a group's: one member's stuck tty holds up
   no other's), so no frame of the session's lands inside it. What a half frame with more bytes
   after it would do (the protocol fact sheets): a GS-232 reads ``S`` then the session's
   ``M180`` as ``SM180``, an unknown command (``?>``), and an Easycomm ``SA S`` then ``AZ180.0``
   as ``SA`` and ``SAZ180.0``: the stop, and the move, lost; a Rotor-EZ's ``;`` is one byte and
   cannot be cut. No leading byte is added to clear the controller's line first: a GS-232
   answers an empty line with ``?>`` (a reply nobody owes: rule 4's reason), and a leading
   terminator would also carry out a session frame a full buffer had cut short before it (a
   GS-232's ``M18`` of ``M180``: a move). A frame still unfinished after FINISH_WAIT_S (the line
   is stuck: the session finds its port lost, runtime/port.py rule 6) is said (rule 6) until
   that rotator's next whole frame. Such a rotator's tty (a frame of it unfinished, or not
   begun, after the whole wait) is stuck: a later frame it refuses whole is let go at once, not
   waited for, until it takes bytes again or a new port is handed over, or the one thread that
   writes every rotator's frame would spend that wait again at each of its stops, with another
   rotator's stop behind it.
10. Ahead of busy programs: the express raises its own process EXPRESS_RAISE nice steps above
   the priority it was started with, first thing (its threads inherit it), where the system
   lets it: as root, with CAP_SYS_NICE, or under a nice limit that allows it (the systemd
   unit's ``LimitNICE=-10``); elsewhere it runs at the bridge's priority, said at debug. On a
   host whose cores a broker, a backlog's reader or another program keep busy, its frame then
   waits for no one of them. It holds no lock a thread of the bridge waits for, so no stop
   carried in the bridge waits behind it for that; what it does is bounded by what it reads
   (rule 3: a frame per stop or lock ON, per rotator). The bridge's own threads keep its
   priority (but a TCP port's accept thread, fewer steps above it: tcplines.py rule 10): a
   stop read by any of them (rotctld's, a logger's, the console's) is carried
   under the interpreter lock, and a lowered thread holding that lock while the kernel runs
   another program would keep such a stop waiting (docs/architecture.md).
11. A stop only the express heard is the bridge's too. Each frame it writes it says (``wrote``,
   with the time it wrote it, the machine's monotonic clock, its own as the bridge's), and
   when neither of the bridge's connections has had its command topics without a break since
   before the broker took that stop (a broker restart the express came back from first, a
   connection between its drop and its SUBACK: clean starts, so no copy of that stop will ever
   come to them), and neither read a halt of that rotator and has had them since (interfaces/mqtt/
   halts.py ``read_since``: it had the stop, or its halt is the later; an attack pass: a
   second after a broker restart the margin took a STOP both had read for one only the
   express heard, and its second stop dropped the target sent after the STOP), the
   rotator is given a stop (``on_wrote``): the target it holds waiting, a track under way,
   never overtake the STOP the controller had (an attack pass: a Rotor-EZ stopped by the
   express sent the target it held at the brake window's end). "Before the broker took it"
   is an order, not a time (docs/architecture.md rule 15): each connection's SUBACK asks the
   express for a sync word (``vouch``), and a stop it says after that word's answer reached
   the broker after the word, so after the subscription; one said before the answer may have
   come before it, and is carried out here too (twice at worst: the safe side). Judged by
   the time the express read it less a second, an express held up longer than that (a busy
   host) read a stop published before the SUBACKs after them, and the held target went out
   after the STOP (review 102). A frame for a lock ON is such
   a stop too, and the lock ON itself the express says (``locked``, with the time it read it
   and who sent it, a frame written or not): one neither connection could have had, by the
   same test, is set (``on_locked``): the lock is what a user turns on before climbing the
   tower, and a rotator stopped but not locked took the next target from any front end. The
   express reads every rotator's lock topic for this, also of those it writes no frame for (a
   SPID, a SatEL, an RC2800, a rotator of two boxes: each locked as the others; a bridge with
   none it writes for runs no express, and has no such relay). Their stops too, and a group's
   stop for every member: a stop it writes no whole frame for (no frame of that model, its
   port not held, the frame not taken whole: rule 9) it says (``heard``, with the time it
   read it; once
   in GAP_S a rotator), and the same test gives the rotator its stop (an attack pass: after
   a broker restart the express came back first, and a ``G/stop`` stopped the group's
   Rotor-EZ while its SPID turned on to the group's target). A
   lock ON a connection heard too, just after its SUBACK (before the express answered for
   it), is set twice, and a lock OFF carried out between the two is undone: the safe side,
   said in docs/mqtt.md. Who sent it is named in these words only as an operator's name
   (core/model.py ``operator_name``, what the bridge takes of it anyway), never as the user
   property came: a STOP whose ``operator`` held 21,845 non-ASCII characters (the 64 KiB an
   MQTT string may hold) made a word of 131 KB that the bridge read cut at 64 KiB, its reader
   died on the JSON, and no target after a stop went out again (an attack pass). Its name
   is judged after the frame is written, but before a group's next member's frame: a
   property too long to be a name is none at once (a cold review: 64 KiB of a ligature
   NFKC makes 18 characters were normalized whole, some 24 ms before each next member).
   A stop or lock ON read on a connection before its word came back (rule 8: no frame then)
   is said too, ``early`` (``_early``): a CI run of review 88's proxy restart published its
   STOP just after the express, back first, had subscribed, a round trip before its word
   came back; the express dropped it unsaid, the bridge's connections subscribed a few
   milliseconds after it, and the rotor turned on to its target. An early word is judged by
   the halts the bridge's connections read (``read_since``) alone, not by the vouches: a
   vouch answered at once while the express was subscribed and not yet writing (rule 8)
   says nothing of a stop it reads later, which may have been published before that
   connection's SUBSCRIBE. A stop both had is then carried out twice at worst (the safe
   side, as above). Only the main connection and the lane of the word's kind answer for it
   (``read_since``): the lock lane never reads a STOP (review 108: a lock ON it read once,
   since turned OFF, had let a STOP only the express read be dropped). A move or a lock OFF
   read since does not order an early word (review 114: a move the session refused after
   taking it, a lock OFF refused as stale, or one read on a path that had died unseen, let
   a STOP or lock ON only the express read be dropped); review 108's price, open: an early
   STOP read late may stop a target published after it, an early lock ON relock after a
   newer OFF (the safe side).
"""

from __future__ import annotations

import array
import fcntl
import hashlib
import json
import logging
import math
import os
import secrets
import select
import signal
import socket
import subprocess
import sys
import termios
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from paho.mqtt.reasoncodes import ReasonCode

from bridge.core.afterlock import later
from bridge.core.model import operator_name
from bridge.interfaces.fdwait import writable
from bridge.interfaces.mqtt.connection import (
    STABLE_S,
    STOP_KEEPALIVE_S,
    STOP_RECONNECT_MAX_S,
    TAKEOVER_FIRST_S,
    Connection,
    Ending,
    takeover_message,
)
from bridge.interfaces.mqtt.heartbeat import Stamp
from bridge.interfaces.mqtt.paho_client import Waker
from bridge.interfaces.mqtt.payloads import PayloadError, parse_switch
from bridge.settings.mqtt import MqttSettings

log = logging.getLogger(__name__)

START_WAIT_S = 10.0  # rule 6: said when the express is not up by then
EXPRESS_RAISE = 10  # rule 10: nice steps above the bridge, where the system allows it
DROP_WAIT_S = 1.0  # rule 5
STOP_WAIT_S = 2.0  # rule 7
GAP_S = 0.1  # rule 3: one stop frame a rotator in this long, at most
RESTART_FIRST_S = 1.0  # rule 6: the first wait before an express that ended is started again
RESTART_MAX_S = 60.0  # ... doubling up to this
RESTART_STABLE_S = 60.0  # ... back to the first once one ran this long
RESEND_S = 2.0  # rule 8: a sync word asked for again while a hold waits this long
WORD_DIGITS = 20  # rule 8: a sync word's number, at most (a longer one is none of its own)
LONG_HOLD_S = 5.0  # rule 8: a hold this long is said
#: rule 8: sync words kept out at most while a hold waits (asked again each RESEND_S: a broker
#: up to this many RESEND_S slow still ends the hold with the word it brings back)
WORDS_KEPT = 8
TICK_S = 1.0  # rule 1: the reader looks at the start and the holds this often
READ_WAIT_S = 2.0  # rule 8: a word of the bridge's left unread this long: a hung express
FINISH_WAIT_S = 0.5  # rule 9: the rest of a frame a write cut short, written within this
REFUSED_RETRY_S = 0.0002  # rule 9: the pause before a write refused whole is tried again
_PACKET = 65536


def express_client_id(settings: MqttSettings) -> str:
    """Rule 2: the lane's rule (lane.py rule 2) with its own mark."""
    main = settings.effective_client_id()
    if settings.client_id is None and main.startswith("rotor-"):
        return "rfast-" + main[len("rotor-") :]
    mine = main + "-fast"
    if len(mine) <= 23:
        return mine
    digest = hashlib.sha256(main.encode()).hexdigest()[:6]
    return f"{main[:11]}-{digest}-fast"


def _send(
    sock: socket.socket, word: dict[str, Any], fds: list[int] | None = None, flags: int = 0
) -> None:
    data = json.dumps(word).encode()
    if fds:  # (not socket.send_fds: Python 3.11's drops its flags, MSG_DONTWAIT with them)
        rights = array.array("i", fds).tobytes()
        sock.sendmsg([data], [(socket.SOL_SOCKET, socket.SCM_RIGHTS, rights)], flags)
    else:
        sock.send(data, flags)


def _unread(sock: socket.socket) -> bool:
    """Whether the other end has not yet read every word this end sent (SIOCOUTQ: a datagram
    sent counts until its reader takes it); False where it cannot say."""
    try:
        answer = fcntl.ioctl(sock.fileno(), termios.TIOCOUTQ, b"\0\0\0\0")
    except (OSError, ValueError):
        return False
    return int.from_bytes(answer, sys.byteorder, signed=True) > 0


# -- the bridge's side ---------------------------------------------------------------------------
def _no_call() -> None:
    """``_Outbox``'s ``sent`` where nothing waits for its sends (a test's)."""


class _Outbox:
    """Rule 8: every word to one child, sent under one lock, so the request a stop would send
    is left out while the last word sent is a request the child has not read yet (that one is
    read after this stop was, and its answer answers this stop's too): however fast stops
    come, the socket holds one request unread at most. None of it waits for room.

    Only a request numbered above every one sent before it stands for later ones: the child
    answers the newest number it has read (Sync), so an answer that reaches m then proves it
    read m. (Two threads carry stops out, and their requests may go in either order.)"""

    def __init__(
        self, sock: socket.socket, clock: Callable[[], float], sent: Callable[[], None] = _no_call
    ) -> None:
        self.sock = sock
        self._clock = clock
        self._sent = sent  # (rule 1: wakes the reader, asleep while nothing waits)
        self._lock = threading.Lock()
        self._last: int | None = None  # the last word sent, when it was sync request n
        self._top = 0  # the highest request sent
        self._sent_at = clock()  # when the last word was sent
        self._cover: tuple[int, int] | None = None  # (m, n): the answer to m answers n too

    def send(self, word: dict[str, Any], fds: list[int] | None = None) -> None:
        """Raises BlockingIOError when the socket is full, OSError when the child is gone."""
        with self._lock:
            _send(self.sock, word, fds, socket.MSG_DONTWAIT)
            self._last, self._sent_at = None, self._clock()
        self._sent()

    def ask(self, n: int, again: bool) -> None:
        """Request ``n`` (its stop already read by the bridge), or left out; as ``send``."""
        with self._lock:
            m = self._last
            if not again and m is not None and _unread(self.sock):
                # FIFO: the last word sent is one not read yet; the child reads m after this
                # stop was read, and answers m with a word it publishes after that (Sync)
                a, b = self._cover or (m, n)
                self._cover = (max(a, m), max(b, m, n))  # (merged: a later answer, never less)
            else:
                _send(self.sock, {"op": "sync", "n": n, "again": again}, flags=socket.MSG_DONTWAIT)
                self._last = n if n > self._top else None
                self._top, self._sent_at = max(self._top, n), self._clock()
        self._sent()  # (left out too, its hold looked at: review 154, a hold put inside the
        # reader's verdict, its word left out for one the child read meanwhile, slept for good)

    def answer(self, n: int) -> int:
        """The child answered request ``n``: the newest request that answers."""
        with self._lock:
            cover = self._cover
            if cover is None or n < cover[0]:
                return n
            self._cover = None
            return max(n, cover[1])

    def unread_for(self) -> float:
        """How long the last word sent has been waiting unread (0: every word read): the
        child has read nothing for that long."""
        with self._lock:
            return self._clock() - self._sent_at if _unread(self.sock) else 0.0


class Express:
    """The child process, seen from the bridge: its ports (rule 5), its start and restarts,
    its problems (rule 6), its holds (rule 8)."""

    def __init__(
        self,
        settings: MqttSettings,
        *,
        topics: dict[str, tuple[str, str]],
        frames: dict[str, bytes],
        on_problem: Callable[[str, bool], None],
        command: list[str] | None = None,
        groups: dict[str, tuple[str, ...]] | None = None,
        sync_topic: str | None = None,
        on_hold: Callable[[str, int], None] | None = None,
        on_release: Callable[[str, int, bool], None] | None = None,
        on_wrote: Callable[[str, float, str | None, bool], None] | None = None,
        on_locked: Callable[[str, float, str | None, bool], None] | None = None,
    ) -> None:
        """``topics``: each stop and lock topic -> (rotator id, "stop" or "lock"): the stops of
        the rotators in ``frames``, the locks of any (rule 11 says each); ``frames``:
        each rotator of a model with ``stop_anytime`` -> its stop frame (rule 4); ``groups``:
        each group's stop topic -> its members; ``sync_topic``: rule 8's (without it the
        express never writes); ``on_hold``, ``on_release``: a rotator's hold put, ended;
        ``on_wrote``: a rotator's stop frame written, or its stop read, at that time, from
        that operator; ``on_locked``: its lock ON read, at that time, from that operator; each
        ``early`` when read before the express's connection could order it against the
        bridge's connections' subscriptions (rule 11)."""
        self._settings = settings
        self.client_id = express_client_id(settings)
        self._topics = dict(topics)
        self._groups = {t: list(members) for t, members in (groups or {}).items() if members}
        self._frames = frames
        self._sync_topic = sync_topic
        self._on_problem = on_problem
        self._on_hold = on_hold
        self._on_release = on_release
        self._on_wrote = on_wrote
        self._on_locked = on_locked
        self._command = command or [sys.executable, "-m", "bridge.interfaces.mqtt.express"]
        self._lock = threading.Lock()  # the ports, the socket, the child, the holds
        self._ports: dict[str, tuple[int, int]] = {}  # rotator id -> (number, fd), while open
        self._number = 0
        self._dropped: dict[int, threading.Event] = {}
        self._sock: _Outbox | None = None
        self._child: subprocess.Popen[bytes] | None = None
        self._killed: subprocess.Popen[bytes] | None = None  # the child _kill killed
        self._started = False
        self._stopping = False
        self._ending = False  # rule 7: the bridge stops (shutting_down): no restart
        self._wake = threading.Event()  # stop(), shutting_down(): no restart, no wait for one
        self.runner: threading.Thread | None = None  # the thread that starts the children
        self._said: set[str] = set()
        self._sync = 0  # rule 8: the newest sync word asked for
        self._holds: dict[str, int] = {}  # rotator -> the sync word its hold waits for
        self._held_since: dict[str, float] = {}  # ... since when (rule 8: resent, said)
        # rule 11: a bridge connection's subscription (its ``since``) waiting for a sync word,
        # and the newest one each connection had vouched for by an answer
        self._vouching: dict[int, tuple[str, float]] = {}
        self._vouched: dict[str, float] = {}
        self._asked_at = 0.0  # when a sync word was last asked for again
        self.clock: Callable[[], float] = time.monotonic
        self.up = threading.Event()  # its connection subscribed (the tests wait for it)
        self.held: set[str] = set()  # the rotators whose port it holds (said by the child)
        self.held_changed = threading.Event()  # set on every change of ``held`` (the tests)
        # (rotator, the child's clock) of the latest frames written (the tests, the log)
        self.wrote: deque[tuple[str, float]] = deque(maxlen=64)
        self.ended = threading.Event()  # the child is gone (rule 6), until the next starts
        self.starts = 0  # children started (rule 6: the restarts)
        self._heard = threading.Event()  # a word from the child: it reads its socket (rule 5)
        self._started_at = 0.0  # when the child was started (its START_WAIT_S, rule 5)

    @property
    def wanted(self) -> bool:
        """Whether any rotator's model lets the express write its stop (rule 4)."""
        return bool(self._frames)

    def watch(self, rotator_id: str) -> _PortWatch | None:
        """What the rotator's worker tells of its ports (runtime/port.py rule 7), where rule 4
        lets the express write."""
        return _PortWatch(self, rotator_id) if rotator_id in self._frames else None

    def start(self, mqtt311: bool) -> None:
        """Rule 1: once, never after ``stop``; the child is started off the caller's thread."""
        with self._lock:
            if self._started or self._stopping or self._ending or not self._frames:
                return
            self._started = True
        self.runner = threading.Thread(
            target=self._run, args=(mqtt311,), name="stop express", daemon=True
        )
        self.runner.start()

    def shutting_down(self) -> None:
        """Rule 7: the bridge begins to stop; the child runs on until ``stop``, but one that
        ends meanwhile is not started again."""
        with self._lock:
            self._ending = True
        self._wake.set()

    def stop(self) -> None:
        """Rule 7."""
        with self._lock:
            self._stopping = True
            sock, child = self._sock, self._child
        self._wake.set()
        if sock is not None:
            try:
                sock.sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if child is not None:
            try:
                child.wait(STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()

    # -- rule 8: the holds (on the thread that carries a stop out, under the last word's lock)
    def hold(self, rotator_id: str) -> None:
        """A stop or lock ON of ``rotator_id`` is being carried out: while an express runs that
        may write its frame, the rotator's targets wait for the answer to a new sync word."""
        if rotator_id not in self._frames or self._on_hold is None:
            return
        with self._lock:
            if self._sock is None:
                return  # no express: nothing of one can write
            self._sync += 1
            n = self._sync
            self._holds[rotator_id] = n
            self._held_since.setdefault(rotator_id, self.clock())
            self._on_hold(rotator_id, n)  # before the stop's put (halts.py)
        later(partial(self._ask, n))  # a system call: once the last word's lock is let go

    # -- rule 11: which subscriptions of the bridge's a stop the express reads came after
    def vouch(self, via: str, since: float) -> None:
        """The bridge's connection ``via`` ("main" or "lane") has had its command topics since
        ``since`` (its SUBACK, on its paho thread): a sync word is asked for, and once it is
        answered every stop the express says after the answer reached the broker after that
        subscription, so reaches that connection too (``vouched``)."""
        with self._lock:
            if self._sock is None:  # no express: one started later subscribes after this
                self._vouched[via] = since
                return
            self._sync += 1
            n = self._sync
            self._vouching[n] = (via, since)
        later(partial(self._ask, n))

    def vouched(self, via: str) -> float | None:
        """Rule 11: the ``since`` of ``via``'s newest subscription the express answered for (on
        the reader's thread, in the order of the express's words), or None."""
        with self._lock:
            return self._vouched.get(via)

    def _vouch_up_to(self, n: int) -> None:
        """Under the lock: the subscriptions waiting for sync words up to ``n`` are vouched for
        (an answer given at once, or by the express's end, too: whatever it reads later comes
        on a subscription of its own made after it)."""
        for m in [m for m in self._vouching if m <= n]:
            via, since = self._vouching.pop(m)
            self._vouched[via] = since

    def _ask(self, n: int, again: bool = False) -> None:
        """Rule 8: sync word ``n`` asked for (or answered with one not read yet); a socket the
        express does not read is a hang."""
        with self._lock:
            sock = self._sock
        if sock is None:
            return  # gone: its end answered every hold
        try:
            sock.ask(n, again)
        except BlockingIOError:
            self._kill("does not read its socket")
        except OSError:
            pass  # gone: its end answers every hold

    def _answered(self, n: int, lost: bool = False) -> None:
        """Rule 8: the holds up to sync word ``n`` end (and those it answers, _Outbox); ``lost``:
        by the express's connection's end, not its word."""
        with self._lock:
            sock = self._sock
        if sock is not None:  # (its lock apart: a send under it must not hold up a hold)
            n = sock.answer(n)
        with self._lock:
            self._vouch_up_to(n)
            done = [rid for rid, m in self._holds.items() if m <= n]
            for rid in done:
                del self._holds[rid]
                self._held_since.pop(rid, None)
                if self._on_release is not None:
                    self._on_release(rid, n, lost)

    def _gone(self) -> None:
        """Under the lock: the child is gone; every hold ends (nothing of it writes)."""
        self._sock = None
        self._vouch_up_to(self._sync)
        for rid in list(self._holds):
            if self._on_release is not None:
                self._on_release(rid, self._sync, True)
        self._holds.clear()
        self._held_since.clear()

    def _long_hold(self) -> str:
        return (
            "stop express: it has not yet answered for a stop carried out more than "
            f"{LONG_HOLD_S:g} s ago, and that rotator's targets wait until it does (its "
            "connection to the broker slow, or the broker dropping its sync words on "
            f"{self._sync_topic}: check the broker's ACL for client id {self.client_id!r}); "
            "stops and locks go through"
        )

    def _tick(self, came_up: bool, late: str) -> bool:
        """On the reader's thread, once a second while the child starts, a word sent to it is
        unread or a hold waits (rule 1), and at each word sent: whether any of them is so."""
        if not came_up and time.monotonic() - self._started_at >= START_WAIT_S:
            self._problem(late, True)
        with self._lock:
            sock = self._sock
        unread_s = sock.unread_for() if sock is not None else 0.0
        if unread_s >= READ_WAIT_S and self._heard.is_set():  # rule 8 (a start is rule 6's:
            # however long, said as late, never killed: importing Python on a slow host is no hang)
            self._kill(f"does not read its socket (a word unread for {unread_s:.1f} s)")
        now = self.clock()
        with self._lock:
            oldest = min(self._held_since.values(), default=None)
            newest = self._sync
        if oldest is None:
            self._problem(self._long_hold(), False)
            return not came_up or (sock is not None and _unread(sock.sock))
        if now - oldest >= RESEND_S and now - self._asked_at >= RESEND_S:
            self._asked_at = now
            self._ask(newest, again=True)
        if now - oldest >= LONG_HOLD_S:
            self._problem(self._long_hold(), True)
        return True

    # -- the ports (runtime/port.py rule 7, on the ports' open and close threads) ---------------
    def opened(self, rotator_id: str, fd: int) -> None:
        with self._lock:
            self._number += 1
            self._ports[rotator_id] = (self._number, fd)
            hung = self._sock is not None and not self._hand(rotator_id, self._number, fd)
        if hung:
            self._kill("does not read its socket")

    def closing(self, rotator_id: str, fd: int) -> None:
        with self._lock:
            number, held = self._ports.get(rotator_id, (0, -1))
            if held != fd:
                return  # a newer port's (its close ran late): the express dropped this copy
            del self._ports[rotator_id]
            if self._sock is None or self.ended.is_set():
                return
            dropped = self._dropped[number] = threading.Event()
            try:
                word = {"op": "drop", "rotator": rotator_id, "n": number}
                self._sock.send(word)  # (rule 8: no wait under the lock every MQTT stop takes)
                sent = True
            except BlockingIOError:
                sent = False
            except OSError:
                return  # gone: its copies are closed with it
        if not sent:
            self._kill(f"does not read its socket ({rotator_id}'s port going)")
            dropped.wait(STOP_WAIT_S)  # its end: _run sets it once the child is gone
            with self._lock:
                self._dropped.pop(number, None)
            return
        # not reading its socket yet is a start (importing Python on a slow machine), no hang
        wait_s = DROP_WAIT_S
        if not self._heard.is_set():
            with self._lock:
                ending = self._ending
            if ending:  # rule 7: its end closes its copies (``stop``), soon, and no reopen comes
                with self._lock:  # (a shutdown on a busy machine waited up to START_WAIT_S
                    self._dropped.pop(number, None)  # for a child still starting, and said
                return  # the port "still closing after 3 s (a wedged adapter?)")
            wait_s = max(wait_s, self._started_at + START_WAIT_S - time.monotonic())
        if not dropped.wait(wait_s):
            self._kill(f"did not give {rotator_id}'s port back within {wait_s:.1f} s")
        with self._lock:
            self._dropped.pop(number, None)

    def _hand(self, rotator_id: str, number: int, fd: int) -> bool:
        """Under the lock: a copy of the port to the child (rule 5). Never waits (the lock is
        every MQTT stop's, rule 8): False when its socket is full (a hung express: the caller
        kills it once the lock is let go)."""
        assert self._sock is not None
        word = {"op": "port", "rotator": rotator_id, "n": number}
        try:
            self._sock.send(word, [fd])
        except BlockingIOError:
            return False
        except OSError as exc:
            log.warning("stop express: could not hand over %s's port: %s", rotator_id, exc)
        return True

    # -- the child (rules 1 and 6, on the express's thread) ------------------------------------
    def _run(self, mqtt311: bool) -> None:
        """Rule 6: a child, and another after it ends, until ``stop``."""
        wait_s = RESTART_FIRST_S
        while True:
            t0 = time.monotonic()
            why = self._life(mqtt311)
            if why is None:  # stopping
                self.ended.set()
                return
            with self._lock:
                ending = self._ending
            if ending:  # rule 7: nothing is started again while the bridge stops
                self._ended(f"{why} as the bridge stops")
                return
            if time.monotonic() - t0 >= RESTART_STABLE_S:
                wait_s = RESTART_FIRST_S
            self._ended(f"{why}: started again in {wait_s:g} s")
            if self._wake.wait(wait_s):
                return
            wait_s = min(2 * wait_s, RESTART_MAX_S)

    def _life(self, mqtt311: bool) -> str | None:
        """One child, from its start to its end: why it ended (None: ``stop``)."""
        t0 = self._started_at = time.monotonic()
        self._heard.clear()
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        env = dict(os.environ)
        root = str(Path(__file__).resolve().parents[2])  # the bridge's own code, whatever runs it
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
        with self._lock:
            if self._stopping:
                mine.close()
                theirs.close()
                return None
        try:
            child = subprocess.Popen(
                [*self._command, str(theirs.fileno())],
                pass_fds=[theirs.fileno()],
                stdin=subprocess.DEVNULL,
                env=env,
                close_fds=True,
            )
        except OSError as exc:
            theirs.close()
            mine.close()
            return f"the stop express could not start: {exc}"
        theirs.close()
        self.starts += 1
        s = self._settings
        secret = s.password.get_secret_value() if s.password is not None else None
        config = {
            "op": "config",
            "mqtt": {**s.model_dump(mode="json"), "password": secret, "password_file": None},
            "client_id": self.client_id,
            "mqtt311": mqtt311,
            "topics": self._topics,
            "groups": self._groups,
            "sync_topic": self._sync_topic,
            "frames": {rid: frame.hex() for rid, frame in self._frames.items()},
            "log_level": logging.getLogger("bridge").getEffectiveLevel(),
        }
        waker = Waker()  # rule 1: a word sent wakes the reader (its own thread's close)
        with self._lock:
            self._child = child
            if self._stopping:
                mine.close()
                waker.close()
                child.kill()
                child.wait()
                return None
            self._sock = _Outbox(mine, lambda: self.clock(), waker.wake)
            try:
                self._sock.send(config)
            except OSError:
                pass  # it died at once: read below as an end of file
            self.ended.clear()
            hung = not all(self._hand(rid, n, fd) for rid, (n, fd) in self._ports.items())
        if hung:
            self._kill("does not read its socket")
        late = f"the stop express did not come up within {START_WAIT_S:g} s"
        passing: set[str] = set()  # problems said until it is up (rule 6)
        came_up = False  # rule 6: its start is judged once, a child
        ticked = time.monotonic()
        waits = True  # rule 1: something for the tick to look at (the start, a word, a hold)
        poller = select.poll()  # (not select.select: a bridge with many clients has fds > 1023)
        poller.register(mine, select.POLLIN)
        poller.register(waker.fileno(), select.POLLIN)
        while True:
            # (a hold put meanwhile: rule 8's tick) The socket stays blocking: a timeout on it
            # would make every send to it wait for room (MSG_DONTWAIT only fails at once on a
            # blocking socket), the stops' sends among them.
            try:
                events = poller.poll(TICK_S * 1000 if waits else None)
                woken = any(fd == waker.fileno() for fd, _ in events)
                if woken:
                    waker.drain()  # a word sent: its reading is looked at from now on
                readable = any(fd != waker.fileno() for fd, _ in events)
                if woken or not events or time.monotonic() - ticked >= TICK_S:
                    ticked = time.monotonic()  # (due even while its words keep coming)
                    waits = self._tick(came_up, late)
                if not readable:
                    continue
                data = mine.recv(_PACKET)
            except (OSError, ValueError):
                data = b""
            if not data:
                break
            self._heard.set()
            try:  # rule 6: a word it cannot read ends this child, said, never this reader
                word = json.loads(data)
                op = word.get("op")
                if op == "up":
                    ended = [t for t in self._said if t.startswith("the stop express ")]
                    for text in (late, *passing, *ended):
                        self._problem(text, False)
                    passing.clear()
                    if came_up:  # (the time since its start would count the broker's absence)
                        log.info(
                            "stop express up again as %s (its connection back)", self.client_id
                        )
                    else:
                        log.info(
                            "stop express up as %s (pid %d, %.2f s)",
                            self.client_id,
                            child.pid,
                            time.monotonic() - t0,
                        )
                    came_up = True
                    self.up.set()
                elif op == "down":  # its connection ended: up again when it is back (rule 8);
                    self.up.clear()  # no start to judge (rule 6): its broker went away
                elif op == "synced":
                    self._answered(word["n"], bool(word.get("lost")))
                elif op == "held":
                    self._held(word["rotator"], True)
                elif op == "dropped":
                    self._held(word["rotator"], False)
                    with self._lock:
                        event = self._dropped.get(word["n"])
                    if event is not None:
                        event.set()
                elif op == "wrote":
                    self.wrote.append((word["rotator"], word["t"]))
                    self._problem(self._half(word["rotator"]), False)
                    log.debug("stop express: %s's stop frame written", word["rotator"])
                    self._carry_alone(
                        "a stop it wrote",
                        self._on_wrote,
                        word["rotator"],
                        word["t"],
                        word.get("operator"),
                        False,
                    )
                elif op == "heard":
                    log.debug("stop express: %s's stop read, no frame written", word["rotator"])
                    self._carry_alone(
                        "a stop it heard",
                        self._on_wrote,
                        word["rotator"],
                        word["t"],
                        word.get("operator"),
                        word.get("early") is True,
                    )
                elif op == "locked":
                    log.debug("stop express: %s's lock ON read", word["rotator"])
                    self._carry_alone(
                        "a lock ON it read",
                        self._on_locked,
                        word["rotator"],
                        word["t"],
                        word["operator"],
                        word.get("early") is True,
                    )
                elif op == "half":
                    self._problem(self._half(word["rotator"]), True)
                elif op == "problem":
                    text = f"stop express: {word['text']}"
                    self._problem(text, not word.get("off"))
                    if word.get("until_up"):  # a connection refused: said until one is accepted
                        passing.add(text)
            except (ValueError, AttributeError, KeyError, TypeError):
                self._kill("said a word the bridge cannot read")
                break
        try:
            code = child.wait(STOP_WAIT_S)
        except subprocess.TimeoutExpired:
            child.kill()
            code = child.wait()
        with self._lock:
            stopping = self._stopping
            self._gone()
            waiting_drops = list(self._dropped.values())
        for event in waiting_drops:  # its copies of the ports went with it
            event.set()
        mine.close()
        waker.close()  # (a send after ``_gone`` on an outbox held meanwhile wakes nothing)
        self.up.clear()
        self.held.clear()
        self._problem(self._long_hold(), False)
        for text in (late, *passing):
            self._problem(text, False)
        return None if stopping else f"the stop express ended (exit code {code})"

    def _half(self, rotator_id: str) -> str:
        return (
            f"stop express: {rotator_id}'s stop frame is half-written: the port took no more "
            f"bytes for {FINISH_WAIT_S:g} s (a stuck line, an adapter gone?)"
        )

    @staticmethod
    def _carry_alone(what: str, carry: Callable[..., None] | None, *args: Any) -> None:
        """Rule 11: what the express heard, handed to the bridge to carry out if only it did
        (a bug there must not end the express's reader)."""
        if carry is None:
            return
        try:
            carry(*args)
        except Exception:
            log.exception("stop express: %s not carried out", what)

    def _held(self, rotator_id: str, held: bool) -> None:
        if held:
            self.held.add(rotator_id)
        else:
            self.held.discard(rotator_id)
        self.held_changed.set()

    def _kill(self, why: str) -> None:
        """Once per child: every stop of a flood that finds its socket full until it has died
        comes here, and the log says it once."""
        with self._lock:
            child = self._child
            if child is None or child is self._killed:
                return
            self._killed = child
        log.error("stop express %s: killed", why)
        child.kill()  # its copies of the ports close with it; _run says it ended

    def _ended(self, why: str) -> None:
        """Rule 6: said until the next child is up."""
        self.ended.set()
        for event in list(self._dropped.values()):
            event.set()
        text = f"{why}; meanwhile stops take the stop lane in the bridge's process"
        for said in [t for t in self._said if t.startswith("the stop express ")]:
            self._problem(said, False)
        self._problem(text, True)

    def _problem(self, text: str, on: bool) -> None:
        if on == (text in self._said):
            return
        if on:
            self._said.add(text)
            log.error("%s", text)
        else:
            self._said.discard(text)
        try:
            self._on_problem(text, on)
        except Exception:
            log.exception("error reporting a problem of the stop express")


class _PortWatch:
    """One rotator's ports, told to the express (runtime/port.py PortWatch)."""

    def __init__(self, express: Express, rotator_id: str) -> None:
        self._express = express
        self._id = rotator_id

    def opened(self, fd: int) -> None:
        self._express.opened(self._id, fd)

    def closing(self, fd: int) -> None:
        self._express.closing(self._id, fd)


# -- the child's side ----------------------------------------------------------------------------
@dataclass
class Sync:
    """Rule 8 in the express, pure: the bridge's requests and its own words read back in,
    the words to publish and the answers out. Its caller holds one lock around each call."""

    linked: bool = False  # a connection accepted, not yet ended (its subscription may come)
    writing: bool = False  # a word published after the last answer given at once came back
    _word: int = 0  # words published so far
    _clean_from: int = 0  # only a word numbered above this lets it write
    _out: dict[int, int] = field(default_factory=dict)  # word out -> the newest request it answers
    _asked: int = 0  # the newest request
    _answered: int = 0  # the newest request answered

    def asked(self, n: int, again: bool = False) -> tuple[int | None, int | None]:
        """Request ``n``: (the answer to give now, the word to publish now), each or None."""
        self._asked = max(self._asked, n)
        if not self.linked or not self.writing:
            # it writes nothing now, and nothing older later: only a word published after
            # this answer lets it write again (those out now answer nothing more: forgotten,
            # or a broker that drops them would have them pile up, one a stop)
            self._clean_from = self._word
            self._out.clear()
            return self._answer_all(), self._publish() if self.linked else None
        if again or not self._out:  # a word out now was published before the request
            # the new word answers every request the words out answer, and more; the oldest
            # beyond WORDS_KEPT are forgotten (a broker that stopped passing its words back
            # would otherwise have one kept each RESEND_S for as long as the hold waits), but
            # not all of them: a broker slower than RESEND_S brings each word back after the
            # next is out, and the hold must still end then
            for k in sorted(self._out)[: max(0, len(self._out) - WORDS_KEPT + 1)]:
                del self._out[k]
            return None, self._publish()
        return None, None

    def read_back(self, w: int) -> tuple[int | None, int | None]:
        """Its word ``w`` came back: (the answer to give, the next word to publish)."""
        if w not in self._out:
            return None, None  # an earlier connection's, or answered already
        upto = self._out[w]
        for k in [k for k in self._out if k <= w]:
            del self._out[k]
        if w > self._clean_from:
            self.writing = True
        answer = None
        if upto > self._answered:
            self._answered = answer = upto
        word = self._publish() if self._asked > self._answered and not self._out else None
        return answer, word

    def accepted(self) -> None:
        """A connection accepted (before it subscribes): its words are still to come."""
        self.linked, self.writing = True, False
        self._clean_from = self._word
        self._out.clear()

    def subscribed(self) -> int:
        """Its subscriptions are acknowledged: the first word to publish (rule 8's ``up``)."""
        return self._publish()

    def ended(self) -> int | None:
        """The connection ended: the answer to every request (nothing more comes on it)."""
        self.linked = self.writing = False
        self._out.clear()
        return self._answer_all()

    def _answer_all(self) -> int | None:
        if self._asked <= self._answered:
            return None
        self._answered = self._asked
        return self._answered

    def is_out(self, w: int) -> bool:
        """Word ``w`` is out and kept (its mark is kept with it)."""
        return w in self._out

    def _publish(self) -> int:
        self._word += 1
        self._out[self._word] = self._asked
        return self._word


class _Link(Connection):
    """The express's connection (rule 2): the lane's hooks, its words to the bridge."""

    FIGHT_BACKOFF_MAX_S = TAKEOVER_FIRST_S  # rule 6: it carries stops (connection.py rule 7)
    RECONNECT_MAX_S = STOP_RECONNECT_MAX_S  # connection.py rule 6: back soon after a broker
    KEEPALIVE_MAX_S = STOP_KEEPALIVE_S  # connection.py rule 6: a dead path found soon

    def __init__(
        self,
        settings: MqttSettings,
        client_id: str,
        say: Callable[..., None],
        on_link: Callable[[bool], None],
        **kw: Any,
    ):
        super().__init__(settings, client_id, **kw)
        self._auto = False  # the main connection settled the protocol (rule 2)
        self._say = say
        self._on_link = on_link
        self._fight: str | None = None  # rule 6: a takeover fight said, until a connection lasts

    def publish(self, topic: str, payload: str) -> None:
        self._client.publish(topic, payload, qos=0)

    def _refused(self, reason: str) -> None:
        self._say(
            op="problem", text=f"the MQTT broker refused its connection: {reason}", until_up=True
        )

    def _failed(self) -> None:
        pass  # the main connection says why the broker cannot be reached

    def _accepted(self) -> None:
        self._on_link(True)  # before it subscribes (rule 8)

    def _denied(self, topic: str, reason: str) -> None:
        self._say(
            op="problem", text=f"the MQTT broker does not let it subscribe to {topic}: {reason}"
        )

    def _closed_early(self, reason: str) -> None:
        pass

    def _unanswered(self, waited: str) -> None:
        pass  # the main connection says it (connection.py rule 6)

    def _closed(self, was_up: bool, reason_code: ReasonCode) -> bool:
        if was_up:
            self._on_link(False)  # after its last message (rule 8)
        elif not self._gave_up:  # (unanswered: no close of the broker's, connection.py rule 6)
            text = f"the MQTT broker closed its connection: {reason_code}"
            self._say(op="problem", text=text, until_up=True)
        return was_up

    def _ended(self, reason_code: ReasonCode, ending: Ending, fight: bool) -> None:
        log.debug("stop express disconnected (%s)", reason_code)
        if fight and self._fight is None:  # rule 6: said, not only slowed down
            self._fight = takeover_message(self._client_id, ending, TAKEOVER_FIRST_S)
            self._say(op="problem", text=self._fight)  # (the bridge logs it)

    def _tick(self) -> float | None:
        """Rule 6: a fight said is unsaid once a connection lasted STABLE_S (cheap: a compare);
        when that is due (paho_client.py rule 2), or never while none is said."""
        since = self._guard.connected_at
        if self._fight is None or since is None:
            return math.inf  # (a connection's start runs a round, and this, again)
        left_s = since + STABLE_S - self._clock()
        if left_s > 0:
            return time.monotonic() + left_s
        self._say(op="problem", text=self._fight, off=True)
        self._fight = None
        return math.inf


class _Child:
    """The express itself (rules 3, 5, 8 and 9): the ports it holds, the frames it writes."""

    def __init__(self, sock: socket.socket, config: dict[str, Any]) -> None:
        self._sock = sock
        self._send_lock = threading.Lock()
        self._lock = threading.Lock()  # the ports: never closed while written to
        self._ports: dict[str, tuple[int, int]] = {}  # rotator id -> (number, fd)
        self._topics: dict[str, list[str]] = {
            t: [r] for t, (r, k) in config["topics"].items() if k == "stop"
        }
        self._locks: dict[str, str] = {
            t: r for t, (r, k) in config["topics"].items() if k == "lock"
        }
        for t, members in (config.get("groups") or {}).items():
            self._topics[t] = list(members)
        self._frames = {rid: bytes.fromhex(f) for rid, f in config["frames"].items()}
        self._v5 = not config["mqtt311"]
        self._next: dict[str, float] = {}  # rotator id -> when it may get a frame again (rule 3)
        self._locked_next: dict[str, float] = {}  # ... when its lock ON is said again (rule 11)
        self._heard_next: dict[str, float] = {}  # ... when a stop it wrote no frame for is said
        self._stuck: set[str] = set()  # rule 9: rotators whose tty took nothing for a whole wait
        self.clock: Callable[[], float] = time.monotonic
        self.write: Callable[[int, bytes], int] = os.write  # (the tests cut writes short)
        self._sync_topic: str | None = config.get("sync_topic")
        self._marks: dict[int, str] = {}  # rule 8: each word out -> its own random mark
        self._sync_lock = threading.Lock()
        self.sync = Sync()
        self._upped = False  # rule 8: ``up`` said on this connection
        settings = MqttSettings.model_validate(config["mqtt"])
        filters = [*self._topics, *self._locks]
        self.link = _Link(
            settings,
            config["client_id"],
            self.say,
            self._linked,
            subscriptions=[*filters, *([self._sync_topic] if self._sync_topic else [])],
            on_message=self.on_message,
            on_subscribed=self._subscribed,
            no_replay=filters,
        )
        if config["mqtt311"]:
            self.link.use_mqtt311()

    def say(self, **word: Any) -> None:
        with self._send_lock:
            try:
                _send(self._sock, word)
            except OSError:
                pass  # the bridge is gone: the main loop ends on it

    # -- rule 8 -------------------------------------------------------------------------------
    def _publish(self, word: int | None) -> None:
        """A word out, with a mark of its own nobody could know before it was published: a
        word another client forges, or left retained, is not its own (rule 8)."""
        if word is None or self._sync_topic is None:
            return
        mark = secrets.token_hex(8)
        with self._sync_lock:
            self._marks[word] = mark
        self.link.publish(self._sync_topic, f"{mark} {word}")

    def _answer(self, answer: int | None, lost: bool = False) -> None:
        if answer is not None:
            self.say(op="synced", n=answer, **({"lost": True} if lost else {}))

    def asked(self, n: int, again: bool) -> None:
        """A request from the bridge (its socket's thread)."""
        with self._sync_lock:
            answer, word = self.sync.asked(n, again)
            for k in [k for k in self._marks if not self.sync.is_out(k)]:
                del self._marks[k]  # (as Sync forgot its words out: WORDS_KEPT at most)
            self._answer(answer)  # (under the lock: the answers in order)
        self._publish(word)

    def _linked(self, up: bool) -> None:
        """Paho's thread: a connection accepted (before it subscribes), or ended."""
        with self._sync_lock:
            self._marks.clear()  # (as Sync forgets its words out)
            if up:
                self.sync.accepted()
                return
            self._answer(self.sync.ended(), lost=True)  # (rule 8: what waited is dropped)
            if self._upped:
                self._upped = False
                self.say(op="down")

    def _subscribed(self) -> None:
        with self._sync_lock:
            word = self.sync.subscribed()
        self._publish(word)

    def _read_back(self, payload: bytes) -> None:
        mark, _, number = payload.decode("ascii", "replace").partition(" ")
        if not number.isdigit() or len(number) > WORD_DIGITS:  # (5000 digits: int() raised)
            return
        w = int(number)
        with self._sync_lock:
            if self._marks.get(w) != mark:
                return  # another's, forged or replayed (rule 8)
            for k in [k for k in self._marks if k <= w]:
                del self._marks[k]  # (as Sync forgets its words out up to it)
            answer, word = self.sync.read_back(w)
            self._answer(answer)
            if self.sync.writing and not self._upped:
                self._upped = True
                self.say(op="up")
        self._publish(word)

    # -- rule 3 -------------------------------------------------------------------------------
    def on_message(
        self, topic: str, payload: bytes, retain: bool, operator: str | None, stamp: Stamp | None
    ) -> None:
        """Rule 3, on paho's thread."""
        if topic == self._sync_topic:
            self._read_back(payload)
            return
        rids, locks = self._topics.get(topic), False
        if rids is None:
            rid = self._locks.get(topic)
            if rid is None or not _switch_on(payload):
                return
            rids, locks = [rid], True
        if retain and (not self._v5 or not payload):
            return  # a replay (3.1.1), or a retained message being deleted (service.py rule 1)
        read_t = self.clock()
        if not self.sync.writing:  # rule 8 (changed on this thread only, or to no write)
            self._early(rids, locks, read_t, operator)
            return
        owed, unwritten = [], []
        for rid in rids:
            tried = self._stop(rid, operator)
            if tried is False:
                unwritten.append(rid)
            elif tried is not True:
                owed.append((rid, *tried))
        for rid, now, held, done in owed:  # rule 9: no member's wait before another's frame
            if not self._finish(rid, now, held, done, operator):
                unwritten.append(rid)
        if locks:  # rule 11: the lock itself, its frame gone or not, and who sent it
            if read_t >= self._locked_next.get(rids[0], read_t):  # (a flood: said once)
                self._locked_next[rids[0]] = read_t + GAP_S
                self.say(op="locked", rotator=rids[0], t=read_t, operator=_named(operator))
            return
        for rid in unwritten:  # rule 11: a stop with no frame of this express's, said
            if read_t >= self._heard_next.get(rid, read_t):  # (a flood: once in GAP_S)
                self._heard_next[rid] = read_t + GAP_S
                self.say(op="heard", rotator=rid, t=read_t, **_sender(operator))

    def _early(self, rids: list[str], locks: bool, read_t: float, operator: str | None) -> None:
        """Rule 11: a stop or lock ON read before this connection's word came back: no frame
        (rule 8), but said, ``early`` (the bridge's vouches answered meanwhile do not order
        it: rule 11), once in GAP_S a rotator."""
        if locks:
            if read_t >= self._locked_next.get(rids[0], read_t):
                self._locked_next[rids[0]] = read_t + GAP_S
                self.say(
                    op="locked", rotator=rids[0], t=read_t, operator=_named(operator), early=True
                )
            return
        for rid in rids:
            if read_t >= self._heard_next.get(rid, read_t):
                self._heard_next[rid] = read_t + GAP_S
                self.say(op="heard", rotator=rid, t=read_t, early=True, **_sender(operator))

    def _stop(self, rid: str, operator: str | None) -> tuple[float, tuple[int, int], int] | bool:
        """Rule 3: the frame's one write, at once (True: written; False: nothing went, or
        another frame went within GAP_S); what a write cut short or refused leaves owed (when
        the stop came, the port, the bytes taken) is returned for ``_finish``."""
        with self._lock:
            held, now = self._ports.get(rid), self.clock()
            if held is None or rid not in self._frames:
                return False
            if now < self._next.get(rid, now):
                return True  # (rule 3: one went, and was said, less than GAP_S ago)
            frame = self._frames[rid]
            try:
                done = self.write(held[1], frame)
            except BlockingIOError:  # refused whole: the serial-lines thread inside its write
                done = 0
            except OSError:
                return False  # rule 3: nothing went; the session's own stop follows
            if done == 0 and rid in self._stuck:
                return False  # rule 9: its tty is stuck; the session's own stop follows
            if done < len(frame):  # (part taken: a stuck tty moves again)
                return now, held, done
            self._next[rid] = now + GAP_S
            self._stuck.discard(rid)
        self.say(op="wrote", rotator=rid, t=now, **_sender(operator))  # (rule 11: who)
        return True

    def _finish(
        self, rid: str, now: float, held: tuple[int, int], done: int, operator: str | None
    ) -> bool:
        """Rule 9: the rest of a frame a write left owed, when the port takes bytes again;
        False if it is not whole (a half frame is no stop: rule 11 says it as none)."""
        with self._lock:
            if self._ports.get(rid) is not held:
                return False  # given back meanwhile (closed): nothing more goes to it
            whole = self._write_whole(held[1], self._frames[rid], done)
            if whole:
                self._stuck.discard(rid)
            else:  # rule 9: stuck: no more waits for it until it takes bytes again
                self._stuck.add(rid)
            if whole is None:
                return False  # rule 3: nothing went; the session's own stop follows
            self._next[rid] = now + GAP_S
        if whole:
            self.say(op="wrote", rotator=rid, t=now, **_sender(operator))
        else:
            self.say(op="half", rotator=rid)
        return whole

    def _write_whole(self, fd: int, frame: bytes, done: int) -> bool | None:
        """Rule 9: ``done`` bytes of ``frame`` written; True: the rest written too; None:
        nothing of it; False: half of it."""
        rest, end = frame[done:], self.clock() + FINISH_WAIT_S
        while rest:
            left = end - self.clock()
            if left <= 0:
                return False if len(rest) < len(frame) else None
            try:
                writable(fd, left)
                rest = rest[self.write(fd, rest) :]
            except BlockingIOError:
                # refused whole with room in the buffer: another writer is inside its own write
                # (microseconds); raised above it (rule 10), a spin here could keep it off the
                # only core it has, so the retry waits a little (a pace, no decision)
                time.sleep(REFUSED_RETRY_S)
                continue
            except (OSError, ValueError):
                return False if len(rest) < len(frame) else None
        if done:
            log.info("a stop frame cut short by a full output buffer was finished")
        return True

    def serve(self) -> None:
        """The bridge's words until its end of file (rule 7)."""
        while True:
            try:
                data, fds, _flags, _addr = socket.recv_fds(self._sock, _PACKET, 4)
            except OSError:
                break
            if not data:
                break
            word = json.loads(data)
            rid, number = word.get("rotator"), word.get("n")
            if word.get("op") == "sync":
                self.asked(int(word["n"]), bool(word.get("again")))
            elif word.get("op") == "port" and fds:
                with self._lock:
                    old = self._ports.get(rid)
                    self._ports[rid] = (number, fds[0])
                    self._stuck.discard(rid)  # (rule 9: a new port is waited for again)
                if old is not None:
                    os.close(old[1])
                self.say(op="held", rotator=rid, n=number)
            elif word.get("op") == "drop":
                with self._lock:
                    held = self._ports.get(rid)
                    if held is not None and held[0] == number:
                        del self._ports[rid]
                        os.close(held[1])
                self.say(op="dropped", rotator=rid, n=number)
            for extra in fds[1:] if word.get("op") == "port" else fds:
                os.close(extra)
        with self._lock:  # the bridge is gone: its ports are free at once (rule 7)
            for _number, fd in self._ports.values():
                os.close(fd)
            self._ports.clear()


def _switch_on(payload: bytes) -> bool:
    try:
        return parse_switch(payload)
    except PayloadError:
        return False


def _raise_priority() -> None:
    """Rule 10: this process EXPRESS_RAISE above the priority it started with, where allowed."""
    if not hasattr(os, "setpriority"):  # Windows: never the service's express
        return
    try:
        now = os.getpriority(os.PRIO_PROCESS, 0)
        os.setpriority(os.PRIO_PROCESS, 0, max(-20, now - EXPRESS_RAISE))
    except OSError as exc:  # EACCES/EPERM: no privilege, or above the nice limit
        log.debug("runs at the bridge's priority: %s", exc)


def main(argv: list[str]) -> int:
    sock = socket.socket(fileno=int(argv[1]))
    data = sock.recv(_PACKET)
    if not data:
        return 0
    config = json.loads(data)
    for sig in (signal.SIGINT, signal.SIGTERM):  # rule 7: it ends with the bridge, not before
        signal.signal(sig, signal.SIG_IGN)
    logging.basicConfig(
        level=config.get("log_level", logging.INFO),
        format="stop express: %(levelname)s %(message)s",
    )
    _raise_priority()  # rule 10: before any thread, which inherits it
    child = _Child(sock, config)
    child.link._connect()
    try:
        child.serve()
    finally:
        child.link._disconnect()
    return 0


def _named(operator: str | None) -> str | None:
    """Rule 11: who sent it as a word may carry it, an operator's name or none (a word is
    read whole only up to _PACKET bytes)."""
    return None if operator is None else operator_name(operator)


def _sender(operator: str | None) -> dict[str, str]:
    """Rule 11: who sent a stop, in the word that says it was written or heard (none: no
    key, as before operators were named)."""
    name = _named(operator)
    return {} if name is None else {"operator": name}


if __name__ == "__main__":
    sys.exit(main(sys.argv))
