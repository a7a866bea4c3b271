"""What `rotor-bridge check-config` prints about valid settings: the values and the warnings.

Rules:
1. masked() shows every value the bridge will use, model defaults filled in; null only where
   nothing applies (no elevation axis, no rotctld port, no park position, no credentials).
   What a value means where that is not plain is shown beside it: the station's position from
   its locator, the true bearings a rotator takes (its raw limits seen through the offset).
2. Secrets never appear: the MQTT password is shown as asterisks, wherever it came from.
3. A warning is for what is legal but probably wrong; it never makes valid settings invalid.
"""

from __future__ import annotations

import ipaddress
import os
from typing import Any

from bridge.settings import Settings

IDENTITY = ("id", "name", "model", "port", "baud", "topic")


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


def _is_loopback(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name (or "" = every address): reachable from elsewhere, say so


def config_warnings(settings: Settings) -> list[str]:
    """Legal but probably wrong: check-config prints these on stderr and still succeeds."""
    found = []
    if settings._password_in_file:  # set by load_settings, which saw the file
        found.append(
            "mqtt.password is written in the configuration file: put it in a file of its own, "
            "readable only by the service user, and name that in mqtt.password_file"
        )
    tle = settings.tracking.tle_file
    if tle is not None and not os.path.isfile(tle):
        found.append(
            f"tracking.tle_file: {tle} does not exist now; satellites can be tracked by name "
            "once it does (it is read when it changes)"
        )
    for i, r in enumerate(settings.rotators):
        where = f"rotators[{i}]"
        if not os.path.exists(r.port):
            found.append(
                f"{where}.port: {r.port} does not exist now (unplugged? `rotor-bridge ports` "
                "lists the serial ports); the bridge keeps trying to open it"
            )
        for key, on, bind in (
            ("pst_udp_bind", r.pst_udp_port is not None, r.pst_udp_bind),
            ("n1mm_udp_bind", r.n1mm_rotor_name is not None, r.n1mm_udp_bind),
        ):
            if on and not _is_loopback(bind):
                found.append(
                    f"{where}.{key}: {bind or '(every address)'} is not a loopback address: "
                    "the loggers' UDP protocols have no authentication, anyone who can reach "
                    "it can turn the antenna"
                )
        if r.rotctld_port is not None and not _is_loopback(r.rotctld_bind):
            found.append(
                f"{where}.rotctld_bind: {r.rotctld_bind or '(every address)'} is not a loopback "
                f"address: rotctld has no authentication, anyone who can reach port "
                f"{r.rotctld_port} there can turn the antenna"
            )
    return found
