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


# A diagnosis reports an effect's coordinates under the parameter names the truth uses (rotor_drag:
# rotor_drag_coefficient and flapping_moment_coefficient apart, as refine writes them).
def truth_of(truth, key):
    return truth["effects"].get(key, 0)


def withheld_effects(truth, ranking):
    """Names of the effects whose truth is non-zero: the ranking's effect name where a ranked entry
    reports that parameter, else the truth's key (an effect that was not a candidate)."""
    owner = {key: e["effect"] for e in ranking for key in e.get("magnitude", {})}
    return {owner.get(key, key + " (not a candidate)") for key, value in truth["effects"].items()
            if any(v != 0 for v in as_list(value))}


def judge_scale_free(key, scale_free, truth, withheld):
    """(within tolerance, text) of a scale-free selection: each value `<key> / <coefficient>` against
    the truth's value over the truth's coefficient, with the parameter's own tolerance."""
    coefficient = scale_free["rotor_coefficient"]
    parts, ok = [], True
    for label, m in scale_free["values"].items():
        want = truth_of(truth, key)
        if m.get("ratio"):
            want = want / truth["parameters"][coefficient]
        if not withheld:
            parts.append(f"{label} {m['value']:.4g} (false)")
            continue
        good, text = judge_effect(key, m["value"], m["std"], want)
        ok = ok and good
        parts += [t.replace(key, label, 1) for t in text]
    return ok, parts


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
            if m["value"] is None and "scale_free" in entry:
                # Selected by the scale-free test of a component without rotor term: its size is a
                # ratio to that rotor coefficient (J / kd), judged against the truth's ratio.
                good, text = judge_scale_free(key, entry["scale_free"], t, entry["effect"] in withheld)
                magnitudes_ok = magnitudes_ok and good
                parts += text
            elif entry["effect"] in withheld:
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
