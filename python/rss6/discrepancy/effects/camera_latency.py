"""Camera latency the model does not know: every CMM frame shows the pose of ``latency`` s before
its time stamp (the model twin's ``camera_latency``); the visual PID acts on older poses."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    del scope
    return Change(twin={"camera_latency": {"latency": v["latency"]}} if v["latency"] else {})


EFFECT = EffectDef(
    name="camera_latency",
    physics="extra delay of every camera frame",
    params=(ParamDef("latency", "s", 0.0, (0.0, 0.2), 2e-3),),
    scopes=("sensor",),
    apply_fn=_apply,
)
