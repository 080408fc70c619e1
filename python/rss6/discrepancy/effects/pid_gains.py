"""The drive's built-in PID gains differ from the model's: l_p, l_i, l_d each multiplied by
1 + its relative change (eq. 5.5; the same on every joint, as the drives share one gain set)."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    del scope
    return Change(gains=(v["l_p"], v["l_i"], v["l_d"]))


EFFECT = EffectDef(
    name="pid_gains",
    physics="built-in PID gains other than the model's (relative change of l_p, l_i, l_d)",
    params=(
        ParamDef("l_p", "1", 0.0, (-0.8, 3.0), 0.02),
        ParamDef("l_i", "1", 0.0, (-0.8, 3.0), 0.02),
        ParamDef("l_d", "1", 0.0, (-0.8, 3.0), 0.05),
    ),
    scopes=("drive",),
    apply_fn=_apply,
)
