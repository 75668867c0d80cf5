#!/usr/bin/env bash
# The effects of real vehicles (INTERFACE.md v2) on rotorid's simulator, several seeds: each effect
# alone, and pairs, simulated on configuration A with motion capture, then refined with the
# effect(s) named. One line per run: truth, estimate +- std, and whether it is within issue 12's
# tolerance. Then the independent simulator's flights (../shared/data/independent-sim).
#
#   bench/real_vehicle_effects.sh [ROTORID=build/release/apps/rotorid] [SEEDS="1 2 3"] [OUT=/tmp/rotorid-v2]
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
SEEDS=${2:-"1 2 3"}
OUT=${3:-/tmp/rotorid-v2}
PY=/usr/bin/python3
mkdir -p "$OUT"

# effect-name | --effect assignment | simulate options | tolerance per coordinate
CASES=(
  "rotor_drag|rotor_drag=4e-5,6e-6||rel:0.10"
  "rotor_inertia|rotor_inertia=3e-6||rel:0.15"
  "rotor_inertia,motor_lag|rotor_inertia=3e-5 motor_tau_s=0.02||rel:0.15"
  "rotor_thrust_scale|rotor_thrust_scale=0.03,-0.02,-0.03,0.02||abs:0.01"
  "acc_delay|acc_delay=0.005||abs:0.001"
  "ground_effect|ground_effect=1.0|--hover-altitude 0.3|rel:0.20"
  "rotor_drag,rotor_inertia|rotor_drag=4e-5,6e-6 rotor_inertia=3e-6||rel:0.15"
  "acc_delay,delay|acc_delay=0.005 delay=0.01||abs:0.001"
)

check() {  # check LABEL REPORT TRUTH TOLERANCE
  "$PY" - "$@" <<'EOF'
import json, sys
label, report, truth_path, tol = sys.argv[1:5]
kind, size = tol.split(":"); size = float(size)
try:
    r = json.load(open(report)); t = json.load(open(truth_path))
except Exception as e:
    print(f"{label:44s} no report ({e})"); sys.exit(0)
eff = r["refined"]["effects"]; truth = t["effects"]
ok = True; parts = []
for key, entry in eff.items():
    if not entry.get("enabled"): continue
    v, s, want = entry["value"], entry["std"], truth.get(key)
    vs = v if isinstance(v, list) else [v]; ss = s if isinstance(s, list) else [s]
    ws = want if isinstance(want, list) else [want]
    for a, (x, sd, w) in enumerate(zip(vs, ss, ws)):
        limit = size * abs(w) if kind == "rel" else size
        good = abs(x - w) <= limit
        ok = ok and good
        parts.append(f"{key}{'' if len(vs) == 1 else '_' + str(a + 1)} {w:.4g} -> {x:.4g} +- {sd if sd is None else float(sd):.2g}{'' if good else ' (!)'}")
print(f"{label:44s} {'ok ' if ok else 'OUT'} " + "; ".join(parts))
EOF
}

for c in "${CASES[@]}"; do
  IFS='|' read -r effects assigns simopts tol <<<"$c"
  for seed in $SEEDS; do
    base="$OUT/${effects//,/+}_s$seed"
    args=()
    for a in $assigns; do args+=(--effect "$a"); done
    # shellcheck disable=SC2086
    "$R" simulate -q --preset A --mocap --seconds 60 --seed "$seed" "${args[@]}" $simopts \
      --out "$base.csv" --truth "$base.truth.json" --vehicle-out "$base.yaml" || { echo "$base: simulate failed"; continue; }
    "$R" refine -q --vehicle "$base.yaml" --log "$base.csv" --effects "$effects" --json "$base.json" 2>"$base.err"
    check "$effects seed $seed (exit $?)" "$base.json" "$base.truth.json" "$tol"
  done
done

IND=../shared/data/independent-sim
[ -d "$IND" ] || { echo "no $IND"; exit 0; }
for pair in A_rotor_drag:rotor_drag:rel:0.10 A_rotor_inertia:rotor_inertia:rel:0.15 \
            A_rotor_thrust_scale:rotor_thrust_scale:abs:0.01 A_ground_effect:ground_effect:rel:0.20 \
            CF_acc_delay:acc_delay:abs:0.001 A_imu_lever_arm:imu_lever_arm:abs:0.002; do
  IFS=':' read -r flight effect kind size <<<"$pair"
  "$R" refine -q --vehicle "$IND/$flight.yaml" --log "$IND/$flight.csv" --effects "$effect" \
    --json "$OUT/$flight.json" 2>"$OUT/$flight.err"
  check "independent $flight (exit $?)" "$OUT/$flight.json" "$IND/${flight}_truth.json" "$kind:$size"
done
