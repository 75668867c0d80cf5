#!/usr/bin/env bash
# Regenerates the simulated flights bundled in data/sim/ with the built `rotorid simulate`.
# Reproducible: the simulator is deterministic for a seed, so the same sources give the same bytes.
#
#   scripts/make_data.sh [path/to/rotorid]
#
# Without an argument the first existing of build/release/apps/rotorid, build-sim/apps/rotorid and
# build/apps/rotorid is used. Every flight has the default Pixhawk-like noise plus a small, realistic
# command-to-rotor delay (5 ms) and motor lag (20 ms), for the refinement to find (data/sim/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."

ROTORID=${1:-}
if [ -z "$ROTORID" ]; then
  for candidate in build/release/apps/rotorid build-sim/apps/rotorid build/apps/rotorid; do
    if [ -x "$candidate" ]; then ROTORID=$candidate; break; fi
  done
fi
if [ -z "$ROTORID" ] || [ ! -x "$ROTORID" ]; then
  echo "make_data.sh: no rotorid binary found; build rotorid_cli first or pass its path" >&2
  exit 1
fi

OUT=data/sim
mkdir -p "$OUT"
EFFECTS=(--effect delay_s=0.005 --effect motor_tau_s=0.02)

# simulate PRESET NAME SECONDS SEED
simulate() {
  "$ROTORID" simulate --preset "$1" --seconds "$3" --seed "$4" --noise pixhawk --rate 200 "${EFFECTS[@]}" \
    --out "$OUT/$2.csv" --truth "$OUT/$2_truth.json" --vehicle-out "$OUT/$1.yaml"
}

simulate A A_train 60 1
simulate B B_train 60 2
simulate A A_val 30 3
simulate B B_val 30 4
