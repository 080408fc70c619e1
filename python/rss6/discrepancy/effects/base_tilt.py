"""A tilted base: gravity = R_x(roll)·R_y(pitch)ᵀ·[0, 0, −9.81] in the base frame (the model twin's
``base_tilt``)."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    del scope
    if v["roll"] == 0.0 and v["pitch"] == 0.0:
        return Change()
    return Change(twin={"base_tilt": {"roll": v["roll"], "pitch": v["pitch"]}})


EFFECT = EffectDef(
    name="base_tilt",
    physics="the base is tilted: gravity is not along −z of the base frame",
    params=(
        ParamDef("roll", "rad", 0.0, (-0.3, 0.3), 2e-3),
        ParamDef("pitch", "rad", 0.0, (-0.3, 0.3), 2e-3),
    ),
    scopes=("base",),
    apply_fn=_apply,
    # Under stick–slip the tilt's cost has several minima: on the plant a (0.3, 0.25) rad tilt was
    # fitted to (0.14, −0.02) from the best of 8 Sobol starts, to (0.300, 0.253) from 32.
    sobol=32,
)
