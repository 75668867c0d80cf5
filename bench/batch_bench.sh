#!/usr/bin/env bash
# Bench of `rotorid batch`: N simulated logs (rotorid simulate, short flights, seeds 1..N), one
# manifest, then `rotorid batch --command identify --jobs J`; prints the wall time.
#   bench/batch_bench.sh [ROTORID] [N=100] [SECONDS=10] [JOBS=2]
set -euo pipefail
rotorid=${1:-build/release/apps/rotorid}
n=${2:-100}
seconds=${3:-10}
jobs=${4:-2}
work=$(mktemp -d /tmp/rotorid-batch-bench-XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/logs"
echo "logs:" > "$work/manifest.yaml"
for seed in $(seq 1 "$n"); do
  "$rotorid" simulate --preset B --seconds "$seconds" --seed "$seed" --out "$work/logs/f$seed.csv" \
    --vehicle-out "$work/B.yaml" --quiet
  echo "  - {vehicle: B.yaml, log: logs/f$seed.csv}" >> "$work/manifest.yaml"
done
start=$(date +%s.%N)
"$rotorid" batch --manifest "$work/manifest.yaml" --out "$work/out.jsonl" --jobs "$jobs" || true
end=$(date +%s.%N)
ok=$(grep -c '"status":"ok"' "$work/out.jsonl" || true)
echo "batch: $n logs of $seconds s, --jobs $jobs: $(echo "$end - $start" | bc) s wall, $ok ok"
