"""What a rotator keeps in the state file of its own settings: the options its model has, the
safety lock, and a storm it is parked for. Rotator (rotator.py) owns one; the state file is
written on its writer thread (state_store.py rule 5), never on a front end's nor the lines
thread's.

Rules:
1. An option remembered for this id that this model does not have (the id may have been
   another model's) is logged and left out.
2. Each save of the lock writes the lock as it is when the save runs, so the last one writes
   the newest word, whatever order the front ends asked in.
3. A save that fails is reported (kind ``state``): the setting is in effect but will not
   survive a restart.
4. A storm outlives a restart (wind.py rule 2: only readings end it): ``seen_wind`` looks at
   every status on the lines thread and hands a storm begun or ended to the writer; the next
   start begins in the storm (parked again, motion refused) until readings end it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from bridge.engine.state_store import StateStore
from bridge.model import ErrorKind, WindInfo
from bridge.protocols.base import ModelSpec

log = logging.getLogger(__name__)


class Kept:
    def __init__(
        self,
        store: StateStore,
        rotator_id: str,
        spec: ModelSpec,
        *,
        locked: Callable[[], bool],
        report: Callable[[ErrorKind, str, str | None], None],
    ) -> None:
        self._store = store
        self._id = rotator_id
        self._spec = spec
        self._locked = locked  # the lock as the rotator has it now (rule 2)
        self._report = report
        self._save_lock = threading.Lock()
        self.storm = store.storm(rotator_id)  # rule 4: as the last start left it

    def seen_wind(self, wind: WindInfo | None) -> None:
        """Rule 4 (lines thread: it only compares and hands over)."""
        storm = wind is not None and wind.storm
        if storm != self.storm:
            self.storm = storm
            self._store.later(lambda: self._save_storm_now(storm))

    def _save_storm_now(self, storm: bool) -> None:
        if not self._store.set_storm(self._id, storm):
            self._report(
                ErrorKind.STATE,
                f"the storm's {'start' if storm else 'end'} could not be saved: a restart "
                "would not know it (state file not writable)",
                "wind",
            )

    def options(self) -> dict[str, bool]:
        """Rule 1."""
        kept = {}
        for name, enabled in self._store.options(self._id).items():
            if name in self._spec.options:
                kept[name] = enabled
            else:
                log.warning(
                    "%s: stored option %r ignored: %s has no such option",
                    self._id,
                    name,
                    self._spec.display_name,
                )
        return kept

    def save_option(self, name: str, enabled: bool) -> None:
        self._store.later(lambda: self._save_option_now(name, enabled))

    def _save_option_now(self, name: str, enabled: bool) -> None:
        if not self._store.set_option(self._id, name, enabled):
            self._report(
                ErrorKind.STATE,
                f"option {name} is in effect but could not be saved: it will not survive a "
                "restart (state file not writable)",
                name,
            )

    def save_lock(self) -> None:
        """Rule 2."""
        self._store.later(self._save_lock_now)

    def _save_lock_now(self) -> None:
        with self._save_lock:
            locked = self._locked()
            saved = self._store.set_locked(self._id, locked)
        if not saved:
            self._report(
                ErrorKind.STATE,
                f"lock {'ON' if locked else 'OFF'} is in effect but could not be saved: "
                "it will not survive a restart (state file not writable)",
                "lock",
            )
