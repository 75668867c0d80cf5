#!/usr/bin/python3
"""A numpy/scipy implementation of `rotorid identify` (IMU source, noise-aware TLS), the reference
that bench/identify_vs_numpy.sh times rotorid against (issue 14: speed as a ratio measured in the
same run on the same machine).

It follows the same pipeline step by step (docs/method.md, src/ident/observation.cc, tls.cc):
rotorid CSV -> median sample interval -> uniform time base (linear interpolation) -> 4th-order
Butterworth low-pass at 10 Hz, zero phase (scipy.signal.sosfiltfilt; rotorid's filter is built to
match it, padding included) on gyro, accelerometer and Omega^2 -> 4th-order central difference of
the filtered gyro -> rows every fs/50 samples after 0.5 s trimmed at each end -> IDIM rows
(MODEL.md 1) and their noise covariance -> per-group QR -> the noise-aware fixed point of the
generalized TLS -> sandwich covariance (Newey-West) -> essential parameters (drop the worst %sigma
while it exceeds 10 %). It prints the parameters as JSON; with --check REPORT.json it compares
them with rotorid's report and exits 1 when a value differs by more than 1e-3 of its std (or the
essential set differs); on the bundled flights they agree to about 1e-9 std.

usage: identify_reference.py --vehicle V.yaml --log L.csv [--vehicle ... --log ...] [--check R.json]
Needs python3-numpy, python3-scipy and python3-yaml (Debian packages).
"""
import argparse
import json
import math
import sys

import numpy as np
import scipy.linalg
import scipy.signal
import yaml

BODY = ["ms_x", "ms_y", "ms_z", "I_xx", "I_yy", "I_zz", "I_xy", "I_xz", "I_yz"]
CUTOFF_HZ, ORDER, ROW_RATE_HZ, EDGE_TRIM_S = 10.0, 4, 50.0, 0.5
MAX_ITERATIONS, MAX_REL_STD_PCT, SCALE_LOST, MAX_VARIANCE_DROP = 30, 10.0, 1e-3, 0.1


def read_csv(path):
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    header = lines[0].strip().split(",")
    data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    col = {name: k for k, name in enumerate(header)}
    rotors = sorted((n for n in header if n.startswith("rotor_")), key=lambda n: int(n[6:]))
    pick = lambda names: data[:, [col[n] for n in names]]
    return data[:, col["t"]], pick(["gyro_x", "gyro_y", "gyro_z"]), pick(["acc_x", "acc_y", "acc_z"]), pick(rotors)


def white_noise_std(x):
    curvature = np.abs(x[:-2] - 2.0 * x[1:-1] + x[2:])
    return np.median(curvature, axis=0) / (0.6745 * math.sqrt(6.0))


def noise_variance_gain(sos, fs, differentiations):
    f = np.linspace(0.0, 0.5 * fs, 4001)
    _, h = scipy.signal.sosfreqz(sos, worN=f, fs=fs)
    value = np.abs(h) ** 4
    phase = 2.0 * np.pi * f / fs
    d = (8.0 * np.sin(phase) - np.sin(2.0 * phase)) * fs / 6.0
    value = value * (d * d) ** differentiations
    return np.trapz(value, f) / (0.5 * fs)


def fourth_order_difference(x, dt):
    d = np.empty_like(x)
    d[1:-1] = (x[2:] - x[:-2]) / (2.0 * dt)
    d[0] = (-3.0 * x[0] + 4.0 * x[1] - x[2]) / (2.0 * dt)
    d[-1] = (3.0 * x[-1] - 4.0 * x[-2] + x[-3]) / (2.0 * dt)
    d[2:-2] = (x[:-4] - 8.0 * x[1:-3] + 8.0 * x[3:-1] - x[4:]) / (12.0 * dt)
    return d


def process(path, vehicle):
    t, gyro, acc, rotor = read_csv(path)
    dt = np.median(np.diff(t))
    fs = 1.0 / dt
    base = t[0] + np.arange(int(math.floor((t[-1] - t[0]) * fs + 1e-6)) + 1) / fs
    interp = lambda x: np.column_stack([np.interp(base, t, x[:, k]) for k in range(x.shape[1])])
    gyro, acc, rotor = interp(gyro), interp(acc), interp(rotor)
    sos = scipy.signal.butter(ORDER, CUTOFF_HZ, fs=fs, output="sos")
    lowpass = lambda x: scipy.signal.sosfiltfilt(sos, x, axis=0)
    w = lowpass(gyro)
    flight = {
        "w": w, "w_dot": fourth_order_difference(w, dt), "s": lowpass(acc),
        "omega": np.sqrt(np.maximum(lowpass(rotor * rotor), 0.0)),
        "sigma": np.concatenate([white_noise_std(gyro) * math.sqrt(noise_variance_gain(sos, fs, 0)),
                                 white_noise_std(gyro) * math.sqrt(noise_variance_gain(sos, fs, 1)),
                                 white_noise_std(acc) * math.sqrt(noise_variance_gain(sos, fs, 0))]),
        "vehicle": vehicle,
    }
    trim, step = int(math.ceil(EDGE_TRIM_S * fs)), max(1, int(round(fs / ROW_RATE_HZ)))
    flight["rows"] = np.arange(trim, len(base) - trim, step)
    return flight


def skew(v):
    z = np.zeros(v.shape[0])
    return np.stack([np.stack([z, -v[:, 2], v[:, 1]], 1), np.stack([v[:, 2], z, -v[:, 0]], 1),
                     np.stack([-v[:, 1], v[:, 0], z], 1)], 1)


def inertia_product(v):
    z = np.zeros(v.shape[0])
    x, y, w = v[:, 0], v[:, 1], v[:, 2]
    return np.stack([np.stack([x, z, z, y, w, z], 1), np.stack([z, y, z, x, z, w], 1),
                     np.stack([z, z, w, z, x, y], 1)], 1)


def idim_rows(w, w_dot, s, omega, vehicle):
    """(n, 6, 12) rows [-D_k | D | m D_m] (MODEL.md 1)."""
    n = w.shape[0]
    rows = np.zeros((n, 6, 12))
    sq = omega * omega
    pos, spin = vehicle["positions"], vehicle["spins"]
    rows[:, 2, 0] = -sq.sum(1)
    rows[:, 3, 0] = -(sq * pos[:, 1]).sum(1)
    rows[:, 4, 0] = (sq * pos[:, 0]).sum(1)
    rows[:, 5, 1] = (sq * spin).sum(1)
    ws = skew(w)
    rows[:, :3, 2:5] = skew(w_dot) + ws @ ws
    rows[:, 3:, 2:5] = -skew(s)
    rows[:, 3:, 5:11] = inertia_product(w_dot) + ws @ inertia_product(w)
    rows[:, :3, 11] = vehicle["mass"] * s
    return rows


def flight_rows_and_noise(flight):
    r = flight["rows"]
    signals = [flight["w"][r], flight["w_dot"][r], flight["s"][r]]
    omega, vehicle = flight["omega"][r], flight["vehicle"]
    rows = idim_rows(*signals, omega, vehicle)
    cov = np.zeros((6, 12, 12))
    for k in range(9):
        if flight["sigma"][k] == 0.0:
            continue
        plus = [x.copy() for x in signals]
        minus = [x.copy() for x in signals]
        plus[k // 3][:, k % 3] += 1.0
        minus[k // 3][:, k % 3] -= 1.0
        jac = 0.5 * (idim_rows(*plus, omega, vehicle) - idim_rows(*minus, omega, vehicle))
        cov += flight["sigma"][k] ** 2 * np.einsum("nci,ncj->cij", jac, jac)
    return rows, cov


def build_system(flights):
    configs = []
    for f in flights:
        if f["vehicle"]["name"] not in configs:
            configs.append(f["vehicle"]["name"])
    names = ["kt", "kd"] + [c + "." + b for c in configs for b in BODY]
    p = len(names)
    blocks, group_cov, group_of_row, sample_of_row = [], [], [], []
    for fi, f in enumerate(flights):
        rows, cov = flight_rows_and_noise(f)
        c0 = 2 + 9 * configs.index(f["vehicle"]["name"])
        cols = list(range(2)) + list(range(c0, c0 + 9)) + [p]
        w = np.zeros((rows.shape[0] * 6, p + 1))
        w[:, cols] = rows.reshape(-1, 12)
        blocks.append(w)
        for c in range(6):
            mapped = np.zeros((p + 1, p + 1))
            mapped[np.ix_(cols, cols)] = cov[c]
            group_cov.append(mapped)
        group_of_row.append(6 * fi + np.tile(np.arange(6), rows.shape[0]))
        sample_of_row.append(np.repeat(np.arange(rows.shape[0]), 6))
    return {"w": np.vstack(blocks), "names": names, "group_cov": group_cov,
            "group": np.concatenate(group_of_row), "weights": [f["weight"] for f in flights]}


def generalized_tls(r, metric):
    n = r.shape[1]
    norms = np.maximum(np.linalg.norm(r, axis=0), 1e-300)
    r_eq = r / norms
    metric_eq = metric / np.outer(norms, norms)
    metric_eq[np.diag_indices(n)] += 1e-9 * max(np.trace(metric_eq) / n, 1.0) + 1e-12
    l = np.linalg.cholesky(metric_eq)
    b = scipy.linalg.solve_triangular(l, r_eq.T, lower=True).T
    _, sv, vt = np.linalg.svd(b)
    x_eq = scipy.linalg.solve_triangular(l.T, vt[-1], lower=False)
    x_eq /= np.linalg.norm(x_eq)
    x = x_eq / norms
    effective = metric_eq * np.outer(norms, norms)
    return x / x[-1], abs(x_eq[-1]), x_eq, effective


def stacked_r(factors, columns, group_weight):
    stacked = np.vstack([math.sqrt(gw) * r[:, columns] for r, gw in zip(factors, group_weight)])
    return np.linalg.qr(stacked, mode="r")


def autocorrelation_lag(resid, system):
    lag_max = 0
    first = system["group"] < 6
    for j in range(6):
        series = resid[j::6][first[j::6]]
        n = len(series)
        c0 = series @ series
        if n < 20 or c0 <= 0.0:
            continue
        lag = 1
        while lag < min(n // 10, 200):
            if series[:-lag] @ series[lag:] / c0 < 0.1:
                break
            lag += 1
        lag_max = max(lag_max, lag)
    return max(2, 2 * lag_max)


def solve_noise_aware(system, factors, counts, columns, start_var):
    groups, n, rows = len(factors), len(columns), system["w"].shape[0]
    group_cov = [c[np.ix_(columns, columns)] for c in system["group_cov"]]
    r = stacked_r(factors, columns, np.ones(groups))
    chi_t, scale, direction, _ = generalized_tls(r, np.diag(np.linalg.norm(r, axis=0) ** 2))
    group_weight = np.ones(groups)
    for _ in range(MAX_ITERATIONS):
        full = np.zeros(system["w"].shape[1])
        full[columns] = chi_t
        metric = np.zeros((n, n))
        for g in range(groups):
            rotor_sq = chi_t[0] ** 2 * np.sum(factors[g][:, columns[0]] ** 2)
            noise_var = chi_t @ group_cov[g] @ chi_t / counts[g]
            residual_var = np.sum((factors[g] @ full) ** 2) / counts[g]
            floor = 1e-24 * rotor_sq / counts[g] + 1e-300
            if start_var[g] < 0.0:
                start_var[g] = max(residual_var, noise_var)
            total = max(residual_var, noise_var, floor, MAX_VARIANCE_DROP * start_var[g])
            user = system["weights"][g // 6]
            group_weight[g] = user * user / total
            metric += group_weight[g] * group_cov[g]
            metric[n - 1, n - 1] += group_weight[g] * counts[g] * (total - noise_var)
        r = stacked_r(factors, columns, group_weight)
        previous = chi_t
        chi_t, scale, direction, metric = generalized_tls(r, metric)
        if not np.max(np.abs(chi_t - previous) / (np.abs(previous) + 1e-300)) > 1e-10:
            break
    # Sandwich covariance of the whitened residuals (as SolveNoiseAware).
    row_weight = group_weight[system["group"]]
    d_sq = max(chi_t @ metric @ chi_t / rows, 1e-300)
    d = math.sqrt(d_sq)
    c = (metric @ chi_t)[:-1] / (rows * d_sq)
    w = system["w"][:, columns]
    sqrt_weight = np.sqrt(row_weight)
    resid = sqrt_weight * (w @ chi_t) / d
    gram = (r.T @ r)[:-1, :-1]
    u = (r.T @ (r @ chi_t))[:-1] / d
    h = gram / d_sq - (np.outer(u, c) + np.outer(c, u)) / d + (resid @ resid) * np.outer(c, c)
    lag = autocorrelation_lag(resid, system)
    s = np.zeros((n - 1, n - 1))
    flight_of_row = system["group"] // 6
    for fl in np.unique(flight_of_row):
        idx = np.nonzero(flight_of_row == fl)[0]
        weighted = (sqrt_weight[idx] * resid[idx] / d)[:, None] * w[idx, :-1]
        scores = weighted.reshape(-1, 6, n - 1).sum(1) - np.outer((resid[idx] ** 2).reshape(-1, 6).sum(1), c)
        s += scores.T @ scores
        for l in range(1, min(lag, len(scores) - 1) + 1):
            cross = scores[:-l].T @ scores[l:]
            s += (1.0 - l / (lag + 1)) * (cross + cross.T)
    h_inv = np.linalg.inv(h)
    return chi_t, h_inv @ s @ h_inv, scale, direction


def identify(flights):
    system = build_system(flights)
    p = len(system["names"])
    groups = len(system["group_cov"])
    factors, counts = [], []
    for g in range(groups):
        rows = system["w"][system["group"] == g]
        counts.append(rows.shape[0])
        factors.append(np.linalg.qr(rows, mode="r") if rows.shape[0] >= p + 1 else rows)
    free, discarded, start_var = list(range(p)), [], [-1.0] * groups
    while True:
        columns = free + [p]
        chi_t, cov, scale, direction = solve_noise_aware(system, factors, counts, columns, start_var)
        if len(free) <= 1:
            break
        if scale < SCALE_LOST:
            discarded.append(system["names"][free.pop(int(np.argmax(np.abs(direction[:-1]))))])
            continue
        rel = 100.0 * np.sqrt(np.maximum(np.diag(cov), 0.0)) / np.maximum(np.abs(chi_t[:-1]), 1e-300)
        if rel.max() <= MAX_REL_STD_PCT:
            break
        discarded.append(system["names"][free.pop(int(np.argmax(rel)))])
    out = {}
    for k, name in enumerate(system["names"]):
        if k in free:
            a = free.index(k)
            out[name] = {"value": chi_t[a], "std": math.sqrt(max(cov[a, a], 0.0)), "essential": True}
        else:
            out[name] = {"value": 0.0, "std": 0.0, "essential": False}
    return out


def read_vehicle(path):
    with open(path) as f:
        v = yaml.safe_load(f)
    return {"name": v["name"], "mass": float(v["mass"]),
            "positions": np.array([r["position"] for r in v["rotors"]], float),
            "spins": np.array([r["spin"] for r in v["rotors"]], float)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vehicle", action="append", required=True)
    parser.add_argument("--log", action="append", required=True)
    parser.add_argument("--check", help="rotorid identify --json report to compare with")
    args = parser.parse_args()
    if len(args.vehicle) != len(args.log):
        parser.error("--vehicle and --log must pair up")
    flights = []
    for vehicle_path, log_path in zip(args.vehicle, args.log):
        flight = process(log_path, read_vehicle(vehicle_path))
        flight["weight"] = 1.0
        flights.append(flight)
    parameters = identify(flights)
    print(json.dumps({"parameters": parameters}, indent=1))
    if args.check:
        with open(args.check) as f:
            theirs = json.load(f)["linear"]["parameters"]
        worst = 0.0
        for name, mine in parameters.items():
            if mine["essential"] != theirs[name]["essential"]:
                print(f"{name}: essential differs", file=sys.stderr)
                return 1
            if mine["essential"]:
                worst = max(worst, abs(mine["value"] - theirs[name]["value"]) / theirs[name]["std"])
        print(f"largest difference from rotorid: {worst:.2e} std", file=sys.stderr)
        return 0 if worst < 1e-3 else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
