"""What `rotor-bridge check-config` prints about valid settings: a summary, the warnings and
(``--full``) every value.

Rules:
1. masked() shows every value the bridge will use, model defaults filled in; null only where
   nothing applies (no elevation axis, no rotctld port, no park position, no credentials).
   What a value means where that is not plain is shown beside it (SHOWN: the station's position
   from its locator, the true bearings a rotator takes); docs/configuration.md lists these too.
2. Secrets never appear: the MQTT password is shown as asterisks, wherever it came from, and
   the summary only says whether there is one; the console's password is no field, so it is
   not in the values at all.
3. A warning is for what is legal but probably wrong; it never makes valid settings invalid.
   The remote, whose file has no check-config, logs its ``[web]`` table's as it starts
   (settings/web.py web_warnings: no POSIX module in it, as the remote runs on Windows too).
4. The summary says what a user checks first: each rotator's model and whether its port is
   there, the broker, and what is on (Home Assistant, the web console, rotctld and loggers'
   ports, the station, tracking). Looking at a port never opens it.
5. The state file is tried as the start tries it (runtime/state_store.py), short of writing:
   what the start would refuse whoever runs it (a directory, a FIFO, a file where a directory
   must be, a link or a FIFO where the installation's lock goes) is an error worded as the
   start's (check_state_file); a directory this user cannot
   write is a warning, since the service may run as another user.
6. Run by hand (no STATE_DIRECTORY) with state_file left out, the summary also says the state
   file the systemd unit would use, and the default client id that goes with it (it hashes the
   state file): check-config run as root before the service starts must not show an id or a
   file the service will not use. On Linux only, and not in a container: a Mac or a container
   has no systemd unit to name (a review).
7. A port that is there but that this user may not read and write is warned about, with the
   group that may (``os.access``: it is not opened). A user the system's files put in that
   group, whose login has not the group yet (added since it logged in), is told to log in
   again, not to join the group it is in (a review). In a container the port keeps the host's
   group number, and that number, for compose's group_add, is what is said (a review: it was
   told to usermod, log in again, and that the systemd unit's user is in dialout). A user id
   with no name (``docker run --user 1000``) is named by its number.
8. Every path printed (a port, a pty's link, the state, audit, TLE and cty files) is spelled
   by ``shown_path`` (core/text.py): a path may be any bytes, a home folder's name above all
   (settings/base.py rule 3), and what is printed is UTF-8 text (review 76).
"""

from __future__ import annotations

import getpass
import grp
import os
import pwd
import re
import stat
import sys
from pathlib import Path
from typing import Any

from bridge.core.readfile import stream_fd
from bridge.core.text import shown_path
from bridge.protocols.axes import Axis
from bridge.runtime.state_store import StateStore
from bridge.settings import ConfigError, RotatorSettings, Settings, state_file_in
from bridge.settings.loggers import is_loopback
from bridge.settings.rotator import EMULATION_KEYS
from bridge.settings.web import web_warnings

# a container's marks (Docker's, Podman's): no systemd unit nor a login there (rules 6, 7)
CONTAINER_MARKS = ("/.dockerenv", "/run/.containerenv")
# the state file under deploy/systemd/rotor-bridge.service (StateDirectory=rotor-bridge)
SERVICE_STATE_FILE = str(state_file_in("/var/lib/rotor-bridge"))
IDENTITY = ("id", "name", "model", "port", "baud", "topic")
# a USB serial adapter's name the kernel gives in the order adapters appear (not by-id, no udev
# link): which controller it reaches can change with a re-plug or a reboot
_NUMBERED = re.compile(r"/dev/tty(?:USB|ACM)\d+")
# what masked() shows besides the keys of the file, and what it means (docs/configuration.md)
SHOWN = {
    "mqtt.client_id": "the client id in use: the one set, or the default made for this "
    "installation",
    "station.position_deg": "[latitude, longitude] of the station, from its locator (the "
    "square's centre) or its coordinates: to check on a map",
    "rotators.az_targets_deg": "[lowest, highest] true bearing this rotator takes as a target: "
    "its azimuth limits seen through az_offset_deg (0..360 on a scale that wraps)",
}


def masked(settings: Settings) -> dict[str, Any]:
    """The effective settings as plain data, secrets replaced, for check-config and logs."""
    out = settings.model_dump(mode="json")
    if settings.mqtt.password is not None:
        out["mqtt"]["password"] = "********"
    if settings.station.position is not None:  # what a locator means, to check it on a map
        lat, lon = settings.station.position
        out["station"]["position_deg"] = [round(lat, 4), round(lon, 4)]
    shown = []
    for r, rs in zip(out["rotators"], settings.rotators, strict=True):
        r["name"] = rs.name or rs.id
        r["topic"] = settings.rotator_topic(rs)
        r["baud"] = rs.effective_baud
        r["brake_delay_s"] = rs.effective_brake_delay_s
        r["idle_poll_interval_s"] = rs.effective_idle_poll_interval_s
        r["silence_timeout_s"] = rs.effective_silence_timeout_s
        r["noise_deg"] = rs.effective_noise_deg
        r["unasked_moves"] = _unasked_moves(rs)
        r["track_step_deg"] = rs.effective_track_step_deg
        az_speed, el_speed = rs.effective_speeds_deg_s
        r["az_speed_deg_s"] = az_speed
        r["az_min_deg"], r["az_max_deg"] = rs.effective_az_limits
        if rs.spec.has_elevation:
            r["el_speed_deg_s"] = el_speed
            r["el_min_deg"], r["el_max_deg"] = rs.effective_el_limits
        # the bearings a user may name: the limits (raw) seen through the offset
        r["az_targets_deg"] = list(rs.pointing.target_range())
        shown.append({k: r.pop(k) for k in IDENTITY} | r)  # who it is first, then the rest
    out["rotators"] = shown
    out["mqtt"]["client_id"] = settings.mqtt.effective_client_id()
    return out


def check_state_file(settings: Settings) -> None:
    """ConfigError, in the start's words (app.py), if the start would refuse the state file
    whoever runs it (rule 5). Nothing is written."""
    path = settings.state_file
    try:
        StateStore(path).check_kind()
    except OSError as exc:
        where = f" ({shown_path(exc.filename)})" if exc.filename else ""
        raise ConfigError(
            f"state_file {shown_path(path)} cannot be written: {exc.strerror or exc}{where}"
        ) from None


def _unwritable_state_dir(path: Path) -> Path | None:
    """The directory the start would write the state file in (or make it in), if this user
    may not write there (rule 5)."""
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    return None if os.access(parent, os.W_OK | os.X_OK) else parent


def config_warnings(settings: Settings) -> list[str]:
    """Legal but probably wrong: check-config prints these on stderr and still succeeds."""
    found = []
    closed = _unwritable_state_dir(settings.state_file)
    if closed is not None:
        found.append(
            f"state_file: {shown_path(closed)} cannot be written by {_who()}: the bridge does "
            f"not start unless the user it runs as may write {shown_path(settings.state_file)} "
            "there"
        )
    if settings._password_in_file:  # set by load_settings, which saw the file
        found.append(
            "mqtt.password is written in the configuration file: put it in a file of its own, "
            "readable only by the service user, and name that in mqtt.password_file"
        )
    wsjtx = settings.wsjtx
    if wsjtx.enabled and not is_loopback(wsjtx.bind):  # a forged Status turns a follower
        found.append(
            f"wsjtx.bind: {wsjtx.bind} is not a loopback address: WSJT-X's UDP protocol has no "
            "authentication, anyone who can reach it can name the grid a following rotator "
            "turns to"
        )
    for i, r in enumerate(settings.rotators):
        where = f"rotators[{i}]"
        keys = [f"{a}.port" for a in ("azimuth", "elevation")] if r.axes else ["port"]
        for key, path in zip(keys, r.ports, strict=True):  # a composite's both
            if not os.path.exists(path):
                found.append(
                    f"{where}.{key}: {shown_path(path)} does not exist now (unplugged? "
                    "`rotor-bridge ports` lists the serial ports); the bridge keeps trying to "
                    "open it"
                )
            elif not os.access(path, os.R_OK | os.W_OK):  # rule 7
                found.append(f"{where}.{key}: {_no_access(path)}")
            if _NUMBERED.fullmatch(path):  # two alike controllers swapped turn the wrong antenna
                found.append(
                    f"{where}.{key}: {shown_path(path)} is numbered in the order the adapters "
                    "appear: after a re-plug or a reboot it can name another adapter (another "
                    "rotator's controller, a radio), or none; name the adapter by its "
                    "/dev/serial/by-id/ path (`rotor-bridge ports`)"
                )
        for key, on, bind in (
            ("pst_udp_bind", r.pst_udp_port is not None, r.pst_udp_bind),
            ("n1mm_udp_bind", r.n1mm_rotor_name is not None, r.n1mm_udp_bind),
        ):
            if on and not is_loopback(bind):
                found.append(
                    f"{where}.{key}: {bind or '(every address)'} is not a loopback address: "
                    "the loggers' UDP protocols have no authentication, anyone who can reach "
                    "it can turn the antenna"
                )
        if r.rotctld_port is not None and not is_loopback(r.rotctld_bind):
            found.append(
                f"{where}.rotctld_bind: {r.rotctld_bind or '(every address)'} is not a loopback "
                f"address: rotctld has no authentication, anyone who can reach port "
                f"{r.rotctld_port} there can turn the antenna"
            )
        for label in EMULATION_KEYS:
            port, bind = getattr(r, f"{label}_port"), getattr(r, f"{label}_bind")
            if port is not None and not is_loopback(bind):
                found.append(
                    f"{where}.{label}_bind: {bind or '(every address)'} is not a loopback "
                    f"address: {label} has no authentication, anyone who can reach port {port} "
                    "there can turn the antenna"
                )
    return found + web_warnings(settings.web)


def summary(settings: Settings) -> list[str]:
    """The lines check-config prints first (rule 4)."""
    lines = ["rotators:"]
    for r in settings.rotators:
        lines += [f"  {line}" for line in _rotator(settings, r)]
    m = settings.mqtt
    login = "no login"
    if m.username is not None:
        login = f"user {m.username}, " + ("a password" if m.password is not None else "no password")
    tls = "TLS" if m.tls.enabled else "no TLS"
    version = "MQTT 5, else 3.1.1" if m.protocol == "auto" else f"MQTT {m.protocol}"
    client_id = m.effective_client_id()
    service = _service_state_file(settings)
    if service is not None and not m.client_id:  # rule 6: the default follows the state file
        client_id += f" (under the systemd unit {m.effective_client_id(service)})"
    lines.append(f"broker: {m.host}:{m.port}, {version}, {tls}, {login}, client id {client_id}")
    ha = settings.homeassistant
    lines.append(
        f"home assistant: on (discovery prefix {ha.discovery_prefix})" if ha.enabled else
        "home assistant: off"
    )  # fmt: skip
    lines.append(_web(settings))
    st = settings.station
    if st.position is None:
        lines.append("station: not set (targets by locator and tracking need it)")
    else:
        lat, lon = st.position
        where = f"locator {st.locator}, " if st.locator is not None else ""
        lines.append(f"station: {where}latitude {lat:.4f}, longitude {lon:.4f}")
    tle = settings.tracking.tle_file
    sky = "the sun and the moon" if st.position is not None else "nothing (no station)"
    if tle is None:
        lines.append(f"tracking: {sky}; no TLE file, so no satellites")
    else:
        there = "found" if os.path.lexists(tle) else "NOT FOUND"  # (read: features/tracking/)
        lines.append(f"tracking: {sky} and the satellites in {shown_path(tle)} ({there})")
    wsjtx = settings.wsjtx
    where = f"{wsjtx.multicast_group or wsjtx.bind}:{wsjtx.port}"
    lines.append(f"wsjtx: listening on {where}" if wsjtx.enabled else "wsjtx: off")
    dx = settings.dxcluster
    if dx.enabled:
        there = "found" if dx.cty_file is not None and os.path.isfile(dx.cty_file) else "NOT FOUND"
        cty = shown_path(str(dx.cty_file))
        lines.append(f"dxcluster: {dx.host}:{dx.port} as {dx.login}, {cty} ({there})")
    else:
        lines.append("dxcluster: off")
    state = f"state file: {shown_path(settings.state_file)}"
    if service is not None:  # rule 6
        state += f" (run by hand as {_who()}; under the systemd unit {service})"
    lines.append(state)
    if settings.audit_file is not None:
        most = settings.audit_max_bytes
        kept = (  # (runtime/audit.py rule 11: the process's own output is never rotated)
            "the bridge's own output, never rotated"
            if stream_fd(settings.audit_file) is not None
            else f"renamed to .1 at {most} bytes"
        )
        lines.append(f"audit file: {shown_path(settings.audit_file)} ({kept})")
    return lines


def _no_access(port: str) -> str:
    """Rule 7: a port there that this user may not open, and the group that may."""
    user = _who()
    said = (
        f"{shown_path(port)} cannot be opened by {user}: run by hand, the bridge keeps trying "
        "and says 'no permission'"
    )
    try:
        st = os.stat(port)
    except OSError:
        return said
    if st.st_mode & (stat.S_IRGRP | stat.S_IWGRP) != stat.S_IRGRP | stat.S_IWGRP:
        return said + f" (mode {stat.S_IMODE(st.st_mode):04o}: not even its group)"
    if _in_container():  # the host's group number; no login, no systemd unit here
        return said + (
            f"; in this container: give it the port's group, number {st.st_gid} "
            f"on the host, in compose's group_add (docker run --group-add {st.st_gid})"
        )
    try:
        group = grp.getgrgid(st.st_gid).gr_name
    except KeyError:
        return said
    if st.st_gid not in {os.getegid(), *os.getgroups()} and _member(user, st.st_gid):
        return said + (
            f"; {user} is in group {group}, but not this login, from before: "
            f"log out and in again (or run `newgrp {group}`)"
        )
    return said + (
        f"; add {user} to group {group} (`sudo usermod -aG {group} {user}`, then "
        "log in again). The systemd unit's user is in dialout"
    )


def _who() -> str:
    """This user's name, or ``uid N`` for a user id the system names not (``docker run --user
    1000``: getpass raised, and check-config ended in a traceback)."""
    try:
        return getpass.getuser()
    except (KeyError, OSError):
        return f"uid {os.getuid()}"


def _in_container() -> bool:
    """Rules 6 and 7: run in a container (Docker's or Podman's mark is there)."""
    return any(os.path.exists(mark) for mark in CONTAINER_MARKS)


def _member(user: str, gid: int) -> bool:
    """Rule 7: the system's files put ``user`` in group ``gid`` (a login may not have it yet)."""
    try:
        return user in grp.getgrgid(gid).gr_mem or pwd.getpwnam(user).pw_gid == gid
    except KeyError:
        return False


def _service_state_file(settings: Settings) -> str | None:
    """Rule 6: the state file the systemd unit would use instead of the one shown, if another
    (on Linux: no other system has systemd)."""
    if sys.platform != "linux" or _in_container():
        return None
    if "state_file" in settings.model_fields_set or os.environ.get("STATE_DIRECTORY"):
        return None
    return SERVICE_STATE_FILE


def _web(settings: Settings) -> str:
    """Where to open the console, and whether it asks for a password (never which: rule 2)."""
    w = settings.web
    if not w.enabled:
        return "web console: off"
    host = w.bind or "0.0.0.0"
    if ":" in host and not host.startswith("["):
        host = f"[{host}]"  # an IPv6 address in a URL
    asks = "a password" if w.password is not None else "no password"
    return f"web console: http://{host}:{w.port}/, {asks}"


def _bearings(r: RotatorSettings) -> str:
    """The true bearings a rotator takes, as a user would say them: on a scale that wraps, an
    offset turns limits narrower than a circle into a gap anywhere on it (limits 20..340 with
    offset 180 refuse 160..200, not the ends of 0..360)."""
    p = r.pointing
    lo, hi = p.target_range()
    gap = 360.0 - (p.az_max_deg - p.az_min_deg)
    if not (p.az_wraps and p.offset_deg and gap > 0.0):
        return f"{lo:g}..{hi:g}"
    start = (p.az_max_deg + p.offset_deg) % 360.0
    end = (p.az_min_deg + p.offset_deg) % 360.0
    return f"0..360 except {start:g}..{end:g}"


def _rotator(settings: Settings, r: RotatorSettings) -> list[str]:
    found = "found" if os.path.exists(r.port) else "NOT FOUND"
    name = f"{r.id} ({r.name})" if r.name and r.name != r.id else r.id
    on = [f"topic {settings.rotator_topic(r)}", f"takes bearings {_bearings(r)}"]
    if r.pointing.has_elevation:  # (review 46: an az/el rotator's elevations were never said)
        on.append(f"elevations {r.pointing.el_min_deg:g}..{r.pointing.el_max_deg:g}")
    if r.rotctld_port is not None:
        on.append(f"rotctld on {r.rotctld_bind}:{r.rotctld_port}")
    titles = {"gs232": f"GS-232{r.gs232_replies}", "easycomm": "Easycomm II", "dcu1": "DCU-1"}
    for key in EMULATION_KEYS:
        if (port := getattr(r, f"{key}_port")) is not None:
            on.append(f"{titles[key]} on {getattr(r, f'{key}_bind')}:{port}")
    for key in EMULATION_KEYS:
        if (path := getattr(r, f"{key}_pty")) is not None:
            on.append(f"{titles[key]} on a pty at {shown_path(path)}")
    if r.pst_udp_port is not None:
        on.append(f"PstRotator UDP on {r.pst_udp_bind}:{r.pst_udp_port}")
    if r.n1mm_rotor_name is not None:
        on.append(f"N1MM {r.n1mm_rotor_name!r} on {r.n1mm_udp_bind}:{r.n1mm_udp_port}")
    if r.park_az_deg is not None:
        on.append(f"parks at {r.park_az_deg:g}")
    if r.wind_topic is not None:
        unit = r.wind_unit
        on.append(f"parks for the wind above {r.wind_park_above:g} {unit} on {r.wind_topic}")
    first = f"{name}: {r.spec.display_name} ({r.model}) on {shown_path(r.port)} ({found}), "
    first += f"{r.effective_baud} baud"
    if r.axes:  # a composite rotator: each box on its own port (settings/rotator.py rule 4)
        boxes = []
        for axis in Axis:
            own = r.axis_settings(axis)
            there = "found" if os.path.exists(own.port) else "NOT FOUND"
            boxes.append(
                f"{axis.value} by {own.spec.display_name} ({own.model}) on {shown_path(own.port)} "
                f"({there}), {own.effective_baud} baud"
            )
        first = f"{name}: {'; '.join(boxes)}"
    return [first, "  " + "; ".join(on)]


def _unasked_moves(rs: RotatorSettings) -> str:
    """What each box does with a turn nobody asked for (a composite's by its own model)."""
    if not rs.axes:
        return rs.effective_unasked_moves
    said = [f"{axis.value} box: {rs.unasked_moves_of(axis)}" for axis in Axis]
    return ", ".join(said)
