"""A load fixed to the platform that the model does not carry: mass (kg) and centre of mass (m, in
ΣE), as a point mass (the model twin's ``payload``; its gravity moment and inertia enter the
dynamics). Near its null value the signature is linear in the mass and the first moments m·x,
m·y, m·z; the centre of mass is only defined once the mass is not 0."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    del scope
    if v["mass"] <= 0.0:
        return Change()
    return Change(twin={"payload": {"mass": v["mass"], "x": v["x"], "y": v["y"], "z": v["z"]}})


EFFECT = EffectDef(
    name="payload",
    physics="a load fixed to the platform (mass, centre-of-mass offset)",
    params=(
        ParamDef("mass", "kg", 0.0, (0.0, 60.0), 0.5),
        ParamDef("x", "m", 0.0, (-0.2, 0.2), 0.02),
        ParamDef("y", "m", 0.0, (-0.2, 0.2), 0.02),
        ParamDef("z", "m", 0.0, (-0.2, 0.2), 0.02),
    ),
    scopes=("payload",),
    apply_fn=_apply,
    # Masses on a doubling grid (the mass bound is 60 kg): where the load moves the stuck joints.
    scan=(0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0),
)
