"""Attack 21, a hostile neighbour on the LAN, at the console's port: a file name that holds a
line break. Real parts: the bridge in this process on an emulated Rotor-EZ (pty), a real
mosquitto, the console with a password (as one on the LAN has).

The finding: ``GET /a%0ab`` (no token, no password; or an ``<img>`` on any page the operator
opens, pointed at the console) is a 500 Internal Server Error, and the log gets "Error handling
request" at ERROR with its traceback: server.py ``_serve`` names the file it did not find in
the 404's reason, ``web.HTTPNotFound(reason=f"no {name}")``, and aiohttp refuses a reason
holding CR or LF with a ValueError (the name is the path percent-decoded). Every other name
not found is a 404 saying which; attack passes 3 to 5 made every other request a client could
get wrong a 4xx with no traceback (server.py rule 7).
"""

from __future__ import annotations

import logging

import pytest

from bridge.interfaces.web import server
from tests.support.console import ConsoleClient
from tests.support.rig import Rig


@pytest.mark.parametrize("path", ["/a%0ab", "/%0d%0aX-Evil:%201"])
def test_a_file_name_holding_a_line_break_is_a_404_not_a_500(
    guarded: tuple[Rig, ConsoleClient], caplog: pytest.LogCaptureFixture, path: str
) -> None:
    """No such file: 404, as for any name the console does not serve, and nothing at ERROR,
    no traceback."""
    _rig, client = guarded
    caplog.set_level(logging.DEBUG, logger=server.http_log.name)  # (past the noise limit too)
    answer = client.get(path)
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert answer.status == 404, answer
    assert not loud, [f"{r.levelname} {r.getMessage()}" for r in loud]
