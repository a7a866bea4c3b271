"""Yaesu GS-232A/B, Easycomm II and DCU-1 / Rotor-EZ on TCP ports and pseudo-terminals onto one
rotator, beside rotctld: for programs that drive a rotator controller over a serial line
(PstRotator, loggers, satellite trackers, DXView and the Windows loggers that speak DCU-1,
Hamlib's ``rotctl -m 603``, ``-m 601``, ``-m 202`` and ``-m 401``/``-m 403``). Every move goes
through the same judge as MQTT and rotctld.

Protocol facts relied on, from Hamlib 4.5.4's backends (rotators/gs232a/gs232b.c,
rotators/easycomm/easycomm.c, rotators/easycomm/easycomm.txt), which are the judge in the tests:

- GS-232B (``rotctl -m 603``): commands end with CR; set position is ``Waaa eee`` (integers,
  zero-padded to three digits, a negative azimuth sent +360) followed by CR twice; stop is ``S``;
  a manual move is ``X1``..``X4`` (speed) then ``L``/``R``/``U``/``D``. Hamlib reads no reply to
  any of these, and empties its input before every command. Reading is ``C2``: it reads up to LF
  and takes ``AZ=%d EL=%d`` with any spacing (at least 10 characters); a reply that starts with
  ``?`` or holds ``>`` (the ``?>`` prompt) is an error, retried up to 3 times. Its serial
  backends accept ``-r 127.0.0.1:PORT`` as a TCP address (src/rotator.c, rot_open).
- GS-232A (``rotctl -m 601``): the same commands; reading is ``C2``, read up to LF and taken
  as ``+0%d+0%d`` (ARSVCOM and PstRotatorAz set to GS-232A read ``C`` as ``+0nnn``).
- DCU-1 / Rotor-EZ (rotators/rotorez/rotorez.c, rotorez.txt; ``rotctl -m 401`` Rotor-EZ, ``402``
  RotorCard, ``403`` DCU-1): no line ends; ``AP1ddd;`` stores a bearing (exactly three digits,
  000..360), ``AM1;`` turns to it, ``AP1ddd`` CR stores and turns; ``AI1;`` is answered with
  exactly four bytes ``;ddd`` (000..359; Hamlib reads four bytes, a reply not starting ``;``
  makes it flush and ask again, no answer is a timeout error); ``;`` stops (401, 402), and so
  does ``AS1;`` (403, whose ``R`` reset sends ``;``); single letters ``E e J j O o S s`` set
  options (``S`` is "unstick on", not stop). After an invalid command the Idiom board prints
  ``C2000 IDIOM V1.4S `` (also its answer to ``V``). DXView, DXbase, WriteLog and Win-EQF
  speak this at 4800 8N1.
- Easycomm II (``rotctl -m 202``): commands end with LF; set position ``AZ%.1f EL%.1f``, stop
  ``SA SE ``, park ``PARK``, reset ``RESET``, moves ``ML``/``MR``/``MU``/``MD``, no reply read to
  any of them; reading is ``AZ EL `` answered with one line up to LF, taken as ``AZ%f EL%f``
  (anything else is "rejected"). The protocol's controller-to-host ``ALxxx`` is an alarm.

Rules:
1. Lines end at CR or LF; empty lines are nothing (Hamlib's ``W`` ends with CR CR). A line longer
   than any command is junk: GS-232 answers it with the error prompt, Easycomm with nothing
   (rule 3).
2. GS-232B: ``C`` (``AZ=aaa``), ``B`` (``EL=eee``) and ``C2`` (``AZ=aaa  EL=eee``) answer with
   CR LF; ``Maaa`` and ``Waaa eee`` set; ``S``, ``A`` and ``E`` stop. Anything else, a refused
   target and a position the bridge does not have answer ``?>`` CR LF; an accepted command
   answers nothing. With GS-232A replies (``gs232_replies = "A"``) the readings are ``+0aaa``,
   ``+0eee`` and ``+0aaa+0eee``; everything else is the same.
3. Easycomm II: a line's words are read together; ``AZ`` and ``EL`` without a number are
   questions, answered in one line in the order asked (``AZ120.0 EL0.0``), ``VE`` with
   ``VErotor-bridge``; ``AZx``/``ELy`` set (the axis left out keeps its target), ``SA``/``SE``
   stop, ``PARK`` parks. A malformed number, or an axis given twice (``AZ190 AZ200``: which
   is meant?), makes the whole line do nothing but stop (rule 6: ``SA AZ1x`` stops). Only a
   line that asks something is answered, with one line: its answers, ``ALposition unknown``
   when the bridge does not have the position, ``ALinvalid <word>`` when the line is
   malformed. A line that asks nothing is answered with nothing, also when it is refused, a
   move the bridge cannot do (``ML``, ``RESET``) or malformed: Hamlib's ``-m 202``/``-m 204``
   read no reply to a set, stop, park, reset or move, and took such an alarm line as the next
   ``AZ EL``'s answer (the tracker's next ``p`` failed, "Command rejected by the rig"). What
   was refused or not carried out is said on ``R/error`` (rules 5 and 12). Words are
   separated by ASCII spaces and tabs alone. A radio's words (``UP000``, ``XXX``, ...) and an
   Easycomm III word the bridge does not serve (``GS``) are ignored: a word it does not know
   is ignored only when it is letters, digits and points; any other is malformed
   (``\x1fAZ200.0``, ``AZ200.0;``: dropped as a radio's word, it left ``EL30.0`` beside it to
   turn the elevation alone). One ``;`` that starts a line is no word of it: Hamlib's ``-m 204``
   ends its configuration commands with ``\n;`` (``GS\n;``), which puts it in front of its
   next line, ``;AZ200.0 EL30.0`` or ``;AZ`` (a review: refused as malformed, Hamlib's own
   move did nothing and its next ``p`` failed).
4. Readings come from the rotator's status (no serial traffic): true bearings, as rotctld's
   ``p`` answers, in 0..360, and 0 elevation on an azimuth-only rotator; a GS-232 or Easycomm
   client whose last accepted bearing was past 360 (``W400``, ``AZ400.0``: a 450-degree
   controller's overlap) reads the bearing unfolded, past 360 where the rotor is there
   (``AZ=400``, ``AZ400.0``), as rotctld's ``p`` answers a client that named the side: read
   back as 040, its rotor seemed 360 degrees short of the target it had reached (a review:
   the Easycomm port still read it back so). The clockwise end of a scale that wraps reads
   360 (``AZ=360``, ``AZ360.0``), as a GS-232B or an Easycomm box there answers and as
   ``W360`` sends it there (pointing.py rule 2); it read ``000``, the other end. A position
   the bridge does not currently have is an error, never the last value seen.
5. Targets go through Rotator.submit with Source.GS232 / EASYCOMM / DCU1: the lock, the limits,
   keep-out sectors and the link are judged there and a refusal is published on ``R/error``.
   Elevation 0 to an azimuth-only rotator is no elevation (Hamlib always sends one). Every
   command carries who sent it (model.Origin, for the audit trail and the control lease): the
   TCP client's address; a pty has none.
6. A stop is never refused by the bridge; ``A`` (azimuth) and ``E`` (elevation) stop the whole
   rotator, more than asked but never less. A line that stops does nothing else. On the remote
   (remote/rotator.py) a stop that cannot be delivered (its broker away) is answered as a
   refusal is: ``?>``, nothing on Easycomm (rule 3: the log says it), the DCU-1's banner.
7. The sockets, threads, idle timeout, HTTP refusal and budgets are the shared line server's
   (interfaces/tcplines.py), the pty, its link and its thread the pty server's
   (interfaces/ptylines.py); this package owns what the bytes mean, and cuts lines in time linear in
   the bytes.
8. The pty server is imported only when a pty is asked for: it needs a POSIX system, and the
   remote, which imports this package, also runs where there is none (a TCP port only).
9. DCU-1 input (parser.Dcu1Reader): a frame opens at ``A`` and ends at ``;`` or CR, a seventh
   byte without an end makes it invalid; outside a frame each byte is a command (``;`` stop,
   an option letter, ``V``), CR and LF are nothing, a run of anything else is one invalid
   command. A ``;`` always stops: alone, or ending a frame that is no command (a torn one, a
   bearing past 360), whose ``;`` may have been the stop; a stop goes first, before anything
   else of its frame is answered. Junk never turns anything.
10. DCU-1 commands: ``AP1ddd;`` keeps the bearing and turns nothing; ``AM1;`` turns to it once,
    if it was kept within DCU1_STORED_S (1 s: the programs send both together; a pty outlives
    its clients and cannot tell one from the next, so a bearing one left must not be the
    next one's), and if no STOP or lock ON (from any interface, this client's ``;`` too) came
    after it: a bearing given before a STOP is never turned to after it (docs/architecture.md
    rule 11; review 102: the clock alone let an ``AM1;`` after an operator's STOP turn the
    rotor to the ``AP1``'s bearing). "After it" is after its bytes came, not after it was
    read: the halts are those of the look that held its bytes (tcplines.py rule 9, ``Fence``;
    ptylines.py for a pty), and a halt not this client's own counted between that look and
    the ``AP1``'s read overtook it (attack 11: a client paused over its byte budget had its
    ``AP1200;`` read after an MQTT STOP sent after it, and its ``AM1;`` turned the rotor to
    200); else it is refused on ``R/error`` and turns nothing;
    ``AP1ddd`` CR
    turns at once; a bearing of 000 is north, a direction (the protocol has no 360: Hamlib
    sends 360 as ``AP1000;``), so it goes to whichever end of the travel is nearer where
    0 and 360 are both (``Target.az_either_end``, pointing.py rule 2; attack 17: a Yaesu
    behind a GS-232 at 355 asked for north was sent ``M000`` and turned back through south);
    ``AI1;`` (or ``AI1`` CR) answers ``;ddd``, the true bearing rounded to a
    whole degree, 360 as 000, and nothing while the bridge does not have it (Hamlib's
    ``-m 401`` would otherwise ask for ever); the options are taken and change nothing (the
    station's own are set on ``R/option``). An invalid command, a refused move and a stop the
    remote cannot deliver are answered with the banner; a stop itself is never answered (a
    real board prints the banner for a ``;`` while still, which only makes Hamlib flush).
11. The protocols offered are one table, commands.EMULATIONS (key, session, the parser's
    look for a stop that lets a connection ahead of the accept budget, ends, the one-byte
    commands that move nothing and so go before the first line's end: tcplines rule 2): the
    station (app.py) and the remote (remote/run.py) make every port and pty from it, and
    the settings' keys (settings_rotator.EMULATION_KEYS) name the same ones.
12. A line that is no command the bridge carries out (GS-232's ``?>``: one it does not know,
    one too long; an Easycomm line with a malformed word, or a word it cannot do, ``ML`` or
    Easycomm III's ``VL0050``; a
    DCU-1 command that is none) is said on ``R/error`` and in the log too, with what was
    sent (rate-limited there, as every refusal is; not in the audit trail, which is not, and
    which it would flood: it is no command), besides the protocol's answer (an
    attack pass: ``M180.5``, ``AZnan``, ``AP1999;`` were answered on the wire alone, and the
    client's user never learnt why nothing moved). Blanks around a line are ASCII's alone:
    ``\x1fM180`` is no ``M180``.
"""

from bridge.interfaces.gs232.commands import (
    EMULATIONS,
    Dcu1Session,
    EasycommSession,
    Emulation,
    Gs232Session,
    Rotator,
    easycomm_pty,
    easycomm_server,
    gs232_pty,
    gs232_server,
)

__all__ = [
    "EMULATIONS",
    "Dcu1Session",
    "EasycommSession",
    "Emulation",
    "Gs232Session",
    "Rotator",
    "easycomm_pty",
    "easycomm_server",
    "gs232_pty",
    "gs232_server",
]
