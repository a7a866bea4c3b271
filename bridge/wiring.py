"""A rotator's settings turned into the engine's configuration (engine/worker.py WorkerConfig):
the one place where the user's keys meet the engine's terms, for the app and for the tests that
build a rotator of their own."""

from __future__ import annotations

from bridge.engine.config import HealthConfig, TrackConfig
from bridge.engine.motion import MotionConfig
from bridge.engine.worker import WorkerConfig
from bridge.settings import RotatorSettings
from bridge.sky import Sky


def worker_config(r: RotatorSettings, sky: Sky | None = None) -> WorkerConfig:
    """``r``'s engine settings; ``sky`` is the station's (None: nothing can be tracked)."""
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
    )
