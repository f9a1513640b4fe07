"""Exponential backoff for `Deferred` retries: quick first retries, capped so a late dependency is
noticed within a couple of seconds."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class Backoff:
    initial: float = 0.2
    factor: float = 2.0
    maximum: float = 2.0
    attempts: int = 0

    def next_delay(self) -> float:
        """Delay before the next attempt: initial, initial*factor, ... capped at maximum."""
        delay = min(self.maximum, self.initial * self.factor**self.attempts)
        self.attempts += 1
        return delay

    def reset(self) -> None:
        self.attempts = 0
