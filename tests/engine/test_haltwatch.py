"""core/haltwatch.py through the mailbox (mailbox.py rule 10): those told before a halt is
counted see the count before it, and one that raises does not keep the halt from counting."""

from __future__ import annotations

import logging

import pytest

from bridge.core.model import Stop
from bridge.session.mailbox import Mailbox


def test_a_watcher_sees_the_count_before_each_stop_and_lock_on_and_not_a_lock_off() -> None:
    box = Mailbox()
    seen: list[int] = []
    box.halt_watchers.add(lambda: seen.append(box.epoch))
    box.put(Stop())
    box.put_lock(True)
    box.put_lock(False)
    box.put(Stop())
    assert seen == [0, 1, 2]
    assert box.epoch == 3


def test_a_watcher_that_raises_is_logged_and_the_stop_still_counts(
    caplog: pytest.LogCaptureFixture,
) -> None:
    box = Mailbox()
    seen: list[int] = []

    def broken() -> None:
        raise RuntimeError("a look failed")

    box.halt_watchers.add(broken)
    box.halt_watchers.add(lambda: seen.append(box.epoch))
    with caplog.at_level(logging.ERROR, logger="bridge.core.haltwatch"):
        box.put(Stop())
        box.put(Stop())
    assert box.epoch == 2
    assert seen == [0, 1]  # the one after it was told both times
    said = [r for r in caplog.records if "a look before a halt failed" in r.getMessage()]
    assert len(said) == 1  # once per kind of error (rule 2)


def test_a_watcher_removed_is_told_no_more() -> None:
    box = Mailbox()
    seen: list[int] = []

    def watcher() -> None:
        seen.append(box.epoch)

    box.halt_watchers.add(watcher)
    box.put(Stop())
    box.halt_watchers.remove(watcher)
    box.put(Stop())
    assert seen == [0]
