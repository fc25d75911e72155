"""A run killed mid-way, for the tests of resuming: a trainer whose compiled chunk of
iterations raises ``KeyboardInterrupt`` at its ``n``-th call, as a kill would stop it."""

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from sgb.rl.trainer import Trainer


@contextmanager
def killed_at_chunk(trainer: Trainer, n: int, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Within the block, ``trainer.iterations`` raises ``KeyboardInterrupt`` at its ``n``-th
    call (the earlier ones run); after it, the real one is back."""
    real, calls = trainer.iterations, []

    def killed(*args, **kwargs):
        calls.append(1)
        if len(calls) == n:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setitem(trainer.__dict__, "iterations", killed)
    try:
        yield
    finally:
        monkeypatch.setitem(trainer.__dict__, "iterations", real)
