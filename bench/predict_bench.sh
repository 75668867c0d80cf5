#!/usr/bin/env bash
# Speed of `rotorid predict` (issue 38's target: 35 s at 100 Hz, H = 50, stride 1, i.e. 175 000
# integration steps, in at most 0.5 s for the whole process). Simulates a 35 s flight at 100 Hz with
# motion capture, identifies it, then times the whole predict process five times with one and with
# two threads, and with two threads and the torque bias observer (--torque-bias-window 0.2), and prints
# the best wall-clock and CPU times (a shared machine makes the slower runs noise). docs/prediction.md
# gives the measured numbers.
#
#   bench/predict_bench.sh [ROTORID=build/release/apps/rotorid]
set -euo pipefail
cd "$(dirname "$0")/.."
R=${1:-build/release/apps/rotorid}
DIR=$(mktemp -d /tmp/rotorid-predict-bench-XXXXXX)
trap 'rm -rf "$DIR"' EXIT
"$R" simulate --seconds 35 --rate 100 --mocap --noise low --out "$DIR/f.csv" --vehicle-out "$DIR/v.yaml" -q
"$R" refine --vehicle "$DIR/v.yaml" --log "$DIR/f.csv" --effects delay,motor_lag --json "$DIR/r.json" -q
/usr/bin/python3 - "$R" "$DIR" <<'PY'
import json, resource, subprocess, sys, time
rotorid, d = sys.argv[1:3]
for threads, observer in ((1, "0"), (2, "0"), (2, "0.2")):
    wall, cpu = [], []
    for _ in range(5):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run([rotorid, "predict", "--params", d + "/r.json", "--vehicle", d + "/v.yaml", "--log", d + "/f.csv",
                        "--horizon", "50", "--stride", "1", "--threads", str(threads), "--scope", "whole",
                        "--torque-bias-window", observer,
                        "--json", d + "/p.json", "-q"], check=True)
        wall.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    windows = json.load(open(d + "/p.json"))["prediction"]["windows"]
    print(f"threads {threads}, torque bias window {observer} s: {windows} windows x 50 steps, best of 5: wall {min(wall):.3f} s, CPU {min(cpu):.3f} s")
PY
