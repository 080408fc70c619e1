"""``argparse`` types for the command line's numbers: a bad value is a usage error that names the
option (exit status 2), not a traceback from deep inside a run."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

__all__ = ["count", "nonnegative", "positive", "seed"]

#: Seeds go to numpy's 32-bit and the Rust side's 64-bit seeding; the commands derive further seeds
#: by adding offsets (seed + 2, 7000 + seed, …), so the command line keeps below 2³¹.
SEED_MAX = 2**31 - 1


def _int(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def _float(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return x


def seed(text: str) -> int:
    """A random seed: an integer in [0, SEED_MAX]."""
    n = _int(text)
    if not 0 <= n <= SEED_MAX:
        raise argparse.ArgumentTypeError(f"a seed must be in [0, {SEED_MAX}], got {n}")
    return n


def count(minimum: int) -> Callable[[str], int]:
    """An integer ≥ ``minimum``."""

    def parse(text: str) -> int:
        n = _int(text)
        if n < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {n}")
        return n

    return parse


def positive(text: str) -> float:
    """A finite number > 0."""
    x = _float(text)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return x


def nonnegative(text: str) -> float:
    """A finite number ≥ 0."""
    x = _float(text)
    if x < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return x
