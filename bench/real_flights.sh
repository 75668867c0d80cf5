#!/usr/bin/env bash
# Runs rotorid on every real flight of ../shared/data/real that it can read and prints one line per
# run: exit code, kt, roll/pitch inertia, Table III (Fz/Mx/My) and the checks that did not pass.
# The regression check for "a real flight is the final judge": run it before and after a change.
#
#   bench/real_flights.sh [ROTORID=build/release/apps/rotorid] [OUT_DIR=/tmp/rotorid-real]
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
OUT=${2:-/tmp/rotorid-real}
REAL=../shared/data/real
PY=/usr/bin/python3
mkdir -p "$OUT"
[ -d "$REAL" ] || { echo "no $REAL: nothing to run"; exit 0; }

summary() {  # summary LABEL JSON EXIT STDERR_FILE
  "$PY" - "$@" <<'EOF'
import json, sys
label, path, code, err = sys.argv[1:5]
try:
    r = json.load(open(path))
except Exception:
    msg = open(err).read().strip().splitlines()
    print(f"{label:34s} exit {code}  {msg[-1][:150] if msg else ''}")
    sys.exit(0)
block = r.get("refined") or r.get("linear") or {}
p = block.get("parameters", {})
def val(name):
    for k, v in p.items():
        if k == name or k.endswith("." + name):
            return f"{v['value']:.3g}" + ("" if v.get("essential", True) else "(x)")
    return "-"
rel = block.get("relative_error_pct") or r.get("relative_error_pct") or r.get("baseline", {}).get("relative_error_pct") or {}
t3 = "/".join("-" if rel.get(c) is None else f"{rel[c]:.0f}" for c in ("Fz", "Mx", "My"))
bad = [c["name"] + ":" + c["status"] for c in r.get("checks", []) if c.get("status") != "ok"]
extra = ""
if "selected" in r:
    extra = " selected=" + (",".join(s.get("effect", "?") for s in r["selected"]) or "none")
eff = block.get("effects", {})
for k, v in eff.items():
    value = v.get("value")
    if isinstance(value, (int, float)):
        extra += f" {k}={value:.3g}" + ("(bound)" if v.get("on_bound") else "")
print(f"{label:34s} exit {code}  kt {val('kt'):9s} Ixx {val('I_xx'):10s} Iyy {val('I_yy'):10s} "
      f"T3 Fz/Mx/My {t3:11s} checks {','.join(bad) or 'ok'}{extra}")
EOF
}

run() {  # run LABEL ARGS...
  local label=$1; shift
  local json="$OUT/${label//[^A-Za-z0-9_]/_}.json"
  rm -f "$json"
  "$R" "$@" --json "$json" -q 2> "$OUT/err.txt" > /dev/null
  summary "$label" "$json" "$?" "$OUT/err.txt"
}

IMRC=$REAL/crazyflie-imrc-rpm
for f in jana00 jana01 jana04 jana06; do
  [ -f "$IMRC/brushed/raw/$f" ] || continue
  run "identify brushed $f rpm" identify --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$IMRC/brushed/raw/$f" --allow-partial
  run "identify brushed $f pwm" identify --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$IMRC/brushed/raw/$f" --allow-partial --rotor-signal command
done
for f in eckart00 eckart17 eckart34; do
  [ -f "$IMRC/brushless/raw/$f" ] || continue
  run "identify brushless $f" identify --vehicle data/vehicles/crazyflie21_brushless.yaml --log "$IMRC/brushless/raw/$f" --allow-partial
done
if [ -f "$IMRC/brushed/raw/jana01" ]; then
  for signal in rpm command; do
    run "refine jana01 $signal delay+lag" refine --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$IMRC/brushed/raw/jana01" \
      --allow-partial --rotor-signal $signal --effects delay,motor_lag
    run "refine jana04 $signal delay+lag" refine --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$IMRC/brushed/raw/jana04" \
      --allow-partial --rotor-signal $signal --effects delay,motor_lag
  done
  # The effects of real vehicles (docs/real_flights.md, "The effects of real vehicles on the Crazyflies"); the velocity is the pose estimate's.
  for f in jana00 jana01 jana04 jana06; do
    run "refine $f rpm v2 effects" refine --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$IMRC/brushed/raw/$f" \
      --allow-partial --effects delay,motor_lag,rotor_drag,rotor_inertia,acc_delay
  done
fi
