"""Joint friction the model lacks: extra Coulomb f_c sign(θ̇) + viscous f_v θ̇ at the revolute
joints (eq. 3.48's form), on one joint or the same on all. Added to the model's own friction
coefficients, so it is smoothed like them (the model's ``friction_smoothing``)."""

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
    j = joint_index(scope)
    on = [1.0 if j is None or i == j else 0.0 for i in range(6)]
    return Change(
        coulomb=tuple(v["coulomb"] * o for o in on), viscous=tuple(v["viscous"] * o for o in on)
    )


EFFECT = EffectDef(
    name="joint_friction",
    physics="extra Coulomb + viscous friction at the revolute joints",
    params=(
        ParamDef("coulomb", "N·m", 0.0, (-2.0, 5.0), 0.02),
        ParamDef("viscous", "N·m·s/rad", 0.0, (-5.0, 20.0), 0.05),
    ),
    scopes=joint_scopes(),
    apply_fn=_apply,
)
