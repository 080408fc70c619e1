"""The effect library of the discrepancy workflow: one file per effect, each holding its physical
parameters with bounds, the null value at which it vanishes, its scopes and the change it makes to
the simulated model (:class:`~rss6.discrepancy.effects.base.EffectDef`). :data:`CANDIDATES` names
them; :func:`candidates` lists every effect × scope the search screens."""

from __future__ import annotations

from collections.abc import Sequence

from rss6.discrepancy.effects import (
    backlash,
    base_tilt,
    camera_latency,
    joint_friction,
    joint_offset_drift,
    payload,
    pid_gains,
)
from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope, joint_index
from rss6.errors import InvalidInputError

__all__ = [
    "CANDIDATES",
    "EFFECTS",
    "Change",
    "EffectDef",
    "ParamDef",
    "Scope",
    "candidates",
    "get",
    "joint_index",
]

EFFECTS: dict[str, EffectDef] = {
    m.EFFECT.name: m.EFFECT
    for m in (
        joint_friction,
        backlash,
        camera_latency,
        payload,
        base_tilt,
        pid_gains,
        joint_offset_drift,
    )
}

CANDIDATES: tuple[str, ...] = tuple(EFFECTS)
"""The names of the library's effects."""


def get(name: str) -> EffectDef:
    """The effect called ``name``."""
    try:
        return EFFECTS[name]
    except KeyError:
        raise InvalidInputError(
            f"unknown effect {name!r}; the library has: {', '.join(CANDIDATES)}"
        ) from None


def candidates(names: Sequence[str] | None = None) -> list[tuple[EffectDef, Scope]]:
    """Every (effect, scope) pair of the effects ``names`` (all of :data:`CANDIDATES` if None).
    A name may carry its scope: "joint_friction@joint 2"."""
    out: list[tuple[EffectDef, Scope]] = []
    for n in names if names is not None else CANDIDATES:
        name, _, scope = n.partition("@")
        e = get(name)
        if scope:
            e.check({}, scope)
            out.append((e, scope))
        else:
            out.extend((e, s) for s in e.scopes)
    return out
