"""The fit releases the GIL: another Python thread runs while `calibrate` works."""

import threading
import time

import accelcal
from conftest import UNIT_ID

BIN_S = 0.02


def test_other_threads_run_during_calibrate(hand):
    session = accelcal.segment_file(
        hand["csv"], acc_unit="m/s2", gyro_unit="deg/s", time_column="t", unit_id=UNIT_ID
    )
    span = {}

    def fit():
        span["start"] = time.perf_counter()
        while time.perf_counter() - span["start"] < 1.0:
            accelcal.calibrate(session)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=fit)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    duration = span["end"] - span["start"]
    # Held through each fit (about 0.1 s), the GIL would let this thread run only between fits:
    # about one 20 ms bin in five would see it. Released, it runs all through.
    bins = {int((t - span["start"]) / BIN_S) for t in ticks if span["start"] < t < span["end"]}
    covered = len(bins) * BIN_S
    assert covered > 0.6 * duration, (covered, duration)
