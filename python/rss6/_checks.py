"""Checks of common arguments shared by the Python API: they raise the project's typed errors
where numpy would raise a bare ``ValueError`` or ``OverflowError`` that names nothing."""

from __future__ import annotations

import math
import operator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rss6.errors import InvalidInputError, NonFiniteError, ShapeError

__all__ = ["count", "gains3", "pose6", "rng", "seed"]


def seed(value: Any, name: str = "seed") -> int:
    """``value`` as a seed numpy takes everywhere: an int in [0, 2³² − 1]."""
    try:
        n = operator.index(value)
    except TypeError:
        raise InvalidInputError(f"{name} must be an int, got {value!r}") from None
    if not 0 <= n < 2**32:
        raise InvalidInputError(f"{name} must be in [0, 2**32 - 1], got {n}")
    return n


def rng(value: Any, name: str = "seed") -> np.random.Generator:
    """numpy's default generator seeded with the checked ``value``."""
    return np.random.default_rng(seed(value, name))


def pose6(value: Any, name: str) -> NDArray[np.float64]:
    """``value`` as a finite pose (x, y, z, α, β, γ)."""
    p = np.asarray(value, dtype=np.float64)
    if p.shape != (6,):
        raise ShapeError(f"{name} must have shape (6,), got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise NonFiniteError(
            f"{name} contains NaN or infinity at index [{np.argmin(np.isfinite(p))}]"
        )
    return p


def gains3(value: Any, name: str, *, nonnegative: bool = False) -> tuple[float, float, float]:
    """``value`` as three finite drive gains (l_p, l_i, l_d), each ≥ 0 with ``nonnegative``."""
    try:
        g = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"{name} must be three gains (l_p, l_i, l_d), got {value!r}"
        ) from None
    if len(g) != 3 or not all(math.isfinite(x) and (x >= 0 or not nonnegative) for x in g):
        raise InvalidInputError(
            f"{name} must be three finite gains (l_p, l_i, l_d)"
            + (" >= 0" if nonnegative else "")
            + f", got {value!r}"
        )
    return (g[0], g[1], g[2])


def count(value: Any, name: str, least: int = 0) -> int:
    """``value`` as an int ≥ ``least`` (a count, a number of iterations or lags)."""
    try:
        n = operator.index(value)
    except TypeError:
        raise InvalidInputError(f"{name} must be an int >= {least}, got {value!r}") from None
    if n < least:
        raise InvalidInputError(f"{name} must be an int >= {least}, got {value!r}")
    return n
