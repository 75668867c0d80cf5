#!/usr/bin/env bash
# Issue 12's recovery study on rotorid's simulator: each effect of real vehicles (INTERFACE.md v2)
# alone and in pairs, seeds 1-3, on configuration A (200 Hz, pixhawk noise, 60 s) and on the
# Crazyflie-like preset CF (500 Hz, bmi088 noise, 40 s), and X, a 0.6 kg 5-inch X quad
# (data/vehicles/betaflight_gecko.yaml, derived parameters, 200 Hz, pixhawk noise, 60 s), each with the flight profile that excites
# it, motion capture on; refined with `rotorid refine --effects <the effect(s)>`. One line per run:
# truth -> estimate +- std per coordinate, `ok` when every coordinate is within issue 12's tolerance:
# lever arm 2 mm or 3 std, acc_delay 1 ms, drag coefficients 10 %, rotor inertia 15 %, thrust
# scales 0.01, battery exponent 0.1, ground-effect coefficient 20 % (motor lag and delay, named in
# pairs, 10 %). Results: docs/adding_an_effect.md, "Status of the other effects".
#
#   bench/sim_effects_study.sh [ROTORID=build/release/apps/rotorid] [SEEDS="1 2 3"] [OUT=/tmp/rotorid-sim-study] [VEHICLES="A CF"] [MATCH=] [MODE=refine]
#
# MATCH (a grep -E pattern) keeps only the cases whose line matches it, e.g. "circle".
# MODE=diagnose runs the blind diagnosis instead (`rotorid diagnose --effects $CANDIDATES`, every
# registered effect by default) and judges it with bench/diagnosis_check.py: the withheld effect
# ranked first, the withheld ones selected, nothing else; magnitudes with the same tolerances.
# The `clean` cases (no effect, every candidate's inputs logged) only run in diagnose mode: a false
# alarm is any selection, e.g. `bench/sim_effects_study.sh R "$(seq -s' ' 101 120)" OUT CF clean diagnose`.
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
SEEDS=${2:-"1 2 3"}
OUT=${3:-/tmp/rotorid-sim-study}
VEHICLES=${4:-"A CF"}
MATCH=${5:-}
MODE=${6:-refine}
CANDIDATES=${CANDIDATES:-every}
PY=/usr/bin/python3
mkdir -p "$OUT"

# vehicle | effects | --effect assignments | simulate options | refine options
# (the lever arm's uncorrected centripetal acceleration makes the linear step call I_xx, I_yy of the
# Crazyflie-like vehicle unidentifiable on the yaw spin: --allow-partial lets the refinement go on)
CASES=(
  "A|rotor_drag|rotor_drag=4e-5,6e-6|--profile circle --circle-radius 3 --circle-speed 3"
  "A|rotor_inertia,motor_lag|rotor_inertia=5e-5 motor_tau_s=0.02|--profile yaw-spin"
  "A|rotor_inertia|rotor_inertia=3e-6|--profile yaw-spin"
  "A|rotor_thrust_scale|rotor_thrust_scale=0.03,-0.02,-0.03,0.02|"
  "A|acc_delay|acc_delay=0.005|"
  "A|ground_effect|ground_effect=1.0|--profile takeoff-landing"
  "A|battery|battery_exponent=1.0|--battery"
  "A|imu_lever_arm|imu_lever_arm=0.02,0.01,-0.03|--profile yaw-spin"
  "A|acc_delay,delay|acc_delay=0.005 delay=0.01|"
  "A|battery,motor_lag|battery_exponent=1.0 motor_tau_s=0.02|--battery"
  "A|rotor_drag,imu_lever_arm|rotor_drag=4e-5,6e-6 imu_lever_arm=0.02,0.01,-0.03|--profile circle --circle-radius 3 --circle-speed 3"
  "A|ground_effect,rotor_thrust_scale|ground_effect=1.0 rotor_thrust_scale=0.03,-0.02,-0.03,0.02|--profile takeoff-landing"
  "CF|rotor_drag|rotor_drag=1e-6,2.5e-8|--profile circle --circle-radius 1 --circle-speed 1.5"
  "CF|rotor_inertia|rotor_inertia=5e-8|--profile yaw-spin"
  "CF|rotor_thrust_scale|rotor_thrust_scale=0.03,-0.02,-0.03,0.02|"
  "CF|acc_delay|acc_delay=0.004|"
  "CF|ground_effect|ground_effect=1.0|--profile takeoff-landing"
  "CF|battery|battery_exponent=1.0|--battery"
  "CF|imu_lever_arm|imu_lever_arm=0.01,-0.005,0.005|--profile yaw-spin|--allow-partial"
  "CF|acc_delay,delay|acc_delay=0.004 delay=0.01|"
  "CF|battery,motor_lag|battery_exponent=1.0 motor_tau_s=0.03|--battery"
  "CF|rotor_inertia,imu_lever_arm|rotor_inertia=5e-8 imu_lever_arm=0.01,-0.005,0.005|--profile yaw-spin|--allow-partial"
  "CF|ground_effect,rotor_thrust_scale|ground_effect=1.0 rotor_thrust_scale=0.03,-0.02,-0.03,0.02|--profile takeoff-landing"
  "A|clean||--battery"
  "CF|clean||--battery"
  "X|rotor_thrust_scale|rotor_thrust_scale=0.03,-0.02,-0.03,0.02|--profile yaw-spin"
  "X|imu_lever_arm|imu_lever_arm=0.015,-0.01,0.01|--profile yaw-spin"
  "X|clean||--battery"
)

check() {  # check LABEL REPORT TRUTH SECONDS
  "$PY" bench/effect_check.py "$@"
}

for c in "${CASES[@]}"; do
  IFS='|' read -r vehicle effects assigns simopts refineopts <<<"$c"
  case " $VEHICLES " in *" $vehicle "*) ;; *) continue ;; esac
  [ -z "$MATCH" ] || grep -qE -- "$MATCH" <<<"$c" || continue
  [ "$effects" != clean ] || [ "$MODE" = diagnose ] || continue
  seconds=60; [ "$vehicle" = CF ] && seconds=40
  for seed in $SEEDS; do
    base="$OUT/${vehicle}_${effects//,/+}_s$seed"
    args=()
    for a in $assigns; do args+=(--effect "$a"); done
    # shellcheck disable=SC2086
    vehicle_args=(--preset "$vehicle")
    [ "$vehicle" = X ] && vehicle_args=(--vehicle data/vehicles/betaflight_gecko.yaml)
    "$R" simulate -q "${vehicle_args[@]}" --mocap --seconds "$seconds" --seed "$seed" "${args[@]}" $simopts \
      --out "$base.csv" --truth "$base.truth.json" --vehicle-out "$base.yaml" 2>"$base.simerr" ||
      { echo "$vehicle $effects seed $seed: simulate failed: $(head -c 300 "$base.simerr")"; continue; }
    start=$(date +%s.%N)
    if [ "$MODE" = diagnose ]; then
      # shellcheck disable=SC2086
      "$R" diagnose -q --vehicle "$base.yaml" --log "$base.csv" --effects "$CANDIDATES" --json "$base.diag.json" \
        $refineopts 2>"$base.diag.err"
    else
      # shellcheck disable=SC2086
      "$R" refine -q --vehicle "$base.yaml" --log "$base.csv" --effects "$effects" --json "$base.json" $refineopts \
        2>"$base.err"
    fi
    code=$?
    took=$(printf '%.1f' "$(echo "$(date +%s.%N) - $start" | bc)")
    label="$vehicle ${effects} ${simopts%% --circle*} seed $seed (exit $code)"
    if [ "$MODE" = diagnose ]; then
      "$PY" bench/diagnosis_check.py "$label" "$base.diag.json" "$base.truth.json" "$took"
    else
      check "$label" "$base.json" "$base.truth.json" "$took"
    fi
  done
done
