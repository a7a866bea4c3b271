"""Opening a controller's serial port, the way a long-running service must.

Rules:
1. Ports are opened by path, ideally a stable /dev/serial/by-id/... link, so a replugged adapter
   that comes back as another ttyUSB is found again.
2. ``exclusive=True``: two programs on one tty silently steal each other's bytes; a held port is
   a clear "port busy" error instead (pyserial uses flock on POSIX).
3. Junk already waiting (the 0xE0 power-on byte, a banner) is drained right after opening.
4. Every failure is a PortError with a message a user can act on; nothing here retries or
   sleeps: the worker owns back-off.
5. Listing the machine's ports (``rotor-bridge ports``) is here too: the engine is the only
   layer that imports pyserial.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias

import serial
from serial.tools import list_ports

from bridge.protocols.base import ModelSpec


class PortError(Exception):
    pass


# what opens a port: open_port, or a test's stand-in (path, spec, baud or the model's)
PortOpener: TypeAlias = Callable[[str, ModelSpec, int | None], serial.Serial]


_PARITY = {"N": serial.PARITY_NONE, "E": serial.PARITY_EVEN, "O": serial.PARITY_ODD}


def open_port(path: str, spec: ModelSpec, baud: int | None = None) -> serial.Serial:
    try:
        port = serial.Serial(
            port=None,
            baudrate=baud or spec.baud,
            bytesize=spec.bytesize,
            parity=_PARITY[spec.parity],
            stopbits=spec.stopbits,
            timeout=0,  # the worker selects on the fd and reads what is there
            write_timeout=2.0,
            xonxoff=False,
            rtscts=False,
            dsrdtr=False,
            exclusive=True,
        )
        port.port = path
        port.open()
    except serial.SerialException as exc:
        raise PortError(_explain(path, exc)) from None
    except (OSError, ValueError) as exc:
        raise PortError(f"cannot open {path}: {exc}") from None
    try:
        port.reset_input_buffer()
    except (serial.SerialException, OSError) as exc:
        port.close()
        raise PortError(f"cannot flush {path}: {exc}") from None
    return port


def _explain(path: str, exc: serial.SerialException) -> str:
    text = str(exc)
    err = getattr(exc, "errno", None)
    if err == errno.ENOENT or (not os.path.exists(path) and "No such file" in text):
        return f"{path} does not exist (adapter unplugged? see `rotor-bridge ports`)"
    if err == errno.EACCES or "Permission denied" in text:
        return f"no permission to open {path} (add the user to the 'dialout' group)"
    if "exclusively lock" in text or err in (errno.EAGAIN, errno.EWOULDBLOCK):
        return f"{path} is busy: another program holds it (rotctld, another bridge?)"
    return f"cannot open {path}: {text}"


BY_ID_DIR = "/dev/serial/by-id"


@dataclass(frozen=True)
class PortInfo:
    device: str
    stable_path: str | None  # the /dev/serial/by-id link to it (rule 1), if there is one
    description: str
    vid: int | None
    pid: int | None
    serial_number: str | None


def list_serial_ports() -> list[PortInfo]:
    """The machine's serial ports, sorted by device path (rule 5)."""
    by_id: dict[str, str] = {}
    if os.path.isdir(BY_ID_DIR):
        for name in sorted(os.listdir(BY_ID_DIR)):
            link = os.path.join(BY_ID_DIR, name)
            by_id[os.path.realpath(link)] = link
    return [
        PortInfo(
            device=p.device,
            stable_path=by_id.get(os.path.realpath(p.device)),
            description=p.description,
            vid=p.vid,
            pid=p.pid,
            serial_number=p.serial_number,
        )
        for p in sorted(list_ports.comports(), key=lambda p: p.device)
    ]
