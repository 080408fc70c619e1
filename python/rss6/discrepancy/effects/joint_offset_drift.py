"""A drifting potentiometer offset: Δθ_i(t) = Δθ_i + rate·t (eq. 4.2's offset, t from the start of
the run), on one joint or the same on all (the model twin's ``joint_offset_drift``)."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import (
    Change,
    EffectDef,
    ParamDef,
    Scope,
    joint_index,
    joint_scopes,
)


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    if v["rate"] == 0.0:
        return Change()
    j = joint_index(scope)
    params = {"rate": v["rate"]} if j is None else {"rate": v["rate"], "joint": float(j)}
    return Change(twin={"joint_offset_drift": params})


EFFECT = EffectDef(
    name="joint_offset_drift",
    physics="potentiometer offset drifting linearly in time",
    params=(ParamDef("rate", "rad/s", 0.0, (-0.01, 0.01), 1e-4),),
    scopes=joint_scopes(),
    apply_fn=_apply,
)
