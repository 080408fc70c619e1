"""The hidden-effect benchmark's figures (:mod:`rss6.discrepancy.benchmark`) from its records: the
confusion matrix and one line per target of issue 14."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rss6.discrepancy._steps import Z95, interval_variance
from rss6.discrepancy.effects import joint_index

__all__ = ["names_model_error", "summary"]


def _truthy(v: Any) -> bool:
    return v is True or str(v) == "True"


def names_model_error(
    name: str,
    scope: str,
    ci: Mapping[str, tuple[float, float]],
    model_error: Mapping[str, Sequence[float]],
) -> bool:
    """Whether an effect named beside the hidden ones names the model's own error (the benchmark's
    ``model_error``: the model drawn around the truth). The rule, fixed before the grids that use
    it were run (twenty-seventh session): a joint friction when its Coulomb interval holds
    truth − model on its joint (on every joint for "all joints"); drive gains when each gain's
    interval holds truth / model − 1. Nothing else can be the model's error (only its friction
    and gains are drawn)."""
    if not model_error:
        return False
    if name == "joint_friction" and "coulomb" in ci:
        lo, hi = ci["coulomb"]
        j = joint_index(scope)
        err = model_error["coulomb"]
        return all(lo <= err[k] <= hi for k in (range(len(err)) if j is None else [j]))
    if name == "pid_gains":
        keys = ("l_p", "l_i", "l_d")
        return all(k in ci for k in keys) and all(
            ci[k][0] <= g <= ci[k][1] for k, g in zip(keys, model_error["gains"], strict=True)
        )
    return False


def summary(records: Sequence[Mapping[str, Any]]) -> str:
    """The benchmark's figures from its records (dicts, or rows read back from CSV): the confusion
    matrix (hidden effect → first named effect, "ambiguous", "unexplained", "none"), and per target
    of issue 14: false alarms on no-effect runs, right effect and scope first at each magnitude,
    95 % interval coverage and relative error of the named parameters, out-of-library handling,
    held-out gap at 5× against the noise floor."""
    lines: list[str] = []
    # Rows read back by pandas carry NaN for empty fields: "" as the csv module gives them (a NaN
    # "model_error_named" was once counted as a name).
    every = [
        {k: ("" if isinstance(v, float) and v != v else v) for k, v in r.items()} for r in records
    ]
    rows = [r for r in every if r.get("kind") != "faulted"]
    if len(rows) < len(every):
        lines.append(f"runs where the robot faulted (not counted): {len(every) - len(rows)}")
    null = [r for r in rows if r["hidden"] == "none"]
    if null:
        fa = sum(r["verdict"] != "no missing effect" for r in null)
        named = sum(r["named"] != "none" for r in null)
        lines.append(
            f"no-effect runs: {len(null)}; any discrepancy reported {fa} ({100 * fa / len(null):.1f} %),"
            f" a library effect named {named} ({100 * named / len(null):.1f} %)"
        )
    lib = [r for r in rows if r["kind"] == "library"]
    for m in sorted({float(r["magnitude"]) for r in lib}):
        rs = [r for r in lib if float(r["magnitude"]) == m]
        right = sum(_truthy(r["first_right"]) for r in rs)
        lines.append(
            f"library effect at {m:g}× noise: right effect and scope first {right}/{len(rs)} "
            f"({100 * right / len(rs):.0f} %)"
        )
    # A case is as large as asked only when its effect lets it be: the tilt at 5× is clipped by its
    # ±0.3 rad on some excitations (records before the twenty-fourth session: backlash too, which
    # was sized with its rotor and mesh and was larger than 2× at any width).
    off = [
        r
        for r in lib
        if r.get("reached") not in (None, "")
        and abs(float(r["reached"]) / float(r["magnitude"]) - 1) > 0.05
    ]
    if off:
        lines.append(
            "not at the asked multiple (bounds; older records: backlash at width 0): "
            + ", ".join(
                f"{r['hidden']} {float(r['magnitude']):g}× reached {float(r['reached']):.2f}× "
                f"(seed {r['seed']})"
                for r in off
            )
        )
    cover = total = cover_fit = cover_held = n_fit = n_held = cover_exact = n_nom = 0
    cover_now = n_now = 0
    rel5: list[float] = []
    for r in lib:
        if r["hidden"] not in str(r["named"]).split("+"):
            continue  # not named in its own scope: no estimate of the truth (older records had one)
        truth, est, ci = (json.loads(r[k]) for k in ("truth", "estimate", "ci"))
        se, held, nom = (json.loads(r.get(k) or "{}") for k in ("se", "heldout", "nominal_se"))
        for k, v in truth.items():
            if k in ci and k in est:
                total += 1
                cover += ci[k][0] <= v <= ci[k][1]
                if k in nom:
                    # The interval with the model taken as exact: the model's uncertainty out of
                    # the half-width (the side a bound did not cut).
                    h = max(ci[k][1] - est[k], est[k] - ci[k][0]) / Z95
                    n_nom += 1
                    cover_exact += abs(est[k] - v) <= Z95 * np.sqrt(max(h * h - nom[k] ** 2, 0))
                # The fitting run's interval alone, and the held-out run's own (bounds aside:
                # the truth is inside them).
                if k in se:
                    n_fit += 1
                    cover_fit += abs(est[k] - v) <= Z95 * se[k]
                if k in held:
                    n_held += 1
                    cover_held += abs(held[k][0] - v) <= Z95 * held[k][1]
                if k in se:
                    # The interval today's rule gives from the recorded errors (records written
                    # under an earlier rule; bounds do not matter: the truth is inside them).
                    n_now += 1
                    ho = held.get(k)
                    d = est[k] - ho[0] if ho is not None else 0.0
                    var = interval_variance(se[k], ho, d, nom.get(k, 0.0))
                    cover_now += abs(est[k] - v) <= Z95 * np.sqrt(var)
                if float(r["magnitude"]) == 5.0 and abs(v) > 0:
                    rel5.append(abs(est[k] - v) / abs(v))
    if total:
        # The two runs' own intervals only where the records carry their errors (records
        # written before the sixth session, or by a study that did not keep them, do not).
        alone = f"; the fitting run's alone {cover_fit}/{n_fit}" if n_fit else ""
        own = f", the held-out run's own {cover_held}/{n_held}" if n_held else ""
        exact = f"; with the model taken as exact {cover_exact}/{n_nom}" if n_nom else ""
        now = f"; today's rule from the records' errors {cover_now}/{n_now}" if n_now else ""
        lines.append(
            f"95 % intervals containing the truth: {cover}/{total} ({100 * cover / total:.0f} %)"
            + alone
            + own
            + exact
            + now
        )
    if rel5:
        lines.append(
            f"relative error of named parameters at 5×: median {100 * float(np.median(rel5)):.1f} %,"
            f" ≤ 10 % in {sum(e <= 0.1 for e in rel5)}/{len(rel5)}"
        )
    ool = [r for r in rows if r["kind"] == "out_of_library"]
    if ool:
        un = sum(_truthy(r["unexplained"]) for r in ool)
        nm = sum(r["named"] != "none" for r in ool)
        lines.append(
            f"out-of-library: unexplained {un}/{len(ool)} ({100 * un / len(ool):.0f} %), given a "
            f"library name {nm}/{len(ool)} ({100 * nm / len(ool):.0f} %)"
        )
    # Effects named beside the hidden ones (library cases and pairs), and those that name the
    # model's own error (records since the twenty-seventh session carry the verdict).
    beside = [
        (r, [n for n in str(r["named"]).split("+") if n not in str(r["hidden"]).split("+")])
        for r in rows
        if r["kind"] in ("library", "pair") and r["named"] != "none"
    ]
    beside = [(r, ns) for r, ns in beside if ns]
    if beside:
        mine = [n for r, _ in beside for n in str(r.get("model_error_named") or "").split("+") if n]
        judged = all("model_error_named" in r for r, _ in beside)
        lines.append(
            f"effects named beside the hidden ones: {sum(len(ns) for _, ns in beside)} in "
            f"{len(beside)} cases"
            + (
                f"; {len(mine)} of them name the model's own error (their interval holds "
                "truth − model)"
                if judged
                else ""
            )
        )
    five = [r for r in lib if float(r["magnitude"]) == 5.0]
    if five:
        ok = sum(
            all(float(r[f"gap_named_{a}"]) <= 1.1 * float(r[f"noise_{a}"]) for a in "xyzabg")
            for r in five
        )
        lines.append(f"held-out gap within 10 % of the noise floor at 5×: {ok}/{len(five)}")

    # Confusion matrix: hidden effect (name) → first named effect, or what was said instead.
    def first(r: Mapping[str, Any]) -> str:
        if r["named"] != "none":
            return str(r["named"]).split("+")[0].split(" (")[0]
        if _truthy(r["ambiguous"]):
            return "ambiguous"
        return "unexplained" if _truthy(r["unexplained"]) else "none"

    hidden = sorted({str(r["hidden"]).split(" (")[0] for r in rows if r["kind"] != "pair"})
    said = sorted({first(r) for r in rows})
    lines.append("")
    lines.append("confusion (rows: hidden; columns: first named, or what was said):")
    lines.append(f"{'':24s}" + "".join(f"{c[:12]:>13s}" for c in said))
    for h in hidden:
        rs = [r for r in rows if r["kind"] != "pair" and str(r["hidden"]).split(" (")[0] == h]
        lines.append(f"{h:24s}" + "".join(f"{sum(first(r) == c for r in rs):13d}" for c in said))
    pairs = [r for r in rows if r["kind"] == "pair"]
    for r in pairs:
        lines.append(f"pair {r['hidden']} (seed {r['seed']}): {r['verdict']}")
    return "\n".join(lines)
