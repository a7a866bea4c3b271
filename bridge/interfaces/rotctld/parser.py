"""rotctld's input, read as rotctld reads it: sans-IO, characters in, complete requests out.
See the package docstring for the rules (1-3)."""

from __future__ import annotations

import logging
import re
import string
from dataclasses import dataclass

log = logging.getLogger(__name__)


_WHITESPACE = frozenset(" \t\r\n\v\f")
_PREFIXES = frozenset(string.punctuation) - {"\\", "_", "#"}
_NAME_CHARS = frozenset(string.ascii_letters + string.digits + "_")
_MAX_NAME = 32
_MAX_TOKEN = 64
_PREFIXES_RE = "".join(re.escape(c) for c in sorted(_PREFIXES))
# rule 1: an argument that would be a stop as a command (``S``, ``\stop``, with the prefixes a
# command may have: ``+S``, ``;S``, ``+\stop``, ``\stop;``): no number begins so
_STOP_ARG = re.compile(rf"\+?[{_PREFIXES_RE}]?(?:S|\\stop(?![A-Za-z0-9_]))")


@dataclass(frozen=True)
class CommandDef:
    short: str | None  # one-character form, if any
    name: str  # long form, also the header of an extended reply
    nargs: int
    returns_values: bool  # success prints values only (no "RPRT 0") in the terse protocol
    numbers: bool = True  # its arguments are numbers (set_conf's are words)


COMMANDS: tuple[CommandDef, ...] = (
    CommandDef("P", "set_pos", 2, False),
    CommandDef("p", "get_pos", 0, True),
    CommandDef("S", "stop", 0, False),
    CommandDef("K", "park", 0, False),
    CommandDef("M", "move", 2, False),
    CommandDef("R", "reset", 1, False),
    CommandDef("C", "set_conf", 2, False, numbers=False),
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
        self._stop_next = False

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
            if self._stop_next:  # rule 1: a stop read as an argument, carried out at once
                self._stop_next = False
                out.append(Request(_BY_NAME["stop"]))
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
            token = "".join(self._token)
            self._args.append(token)
            self._token = []
            assert self._command is not None
            if self._command.numbers and _STOP_ARG.match(token):  # rule 1: a stop at once;
                self._stop_next = True  # the command still takes its arguments as rotctld does
            if len(self._args) == self._command.nargs:
                return self._emit()
        return None

    def _emit(self) -> Request:
        assert self._command is not None
        request = Request(self._command, tuple(self._args), self._extended, self._sep)
        self._clear()
        return request
