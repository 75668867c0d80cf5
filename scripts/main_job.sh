#!/usr/bin/env bash
# The main job: installs the dependencies (Debian, needs root or sudo), builds rotorid (Release)
# and runs identify, refine and diagnose on the simulated flights bundled in data/sim, printing the
# identified parameters. Outputs (JSON reports, HTML report) go to out/.
# Set ROTORID_SKIP_DEPS=1 to skip the package installation.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${ROTORID_SKIP_DEPS:-0}" != "1" ]; then bash scripts/install_deps.sh; fi
JOBS=${JOBS:-$(nproc)}
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DROTORID_BUILD_TESTS=OFF > /dev/null
cmake --build build/release -j"$JOBS" --target rotorid_cli
R=build/release/apps/rotorid
mkdir -p out
D=data/sim

echo "== identify: configurations A and B together (the paper's combined identification, weight 2 on B)"
$R identify --vehicle $D/A.yaml --log $D/A_train.csv --vehicle $D/B.yaml --log $D/B_train.csv --weight 1 --weight 2 \
  --json out/identify.json --report out/identify_report

echo
echo "== validate on held-out flights (the paper's Table III)"
$R validate --params out/identify.json --vehicle $D/A.yaml --log $D/A_val.csv --vehicle $D/B.yaml --log $D/B_val.csv \
  --json out/validate.json

echo
echo "== refine: the same parameters jointly with unmodelled effects"
$R refine --vehicle $D/A.yaml --log $D/A_train.csv --vehicle $D/B.yaml --log $D/B_train.csv --weight 1 --weight 2 \
  --validate-vehicle $D/A.yaml --validate-log $D/A_val.csv --validate-vehicle $D/B.yaml --validate-log $D/B_val.csv \
  --json out/refine.json --report out/refine_report

echo
echo "== diagnose: where the model's residual lies and which effect explains it"
$R diagnose --vehicle $D/B.yaml --log $D/B_train.csv --validate-vehicle $D/B.yaml --validate-log $D/B_val.csv \
  --json out/diagnose.json --report out/diagnose_report

echo
echo "Reports: out/*.json, out/*_report/report.html. Truth of the simulated flights: $D/*_truth.json"
