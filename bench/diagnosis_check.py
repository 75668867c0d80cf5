#!/usr/bin/env python3
"""Judges a blind `rotorid diagnose --json` against a simulator's truth JSON (issue 12): one line
with the top-ranked effect, what was selected (with value +- std, judged with effect_check.py's
tolerances) and `ok` when the withheld effect is ranked first, every withheld effect is selected
(or reported confounded with a selected one) and nothing else is selected. A clean flight (no
effect in the truth) is `ok` when nothing is selected: a false alarm otherwise.

    diagnosis_check.py LABEL REPORT TRUTH [SECONDS]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from effect_check import as_list, judge_effect, read_arguments  # noqa: E402


# A diagnosis reports an effect's coordinates under its parameter name; the truth names some apart.
TRUTH_KEYS = {"rotor_drag_coefficient": ["rotor_drag_coefficient", "flapping_moment_coefficient"]}


def truth_of(truth, key):
    keys = TRUTH_KEYS.get(key, [key])
    values = [v for k in keys for v in as_list(truth["effects"].get(k, 0))]
    return values if len(values) > 1 else values[0]


def withheld_effects(truth, ranking):
    """Names of the effects whose truth is non-zero: the ranking's effect name where a ranked entry
    reports that parameter, else the truth's key (an effect that was not a candidate)."""
    owner = {key: e["effect"] for e in ranking for key in e.get("magnitude", {})}
    for key, values in TRUTH_KEYS.items():
        for k in values:
            if key in owner:
                owner.setdefault(k, owner[key])
    return {owner.get(key, key + " (not a candidate)") for key, value in truth["effects"].items()
            if any(v != 0 for v in as_list(value))}


def main():
    label, d, t, seconds = read_arguments()
    if d is None:
        return
    ranking = d["ranking"]
    withheld = withheld_effects(t, ranking)
    selected = list(d["selected"])
    confounded = {e["effect"] for e in ranking if e.get("status") == "confounded"}
    top = ranking[0]["effect"] if ranking else "-"
    parts, magnitudes_ok = [], True
    for entry in ranking:
        if entry["effect"] not in selected:
            continue
        for key, m in entry["magnitude"].items():
            if entry["effect"] in withheld:
                good, text = judge_effect(key, m["value"], m["std"], truth_of(t, key), m.get("held"))
                magnitudes_ok = magnitudes_ok and good
                parts += text
            else:
                parts.append(f"{key} {m['value']} (false)")
    found = all(e in selected or e in confounded for e in withheld)
    extra = [e for e in selected if e not in withheld]
    ok = (not withheld or top in withheld) and found and not extra
    verdict = "ok " if ok else ("FALSE" if extra and not withheld else "OUT")
    tail = f"; magnitudes {'within' if magnitudes_ok else 'OUT of'} tolerance" if withheld else ""
    if seconds:
        tail += f"; {seconds} s"
    print(f"{label:58s} {verdict} top {top}; selected {','.join(selected) or 'none'}"
          + (f"; confounded {','.join(sorted(confounded))}" if confounded else "")
          + ("; " + "; ".join(parts) if parts else "") + tail)


if __name__ == "__main__":
    main()
