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
OVERLONG = "(overlong)"  # an argument too long to be one: kept as this, refused (rule 1)
_PREFIXES_RE = "".join(re.escape(c) for c in sorted(_PREFIXES))
# rule 1: a word that is a stop and nothing else, as a command would be (``S``, ``+S``, ``;S``,
# ``\stop``, ``\stop;``): where a word is awaited (a level's name, send_cmd's line)
_STOP_WORD = re.compile(rf"\+?[{_PREFIXES_RE}]?(?:S|\\stop[^A-Za-z0-9_]?)")


@dataclass(frozen=True)
class CommandDef:
    short: str | None  # one-character form, if any
    name: str  # long form, also the header of an extended reply
    nargs: int
    returns_values: bool  # success prints values only (no "RPRT 0") in the terse protocol
    numbers: bool = True  # its arguments are numbers (set_conf's are words)
    line: bool = False  # its one argument is the rest of the line (send_cmd)


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
    # rule 3: rotctld's commands the bridge does not carry out, read as rotctld reads them (their
    # arguments are theirs, never commands of their own) and answered "not available"
    CommandDef("V", "set_level", 2, False, numbers=False),
    CommandDef("v", "get_level", 1, True, numbers=False),
    CommandDef("U", "set_func", 2, False, numbers=False),
    CommandDef("u", "get_func", 1, True, numbers=False),
    CommandDef("X", "set_parm", 2, False, numbers=False),
    CommandDef("x", "get_parm", 1, True, numbers=False),
    CommandDef("w", "send_cmd", 1, True, numbers=False, line=True),
    CommandDef("L", "lonlat2loc", 3, True),
    CommandDef("l", "loc2lonlat", 1, True, numbers=False),
    CommandDef("D", "dms2dec", 4, True),
    CommandDef("d", "dec2dms", 1, True),
    CommandDef("E", "dmmm2dec", 3, True),
    CommandDef("e", "dec2dmmm", 1, True),
    CommandDef("B", "qrb", 4, True),
    CommandDef("A", "a_sp2a_lp", 1, True),
    CommandDef("a", "d_sp2d_lp", 1, True),
    CommandDef(None, "pause", 1, False),
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

    def __init__(self, watch: bool = True) -> None:
        self._clear()
        self._watch = watch  # rule 1 (off in the parser that reads an argument as commands)
        self._stop_next = False
        self._sub: RequestParser | None = None  # rule 1: the argument, read as commands
        self._sub_stopped = False

    def _clear(self) -> None:
        self._state = "command"  # command | name | args | comment
        self._extended = False
        self._sep = "\n"
        self._prefixed = False
        self._name: list[str] = []
        self._command: CommandDef | None = None
        self._args: list[str] = []
        self._token: list[str] = []
        self._reread = False  # send_cmd's empty rest of line read again (``_line_char``)

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

    def _stops(self, ch: str) -> bool:
        """Rule 1: whether the argument being read, read as commands up to ``ch``, has just
        made a stop (a parser of its own reads it, one level deep: ``S``, ``+S``, ``;;S``,
        ``pS``, ``\\stop;`` all stop as commands; ``PS`` does not, its S the P's argument).
        Once per argument, over its first _MAX_TOKEN characters."""
        if self._sub is None or self._sub_stopped:
            return False
        made = self._sub.feed(ch.encode("latin-1"))
        self._sub_stopped = any(isinstance(r, Request) and r.command.name == "stop" for r in made)
        return self._sub_stopped

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
        if ch in _WHITESPACE:  # rule 1: after a prefix, rotctld's unknown command ' ': the
            self._clear()  # prefix is forgotten (``+ p`` is answered terse)
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
        command = self._command
        assert command is not None
        if command.line:
            return self._line_char(ch)
        if ch not in _WHITESPACE:
            if not self._token and command.numbers and self._watch:  # rule 1: as commands too
                self._sub, self._sub_stopped = RequestParser(watch=False), False
            if len(self._token) < _MAX_TOKEN:
                self._token.append(ch)
                if self._stops(ch):  # a stop at once; the command still takes its
                    self._stop_next = True  # arguments as rotctld does
            elif self._token[-1] != OVERLONG:  # no number: kept as one argument, refused
                self._token.append(OVERLONG)
            return None
        if self._token:
            token = "".join(self._token)
            if self._stops(" "):  # (a name such as ``\\stop`` ends with the token)
                self._stop_next = True
            elif self._watch and not command.numbers and _STOP_WORD.fullmatch(token):
                self._stop_next = True  # rule 1: a word that is a stop
            overlong = self._token[-1] == OVERLONG
            self._args.append(OVERLONG if overlong else token)
            self._token, self._sub = [], None
            if len(self._args) == 1 and token.startswith("?"):  # rotctld reads no more after
                self._args += [""] * (command.nargs - 1)  # a first argument asking what it takes
            if len(self._args) == command.nargs:
                return self._emit()
        return None

    def _line_char(self, ch: str) -> Request | None:
        """send_cmd's argument (rule 3): the rest of the line up to LF, as rotctld's fgets
        reads it (a CR or a space is part of it); a rest with nothing at all in it is read
        again, once, the next line then the argument. Rule 1: a line that is a stop and nothing
        else stops at once."""
        if ch != "\n":
            if len(self._token) < _MAX_TOKEN:
                self._token.append(ch)
            return None
        raw = "".join(self._token)
        self._token = []
        if not raw and not self._reread:
            self._reread = True
            return None
        line = raw.strip()
        if self._watch and _STOP_WORD.fullmatch(line):
            self._stop_next = True
        self._args.append(line)
        return self._emit()

    def _emit(self) -> Request:
        assert self._command is not None
        request = Request(self._command, tuple(self._args), self._extended, self._sep)
        self._clear()
        return request


def holds_stop(data: bytes) -> bool:
    """Whether the commands ``data`` completes hold a stop the session carries out (before a
    quit, which ends the connection first): interfaces/tcplines.py rule 5, a connection with
    one goes ahead of its address's budget."""
    for item in RequestParser().feed(data):
        if isinstance(item, Quit):
            return False
        if item.command.name == "stop":
            return True
    return False
