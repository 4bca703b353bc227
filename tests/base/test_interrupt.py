"""Ctrl-C as a request to stop (:mod:`supportless.base.interrupt`): a SIGINT that comes twice at once is one."""

from __future__ import annotations

import os
import signal

import pytest

from supportless.base import interrupt
from supportless.base.interrupt import deferred_interrupt, interrupt_once, requested


def _sigint() -> None:
    """A SIGINT to this process, handled before this returns (Python runs handlers between bytecodes)."""
    os.kill(os.getpid(), signal.SIGINT)
    for _ in range(1000):
        pass


def test_a_repeat_at_once_is_the_same_request_and_a_later_one_a_second_ctrl_c(monkeypatch):
    with deferred_interrupt():
        _sigint()
        assert requested()
        _sigint()  # the same SIGINT again (the whole group's, and passed on): no KeyboardInterrupt
        assert requested()
        monkeypatch.setattr(interrupt, "SAME_REQUEST_S", 0.0)  # as if the window had passed
        with pytest.raises(KeyboardInterrupt):
            _sigint()


def test_a_new_block_takes_a_new_request_at_once():
    with deferred_interrupt():
        _sigint()
    with deferred_interrupt():
        assert not requested()
        _sigint()  # within the window of the last block's, yet a request of this one
        assert requested()


def test_interrupt_once_raises_once_for_a_sigint_and_its_repeat(monkeypatch):
    monkeypatch.setitem(interrupt._state, "last", float("-inf"))  # no SIGINT of another test just before
    previous = signal.signal(signal.SIGINT, interrupt_once)
    try:
        with pytest.raises(KeyboardInterrupt):
            _sigint()
        _sigint()  # its repeat
        monkeypatch.setattr(interrupt, "SAME_REQUEST_S", 0.0)
        with pytest.raises(KeyboardInterrupt):
            _sigint()
    finally:
        signal.signal(signal.SIGINT, previous)
