"""One rotator's engine settings, resolved once from the configuration (app.py builds them),
and the session's parts it runs (the features', handed in by the app). Frozen data, imported
by every part of the engine and importing none of them (parts.py is what a part is, no part)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

from bridge.core.text import shown_path
from bridge.pointing import Pointing
from bridge.protocols.base import ModelSpec
from bridge.session import motion as mo
from bridge.session.parts import Part, Speeds
from bridge.sky import Sky


@dataclass(frozen=True)
class TrackConfig:
    """What tracking (tracking.py) needs of the station and the settings."""

    sky: Sky | None = None  # None: no station configured, nothing can be tracked
    min_el_deg: float = 0.0
    step_deg: float = 3.0
    at_los: str = "stay"  # or "park"
    flip: bool = True  # tracking.py rule 4; False on a rotator of two boxes (app.axis_configs)


@dataclass(frozen=True)
class FollowConfig:
    """What following a QSO partner (follow.py) needs of the station and the settings."""

    station: tuple[float, float] | None = None  # (latitude, longitude); None: cannot follow
    hold_while_tx: bool = True  # a new partner's bearing waits for the transmission to end
    wsjtx: bool = False  # the [wsjtx] listener runs: there is something to follow
    bands: tuple[str, ...] = ()  # the rotator's antenna's bands: followed on these alone


@dataclass(frozen=True)
class WindConfig:
    """What the wind-aware park (wind.py) needs of the settings; speeds in km/h."""

    park_above_kmh: float
    release_below_kmh: float
    hold_s: float
    park: tuple[float, float | None]  # (azimuth, elevation) true: where to face the storm
    silent_s: float
    topic: str = ""  # named in what is reported


@dataclass(frozen=True)
class HealthConfig:
    """What rotor health (health.py) is judged by."""

    baseline_moves: int = 20  # the baseline is learned from this many moves
    speed_drop_pct: float = 20.0  # a warning beyond this change
    az_speed_deg_s: float | None = None  # set by hand: the speed baseline, both ways
    el_speed_deg_s: float | None = None


@dataclass(frozen=True)
class WorkerConfig:
    rotator_id: str
    port: str
    spec: ModelSpec
    baud: int
    motion: mo.MotionConfig
    az_speed_deg_s: float  # the rotor's real speeds (settings: the model's nominal by default)
    el_speed_deg_s: float
    idle_poll_interval_s: float = 1.0
    moving_poll_interval_s: float = 0.2
    deadband_deg: float = 2.0
    silence_timeout_s: float = 3.0
    unasked_moves: str = "follow"  # controller.py rule 10: "follow", "stop" or "after-stop"
    reconnect_min_s: float = 0.5
    reconnect_max_s: float = 10.0
    junk_report_interval_s: float = 30.0
    pointing: Pointing | None = None  # None: the model's whole range, no offset
    park_after_idle_s: float = 0.0  # 0: never park by itself (autopark.py)
    tracking: TrackConfig = TrackConfig()  # the sky is None without a station (tracking.py)
    follow: FollowConfig = FollowConfig()  # follow.py
    wind: WindConfig | None = None  # wind.py; None: no wind_topic
    health: HealthConfig = HealthConfig()
    # one box of a rotator of two (app.axis_configs): what becomes of the rotator's turn when
    # its port is lost is runtime/composite.py rule 8's to do and say (session/controller.py
    # rule 13 words a single controller's)
    box: bool = False
    # the session's parts, in the order its step runs them (session.py rule 17): the registered
    # features', handed in by the app; None: the registry's (bridge/feature.py session_parts)
    parts: tuple[Part[Any], ...] | None = None

    def __post_init__(self) -> None:
        if self.pointing is None:
            object.__setattr__(self, "pointing", Pointing.of(self.spec))

    @cached_property
    def shown_port(self) -> str:
        """The port as the bridge names it in what it says (R/error, R/status, the log): a
        path may be any bytes, a home folder's name above all (core/text.py ``shown_path``)."""
        return shown_path(self.port)

    @property
    def aim(self) -> Pointing:
        """The pointing transform (never None after construction)."""
        assert self.pointing is not None
        return self.pointing

    @cached_property
    def speeds(self) -> Speeds:
        """The speeds above as the parts see them (parts.py rule 9): made once a configuration
        (the controller's in effect is replaced whenever a setting retunes it)."""
        return Speeds(self.az_speed_deg_s, self.el_speed_deg_s)
