#!/usr/bin/env bash
# The rotor-acceleration term of the TU Delft 3-inch quad (docs/blackbox.md 6): `rotorid refine
# --effects rotor_inertia` on each log's kept segment (--segment auto), printed in the paper's
# normalised form (B2 = J/I_zz, kd/I_zz, kt*y/I_xx and kt*x/I_yy) with the held-out relative errors
# on LOG00230; the same with a 4x mass; with the refined delay, and as a cross-check the
# rotor speed shifted before processing (Omega and Omega' together, as the refined delay moves
# them); and the diagnosis of LOG00271 with LOG00230 held out.
#
#   bench/blackbox_rotor_inertia.sh [ROTORID=build/release/apps/rotorid] [OUT=/tmp/rotorid-bb-inertia]
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
OUT=${2:-/tmp/rotorid-bb-inertia}
SHIFT=$(dirname "$R")/../bench/blackbox_rotor_shift
D=../shared/data/real/indiflight-tudelft-throw/raw
V=data/vehicles/tudelft_indiflight_3inch.yaml
COMMON=(--cutoff-hz 30 --all-parameters --allow-partial)
mkdir -p "$OUT"
sed 's/^mass: 0.428$/mass: 1.712/' "$V" >"$OUT/heavy.yaml"

summary() {  # summary LABEL REPORT
  /usr/bin/python3 - "$@" <<'PY'
import json, sys
label, path = sys.argv[1:]
r = json.load(open(path))
arm_x, arm_y = 0.0455, 0.0635  # the vehicle file's hub offsets (pitch and roll arms)
def line(stage):
    s = r[stage]; p = {k: v["value"] for k, v in s["parameters"].items()}
    izz = p["tudelft3.I_zz"]
    out = \
          f"p {p['kt'] * arm_y / p['tudelft3.I_xx'] * 1e6:5.1f} q {p['kt'] * arm_x / p['tudelft3.I_yy'] * 1e6:5.1f} " \
          f"kd/Izz {p['kd'] / izz * 1e6:5.2f} (1e-6)"
    j = s.get("effects", {}).get("rotor_inertia_kgm2", {})
    if j.get("enabled"):
        out += f"  J {j['value']:.3g} +- {100 * j['std'] / j['value'] if j['value'] else float('inf'):.0f} %" \
               f"  B2 = J/Izz {j['value'] / izz * 1e3:.3f}e-3"
    rel = s["relative_error_pct"]
    out += "  in-sample Mx/My/Mz %.0f/%.0f/%.0f %%" % (rel["Mx"], rel["My"], rel["Mz"])
    if "held_out" in r:
        h = r["held_out"][stage]["relative_error_pct"]
        out += "  held-out %.0f/%.0f/%.0f %%" % (h["Mx"], h["My"], h["Mz"])
    return out
print(f"{label:28s} linear  {line('linear')}")
print(f"{'':28s} refined {line('refined')}")
PY
}

echo "== refine --effects rotor_inertia, kept segments (held out: LOG00230)"
for L in 271 281 230; do
  HOLD=(--validate-vehicle "$V" --validate-log "$D/LOG00230.BFL")
  [ "$L" = 230 ] && HOLD=(--validate-vehicle "$V" --validate-log "$D/LOG00271.BFL")
  "$R" refine --vehicle "$V" --log "$D/LOG00$L.BFL" "${HOLD[@]}" "${COMMON[@]}" --effects rotor_inertia \
    --json "$OUT/ri_$L.json" -q 2>/dev/null
  summary "LOG00$L" "$OUT/ri_$L.json"
done
"$R" refine --vehicle "$OUT/heavy.yaml" --log "$D/LOG00271.BFL" "${COMMON[@]}" --effects rotor_inertia \
  --json "$OUT/ri_271_heavy.json" -q 2>/dev/null
summary "LOG00271, mass 1.712 kg" "$OUT/ri_271_heavy.json"

echo "== with the refinement's delay (moves Omega and Omega')"
for L in 271 281; do
  "$R" refine --vehicle "$V" --log "$D/LOG00$L.BFL" --validate-vehicle "$V" --validate-log "$D/LOG00230.BFL" \
    "${COMMON[@]}" --effects rotor_inertia,delay --json "$OUT/rid_$L.json" -q 2>/dev/null
  summary "LOG00$L +delay" "$OUT/rid_$L.json"
  /usr/bin/python3 -c "import json; e=json.load(open('$OUT/rid_$L.json'))['refined']['effects']['delay_s']; print(' ' * 29 + 'delay %.1f +- %.1f ms' % (1e3 * e['value'], 1e3 * e['std']))"
done

echo "== rotor speed shifted before processing (Omega and Omega' together), held out: LOG00230 shifted alike"
SHIFTS="0 -5 -10 -15 -20"
for L in 271 281 230; do "$SHIFT" "$D/LOG00$L.BFL" "$OUT/s$L" $SHIFTS >/dev/null; done
for L in 271 281; do
  for S in $SHIFTS; do
    "$R" refine --vehicle "$V" --log "$OUT/s${L}_${S}ms.csv" --validate-vehicle "$V" \
      --validate-log "$OUT/s230_${S}ms.csv" --segment none "${COMMON[@]}" --effects rotor_inertia \
      --json "$OUT/sh_${L}_$S.json" -q 2>/dev/null
    summary "LOG00$L shifted $S ms" "$OUT/sh_${L}_$S.json"
  done
done

echo "== diagnose LOG00271, LOG00230 held out"
for E in all delay,motor_lag,acc_bias,gyro_bias,misalignment,imu_lever_arm,rotor_inertia,acc_delay rotor_inertia; do
  echo "-- --effects $E"
  "$R" diagnose --vehicle "$V" --log "$D/LOG00271.BFL" --validate-vehicle "$V" --validate-log "$D/LOG00230.BFL" \
    "${COMMON[@]}" --effects "$E" --json "$OUT/diag_${E//,/_}.json" 2>/dev/null | sed -n '/^which:/,$p'
done
