#!/usr/bin/env python3
"""`host noise` on 720 000 rows against allantools on the same data.

    python3 -m venv /tmp/at && /tmp/at/bin/pip install allantools
    cargo build --release -p host
    /tmp/at/bin/python scripts/noise_speed.py target/release/host [OTHER_HOST ...]

Writes a 2-hour still at 100 Hz (white noise and a random walk on every axis) to a temporary
directory, times each `host noise` given (wall and CPU of the child) and allantools' `oadev` of the
six axes at octave τ, and prints both tools' Allan deviation and 1σ at each τ of one gyro axis:
the last `host noise`'s from its allan.csv (its `sigma` column), allantools' from Greenhall's EDF (`allantools.ci.edf_greenhall`
for white rate noise, relative 1σ 1/√(2ν)).
"""
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import allantools
import allantools.ci as ci

N, RATE = 720_000, 100.0


def write_still(path):
    rng = np.random.default_rng(5)
    cols = []
    for sd, k in [(0.01, 2e-4)] * 3 + [(1e-3, 1e-5)] * 3:
        cols.append(rng.normal(0, sd, N) + np.cumsum(rng.normal(0, k / np.sqrt(RATE), N)))
    cols[2] += 9.80665
    t = np.arange(N) / RATE
    header = "time,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"
    np.savetxt(path, np.column_stack([t] + cols), delimiter=",", header=header, comments="",
               fmt="%.9g")
    return np.column_stack(cols)


def time_host(host, csv, out):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([host, "-q", "noise", "--input", csv, "--time-column", "time", "--acc-unit",
                    "m/s2", "--gyro-unit", "rad/s", "--out", out], check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main():
    hosts = sys.argv[1:]
    with tempfile.TemporaryDirectory() as d:
        csv = os.path.join(d, "still.csv")
        data = write_still(csv)
        for i, host in enumerate(hosts):
            out = os.path.join(d, f"out{i}")
            wall, cpu = time_host(host, csv, out)
            print(f"{host} noise: wall {wall:.2f} s, cpu {cpu:.2f} s (reading the CSV included)")
        t0, c0 = time.perf_counter(), time.process_time()
        curves = [allantools.oadev(data[:, j], rate=RATE, data_type="freq", taus="octave")
                  for j in range(6)]
        print(f"allantools oadev, 6 axes: wall {time.perf_counter() - t0:.2f} s, "
              f"cpu {time.process_time() - c0:.2f} s (data in memory)")
        if hosts:
            last = os.path.join(d, f"out{len(hosts) - 1}", "allan.csv")
            rows = np.genfromtxt(last, delimiter=",", names=True,
                                 dtype=None, encoding=None)
            print("gyro_x: tau s | host adev, 1σ | allantools adev, 1σ (Greenhall EDF, white)")
            taus, adev = curves[3][0], curves[3][1]
            for tau, a in zip(taus, adev):
                m = int(round(tau * RATE))
                if 3 * m > N:
                    continue
                nu = ci.edf_greenhall(alpha=0, d=2, m=m, N=N + 1, overlapping=True,
                                      modified=False)
                mine = [r for r in rows if r["axis"] == "gyro_x" and abs(r["tau_s"] - tau) < 1e-9]
                h = f"{mine[0]['adev']:.4e}, {mine[0]['sigma']:.2e}" if mine else "-"
                print(f"  {tau:9.2f} | {h} | {a:.4e}, {a / np.sqrt(2 * nu):.2e}")


if __name__ == "__main__":
    main()
