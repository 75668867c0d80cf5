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

# effect-name | --effect assignment | simulate options
CASES=(
  "rotor_drag|rotor_drag=4e-5,6e-6|"
  "rotor_inertia|rotor_inertia=3e-6|"
  "rotor_inertia,motor_lag|rotor_inertia=3e-5 motor_tau_s=0.02|"
  "rotor_thrust_scale|rotor_thrust_scale=0.03,-0.02,-0.03,0.02|"
  "acc_delay|acc_delay=0.005|"
  "ground_effect|ground_effect=1.0|--hover-altitude 0.3"
  "rotor_drag,rotor_inertia|rotor_drag=4e-5,6e-6 rotor_inertia=3e-6|"
  "acc_delay,delay|acc_delay=0.005 delay=0.01|"
)

check() {  # check LABEL REPORT TRUTH (issue 12's tolerances: bench/effect_check.py)
  "$PY" bench/effect_check.py "$@"
}

for c in "${CASES[@]}"; do
  IFS='|' read -r effects assigns simopts <<<"$c"
  for seed in $SEEDS; do
    base="$OUT/${effects//,/+}_s$seed"
    args=()
    for a in $assigns; do args+=(--effect "$a"); done
    # shellcheck disable=SC2086
    "$R" simulate -q --preset A --mocap --seconds 60 --seed "$seed" "${args[@]}" $simopts \
      --out "$base.csv" --truth "$base.truth.json" --vehicle-out "$base.yaml" || { echo "$base: simulate failed"; continue; }
    "$R" refine -q --vehicle "$base.yaml" --log "$base.csv" --effects "$effects" --json "$base.json" 2>"$base.err"
    check "$effects seed $seed (exit $?)" "$base.json" "$base.truth.json"
  done
done

IND=../shared/data/independent-sim
[ -d "$IND" ] || { echo "no $IND"; exit 0; }
for pair in A_rotor_drag:rotor_drag A_rotor_inertia:rotor_inertia A_rotor_thrust_scale:rotor_thrust_scale \
            A_ground_effect:ground_effect CF_acc_delay:acc_delay A_imu_lever_arm:imu_lever_arm; do
  IFS=':' read -r flight effect <<<"$pair"
  "$R" refine -q --vehicle "$IND/$flight.yaml" --log "$IND/$flight.csv" --effects "$effect" \
    --json "$OUT/$flight.json" 2>"$OUT/$flight.err"
  check "independent $flight (exit $?)" "$OUT/$flight.json" "$IND/${flight}_truth.json"
done
