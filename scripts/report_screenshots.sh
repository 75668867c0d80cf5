#!/usr/bin/env bash
# Screenshots of the HTML reports as a browser shows them: runs identify, refine and diagnose on
# the simulated flights bundled in data/sim (the commands of scripts/main_job.sh) into a temporary
# folder, and takes headless Chromium screenshots of each report into docs/figures/
# (report_identify.png, report_refine.png, report_diagnose.png). With the shared real flights
# present (../shared/data/real), also the identify report of the brushed Crazyflie flight jana01
# (report_real_identify.png), and with NanoBench's flights the predict report of B2 + B8 from a model
# refined on B3 + B5 + B10 (report_real_predict.png).
#
#   scripts/report_screenshots.sh            # needs build/release/apps/rotorid (rotorid_cli), gnuplot, chromium
#   ROTORID=path/to/rotorid OUT=dir scripts/report_screenshots.sh
#
# Each page is rendered 1280 px wide at a device scale of 0.6 (768 px wide PNGs, a few hundred KB)
# and cut to the length given per report below.
set -euo pipefail
cd "$(dirname "$0")/.."
R=${ROTORID:-build/release/apps/rotorid}
OUT=${OUT:-docs/figures}
CHROMIUM=${CHROMIUM:-chromium}
SCALE=${SCALE:-0.6}
[ -x "$R" ] || { echo "report_screenshots.sh: $R not found; build the rotorid_cli target first" >&2; exit 1; }
command -v "$CHROMIUM" > /dev/null || { echo "report_screenshots.sh: $CHROMIUM not found" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
D=data/sim

# shot NAME REPORT_DIR HEIGHT_PX [SCALE [PAGE]]: the top HEIGHT_PX (CSS pixels) of REPORT_DIR/PAGE
# (report.html).
shot() {
  local name=$1 dir=$2 height=$3 scale=${4:-$SCALE} page=${5:-report.html}
  "$CHROMIUM" --headless --disable-gpu --no-sandbox --hide-scrollbars --force-device-scale-factor="$scale" \
    --disable-quic --no-first-run --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$TMP/chromium-profile" \
    --screenshot="$OUT/$name.png" --window-size=1280,"$height" "file://$(realpath "$dir")/$page" \
    > "$TMP/chromium.log" 2>&1 || { cat "$TMP/chromium.log" >&2; exit 1; }
  echo "$OUT/$name.png: $(du -k "$OUT/$name.png" | cut -f1) KB"
}
# first NAME REPORT_DIR: the first screen a reader sees (1280 x 900 at scale 1): the answer.
first() { shot "$1_first" "$2" 900 1; }

"$R" identify -q --vehicle $D/A.yaml --log $D/A_train.csv --vehicle $D/B.yaml --log $D/B_train.csv \
  --weight 1 --weight 2 --report "$TMP/identify"
shot report_identify "$TMP/identify" 3300
first report_identify "$TMP/identify"

"$R" refine -q --vehicle $D/A.yaml --log $D/A_train.csv --vehicle $D/B.yaml --log $D/B_train.csv \
  --weight 1 --weight 2 --validate-vehicle $D/A.yaml --validate-log $D/A_val.csv \
  --validate-vehicle $D/B.yaml --validate-log $D/B_val.csv --report "$TMP/refine"
shot report_refine "$TMP/refine" 3700
first report_refine "$TMP/refine"

"$R" diagnose -q --vehicle $D/B.yaml --log $D/B_train.csv --validate-vehicle $D/B.yaml \
  --validate-log $D/B_val.csv --report "$TMP/diagnose"
shot report_diagnose "$TMP/diagnose" 5400
first report_diagnose "$TMP/diagnose"

REAL=../shared/data/real/crazyflie-imrc-rpm/brushed/raw/jana01
if [ -e "$REAL" ]; then
  "$R" identify -q --vehicle data/vehicles/crazyflie21_brushed.yaml --log "$REAL" --allow-partial \
    --report "$TMP/real"
  shot report_real_identify "$TMP/real" 3600
fi

NANOBENCH=../shared/data/real/nanobench-cf21
if [ -d "$NANOBENCH" ]; then
  NV=data/vehicles/crazyflie21_nanobench.yaml
  NM=data/column_maps/nanobench_cf21.yaml
  # docs/prediction.md's model; exit 3 (its checks warn of the yaw axis) still writes the report.
  "$R" refine -q --vehicle $NV --log $NANOBENCH/B3_figure8_fast_rep2.csv --vehicle $NV \
    --log $NANOBENCH/B5_helix_fast_rep1.csv --vehicle $NV --log $NANOBENCH/B10_lissajous_fast_rep1.csv \
    --column-map $NM --all-parameters --first-moment per-flight --effects delay,motor_lag,battery,rotor_drag \
    --allow-partial --json "$TMP/nanobench.json" || [ $? -eq 3 ]
  "$R" predict -q --params "$TMP/nanobench.json" --vehicle $NV --log $NANOBENCH/B2_circle_fast_rep2.csv \
    --vehicle $NV --log $NANOBENCH/B8_star_fast_rep1.csv --column-map $NM --set cf21_nanobench.I_zz=2.98e-5 \
    --set kd=0 --torque-bias-window 0.05 --report "$TMP/predict"
  shot report_real_predict "$TMP/predict" 1500 "$SCALE" predict.html
fi
