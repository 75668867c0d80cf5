#!/usr/bin/env bash
# The blind diagnosis on the independent simulator's flights (../shared/data/independent-sim): each
# flight diagnosed with every candidate (`rotorid diagnose --effects every`), judged against its
# truth by bench/diagnosis_check.py (the withheld effect ranked first, the withheld ones selected,
# nothing else; A_clean: nothing selected). A second simulator's controller, pilot and noise: the
# diagnosis must not depend on rotorid's own simulator. Results: docs/diagnosis.md.
#
#   bench/independent_sim_diagnosis.sh [ROTORID=build/release/apps/rotorid] [OUT=/tmp/rotorid-independent-diag]
set -uo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
OUT=${2:-/tmp/rotorid-independent-diag}
IND=../shared/data/independent-sim
PY=/usr/bin/python3
[ -d "$IND" ] || { echo "no $IND: nothing to run"; exit 0; }
mkdir -p "$OUT"
for truth in "$IND"/*_truth.json; do
  flight=$(basename "$truth" _truth.json)
  start=$(date +%s.%N)
  # --allow-partial: a short flight may leave a parameter unidentifiable (a yaw spin's roll inertia)
  "$R" diagnose -q --vehicle "$IND/$flight.yaml" --log "$IND/$flight.csv" --effects every --allow-partial \
    --json "$OUT/$flight.diag.json" 2>"$OUT/$flight.err"
  code=$?
  took=$(printf '%.1f' "$(echo "$(date +%s.%N) - $start" | bc)")
  "$PY" bench/diagnosis_check.py "independent $flight (exit $code)" "$OUT/$flight.diag.json" "$truth" "$took"
done
