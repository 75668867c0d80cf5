#!/usr/bin/env bash
# Every real-flight diagnosis of docs/real_flights.md, `diagnose --effects every --allow-partial`:
# the brushed IMRC Crazyflies by RPM (jana00/01/04/06) and jana01 through the PWM map (default
# candidates), the ARPL windows of SOURCE.md, and the five NanoBench flights (with pm.vbat). One line
# per run: exit code, the selected effects with their sizes, the timing candidates' statuses, the
# final model's held-out Fz/Mx/My % and the wall time. Run it before and after a change of the
# diagnosis: a real flight is the final judge.
#
#   bench/real_diagnoses.sh [ROTORID=build/release/apps/rotorid] [OUT_DIR=/tmp/rotorid-real-diagnoses]
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
OUT=${2:-/tmp/rotorid-real-diagnoses}
REAL=../shared/data/real
PY=/usr/bin/python3
CF=data/vehicles/crazyflie21_brushed.yaml
mkdir -p "$OUT"
[ -d "$REAL" ] || { echo "no $REAL: nothing to run"; exit 0; }

summary() {  # summary LABEL JSON EXIT STDERR_FILE SECONDS
  "$PY" - "$@" <<'PYEOF'
import json, sys
label, path, code, err, seconds = sys.argv[1:6]
try:
    r = json.load(open(path))
except Exception:
    msg = open(err).read().strip().splitlines()
    print(f"{label:24s} exit {code}  {msg[-1][:150] if msg else ''}")
    sys.exit(0)
def fmt(values):
    return ",".join("held" if v is None else f"{v:.3g}" for v in (values if isinstance(values, list) else [values]))
selected, timing = [], []
for entry in r["ranking"]:
    size = "".join(f" {fmt(m['value'])}" for m in entry.get("magnitude", {}).values())
    if entry["status"] == "selected":
        selected.append(entry["effect"] + size)
    if entry["effect"] in ("delay", "motor_lag"):
        timing.append(f"{entry['effect']}:{entry['status']}")
final = r.get("final", {}).get("relative_error_pct", {})
t3 = "/".join("-" if final.get(c) is None else f"{final[c]:.1f}" for c in ("Fz", "Mx", "My"))
print(f"{label:24s} exit {code}  selected [{'; '.join(selected) or 'none'}]  {' '.join(timing)}  "
      f"final Fz/Mx/My {t3}  {float(seconds):.1f} s")
PYEOF
}

run() {  # run LABEL ARGS...
  local label=$1; shift
  local json="$OUT/${label//[^A-Za-z0-9_]/_}.json" start end
  rm -f "$json"
  start=$(date +%s.%N)
  "$R" diagnose -q --allow-partial --json "$json" "$@" 2> "$OUT/err.txt" > /dev/null
  local code=$?
  end=$(date +%s.%N)
  summary "$label" "$json" "$code" "$OUT/err.txt" "$(echo "$end - $start" | bc)"
}

IMRC=$REAL/crazyflie-imrc-rpm/brushed/raw
for f in jana00 jana01 jana04 jana06; do
  [ -f "$IMRC/$f" ] && run "$f rpm" --vehicle $CF --log "$IMRC/$f" --effects every
done
[ -f "$IMRC/jana01" ] && run "jana01 pwm" --vehicle $CF --log "$IMRC/jana01" --rotor-signal command

ARPL=$REAL/crazyflie-arpl-sysid/raw
if [ -d "$ARPL" ]; then
  run "arpl log10 35-65" --vehicle $CF --log "$ARPL/log10" --window 35,65 --effects every
  run "arpl log15 55-90" --vehicle $CF --log "$ARPL/log15" --window 55,90 --effects every
  run "arpl log16 32-38" --vehicle $CF --log "$ARPL/log16" --window 32,38 --effects every
  run "arpl log16 45-49" --vehicle $CF --log "$ARPL/log16" --window 45,49 --effects every
fi

NANO=$REAL/nanobench-cf21
if [ -d "$NANO" ]; then
  for f in B2_circle_fast_rep2 B3_figure8_fast_rep2 B5_helix_fast_rep1 B8_star_fast_rep1 B10_lissajous_fast_rep1; do
    run "nanobench ${f%%_*}" --vehicle $CF --log "$NANO/$f.csv" --column-map data/column_maps/nanobench_cf21.yaml --effects every
  done
fi
