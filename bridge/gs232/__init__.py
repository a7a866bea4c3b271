"""Yaesu GS-232B and Easycomm II on TCP ports and pseudo-terminals onto one rotator, beside
rotctld: for programs that drive a rotator controller over a serial line (PstRotator, loggers,
satellite trackers, Hamlib's ``rotctl -m 603`` and ``-m 202``). Every move goes through the
same judge as MQTT and rotctld.

Protocol facts relied on, from Hamlib 4.5.4's backends (rotators/gs232a/gs232b.c,
rotators/easycomm/easycomm.c, rotators/easycomm/easycomm.txt), which are the judge in the tests:

- GS-232B (``rotctl -m 603``): commands end with CR; set position is ``Waaa eee`` (integers,
  zero-padded to three digits, a negative azimuth sent +360) followed by CR twice; stop is ``S``;
  a manual move is ``X1``..``X4`` (speed) then ``L``/``R``/``U``/``D``. Hamlib reads no reply to
  any of these, and empties its input before every command. Reading is ``C2``: it reads up to LF
  and takes ``AZ=%d EL=%d`` with any spacing (at least 10 characters); a reply that starts with
  ``?`` or holds ``>`` (the ``?>`` prompt) is an error, retried up to 3 times. Its serial
  backends accept ``-r 127.0.0.1:PORT`` as a TCP address (src/rotator.c, rot_open).
- Easycomm II (``rotctl -m 202``): commands end with LF; set position ``AZ%.1f EL%.1f``, stop
  ``SA SE ``, park ``PARK``, reset ``RESET``, moves ``ML``/``MR``/``MU``/``MD``, no reply read to
  any of them; reading is ``AZ EL `` answered with one line up to LF, taken as ``AZ%f EL%f``
  (anything else is "rejected"). The protocol's controller-to-host ``ALxxx`` is an alarm.

Rules:
1. Lines end at CR or LF; empty lines are nothing (Hamlib's ``W`` ends with CR CR). A line longer
   than any command is junk: GS-232 answers it with the error prompt, Easycomm with an alarm.
2. GS-232B: ``C`` (``AZ=aaa``), ``B`` (``EL=eee``) and ``C2`` (``AZ=aaa  EL=eee``) answer with
   CR LF; ``Maaa`` and ``Waaa eee`` set; ``S``, ``A`` and ``E`` stop. Anything else, a refused
   target and a position the bridge does not have answer ``?>`` CR LF; an accepted command
   answers nothing.
3. Easycomm II: a line's words are read together; ``AZ`` and ``EL`` without a number are
   questions, answered in one line in the order asked (``AZ120.0 EL0.0``), ``VE`` with
   ``VErotor-bridge``; ``AZx``/``ELy`` set (the axis left out keeps its target), ``SA``/``SE``
   stop, ``PARK`` parks. A malformed number makes the whole line do nothing. Refusals, moves
   it cannot do and a position it does not have are answered with an ``AL`` line; a radio's
   words (``UP``, ``DN``, ...) are ignored.
4. Readings come from the rotator's status (no serial traffic): true bearings, as rotctld's
   ``p`` answers, in 0..360, and 0 elevation on an azimuth-only rotator. A position the bridge
   does not currently have is an error, never the last value seen.
5. Targets go through Rotator.submit with Source.GS232 / Source.EASYCOMM: the lock, the limits,
   keep-out sectors and the link are judged there and a refusal is published on ``R/error``.
   Elevation 0 to an azimuth-only rotator is no elevation (Hamlib always sends one). Every
   command carries who sent it (model.Origin, for the audit trail and the control lease): the
   TCP client's address; a pty has none.
6. A stop is never refused by the bridge; ``A`` (azimuth) and ``E`` (elevation) stop the whole
   rotator, more than asked but never less. A line that stops does nothing else. On the remote
   (remote/rotator.py) a stop that cannot be delivered (its broker away) is answered as a
   refusal is: ``?>``, ``ALrefused offline``.
7. The sockets, threads, idle timeout, HTTP refusal and budgets are the shared line server's
   (tcplines.py), the pty, its link and its thread the pty server's (ptylines.py); this
   package owns what the bytes mean, and cuts lines in time linear in the bytes.
8. The pty server is imported only when a pty is asked for: it needs a POSIX system, and the
   remote, which imports this package, also runs where there is none (a TCP port only).
"""

from bridge.gs232.commands import (
    EasycommSession,
    Gs232Session,
    Rotator,
    easycomm_pty,
    easycomm_server,
    gs232_pty,
    gs232_server,
)

__all__ = [
    "EasycommSession",
    "Gs232Session",
    "Rotator",
    "easycomm_pty",
    "easycomm_server",
    "gs232_pty",
    "gs232_server",
]
