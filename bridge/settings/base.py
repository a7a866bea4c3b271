"""The base of every settings table: unknown keys refused, no boolean where a number goes, and
text that is UTF-8 with no NUL in it.

Rules:
1. Every table's model derives from ``Strict`` (the top level, a BaseSettings, calls
   ``plain_value`` itself, on every key as Strict does): an unknown key is an error
   (settings/ rule 1).
2. A key that takes a number (``int`` or ``float``, also with None, or in a list, a tuple or a
   table's values) refuses ``true`` and ``false``: pydantic's lax mode reads them as 1 and 0,
   so ``port = true`` connected to port 1 and ``park_az_deg = true`` parked at 1 degree (an
   attack pass). A number written as text (``"60"``, what the environment gives) is still read
   as one; a key that takes a boolean as well is left alone.
3. No text holds a NUL byte, a path's above all (``state_file``, ``audit_file``, a TLS or
   password file, a TLE or cty file, a pty's link): none can, and a NUL ended check-config in a
   traceback, or named no key (a review). Nor a lone surrogate, what Python makes of a byte
   from the environment that is not UTF-8: a name with one broke its rotator's Home Assistant
   discovery (a JSON parser refuses it), a bind address ended ``run`` in a traceback, a path
   named in an error ended check-config in one (reviews). So every value, a path's too, is
   UTF-8 text (a Linux path may be other bytes: the bridge names its paths in its messages and
   on MQTT, and takes none that is not). The configuration file's own path and the home folder
   are no keys: they may be any bytes; a path in the home folder is judged as the ``~/...``
   it reads as (``beyond_home``, by rules 3 and 6), so a serial port or pty written so is
   taken there, and settings read again (check-config --full's, the stop express's) load.
4. A path given empty (``audit_file = ""``, or ``ROTOR_BRIDGE_AUDIT_FILE=`` from a variable
   left unset) is an error: pydantic reads it as ``.``, the current folder (an attack pass: an
   empty audit_file passed check-config, and every line was lost at run; an empty password
   file was "not a file"). A pty's link too, a text key, here and not by pydantic's
   ``min_length``: that refused a path in a home folder whose name is not UTF-8 (rules 3, 7).
5. A name a person reads (a rotator's, a group's: ``check_name``) is 1 to NAME_MAX characters
   MQTT carries, without blanks at either end: an attack pass gave a rotator the name
   ``"HF\nconfig OK: ..."`` with a terminal's escape sequence, and check-config printed a forged
   line in its summary and turned the terminal red; a blank name gave Home Assistant a device
   with no name.
6. A path (a file's, a serial port's, a pty's: ``check_named_path``) and a bind address (the
   keys ``*bind`` and ``*_pty`` are text) hold no control character: an attack pass gave a
   serial port the name ``"/dev/ttyX\nconfig OK: ..."`` and check-config's report and its
   warning printed a forged line (the log at run too); a pty's path and a bind address
   likewise. (Other text keys judge their own text, with their own words.)
7. A path that begins with ``~`` (``~/...``, ``~user/...``) is the home folder's, as a shell
   reads it, for every key that takes a path: an attack pass wrote ``state_file`` as the
   docs write its default, ``~/.local/state/...``, and the bridge kept its state and its lock
   under a folder named ``~`` of whatever directory it was started from (two runs of one
   installation from two directories both started); a rotator's serial ``port`` too, a text
   key (review 69: ``~/rotor``, a link kept in the service user's home, was never opened);
   a pty's link too, a text key (``*_pty``: the pty server read ``~/`` itself, but a
   ``~user/...`` naming no user passed check-config and was taken as ``./~user/...``, and
   check-config showed ``~/...``). A ``~user`` that names no user here is an error, not a
   folder named so.
8. A refusal names a path as ``shown_path`` spells it: a path in the home folder holds what
   the home folder's name does (rule 3: any bytes), and a byte that is not UTF-8, which Python
   reads as a lone surrogate, in a refusal's text ended check-config and run in a
   UnicodeEncodeError traceback (pydantic cannot hold it), exit 1, where a configuration error
   is exit 2 (the systemd unit restarts after exit 1, for ever). It is escaped as Python's
   stderr, and cli.py's stdout, write it (``\\udce9``). ``shown_path`` is core/text.py's, the
   one spelling of a path in everything the bridge says (R/error, the log, the pty server's
   words: review 76 found the running bridge naming such a port raw on MQTT), not the
   settings' alone; every refusal naming a path uses it, settings/config.py's rules 6 and 7
   too.
9. A value made of parts each judged under its own key (a composite rotator's port of both,
   ``<azimuth's>+<elevation's>``, from its ``azimuth.port`` and ``elevation.port``:
   settings/rotator.py rule 4) is not judged again whole (``Strict.judged_in_parts``): judged
   whole, only its head was the home folder's by rule 3, so an elevation box ``~/el`` in a
   home folder whose name is not UTF-8 was refused as ``port: must be UTF-8 text``, a key the
   file does not give, where the azimuth's box written so was taken (review 76).
"""

from __future__ import annotations

import os
import types
from pathlib import Path
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

from bridge.core.text import NOT_TEXT, bad_char

_NUMBERS = (int, float)
# settings/mqtt.py rule 4, settings/web.py rule 5: why a value holding '@' is not quoted
NOT_SHOWN = "not shown: what comes before it may be a password"
NAME_MAX = 64  # rule 5: a rotator's or a group's name


def check_named_path(v: str) -> str:
    """Rule 6: ``v`` if it is a path the bridge can name in a line of its own; ValueError. The
    home folder's part of it is not judged (rule 3: any bytes, escaped where named: rule 8)."""
    bad = bad_char(beyond_home(v))
    if bad is not None:
        raise ValueError(
            f"holds {bad}, a control character or a non-character: the bridge names its "
            "files and ports in its log and check-config's report, where it would forge a "
            "line of its own"
        )
    return v


def check_name(v: str | None) -> str | None:
    """Rule 5: ``v`` if it is a name to show (None: left out); ValueError naming the fault."""
    if v is None:
        return v
    bad = bad_char(v)
    if bad is not None:
        raise ValueError(f"holds {bad}, {NOT_TEXT}")
    if not v.strip() or v != v.strip() or len(v) > NAME_MAX:
        raise ValueError(f"must be 1..{NAME_MAX} characters without blanks at either end")
    return v


def takes_boolean_for_number(annotation: Any, value: Any) -> bool:
    """Whether ``value`` holds a boolean where ``annotation`` wants a number (rule 2)."""
    origin, args = get_origin(annotation), get_args(annotation)
    if origin is Annotated:
        return takes_boolean_for_number(args[0], value)
    if origin in (Union, types.UnionType):
        if isinstance(value, bool):
            kinds = [get_args(a)[0] if get_origin(a) is Annotated else a for a in args]
            return bool not in kinds and any(k in _NUMBERS for k in kinds)
        return any(takes_boolean_for_number(a, value) for a in args)
    if isinstance(value, bool):
        return annotation in _NUMBERS
    if origin in (list, set, frozenset) and isinstance(value, list | tuple | set):
        return any(takes_boolean_for_number(args[0], v) for v in value)
    if origin is tuple and isinstance(value, list | tuple):
        each = [args[0]] * len(value) if len(args) == 2 and args[1] is ... else args
        return any(takes_boolean_for_number(a, v) for a, v in zip(each, value, strict=False))
    if origin is dict and isinstance(value, dict) and len(args) == 2:
        return any(takes_boolean_for_number(args[1], v) for v in value.values())
    return False


def plain_value(cls: type[BaseModel], value: Any, info: ValidationInfo) -> Any:
    """A before-validator for every field (rules 2 and 3); ValueError names no value."""
    field = cls.model_fields.get(info.field_name or "")
    if field is not None and takes_boolean_for_number(field.annotation, value):
        raise ValueError("must be a number, not true or false")
    named = info.field_name or ""
    if field is not None and issubclass(cls, Strict) and cls.judged_in_parts(named, info):
        return value  # rule 9: each part was judged, under its own key
    if field is not None and value == "" and (_a_path(field.annotation) or named.endswith("_pty")):
        raise ValueError("empty: name a file, or leave the key out")  # rule 4
    # rule 7's paths: the keys that take one, a serial port, a pty's link
    a_path = field is not None and (
        _a_path(field.annotation) or named == "port" or named.endswith("_pty")
    )
    if field is None or not _a_model(field.annotation):
        fault = _text_fault(beyond_home(value) if a_path and isinstance(value, str) else value)
        if fault is not None:
            raise ValueError(fault)
    if field is not None and isinstance(value, str):  # rule 6 (after rule 3's NUL)
        if _a_path(field.annotation) or named.endswith(("bind", "_pty")):
            check_named_path(value)
        if a_path:  # rule 7
            return home_path(value)
    return value


def beyond_home(path: str) -> str:
    """Rule 3: what of ``path`` is not the home folder's (that is any bytes): all of it but
    in the home folder. A path rule 7 put there is judged as the ``~/...`` it was written as,
    and so is the same path read again (what check-config --full prints, the settings the stop
    express is handed: refused as not UTF-8 in a home folder whose name is not)."""
    home = os.path.expanduser("~").rstrip("/")
    if home.startswith("/") and (path == home or path.startswith(home + "/")):
        return "~" + path[len(home) :]
    return path


def home_path(value: str) -> str:
    """Rule 7: ``value``, a path, in the home folder it names if it begins with ``~``."""
    if not value.startswith("~"):
        return value
    home = os.path.expanduser(value)
    if home.startswith("~"):
        user = value[1:].split("/", 1)[0]
        raise ValueError(f"~{user} names no user on this system (a home folder: ~/...)")
    return home


def _text_fault(value: Any) -> str | None:
    """Rule 3: what is wrong with ``value``'s text, or a text in a list or a table of it (a
    table of a model of its own is not looked into here: that model looks, and names its key);
    None. The value is never quoted (a password may be one)."""
    if isinstance(value, str):
        if "\0" in value:
            return "must not hold a NUL byte (no path or name does)"
        try:
            value.encode()
        except UnicodeEncodeError:
            return "must be UTF-8 text: set it again, in UTF-8"
        return None
    if isinstance(value, list | tuple):
        inner = [_text_fault(v) for v in value if not isinstance(v, dict)]
    elif isinstance(value, dict):
        inner = [_text_fault(t) for kv in value.items() for t in kv]
    else:
        return None
    return next((fault for fault in inner if fault is not None), None)


def _a_path(annotation: Any) -> bool:
    """Whether ``annotation`` is a path (also with None)."""
    if get_origin(annotation) in (Union, types.UnionType):
        return any(_a_path(a) for a in get_args(annotation))
    return annotation is Path


def _a_model(annotation: Any) -> bool:
    """Whether ``annotation`` is a settings table of its own (a model, also with None)."""
    if get_origin(annotation) in (Union, types.UnionType):
        return any(_a_model(a) for a in get_args(annotation))
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


class Strict(BaseModel):
    """Rule 1."""

    model_config = ConfigDict(extra="forbid")

    @classmethod
    def judged_in_parts(cls, name: str, info: ValidationInfo) -> bool:
        """Rule 9: whether key ``name``'s value is made of parts each judged under a key of its
        own (the keys validated so far: ``info.data``), so is not judged whole here."""
        return False

    _plain_value = field_validator("*", mode="before")(plain_value)
