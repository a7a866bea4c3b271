"""A Hamlib rotctld-compatible TCP port onto one rotator, beside MQTT.

Gpredict, loggers and Hamlib's own network client (``rotctl -m 2``) speak rotctld's text
protocol. Here they reach the same Rotator as MQTT does: the same mailbox, limits, safety lock
and status. Source: Hamlib 4.5.4's rotctld (rotctl_parse.c); every reply's bytes were compared
with what rotctld 4.5.4 itself sends.

Rules:
1. Input is a character stream, as rotctld reads it: a one-character command or ``\\long_name``,
   optionally prefixed by ``+`` or one punctuation character (extended replies, that character
   as separator) with the command's first character right after it (a blank there is, to
   rotctld, the unknown command ' ', and the prefix is forgotten: ``+ p`` is answered terse),
   then whitespace-separated arguments; CR and LF are plain whitespace, so a
   command still waiting for arguments takes them from the following lines. ``#`` comments out
   the rest of the line. ``q``/``Q`` closes the connection. One departure, towards the safe
   side: an argument that would be a stop as a command (``S``, ``\\stop``, ``+S``, ``;S``, ...)
   where a number is awaited (``P 200``, then ``S`` on the next line) is carried out as a stop
   at once (an argument read as commands by a parser of its own, one level deep: ``pS`` and
   ``;;S`` stop too; where a word is awaited, a word that is a stop and nothing else), and
   answered first; the command still takes it as its argument, as rotctld does, and is
   refused when whole (so ``P S K`` stops and parks nothing): rotctld takes it as the argument
   alone, and the stop a client typed after a command left short was lost. An argument longer
   than any number is kept as one, and refused, as rotctld would (not dropped with its line:
   the next line then ran as commands). As rotctld, a first argument beginning with ``?``
   (asking what the command takes) is the command's last.
2. A command runs only once it is complete (its last argument followed by whitespace). What a
   client leaves unfinished when it disconnects is dropped: it never moves anything.
3. Unknown commands get no reply at all (rotctld logs them on its own stderr and says nothing).
   rotctld's commands the bridge does not carry out (``V``/``v`` levels, ``U``/``u``, ``X``/``x``,
   ``w`` send_cmd, the locator and great-circle helpers, ``\\pause``) are read as rotctld reads
   them and answered "not available": their arguments are theirs (``send_cmd`` takes the rest
   of the line up to LF, the next line if it has nothing at all on it, as rotctld's fgets), never
   commands of their own (``w P 20 30`` once turned the rotor). ``M`` (move) and ``R`` (reset)
   are not carried out either: "not available" once their arguments are what rotctld takes (a
   direction by name, ``LEFT``, ``CCW``, ``RIGHT``, ``CW``, ``UP``, ``DOWN``, or a leading
   integer, as C's ``%d`` reads ``8x``), else "invalid" (``M x 5``), as rotctld answers.
4. Every reply goes out in one send: Gpredict reads ``p`` with a single recv().
5. ``p`` answers from the bridge's status (no serial traffic). A position the bridge does not
   currently have is an error code, never the last value seen. The clockwise end of a scale
   that wraps is ``360.00`` (the true bearing ``P 360`` sends it to, pointing.py rule 2), as
   Hamlib's GS-232, Easycomm, SatEL, Prosistel and RC2800 backends read it; ``0.00`` named the
   other end, a whole turn back. The models whose Hamlib backend reads 360 as 0 (the Rotor-EZ
   family, the RT-21: ``ModelSpec.hamlib_folds_360``) answer ``0.00`` there, as it does.
6. Motion goes through Rotator.submit with Source.ROTCTLD, so the lock, the limits and the link
   state are judged in one place and MQTT shows the refusal or the move. A ``P`` whose
   arguments are no numbers (``nan``, ``inf``, ``12x``) is answered ``RPRT -1`` and said on
   ``R/error`` too, as the GS-232 ports say theirs (package gs232 rule 12).
7. A connection that speaks HTTP is closed at once with a warning and nothing it sent runs
   (interfaces/tcplines.py rule 2): rotctld parses any bytes as commands, so a web page open on the
   shack PC could otherwise turn the antenna through a loopback port (a ``POST`` body of ``P 200
   0``; ``KHTML`` in a browser's User-Agent read as park).
8. A client is disconnected when it sends nothing for ``rotctld_idle_timeout_s`` (300 s), or
   leaves a command unfinished for 60 s (interfaces/tcplines.py rule 3). The sockets and threads are
   the shared line server's (interfaces/tcplines.py); this package owns what the bytes mean.
"""

from bridge.interfaces.rotctld.commands import RotctldCommands
from bridge.interfaces.rotctld.parser import QUIT, Request, RequestParser
from bridge.interfaces.rotctld.server import RotctldServer

__all__ = ["QUIT", "Request", "RequestParser", "RotctldCommands", "RotctldServer"]
