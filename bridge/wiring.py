"""A rotator's settings turned into the engine's configuration (engine/worker.py WorkerConfig):
the one place where the user's keys meet the engine's terms, for the app and for the tests that
build a rotator of their own: the speeds, limits, timings and the judge's terms resolved once,
health's, tracking's, following's and the wind park's terms; and a ``[[groups]]`` table as the
group the MQTT service turns (mqtt/groups.py). Pure: settings in, frozen configuration out.

Rules:
1. Every value the engine uses comes from here: a key left out gets the default
   settings_defaults.py derives for the model (check-config shows the same values).
2. Wind speeds are km/h from here on, whatever the rotator's ``wind_unit``.
3. A composite rotator's two boxes (engine/composite.py) are each configured as a rotator of
   their own model, port and rate, with every other key of the rotator's, its id, and its
   judge's terms: the azimuth box's without elevation (protocols/axes.py rule 1).
"""

from __future__ import annotations

from dataclasses import replace

from bridge.engine.config import FollowConfig, HealthConfig, TrackConfig, WindConfig
from bridge.engine.motion import MotionConfig
from bridge.engine.worker import WorkerConfig
from bridge.mqtt.groups import Group, Member
from bridge.protocols.axes import Axis
from bridge.settings import GroupSettings, RotatorSettings
from bridge.sky import Sky


def worker_config(
    r: RotatorSettings, sky: Sky | None = None, follow: FollowConfig | None = None
) -> WorkerConfig:
    """``r``'s engine settings; ``sky`` is the station's (None: nothing can be tracked);
    ``follow``: the station and whether WSJT-X is heard (its hold_while_tx is ``r``'s)."""
    spec = r.spec
    az_min, az_max = r.effective_az_limits
    az_speed, el_speed = r.effective_speeds_deg_s
    return WorkerConfig(
        rotator_id=r.id,
        port=r.port,
        spec=spec,
        baud=r.effective_baud,
        motion=MotionConfig(
            spec=spec,
            tolerance_deg=r.tolerance_deg,
            stall_timeout_s=r.stall_timeout_s,
            brake_delay_s=r.effective_brake_delay_s,
            settle_s=r.settle_s,
            noise_deg=r.effective_noise_deg,
            az_span_deg=az_max - az_min,
            nominal_speed_deg_s=az_speed,
            # readings while moving come at most 1.5 intervals apart (link.py rule 8), each an
            # exchange long: the rotor may have stopped that long before the last change showed
            poll_margin_s=1.5 * r.moving_poll_interval_s + spec.exchange_time_s(r.effective_baud),
        ),
        idle_poll_interval_s=r.effective_idle_poll_interval_s,
        moving_poll_interval_s=r.moving_poll_interval_s,
        deadband_deg=r.deadband_deg,
        silence_timeout_s=r.effective_silence_timeout_s,
        az_speed_deg_s=az_speed,
        el_speed_deg_s=el_speed,
        pointing=r.pointing,
        park_after_idle_s=r.park_after_idle_s,
        health=HealthConfig(
            baseline_moves=r.health_baseline_moves,
            speed_drop_pct=r.health_speed_drop_pct,
            az_speed_deg_s=r.az_speed_deg_s,
            el_speed_deg_s=r.el_speed_deg_s,
        ),
        tracking=TrackConfig(
            sky=sky,
            min_el_deg=r.track_min_el_deg,
            step_deg=r.effective_track_step_deg,
            at_los=r.track_at_los,
        ),
        follow=replace(
            follow or FollowConfig(), hold_while_tx=r.follow_hold_while_tx, bands=tuple(r.bands)
        ),
        wind=wind_config(r),
    )


def wind_config(r: RotatorSettings) -> WindConfig | None:
    """The wind park's terms in km/h (settings_wind.py), or None without a wind_topic."""
    above = r.wind_kmh(r.wind_park_above)
    if r.wind_topic is None or above is None:
        return None
    park_az = r.wind_park_az_deg if r.wind_park_az_deg is not None else r.park_az_deg
    assert park_az is not None  # settings_wind.py rule 1
    release = r.wind_kmh(r.wind_release_below) or above
    hold_s, silent_s = r.wind_hold_min * 60.0, r.wind_silent_min * 60.0
    return WindConfig(above, release, hold_s, (park_az, r.park_el_deg), silent_s, r.wind_topic)


def group_of(g: GroupSettings) -> Group:
    """A ``[[groups]]`` table as the MQTT service's group (members in the table's order)."""
    members = tuple(Member(rid, g.offsets.get(rid, 0.0), g.limits.get(rid)) for rid in g.rotators)
    return Group(g.id, g.label, members)


def axis_configs(
    r: RotatorSettings, sky: Sky | None = None, follow: FollowConfig | None = None
) -> tuple[WorkerConfig, WorkerConfig] | None:
    """A composite rotator's (azimuth, elevation) boxes (rule 3); None for one controller."""
    if not r.axes:
        return None
    boxes = []
    for axis in Axis:
        spec = r.axis_spec(axis)
        own = r.axis_settings(axis)
        cfg = worker_config(own, sky, follow)
        pointing = r.pointing_for(spec, r.effective_az_limits, r.effective_el_limits)
        motion = replace(cfg.motion, spec=spec)
        boxes.append(replace(cfg, spec=spec, motion=motion, pointing=pointing))
    return boxes[0], boxes[1]
