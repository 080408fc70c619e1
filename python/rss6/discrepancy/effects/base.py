"""What an effect of the library is: its parameters (bounds, null value, scale), its scopes, and the
change it makes to the simulated model (hidden effects of the model twin, drive gains)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from rss6.errors import InvalidInputError

__all__ = ["Change", "EffectDef", "ParamDef", "Scope", "joint_index", "joint_scopes"]

Scope = str
"""Where an effect acts: "all joints", "joint 1" … "joint 6", "sensor", "base", "payload", "drive".
Joints are numbered from 1, as everywhere else in rss6 (CLOE's f_c1 … f_c6, the core's errors, the
CAN bridge); before the twenty-seventh session they were numbered from 0 here (see
:meth:`rss6.discrepancy.Model.load`)."""


@dataclass(frozen=True)
class ParamDef:
    """One physical parameter: SI ``unit``, ``null`` value at which the effect vanishes, ``bounds``
    (low, high) of a fit, and ``scale``: a typical size, the finite-difference step of its signature
    and the scale of the fit's steps."""

    name: str
    unit: str
    null: float
    bounds: tuple[float, float]
    scale: float


@dataclass(frozen=True)
class Change:
    """What a set of effect values does to the simulated model: hidden effects of the model twin
    (``rss6.ModelSim(effects=...)``: name → parameters; values for the same name and key add) and
    relative changes of the drive gains (l_p, l_i, l_d multiplied by 1 + each), and friction added
    to the model's own Coulomb (N·m) and viscous (N·m·s/rad) coefficients per joint."""

    twin: dict[str, dict[str, float]] = field(default_factory=dict)
    gains: tuple[float, float, float] = (0.0, 0.0, 0.0)
    coulomb: tuple[float, ...] = (0.0,) * 6
    viscous: tuple[float, ...] = (0.0,) * 6

    def merged(self, other: Change) -> Change:
        """Both changes at once. The twin allows one instance of each named effect: per-joint
        effects of one name merge into their per-joint form (see :meth:`EffectDef.apply`)."""
        twin = {k: dict(v) for k, v in self.twin.items()}
        for name, params in other.twin.items():
            if name not in twin:
                twin[name] = dict(params)
                continue
            mine = twin[name]
            if set(mine) != set(params) or mine.get("joint") != params.get("joint"):
                raise InvalidInputError(
                    f"effect {name!r} is in the model twice with different scopes; the twin "
                    "takes one instance of each effect (fit one scope)"
                )
            for k, v in params.items():
                if k != "joint":
                    mine[k] = mine[k] + v
        gains = (
            self.gains[0] + other.gains[0],
            self.gains[1] + other.gains[1],
            self.gains[2] + other.gains[2],
        )
        coulomb = tuple(a + b for a, b in zip(self.coulomb, other.coulomb, strict=True))
        viscous = tuple(a + b for a, b in zip(self.viscous, other.viscous, strict=True))
        return Change(twin, gains, coulomb, viscous)


@dataclass(frozen=True)
class EffectDef:
    """An effect of the library: ``name``, one-line ``physics``, ``params``, the ``scopes`` it may
    act on, ``apply(values, scope) -> Change`` (values by parameter name, SI), and how it is
    screened: ``"score"`` (smooth at its null value: signature = the residual Jacobian there) or
    ``"span"`` (not smooth at null, e.g. a dead band: signature = the span of its output changes
    on ``grid`` values of the first parameter). ``scan``: values of the first parameter that the
    fit's global start stage also tries, the others at their null value and at the one-step
    estimate's (for an effect whose size the signature at the null does not tell: stick–slip
    hides a small load, so the one-step estimate of a payload's mass can be 25× too small).
    ``sobol``: how many quasi-random starts that stage draws inside the bounds (more for an effect
    whose cost surface has several minima at the benchmark's magnitudes)."""

    name: str
    physics: str
    params: tuple[ParamDef, ...]
    scopes: tuple[Scope, ...]
    apply_fn: Callable[[Mapping[str, float], Scope], Change]
    screen: str = "score"
    grid: tuple[float, ...] = ()
    scan: tuple[float, ...] = ()
    sobol: int = 8

    @property
    def names(self) -> tuple[str, ...]:
        """The parameter names in order."""
        return tuple(p.name for p in self.params)

    @property
    def null(self) -> dict[str, float]:
        """Every parameter at its null value."""
        return {p.name: p.null for p in self.params}

    def param(self, name: str) -> ParamDef:
        """The parameter called ``name``."""
        for p in self.params:
            if p.name == name:
                return p
        raise InvalidInputError(f"effect {self.name!r} has no parameter {name!r}")

    def check(self, values: Mapping[str, float], scope: Scope) -> dict[str, float]:
        """Values completed with null values and checked against the bounds and the scope."""
        if scope not in self.scopes:
            raise InvalidInputError(
                f"effect {self.name!r} has no scope {scope!r} (scopes: {', '.join(self.scopes)})"
            )
        unknown = set(values) - set(self.names)
        if unknown:
            raise InvalidInputError(
                f"effect {self.name!r} has no parameter {sorted(unknown)[0]!r} "
                f"(parameters: {', '.join(self.names)})"
            )
        out = self.null
        for k, v in values.items():
            v = float(v)
            lo, hi = self.param(k).bounds
            if not lo <= v <= hi:
                raise InvalidInputError(
                    f"effect {self.name!r}: {k} = {v:g} is outside its bounds [{lo:g}, {hi:g}]"
                )
            out[k] = v
        return out

    def apply(self, values: Mapping[str, float], scope: Scope) -> Change:
        """The change to the simulated model of this effect with ``values`` on ``scope``."""
        return self.apply_fn(self.check(values, scope), scope)

    def is_null(self, values: Mapping[str, float]) -> bool:
        """Whether every parameter is at its null value."""
        return all(float(values.get(p.name, p.null)) == p.null for p in self.params)


def joint_scopes() -> tuple[Scope, ...]:
    """ "all joints", then "joint 1" … "joint 6"."""
    return ("all joints", *(f"joint {i + 1}" for i in range(6)))


def joint_index(scope: Scope) -> int | None:
    """The 0-based index of the joint of a "joint i" scope (i from 1; None for "all joints")."""
    return None if scope == "all joints" else int(scope.removeprefix("joint ")) - 1
