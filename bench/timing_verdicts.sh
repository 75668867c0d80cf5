#!/usr/bin/env bash
# Issue 11's check of the diagnosis's timing verdicts on rotorid's simulator: flights with a pure
# command delay (5, 10, 15 ms) or a pure motor lag (10, 20, 40 ms), configuration B, 60 s, seeds
# 1-3, diagnosed blind (all candidates) against a held-out flight of the same vehicle and effect.
# One line per flight: what was selected, and whether the truth is named, named as confounded with
# its rival, or missed; "WRONG" marks a rival named with confidence (distinguishable) instead of the
# truth. Then refine with delay and motor_lag on flights with both (15 + 30 ms): any OTHER effect of
# `all` estimated beyond 3 std is a false finding.
#
#   bench/timing_verdicts.sh [ROTORID=build/release/apps/rotorid] [OUT_DIR=/tmp/rotorid-timing]
set -euo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
OUT=${2:-/tmp/rotorid-timing}
mkdir -p "$OUT"
PY=/usr/bin/python3

sim() {  # sim NAME SEED EFFECT...
  local name=$1 seed=$2; shift 2
  local args=()
  for e in "$@"; do args+=(--effect "$e"); done
  "$R" simulate --preset B --seconds 60 --seed "$seed" "${args[@]}" --out "$OUT/$name.csv" \
    --truth "$OUT/${name}_truth.json" --vehicle-out "$OUT/$name.yaml" -q
}

verdict() {  # verdict LABEL TRUTH RIVAL JSON
  "$PY" - "$@" <<'PY'
import json, sys
label, truth, rival, path = sys.argv[1:5]
r = json.load(open(path))
selected = r.get("selected", [])
confounded = [c for c in r.get("confounded", []) if not c.get("distinguishable", True)]
pair = lambda c: set(c["effects"]) == {truth, rival}
if truth in selected and rival not in selected:
    outcome = "confounded with " + rival if any(pair(c) for c in confounded) else "named"
elif rival in selected and truth not in selected:
    outcome = "confounded (rival selected)" if any(pair(c) for c in confounded) else "WRONG"
elif truth in selected:
    outcome = "both selected"
else:
    outcome = "missed"
print(f"{label:22s} selected={','.join(selected) or 'none':24s} {outcome}")
PY
}

blind() {  # blind EFFECT PARAMETER RIVAL SIZE SEED: simulate, diagnose against a held-out flight, judge
  local effect=$1 parameter=$2 rival=$3 size=$4 seed=$5
  local name="${effect}_${size}_$seed"
  sim "$name" "$seed" "$parameter=$size"
  sim "${name}_val" $((seed + 100)) "$parameter=$size"
  "$R" diagnose --vehicle "$OUT/$name.yaml" --log "$OUT/$name.csv" \
    --validate-vehicle "$OUT/${name}_val.yaml" --validate-log "$OUT/${name}_val.csv" --json "$OUT/$name.json" -q || true
  verdict "$effect $size s seed $seed" "$effect" "$rival" "$OUT/$name.json"
}

for size in 0.005 0.010 0.015; do
  for seed in 1 2 3; do blind delay delay_s motor_lag "$size" "$seed"; done
done
for size in 0.010 0.020 0.040; do
  for seed in 1 2 3; do blind motor_lag motor_tau_s delay "$size" "$seed"; done
done
for seed in 1 2 3; do
  sim "both_$seed" "$seed" delay_s=0.015 motor_tau_s=0.030
  "$R" refine --vehicle "$OUT/both_$seed.yaml" --log "$OUT/both_$seed.csv" --json "$OUT/both_$seed.json" -q || true
  "$PY" - "$OUT/both_$seed.json" "$seed" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["refined"]["effects"]
worst, where = 0.0, "-"
for name, e in r.items():
    if name in ("delay_s", "motor_tau_s"):
        continue
    values = e["value"] if isinstance(e["value"], list) else [e["value"]]
    stds = e["std"] if isinstance(e["std"], list) else [e["std"]]
    for v, s in zip(values, stds):
        if s and abs(v) / s > worst:
            worst, where = abs(v) / s, name
print(f"delay 15 ms + lag 30 ms seed {sys.argv[2]}: delay {1e3 * r['delay_s']['value']:.2f} ms, tau "
      f"{1e3 * r['motor_tau_s']['value']:.2f} ms; largest other effect {worst:.1f} std ({where})")
PY
done
