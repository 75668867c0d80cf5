#!/usr/bin/env python3
"""Judges a `rotorid refine --json` report against a simulator's truth JSON with issue 12's
tolerances: one line, truth -> estimate +- std per coordinate of every enabled effect, `ok` when
all are within (lever arm 2 mm or 3 std, acc_delay 1 ms, drag coefficients 10 %, rotor inertia
15 %, thrust scales 0.01, battery exponent 0.1, ground-effect coefficient 20 %, motor lag and delay
10 %), then kt's error and, when given, the run time. When rotorid says k_f is measured about the
IMU's height (rotor drag with the IMU off O_d's height and no imu_position in the vehicle file), the
line also compares k_f - k_d r_z, what a flight can give. bench/diagnosis_check.py judges a diagnosis
with the same tolerances (`judge_effect`).

    effect_check.py LABEL REPORT TRUTH [SECONDS]
"""
import json
import sys

TOL = {"imu_position_m": ("arm", 0.002), "acc_delay_s": ("abs", 0.001), "rotor_drag_coefficient": ("rel", 0.10),
       "flapping_moment_coefficient": ("rel", 0.10), "rotor_inertia_kgm2": ("rel", 0.15),
       "rotor_thrust_scale": ("abs", 0.01), "battery_exponent": ("abs", 0.1), "ground_effect_coefficient": ("rel", 0.20),
       "motor_tau_s": ("rel", 0.10), "delay_s": ("rel", 0.10)}


def as_list(x):
    return x if isinstance(x, list) else [x]


def held_indices(key, held_labels):
    """Coordinates that rotorid held at the vehicle file's value (report key `held`): not estimates."""
    suffixes = ["_x", "_y", "_z"]
    return {a for a in range(64) for label in held_labels or []
            if label in (key + "_" + str(a + 1), key + (suffixes[a] if a < 3 else ""))}


def judge_effect(key, value, std, want, held_labels=None):
    """(all coordinates within tolerance, text per coordinate) of one effect parameter; held
    coordinates are shown and not judged (rotorid says it cannot estimate them)."""
    vs, ss, ws = as_list(value), as_list(std), as_list(want)
    kind, size = TOL.get(key, ("rel", 0.10))
    held = held_indices(key, held_labels)
    ok, parts = True, []
    for a, (x, sd, w) in enumerate(zip(vs, ss, ws)):
        if a in held:
            parts.append(f"{key}_{a + 1} {w:.4g} -> {x:.4g} held")
            continue
        sd = float(sd) if sd is not None else float("nan")
        err = abs(x - w)
        good = err <= (size * abs(w) if kind == "rel" else size) or (kind == "arm" and err <= 3 * sd)
        ok = ok and good
        parts.append(f"{key}{'' if len(vs) == 1 else '_' + str(a + 1)} {w:.4g} -> {x:.4g} +- {sd:.2g}{'' if good else ' (!)'}")
    return ok, parts


def about_imu_height(report, truth):
    """When rotorid says k_f is measured about the IMU's height (the vehicle file leaves imu_position out)
    and the truth has the IMU off O_d's height: k_f - k_d r_z, what a flight can give, against the estimate."""
    flapping = report["refined"]["effects"].get("flapping_moment_coefficient", {})
    arm = truth["effects"].get("imu_position_m") or [0.0, 0.0, 0.0]
    said = any("measured about the IMU's height" in w for w in report["refined"].get("warnings", []))
    if not flapping.get("enabled") or not said or arm[2] == 0.0:
        return ""
    want = truth["effects"]["flapping_moment_coefficient"] - truth["effects"]["rotor_drag_coefficient"] * arm[2]
    got = flapping["value"]
    return f"; about the IMU's height k_f - k_d r_z {want:.4g} -> {got:.4g} ({100 * (got / want - 1):+.1f} %)"


def read_arguments():
    """(label, report, truth, seconds) from LABEL REPORT TRUTH [SECONDS]; report None if unreadable."""
    label, report, truth_path = sys.argv[1:4]
    seconds = sys.argv[4] if len(sys.argv) > 4 else None
    try:
        return label, json.load(open(report)), json.load(open(truth_path)), seconds
    except Exception as e:
        print(f"{label:58s} no report ({e})")
        return label, None, None, seconds


def main():
    label, r, t, seconds = read_arguments()
    if r is None:
        return
    ok, parts = True, []
    for key, entry in r["refined"]["effects"].items():
        if entry.get("enabled"):
            good, text = judge_effect(key, entry["value"], entry["std"], t["effects"].get(key), entry.get("held"))
            ok, parts = ok and good, parts + text
    tail = about_imu_height(r, t)
    kt_true = t.get("parameters", {}).get("kt")
    if kt_true:
        tail += f"; kt {100 * (r['refined']['parameters']['kt']['value'] / kt_true - 1):+.2f} %"
    if seconds:
        tail += f"; {seconds} s"
    print(f"{label:58s} {'ok ' if ok else 'OUT'} " + "; ".join(parts) + tail)


if __name__ == "__main__":
    main()
