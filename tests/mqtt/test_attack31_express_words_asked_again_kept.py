"""Attack 31 (resources under churn): the stop express keeps every sync word it publishes
again while a hold waits, for as long as its connection lasts.

express.py rule 8: while a rotator's targets wait on a sync word that has not come back, the
bridge asks again every RESEND_S (2 s: ``_tick``), and the express publishes a new word each
time, keeping it (``Sync._out``, and its mark in ``_marks``) until that word or a later one
comes back. A broker that stops passing its words back after they had worked (an ACL
reloaded without the fence topic, mosquitto's SIGHUP keeping the connection) never sends
one: a word and its mark are kept every 2 s, for days. Each request is answered by the
newest word out (``read_back`` answers everything up to it), so the older ones hold nothing
a later one does not; a broker that drops its words before the first came back is already
held to one (tests/mqtt/test_express.py ``test_words_a_broker_drops_are_not_kept_for_ever``).

Pure: Sync, the express's rule 8, decided with no clock and no broker.
"""

from __future__ import annotations

from bridge.interfaces.mqtt.express import WORDS_KEPT, Sync

FEW = WORDS_KEPT + 2  # (past the few a slow broker may still bring back: rule 8)
MANY = 1000  # about half an hour of a hold, asked again every 2 s


def _words_kept_after(asked_again: int) -> int:
    sync = Sync()
    sync.accepted()
    first = sync.subscribed()
    assert sync.read_back(first) == (None, None) and sync.writing  # its words came back
    assert sync.asked(1)[1] is not None  # a stop's request: a word out, never back
    for _ in range(asked_again):  # the bridge asks again while the hold waits
        sync.asked(1, again=True)
    return len(sync._out)


def test_words_asked_again_while_a_hold_waits_are_not_kept_for_ever() -> None:
    few, many = _words_kept_after(FEW), _words_kept_after(MANY)
    assert many == few, f"words kept: {few} after {FEW} asks again, {many} after {MANY}"


def test_a_broker_slower_than_the_asks_again_still_ends_the_hold() -> None:
    """Each word comes back only after the next is out (a broker some RESEND_S slow): the
    word it brings back answers the request, as the newest would have (rule 8)."""
    sync = Sync()
    sync.accepted()
    first = sync.subscribed()
    assert sync.read_back(first) == (None, None) and sync.writing
    _, word = sync.asked(1)
    assert word is not None
    for _ in range(FEW):
        _, newer = sync.asked(1, again=True)
        assert newer is not None
        answer, _ = sync.read_back(word)  # the word before the newest, back late
        if answer is not None:
            break
        word = newer
    assert answer == 1
