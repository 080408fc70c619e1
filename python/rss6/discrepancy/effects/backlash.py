"""Gear backlash: a dead band of total ``width`` between the drive (motor rotor, where the
potentiometer sits) and the wrench, with the model twin's gear mesh (stiffness 5000 N·m/rad,
damping 4 N·m·s/rad, rotor 0.01 kg·m²) — the same on every joint. Not smooth at width 0 and not
quite nested: the rotor and mesh it brings differ from the rigid model even at width 0 (measured:
≤ 9 µm in z on a 10 s excitation), so it is screened on the span of its output changes over
``grid`` widths, and fitted by simulation only."""

from __future__ import annotations

from collections.abc import Mapping

from rss6.discrepancy.effects.base import Change, EffectDef, ParamDef, Scope


def _apply(v: Mapping[str, float], scope: Scope) -> Change:
    del scope
    return Change(twin={"backlash": {"width": v["width"]}})


EFFECT = EffectDef(
    name="backlash",
    physics="dead band in the gear train between drive and wrench",
    params=(ParamDef("width", "rad", 0.0, (0.0, 0.05), 1e-3),),
    scopes=("all joints",),
    apply_fn=_apply,
    screen="span",
    grid=(0.0, 5e-4, 2e-3, 5e-3, 1e-2),
)
