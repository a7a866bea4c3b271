"""``R/target`` ``{"call": "JA1ABC"}`` (optionally ``"path": "long"``): a target named by a
call sign, resolved by the DX cluster client (interfaces/dxcluster/client.py: the newest spot of the
call, else its cty entity). Pure, beside payloads.py, whose ``parse_aim`` hands JSON with ``call``
here.

Rules:
1. A call is 3 to 20 letters, digits and ``/``, with at least one digit and one letter; it is
   upper-cased. Anything else, or another key beside ``path``, is a PayloadError for the user.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

_CALL = re.compile(r"(?=.*[0-9])(?=.*[A-Z])[A-Z0-9/]{3,20}", re.ASCII)


class CallError(ValueError):
    pass


@dataclass(frozen=True)
class Called:
    call: str
    long_path: bool = False


def parse_called(obj: dict[str, object]) -> Called:
    """Rule 1; CallError (payloads.py turns it into a PayloadError)."""
    unknown = set(obj) - {"call", "path"}
    if unknown:
        raise CallError(f"unknown key(s) in a call target: {', '.join(sorted(unknown))}")
    path = obj.get("path", "short")
    if path not in ("short", "long"):
        raise CallError(f'"path" must be "short" or "long", got {json.dumps(path)[:20]}')
    raw = obj["call"]
    call = raw.strip().upper() if isinstance(raw, str) else ""
    if not _CALL.fullmatch(call):
        shown = json.dumps(raw)[:30]
        raise CallError(f'"call" must be a call sign (3 to 20 letters and digits), got {shown}')
    return Called(call, path == "long")
