"""A Hamlib rotctld-compatible TCP port onto one rotator, beside MQTT.

Gpredict, loggers and Hamlib's own network client (``rotctl -m 2``) speak rotctld's text
protocol. Here they reach the same Rotator as MQTT does: the same mailbox, limits, safety lock
and status. Source document: /work/shared/protocols/hamlib-and-rotctld.md section 3 (reply
bytes verified against rotctld 4.5.4).

Rules:
1. Input is a character stream, as rotctld reads it: a one-character command or ``\\long_name``,
   optionally prefixed by ``+`` or one punctuation character (extended replies, that character
   as separator), then whitespace-separated arguments; CR and LF are plain whitespace, so a
   command still waiting for arguments takes them from the following lines. ``#`` comments out
   the rest of the line. ``q``/``Q`` closes the connection.
2. A command runs only once it is complete (its last argument followed by whitespace). What a
   client leaves unfinished when it disconnects is dropped: it never moves anything.
3. Unknown commands get no reply at all (rotctld logs them on its own stderr and says nothing).
4. Every reply goes out in one send: Gpredict reads ``p`` with a single recv().
5. ``p`` answers from the bridge's status (no serial traffic). A position the bridge does not
   currently have is an error code, never the last value seen.
6. Motion goes through Rotator.submit with Source.ROTCTLD, so the lock, the limits and the link
   state are judged in one place and MQTT shows the refusal or the move.
"""

from __future__ import annotations

import logging
import os
import re
import selectors
import socket
import string
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from bridge.errors import Refused
from bridge.model import Source, Stop, Target

if TYPE_CHECKING:
    from bridge.engine.rotator import Rotator

log = logging.getLogger(__name__)

# Hamlib error codes (rig.h, enum rig_errcode_e), sent negated as "RPRT -n".
RIG_OK = 0
RIG_EINVAL = 1  # invalid parameter: out of range, not a number
RIG_ETIMEOUT = 5  # the controller does not answer (port open, no valid reply)
RIG_EIO = 6  # the serial link is down (port closed or gone)
RIG_EINTERNAL = 7
RIG_ERJCTED = 9  # command rejected: the bridge's safety lock is ON
RIG_ENAVAIL = 11  # the model cannot do this

#: bridge model name -> Hamlib rotator model number (shown by \dump_state and dump_caps)
HAMLIB_MODELS: dict[str, int] = {
    "rotorez": 401,
    "rotorcard": 402,
    "dcu1": 403,
    "rot2prog": 901,
    "rot1prog": 902,
    "md01": 903,
    "satel": 2101,
}
# A model Hamlib does not know is shown as its dummy; `rotctl -m 2` ignores the model line.
_HAMLIB_FALLBACK_MODEL = 1

#: what Hamlib's backend answers to get_info, where that differs from our display name
_HAMLIB_INFO: dict[str, str] = {
    "rotorez": "Rotor-EZ",
    "rotorcard": "RotorCard",
    "dcu1": "DCU-1/DCU-1X",
}

_WHITESPACE = frozenset(" \t\r\n\v\f")
_PREFIXES = frozenset(string.punctuation) - {"\\", "_", "#"}
_NAME_CHARS = frozenset(string.ascii_letters + string.digits + "_")
_MAX_NAME = 32
_MAX_TOKEN = 64
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_INTEGER = re.compile(r"[+-]?\d+")


@dataclass(frozen=True)
class CommandDef:
    short: str | None  # one-character form, if any
    name: str  # long form, also the header of an extended reply
    nargs: int
    returns_values: bool  # success prints values only (no "RPRT 0") in the terse protocol


COMMANDS: tuple[CommandDef, ...] = (
    CommandDef("P", "set_pos", 2, False),
    CommandDef("p", "get_pos", 0, True),
    CommandDef("S", "stop", 0, False),
    CommandDef("K", "park", 0, False),
    CommandDef("M", "move", 2, False),
    CommandDef("R", "reset", 1, False),
    CommandDef("C", "set_conf", 2, False),
    CommandDef("s", "get_status", 0, True),
    CommandDef("_", "get_info", 0, True),
    CommandDef("1", "dump_caps", 0, False),
    CommandDef(None, "dump_state", 0, True),
)
_BY_SHORT = {c.short: c for c in COMMANDS if c.short is not None}
_BY_NAME = {c.name: c for c in COMMANDS}


@dataclass(frozen=True)
class Request:
    command: CommandDef
    args: tuple[str, ...] = ()
    extended: bool = False
    sep: str = "\n"


class Quit:
    """The client asked to close the connection (``q`` or ``Q``)."""


QUIT = Quit()


class RequestParser:
    """Sans-IO: bytes in, complete requests out (rules 1-3)."""

    def __init__(self) -> None:
        self._clear()

    def _clear(self) -> None:
        self._state = "command"  # command | name | args | comment
        self._extended = False
        self._sep = "\n"
        self._prefixed = False
        self._name: list[str] = []
        self._command: CommandDef | None = None
        self._args: list[str] = []
        self._token: list[str] = []

    @property
    def idle(self) -> bool:
        """True when no command is half received."""
        return self._state == "command" and not self._extended

    def feed(self, data: bytes) -> list[Request | Quit]:
        out: list[Request | Quit] = []
        for ch in data.decode("latin-1"):
            item = self._step(ch)
            if item is not None:
                out.append(item)
        return out

    def _step(self, ch: str) -> Request | Quit | None:
        if self._state == "comment":
            if ch in "\r\n":
                self._state = "command"
            return None
        if self._state == "name":
            return self._name_char(ch)
        if self._state == "args":
            return self._arg_char(ch)
        return self._command_char(ch)

    def _command_char(self, ch: str) -> Request | Quit | None:
        if ch in _WHITESPACE:
            return None
        if ch == "+" and not self._extended:
            self._extended, self._sep = True, "\n"
            return None
        if ch in _PREFIXES and not self._prefixed:
            self._extended, self._sep, self._prefixed = True, ch, True
            return None
        if ch == "#":
            self._clear()
            self._state = "comment"
            return None
        if ch == "\\":
            self._state = "name"
            return None
        if ch in "qQ":
            self._clear()
            return QUIT
        command = _BY_SHORT.get(ch)
        if command is None:
            log.debug("rotctld: command %r not found", ch)
            self._clear()
            return None
        return self._begin(command)

    def _name_char(self, ch: str) -> Request | None:
        if ch in _NAME_CHARS and len(self._name) < _MAX_NAME:
            self._name.append(ch)
            return None
        name = "".join(self._name)  # the character ending the name is consumed with it
        command = _BY_NAME.get(name)
        if command is None:
            log.debug("rotctld: command \\%s not found", name)
            self._clear()
            return None
        return self._begin(command)

    def _begin(self, command: CommandDef) -> Request | None:
        self._command = command
        if command.nargs == 0:
            return self._emit()
        self._state = "args"
        return None

    def _arg_char(self, ch: str) -> Request | None:
        if ch not in _WHITESPACE:
            self._token.append(ch)
            if len(self._token) > _MAX_TOKEN:  # nonsense, not a number: drop the line
                self._clear()
                self._state = "comment"
            return None
        if self._token:
            self._args.append("".join(self._token))
            self._token = []
            assert self._command is not None
            if len(self._args) == self._command.nargs:
                return self._emit()
        return None

    def _emit(self) -> Request:
        assert self._command is not None
        request = Request(self._command, tuple(self._args), self._extended, self._sep)
        self._clear()
        return request


class RotctldCommands:
    """Executes requests against one rotator and renders rotctld's reply bytes."""

    def __init__(
        self,
        rotator: Rotator,
        *,
        park_az_deg: float | None = None,
        park_el_deg: float | None = None,
    ) -> None:
        self.rotator = rotator
        self.park_az_deg = park_az_deg
        self.park_el_deg = park_el_deg
        spec = rotator.spec
        self.hamlib_model = HAMLIB_MODELS.get(spec.name, _HAMLIB_FALLBACK_MODEL)
        self.info = _HAMLIB_INFO.get(spec.name, spec.display_name)
        if spec.has_elevation:
            self.rot_type = "AzEl"
        elif spec.family == "rotorez":
            self.rot_type = "Other"  # as Hamlib's rotorez backend reports itself
        else:
            self.rot_type = "Az"

    def execute(self, request: Request) -> bytes:
        handler = getattr(self, "_" + request.command.name)
        try:
            code, body = handler(request)
        except Exception:
            log.exception("rotctld: %s failed", request.command.name)
            code, body = -RIG_EINTERNAL, ""
        return _frame(request, code, body).encode()

    # -- commands: each returns (code, body); body is rendered for the request's protocol ------

    def _get_pos(self, req: Request) -> tuple[int, str]:
        spec = self.rotator.spec
        if not spec.can_report_position:
            return -RIG_ENAVAIL, ""
        status = self.rotator.status
        az = status.bearing_deg
        el = status.elevation_deg if spec.has_elevation else 0.0
        if not status.available or az is None or el is None:
            return _link_code(status.connected), ""
        return RIG_OK, _values(req, [("Azimuth", f"{az:.2f}"), ("Elevation", f"{el:.2f}")])

    def _set_pos(self, req: Request) -> tuple[int, str]:
        az, el = (_number(a) for a in req.args)
        if az is None or el is None:
            return -RIG_EINVAL, ""
        el_deg = el if self.rotator.spec.has_elevation or el != 0 else None
        return self._submit_target(az, el_deg, req)

    def _park(self, req: Request) -> tuple[int, str]:
        if self.park_az_deg is None:
            return -RIG_ENAVAIL, ""
        el = self.park_el_deg if self.rotator.spec.has_elevation else None
        return self._submit_target(self.park_az_deg, el, req)

    def _stop(self, req: Request) -> tuple[int, str]:
        self.rotator.submit(Stop(Source.ROTCTLD), _describe(req))
        return RIG_OK, ""

    def _move(self, req: Request) -> tuple[int, str]:
        if not all(_INTEGER.fullmatch(a) for a in req.args):
            return -RIG_EINVAL, ""
        return -RIG_ENAVAIL, ""  # no supported model moves by direction and speed yet

    def _reset(self, req: Request) -> tuple[int, str]:
        if not _INTEGER.fullmatch(req.args[0]):
            return -RIG_EINVAL, ""
        return -RIG_ENAVAIL, ""

    def _set_conf(self, req: Request) -> tuple[int, str]:
        return -RIG_ENAVAIL, ""

    def _get_status(self, req: Request) -> tuple[int, str]:
        return -RIG_ENAVAIL, ""

    def _get_info(self, req: Request) -> tuple[int, str]:
        return RIG_OK, _values(req, [("Info", self.info)])

    def _dump_state(self, req: Request) -> tuple[int, str]:
        lim = self.rotator.limits
        lines = [
            ("rotctld Protocol Ver: 1", "1"),
            (f"Rotor Model: {self.hamlib_model}", str(self.hamlib_model)),
            (f"Minimum Azimuth: {lim.az_min_deg:f}", f"min_az={lim.az_min_deg:f}"),
            (f"Maximum Azimuth: {lim.az_max_deg:f}", f"max_az={lim.az_max_deg:f}"),
            (f"Minimum Elevation: {lim.el_min_deg:f}", f"min_el={lim.el_min_deg:f}"),
            (f"Maximum Elevation: {lim.el_max_deg:f}", f"max_el={lim.el_max_deg:f}"),
            ("South Zero: 0", "south_zero=0"),
            (f"rot_type={self.rot_type}", f"rot_type={self.rot_type}"),
            ("done", "done"),
        ]
        if req.extended:
            return RIG_OK, "".join(labelled + req.sep for labelled, _ in lines)
        return RIG_OK, "".join(terse + "\n" for _, terse in lines)

    def _dump_caps(self, req: Request) -> tuple[int, str]:
        spec, lim = self.rotator.spec, self.rotator.limits

        def yn(flag: bool) -> str:
            return "Y" if flag else "N"

        rot_type = {"AzEl": "Az-El", "Az": "Azimuth"}.get(self.rot_type, self.rot_type)  # as -u
        return RIG_OK, (
            f"Caps dump for model:\t{self.hamlib_model}\n"
            f"Model name:\t\t{spec.display_name}\n"
            f"Mfg name:\t\t{spec.manufacturer}\n"
            "Backend version:\trotor-bridge\n"
            "Backend status:\t\tStable\n"
            f"Rot type:\t\t{rot_type}\n"
            "Port type:\t\tNetwork link (rotor-bridge)\n"
            f"Min Azimuth:\t\t{lim.az_min_deg:.2f}\n"
            f"Max Azimuth:\t\t{lim.az_max_deg:.2f}\n"
            f"Min Elevation:\t\t{lim.el_min_deg:.2f}\n"
            f"Max Elevation:\t\t{lim.el_max_deg:.2f}\n"
            "Can set Position:\tY\n"
            f"Can get Position:\t{yn(spec.can_report_position)}\n"
            "Can Stop:\t\tY\n"
            f"Can Park:\t\t{yn(self.park_az_deg is not None)}\n"
            "Can Reset:\t\tN\n"
            "Can Move:\t\tN\n"
            "Can get Info:\t\tY\n"
            "Can get Status:\t\tN\n"
            "\nOverall backend warnings: 0\n"
        )

    def _submit_target(self, az: float, el: float | None, req: Request) -> tuple[int, str]:
        try:
            self.rotator.submit(Target(az, el, Source.ROTCTLD), _describe(req))
        except Refused as exc:
            return _refusal_code(exc, self.rotator.status.connected), ""
        return RIG_OK, ""


def _refusal_code(exc: Refused, connected: bool) -> int:
    if exc.code in ("limits", "unsupported"):  # unsupported: elevation on an az-only model
        return -RIG_EINVAL
    if exc.code == "offline":
        return _link_code(connected)
    return -RIG_ERJCTED  # locked (and any refusal added later): the bridge said no


def _link_code(connected: bool) -> int:
    # what rotctld itself answers: a vanished port is an I/O error, a silent controller a timeout
    return -RIG_ETIMEOUT if connected else -RIG_EIO


def _number(text: str) -> float | None:
    text = text.replace(",", ".")  # rotctld accepts a decimal comma ("P 10,5 20")
    return float(text) if _NUMBER.fullmatch(text) else None


def _values(req: Request, pairs: Iterable[tuple[str, str]]) -> str:
    if req.extended:
        return "".join(f"{label}: {value}{req.sep}" for label, value in pairs)
    return "".join(f"{value}\n" for _, value in pairs)


def _frame(req: Request, code: int, body: str) -> str:
    if req.extended:
        head = req.command.name + ":" + "".join(" " + a for a in req.args) + req.sep
        return head + (body if code == RIG_OK else "") + f"RPRT {code}\n"
    if code != RIG_OK:
        return f"RPRT {code}\n"
    return body if req.command.returns_values else body + "RPRT 0\n"


def _describe(req: Request) -> str:
    return " ".join(("rotctld", req.command.name, *req.args))


class RotctldServer:
    """One TCP listener for one rotator; one thread per client."""

    def __init__(
        self,
        rotator: Rotator,
        port: int,
        bind: str = "127.0.0.1",
        *,
        park_az_deg: float | None = None,
        park_el_deg: float | None = None,
        max_clients: int = 16,
    ) -> None:
        self.commands = RotctldCommands(rotator, park_az_deg=park_az_deg, park_el_deg=park_el_deg)
        self.rotator_id = rotator.id
        self._bind = bind
        self._requested_port = port
        self._max_clients = max_clients
        self._listener: socket.socket | None = None
        self._wake_r, self._wake_w = -1, -1
        self._accept_thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._clients: dict[socket.socket, threading.Thread] = {}
        self._stopping = False

    @property
    def address(self) -> tuple[str, int]:
        if self._listener is None:
            return self._bind, self._requested_port
        host, port = self._listener.getsockname()[:2]
        return host, port

    @property
    def port(self) -> int:
        return self.address[1]

    @property
    def client_count(self) -> int:
        with self._lock:
            return len(self._clients)

    def start(self) -> None:
        """Listen (OSError if the address cannot be had) and accept clients in a thread."""
        host, port = self._bind, self._requested_port
        try:
            family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
            self._listener = socket.create_server((host, port), family=family)
        except OSError as exc:
            raise OSError(
                exc.errno,
                f"rotctld for rotator {self.rotator_id!r}: cannot listen on {host}:{port}: "
                f"{exc.strerror or exc}",
            ) from None
        if host not in ("127.0.0.1", "::1", "localhost"):
            log.warning(
                "rotctld for %s listens on %s:%d: rotctld has no authentication, anyone who "
                "can reach this address can turn the antenna",
                self.rotator_id,
                host,
                self.port,
            )
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self._accept_thread = threading.Thread(
            target=self._accept_loop, name=f"rotctld-{self.rotator_id}", daemon=True
        )
        self._accept_thread.start()
        log.info("rotctld for %s listening on %s:%d", self.rotator_id, *self.address)

    def stop(self, timeout_s: float = 3.0) -> None:
        """Stop listening, close every client; commands already queued stay queued."""
        if self._listener is None:
            return
        with self._lock:
            self._stopping = True
            clients = list(self._clients.items())
        os.write(self._wake_w, b"x")
        if self._accept_thread is not None:
            self._accept_thread.join(timeout_s)
        for conn, _thread in clients:
            try:
                conn.shutdown(socket.SHUT_RDWR)  # wakes the client thread's recv()
            except OSError:
                pass
        for _conn, thread in clients:
            thread.join(timeout_s)
        self._listener.close()
        self._listener = None
        os.close(self._wake_r)
        os.close(self._wake_w)

    def _accept_loop(self) -> None:
        listener = self._listener
        assert listener is not None
        listener.setblocking(False)  # a client that gave up between select and accept
        with selectors.DefaultSelector() as sel:
            sel.register(listener, selectors.EVENT_READ)
            sel.register(self._wake_r, selectors.EVENT_READ)
            while True:
                events = sel.select()
                if any(key.fileobj == self._wake_r for key, _ in events):
                    return
                try:
                    conn, peer = listener.accept()
                except BlockingIOError:
                    continue
                except OSError as exc:
                    log.warning("rotctld for %s: accept failed: %s", self.rotator_id, exc)
                    continue
                conn.setblocking(True)
                self._admit(conn, peer)

    def _admit(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        with self._lock:
            if self._stopping or len(self._clients) >= self._max_clients:
                log.warning(
                    "rotctld for %s: refusing %s:%d (%d clients connected)",
                    self.rotator_id,
                    peer[0],
                    peer[1],
                    len(self._clients),
                )
                conn.close()
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            thread = threading.Thread(
                target=self._serve,
                args=(conn, peer),
                name=f"rotctld-{self.rotator_id}-{peer[1]}",
                daemon=True,
            )
            self._clients[conn] = thread
        thread.start()

    def _serve(self, conn: socket.socket, peer: tuple[str, int]) -> None:
        log.info("rotctld for %s: client %s:%d connected", self.rotator_id, peer[0], peer[1])
        parser = RequestParser()
        try:
            while True:
                data = conn.recv(4096)
                if not data:
                    break
                for item in parser.feed(data):
                    if isinstance(item, Quit):
                        return
                    conn.sendall(self.commands.execute(item))
        except OSError as exc:
            log.debug("rotctld for %s: client %s:%d: %s", self.rotator_id, *peer, exc)
        finally:
            with self._lock:
                self._clients.pop(conn, None)
            conn.close()
            log.info(
                "rotctld for %s: client %s:%d gone%s",
                self.rotator_id,
                peer[0],
                peer[1],
                "" if parser.idle else " (an unfinished command was dropped)",
            )
