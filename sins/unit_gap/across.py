"""Verdicts across recordings of one unit: which accepted effects hold on all, which on some, which on
one only, with their fitted sizes side by side.

A sensor effect of the unit should be found wherever the recordings excite it; one found on a single
recording of several is as likely that recording's (its reference, its motion) as the unit's, and is
labelled so; one found on several with sizes of opposite signs on a channel is labelled with those
channels (a unit's effect has one sign; a time offset of +2.9 ms on one trial and -2.0 ms on the other
had read as holding on all). The sizes are the accepted effects' fitted coefficients
(:attr:`sins.gap.report.GapReport.sizes`) in their parameters' units
(:func:`sins.gap.report.in_units`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sins.compensation import seed_terms
from sins.core.text import fixed_width
from sins.gap.candidates import processes
from sins.gap.report import GapReport, in_units
from sins.unit_gap.clock import of_the_clock

#: The labels, by on how many of the recordings an effect was accepted.
ALL, SOME, ONE = "all", "some", "one only"


def verdicts(reports: list[tuple[str, GapReport]]) -> dict[str, Any]:
    """Every effect accepted on any of the named ``reports``: on which it holds, its label
    (:data:`ALL`, :data:`SOME`, :data:`ONE`), and its sizes on each, per channel, in its units.

    A sensor's two random biases (a bias instability, a rate random walk) are one finding where a
    recording cannot tell them apart: one accepted there with the other named indistinguishable, the
    other holds there too (``tied_on``). EuRoC's MH_01 took the gyro's walk and MH_03 its instability
    (the walk tied), and each had read as found on one recording only."""
    names = [n for n, _ in reports]
    accepted: list[str] = []
    for _, r in reports:
        accepted += [e for e in r.diagnosis if e not in accepted]
    effects: dict[str, Any] = {}
    for e in accepted:
        tied = [n for n, r in reports if e not in r.diagnosis and _tied(e, r)]
        found = [n for n, r in reports if e in r.diagnosis or n in tied]
        label = ALL if len(found) == len(reports) else ONE if len(found) == 1 else SOME
        sizes = {}
        for n, r in reports:
            if e in r.sizes:
                sizes[n] = {
                    ch: {"values": in_units(e, v)[0], "unit": in_units(e, v)[1]}
                    for ch, v in r.sizes[e].items()
                }
        effects[e] = {"found_on": found, "holds_on": label, "sizes": sizes, "tied_on": tied,
                      "signs_differ_on": _signs_differ(sizes, found)}  # fmt: skip
    shared = {n: r.statistic.get("reference_clock", {}).get("shared_delay") for n, r in reports}
    return {
        "recordings": names,
        "effects": effects,
        # The delay both sensors share on each recording, taken for its reference's clock (s).
        "reference_clock_s": {n: v["shared_s"] for n, v in shared.items() if v},
        "on_all": [e for e, v in effects.items() if v["holds_on"] == ALL],
        "on_some": [e for e, v in effects.items() if v["holds_on"] == SOME],
        "on_one_only": [e for e, v in effects.items() if v["holds_on"] == ONE],
        # The seed model's scale and misalignment terms compared between the recordings.
        "seed_terms": seed_terms.differing(
            {n: r.statistic["seed_model"] for n, r in reports if "seed_model" in r.statistic}
        ),
    }


def _tied(effect: str, report: GapReport) -> bool:
    """Whether ``report`` accepted the other random bias of ``effect``'s sensor and could not tell it from
    ``effect`` (a random bias's alternative; other ties are left as they are)."""
    if effect.split(".", 1)[1] not in processes():
        return False
    return any(
        effect in score.indistinguishable
        for score in report.effects
        if score.accepted and score.name in report.diagnosis
    )


def _signs_differ(sizes: dict[str, dict[str, Any]], found: list[str]) -> list[str]:
    """The channels whose first size has opposite signs on two of the recordings that accepted it."""
    channels = dict.fromkeys(ch for n in found for ch in sizes.get(n, {}))
    out = []
    for ch in channels:
        signs = {np.sign(sizes[n][ch]["values"][0]) for n in found if ch in sizes.get(n, {})} - {0.0}
        if len(signs) > 1:
            out.append(ch)
    return out


def size_lines(report: GapReport) -> list[str]:
    """One recording's accepted effects' sizes, a line each as ``sins gap`` prints them: a delay taken for
    the reference's clock (``statistic.reference_clock.shared_delay``) said so, a size no unit has
    (``implausible``) with why on the next line."""
    clocks = of_the_clock(report.statistic)
    lines = []
    for effect, channels in report.sizes.items():
        shown = {
            ch: {"values": in_units(effect, v)[0], "unit": in_units(effect, v)[1]}
            for ch, v in channels.items()
        }
        clock = " (the reference's clock, not named: above)" if effect in clocks else ""
        lines.append(f"{effect}: {size_text(shown)}{clock}")
        if beyond := report.implausible.get(effect):
            lines.append(f"  implausible: {beyond}")
    return lines


def size_text(per_channel: dict[str, Any]) -> str:
    """One recording's sizes of an effect, short: per channel its value (where each value has a
    parameter of its own, a random bias's σ and τ, all of them; for several of one parameter, the
    largest in magnitude), then the unit."""
    parts, unit = [], ""
    for ch, v in per_channel.items():
        values = np.asarray(v["values"], dtype=float)
        unit = v["unit"]
        if " | " in unit:  # one value per parameter, in the unit's order
            shown = " | ".join(f"{x:.3g}" for x in values)
        elif len(values) == 1:
            shown = f"{values[0]:.3g}"
        else:
            shown = f"{values[np.argmax(np.abs(values))]:.3g} (largest)"
        parts.append(f"{ch.split('.')[1]} {shown}")
    return f"{', '.join(parts)} {unit}".strip()


def table_rows(across: dict[str, Any]) -> list[list[str]]:
    """The verdicts as rows: effect, on which, then each recording's sizes ("-" where not accepted)."""
    rows = []
    for e, v in across["effects"].items():
        label = (
            v["holds_on"]
            if v["holds_on"] != SOME
            else f"some ({len(v['found_on'])} of {len(across['recordings'])})"
        )
        if v.get("signs_differ_on"):
            label += f", signs differ on {', '.join(ch.split('.')[1] for ch in v['signs_differ_on'])}"
        cells = [size_text(v["sizes"][n]) if n in v["found_on"] and n in v["sizes"] else
                 "tied with the other random bias" if n in v.get("tied_on", []) else
                 ("accepted" if n in v["found_on"] else "-") for n in across["recordings"]]  # fmt: skip
        rows.append([e, label, *cells])
    return rows


def lines(across: dict[str, Any]) -> list[str]:
    """The verdicts across the recordings as lines: each accepted effect, on which, its sizes side by side."""
    out = [f"\nacross {len(across['recordings'])} recordings of the unit:"]
    seed = seed_terms.lines(across["seed_terms"]) if "seed_terms" in across else []
    if not across["effects"]:
        return [*out, "  no effect accepted on any", *seed]
    out.append(fixed_width(["effect", "holds on", *across["recordings"]], table_rows(across)))
    if across["on_one_only"]:
        out.append(f"found on one recording only: {', '.join(across['on_one_only'])}")
    if clocks := across.get("reference_clock_s"):
        each = ", ".join(f"{n} {1e3 * v:.2f} ms" for n, v in clocks.items())
        out.append(f"a delay both sensors share, the reference's clock (not named): {each}")
    differ = [
        f"{e} ({', '.join(v['signs_differ_on'])})"
        for e, v in across["effects"].items()
        if v.get("signs_differ_on")
    ]
    if differ:
        out.append(
            f"sizes of opposite signs between recordings (a unit's effect has one): {', '.join(differ)}"
        )
    return out + seed


__all__ = [
    "ALL",
    "ONE",
    "SOME",
    "lines",
    "size_lines",
    "size_text",
    "table_rows",
    "verdicts",
]
