"""The files the settings name (TLS certificates and key, the MQTT password file), checked once.

settings/'s validators call these, so a file that will not do is a configuration error at
start, worded for the user, and not a traceback when the MQTT client first reads it.

Rules:
1. A file is read the way its user will read it: the TLS files through an ssl context as paho's
   tls_set loads them, the password file as text with its line ending stripped and a leading
   byte-order mark dropped (attack 28: a file PowerShell 5 or an old Notepad saved as "UTF-8"
   starts with U+FEFF, which no one types; taken as the password's first character, the
   broker refused the login and the console said "wrong password" to the right one), as
   every MQTT payload's words drop one (interfaces/mqtt/payloads.py ``_words``).
2. Every problem is a ValueError naming the setting and the path (pydantic turns it into one
   line of the configuration error), an OSError's too (pydantic lets those through, as a
   traceback); nothing is changed when one is raised.
3. Secrets never appear in a message: the password is returned, never quoted; a key is never
   decrypted (an encrypted key is an error, or OpenSSL would ask on a terminal there is not).
4. A password file is a regular file (or a pipe: ``<(pass show mqtt)``), of which at most
   PASSWORD_FILE_MAX bytes are read, its kind and mode looked at before a byte is read (an
   attack pass: ``/dev/zero`` ended check-config and run in a MemoryError traceback, a FIFO
   that nothing wrote to held them for ever, and a file every user may read was read all the
   same before it was refused).
5. A password file this user may not read says who this user is and what to do: check-config
   run by hand as oneself on the service's file (root:rotor-bridge, 640) said "Permission
   denied" alone (a first-hour review). ``pwd`` is looked up only then: the remote runs on
   Windows (docs/deployment.md), which has none, and every command died importing it.
"""

from __future__ import annotations

import os
import ssl
import stat
from pathlib import Path

from bridge.core.text import shown_path

# rule 4: the most of a password file read (MQTT's longest password is 64 KiB: a longer one is
# still read whole, to be refused with its length)
PASSWORD_FILE_MAX = 1024 * 1024


def _every_user(key: str, path: Path) -> str:
    """Why a secret's file (``key``'s) every user may read is refused, and the fix."""
    return (
        f"{key} {shown_path(path)} is readable by every user; let only the user that runs "
        "rotor-bridge read it (chmod 600; for the service: chown root:rotor-bridge, chmod 640)"
    )


def _may_not_read(path: Path, exc: OSError) -> str:
    """Rule 5: a password file this user may not read, and what to do."""
    try:
        import pwd  # (rule 5: not at the top, Windows has none)
    except ImportError:  # Windows: no uid; the name its shell gives
        who = os.environ.get("USERNAME") or "this user"
    else:
        try:
            who = pwd.getpwuid(os.getuid()).pw_name
        except KeyError:  # a uid with no name (docker run --user 1000)
            who = f"uid {os.getuid()}"
    return (
        f"password_file {shown_path(path)}: {exc.strerror} for user {who}; run rotor-bridge as "
        "the user that may read it (the service's file: sudo, or as rotor-bridge), or let this "
        "user read it (chmod 600 and chown to it)"
    )


def check_tls_files(ca_file: Path | None, cert_file: Path | None, key_file: Path | None) -> None:
    """Raise ValueError unless the files exist, can be read and load as the MQTT client will."""
    if (cert_file is None) != (key_file is None):
        raise ValueError("cert_file and key_file go together")
    for name, f in (("ca_file", ca_file), ("cert_file", cert_file), ("key_file", key_file)):
        if f is None:
            continue
        try:  # (is_file raises but for a missing file: a folder it may not enter, a name too
            if not f.is_file():  # long ended check-config in a traceback, an attack pass)
                raise ValueError(f"{name} {shown_path(f)} is not a readable file")
            every = os.name == "posix" and f.stat().st_mode & stat.S_IROTH
            if name == "key_file" and every:  # (Windows: no such bits, a review)
                raise ValueError(_every_user("key_file", f))  # (a private key: a secret too)
            f.open("rb").close()
        except OSError as exc:
            raise ValueError(f"{name} {shown_path(f)}: {exc.strerror}") from None
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    if ca_file is not None:
        try:
            context.load_verify_locations(cafile=str(ca_file))
        except ssl.SSLError as exc:
            raise ValueError(
                f"ca_file {shown_path(ca_file)} holds no PEM certificate ({_ssl_reason(exc)})"
            ) from None
    if cert_file is not None and key_file is not None:

        def no_passphrase() -> bytes:  # rule 3
            raise ValueError(f"key_file {shown_path(key_file)} is encrypted: it must not be")

        try:
            context.load_cert_chain(cert_file, key_file, password=no_passphrase)
        except ssl.SSLError as exc:
            raise ValueError(
                f"cert_file {shown_path(cert_file)} and key_file {shown_path(key_file)} are "
                "not a PEM "
                f"certificate and its key ({_ssl_reason(exc)})"
            ) from None


def _ssl_reason(exc: ssl.SSLError) -> str:
    return exc.reason or str(exc.strerror or exc).split(" (_ssl.c")[0]


def read_password_file(path: Path) -> str:
    """The password in `path`; ValueError if it cannot be read, is no regular file or pipe
    (rule 4), is larger than PASSWORD_FILE_MAX or every user may read it."""
    # (O_NONBLOCK: a FIFO's open waits for a writer that never comes; O_BINARY: Windows)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except PermissionError as exc:
        raise ValueError(_may_not_read(path, exc)) from None
    except OSError as exc:
        raise ValueError(f"password_file {shown_path(path)}: {exc.strerror}") from None
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISFIFO(mode):  # a pipe given it (<(...)): read to its end, as before
            os.set_blocking(fd, True)  # (none writing: an end at once, "it holds nothing")
        elif not stat.S_ISREG(mode):
            raise ValueError(
                f"password_file {shown_path(path)} is not a file (a directory or a device): "
                "write the password in a file of its own"
            )
        if mode & (stat.S_IROTH | stat.S_IWOTH):
            raise ValueError(_every_user("password_file", path))
        data = b""
        while len(data) <= PASSWORD_FILE_MAX:
            chunk = os.read(fd, PASSWORD_FILE_MAX + 1 - len(data))
            if not chunk:
                break
            data += chunk
    except OSError as exc:
        raise ValueError(f"password_file {shown_path(path)}: {exc.strerror}") from None
    finally:
        os.close(fd)
    if len(data) > PASSWORD_FILE_MAX:
        raise ValueError(
            f"password_file {shown_path(path)} is larger than {PASSWORD_FILE_MAX // 1024} KiB: "
            "it holds one line, the password"
        )
    try:
        text = data.decode()
    except UnicodeDecodeError:
        raise ValueError(f"password_file {shown_path(path)} is not UTF-8 text") from None
    return text.removeprefix("\ufeff").strip("\r\n")  # rule 1: a BOM is no part of it
