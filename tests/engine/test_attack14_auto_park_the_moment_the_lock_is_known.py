"""Attack 14: auto-park parks the instant the broker's first look says there is no lock, when
the bridge started without knowing the rotator's lock and the broker stayed away longer than
the quiet spell (runtime/kept.py rule 10, session/autopark.py rule 1).

While the lock is not known the rotator refuses motion as a locked one does (someone may be on
the tower); the quiet spell counted from start-up meanwhile. When the broker comes back (a
restart of the broker, a network that came up late) and holds no ``R/lock/state`` ON, the lock
is known OFF, and the rotor starts to park within the same step: a turn at the moment a
broker came back, which nobody at the station did. autopark.py rule 1 starts the spell again
for every such end of a refusal (the lock switched either way, the controller answering again,
a storm's end: "a rotor never parks the moment someone unlocks it ..."), but not for this one.
The control: the same rotator unlocked by a word waits a whole spell.

In virtual time, a Rotor-EZ at 90 with auto-park to 0 after 30 s, as
tests/engine/test_unknown_lock_own_moves.py starts it."""

from __future__ import annotations

from tests.engine.test_unknown_lock_own_moves import AUTOPARK, heard, started_unknown, unmoved

SPELL_S = float(AUTOPARK["park_after_idle_s"])
BROKER_AWAY_S = 10 * SPELL_S  # virtual
A_MOMENT_S = SPELL_S / 2  # virtual: well inside a new quiet spell


def test_control_an_unlock_word_starts_a_new_quiet_spell() -> None:
    with started_unknown("rotorez", AUTOPARK) as v:
        v.lock(True)  # the broker's look said ON: locked
        v.run_for(BROKER_AWAY_S)
        v.lock(False)  # unlocked by a word
        v.run_for(A_MOMENT_S)
        assert unmoved(v)
        v.run_until(lambda h: h.status.parked, 4 * SPELL_S, "parked after a quiet spell")


def test_the_lock_known_at_last_starts_a_new_quiet_spell() -> None:
    with started_unknown("rotorez", AUTOPARK) as v:
        v.run_for(BROKER_AWAY_S)  # the broker away ten quiet spells long: nothing moves
        assert unmoved(v) and v.status.lock_unknown
        heard(v, False)  # the broker is back and holds no lock ON
        v.run_for(A_MOMENT_S)
        assert unmoved(v), f"turning to the park at once: at {v.truth().az_deg:.0f}"
        v.run_until(lambda h: h.status.parked, 4 * SPELL_S, "parked after a quiet spell")
