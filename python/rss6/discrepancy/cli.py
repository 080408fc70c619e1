"""``rss6 diagnose``: the discrepancy workflow from the command line.

``rss6 diagnose --simulate EFFECT[@SCOPE][:param=value,...] [--seed N]`` hides the effect in the
simulated robot (the rapier plant by default), collects a fitting and a validation run, runs the
whole workflow with the truth model without the effect, prints the report and writes it (markdown
+ PNG, the augmented model as TOML) to ``--out``. Without parameters the effect gets the magnitude
whose output is ``--magnitude`` × the camera noise. ``--simulate none`` hides nothing.

``rss6 diagnose RUN.mcap --model DIR [--validation RUN2.mcap]`` on logged identification runs
(:func:`rss6.identify.collect` with ``mcap=``) and a model directory
(:meth:`rss6.discrepancy.Model.save`).

Exit status: 0 no missing effect, 5 a discrepancy was found (named, ambiguous or unexplained).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rss6._argtypes import count, positive, seed
from rss6.errors import InvalidInputError

__all__ = ["add_arguments", "nominal_of", "parse_effect", "run"]


def parse_effect(text: str) -> tuple[str, dict[str, float]]:
    """ "name@scope:p=v,q=w" → ("name@scope", {p: v, q: w}); "joint2" is read as "joint 2"."""
    head, _, tail = text.partition(":")
    name, _, scope = head.partition("@")
    if scope.startswith("joint") and scope[5:].strip().isdigit():
        scope = f"joint {scope[5:].strip()}"
    elif scope == "all":
        scope = "all joints"
    params: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in tail.split(","))):
        key, eq, val = item.partition("=")
        if not eq:
            raise InvalidInputError(f"effect parameter {item!r} is not name=value")
        try:
            params[key.strip()] = float(val)
        except ValueError:
            raise InvalidInputError(f"effect parameter {key!r} = {val!r} is not a number") from None
    return (f"{name}@{scope}" if scope else name), params


def nominal_of(text: str | None) -> dict[str, float] | None:
    """``--nominal``: None → the default spreads, "none" → None (held), "k=v,..." → the spreads."""
    from rss6.discrepancy.nominal import NOMINAL_SPREAD

    if text is None:
        return dict(NOMINAL_SPREAD)
    if text.strip().lower() == "none":
        return None
    return parse_effect(":" + text)[1]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``diagnose`` subcommand's arguments."""
    p.add_argument("run", nargs="?", help="logged identification run (MCAP) to diagnose")
    p.add_argument("--model", help="model directory (kinematics.toml, dynamics.toml, model.toml)")
    p.add_argument("--validation", help="held-out run (MCAP); default: the run's second half")
    p.add_argument(
        "--simulate",
        metavar="EFFECT",
        help="hide EFFECT[@SCOPE][:param=value,...] (or 'none', or 'vibration'/'camera_drift') in "
        "a simulated robot and diagnose it; SCOPE of a joint effect: 'all' or joint1 … joint6",
    )
    p.add_argument(
        "--magnitude", type=positive, default=2.0, help="output × camera noise (default 2)"
    )
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument("--plant", choices=("rapier", "model"), default="rapier")
    p.add_argument(
        "--solver-iterations",
        type=count(1),
        default=None,
        help="the rapier plant's solver iterations (default 100 with the implicit law: "
        "docs/discrepancy.md)",
    )
    p.add_argument(
        "--friction-law",
        choices=("tanh", "implicit"),
        default=None,
        help="robot and model friction: the shared stick–slip law (implicit; default on the rapier "
        "plant, which follows the model only with it) or smoothed (tanh; default on the model twin)",
    )
    p.add_argument(
        "--commands",
        choices=("recorded", "simulated"),
        default="recorded",
        help="replays driven by the run's recorded joint commands (default) or closing the "
        "model's own visual PID",
    )
    p.add_argument(
        "--pot-noise",
        choices=("none", "recorded"),
        default="none",
        help="with recorded commands: replay the robot's estimated potentiometer noise in the "
        "model's drive (run_of(pot_noise=...)); default none",
    )
    p.add_argument("--alpha", type=float, default=0.01)
    p.add_argument("--reidentify", action="store_true", help="re-identify friction and gains")
    p.add_argument(
        "--nominal",
        default=None,
        metavar="SPREADS",
        help="relative half-widths inside which the model's friction and drive gains are refitted, "
        "e.g. 'coulomb=0.1,viscous=0.25,gains=0.05' (the default) or 'fc2=0.2'; 'none' holds them",
    )
    p.add_argument(
        "--no-bias-refresh",
        action="store_true",
        help="take the stick–slip loop's bias of the model as given for every candidate (default:\n"
        "refreshed at each candidate's values, diagnose(bias_refresh=True))",
    )
    p.add_argument("--out", default="out-diagnose", help="report directory (default out-diagnose/)")
    p.add_argument("--quiet", action="store_true")


def run(args: argparse.Namespace) -> int:
    """Runs the subcommand; returns the exit status."""
    from tqdm import tqdm

    from rss6 import discrepancy
    from rss6.cli import out_dir
    from rss6.discrepancy.benchmark import PLANT_SOLVER_ITERATIONS, hidden_case

    if args.pot_noise != "none" and args.commands != "recorded":
        # Checked before any run is collected: the noise is replayed through recorded commands.
        raise InvalidInputError("--pot-noise recorded needs --commands recorded")
    out_dir(args.out)
    quiet = bool(args.quiet)
    bars: dict[str, Any] = {}
    measured: Any
    validation: Any

    def progress(stage: str, done: int, total: int) -> None:
        if quiet:
            return
        bar = bars.get(stage)
        if bar is None:
            bar = bars[stage] = tqdm(total=total, desc=stage, leave=False, file=sys.stderr)
        bar.update(done - bar.n)
        if done >= total:
            bar.close()

    if args.simulate is not None:
        if args.run is not None:
            raise InvalidInputError("give either a run (MCAP) or --simulate, not both")
        if args.simulate == "none":
            spec: dict[str, Any] = {"effect": None}
        else:
            name, params = parse_effect(args.simulate)
            spec = {"effect": name, "magnitude": args.magnitude}
            if params:
                spec["params"] = params
        spec.update(
            seed=args.seed,
            robot="plant" if args.plant == "rapier" else "twin",
            friction_law=args.friction_law,
            commands=args.commands,
        )
        if spec["robot"] == "plant":
            import rss6

            if rss6.Plant is None:
                raise InvalidInputError("this build has no rapier plant: use --plant model")
            its = args.solver_iterations  # the benchmark's default with the shared law
            if its is None and (args.friction_law or "implicit") == "implicit":
                its = PLANT_SOLVER_ITERATIONS
            if its is not None:
                spec["solver_iterations"] = its
        elif args.solver_iterations is not None:
            raise InvalidInputError("--solver-iterations needs the rapier plant (--plant rapier)")
        case = hidden_case(spec, progress=None if quiet else lambda s: print(s, file=sys.stderr))
        measured, validation, model = case.fit, case.validation, case.model
        header = (
            f"hidden in the {'rapier plant' if spec['robot'] == 'plant' else 'model twin'}: "
            + (
                ", ".join(f"{h} {case.params.get(h.split(' ')[0], '')}" for h in case.hidden)
                or "nothing"
            )
        )
    else:
        if args.solver_iterations is not None:
            raise InvalidInputError("--solver-iterations needs --simulate on the rapier plant")
        if args.run is None or args.model is None:
            raise InvalidInputError("rss6 diagnose needs RUN.mcap and --model DIR (or --simulate)")
        model = discrepancy.Model.load(args.model)
        measured, validation = Path(args.run), (Path(args.validation) if args.validation else None)
        header = f"run {args.run}" + (f", held out: {args.validation}" if args.validation else "")
    if args.pot_noise != "none":
        from rss6.discrepancy.model import run_of

        kw = {
            "kinematics": model.kinematics,
            "commands": args.commands,
            "pot_noise": args.pot_noise,
        }
        measured = run_of(measured, **kw)
        validation = None if validation is None else run_of(validation, **kw)
    rep = discrepancy.diagnose(
        measured,
        model,
        validation=validation,
        alpha=args.alpha,
        reidentify=bool(args.reidentify),
        progress=progress,
        commands=args.commands,
        nominal=nominal_of(args.nominal),
        bias_refresh=not args.no_bias_refresh,
    )
    out = Path(args.out)
    files = rep.save(out)
    rep.model.save(out / "model")
    if not quiet:
        print(header)
        print(rep.table())
        print(f"wrote {files[0]} (+ {len(files) - 1} figures) and {out / 'model'}")
    return 0 if rep.verdict == "no missing effect" else 5
