"""The fit releases the GIL: another Python thread runs while `calibrate` works."""

import threading
import time

import accelcal
from conftest import UNIT_ID

# Python may hand the GIL over at most one switch interval (5 ms) after a thread asks; a thread
# that holds it through a call lets no other thread run from this long after the call starts.
MARGIN_S = 0.02


def test_other_threads_run_during_calibrate(hand):
    session = accelcal.segment_file(
        hand["csv"], acc_unit="m/s2", gyro_unit="deg/s", time_column="t", unit_id=UNIT_ID
    )
    spans = []

    def fit():
        start = time.perf_counter()
        while time.perf_counter() - start < 1.0:
            t0 = time.perf_counter()
            accelcal.calibrate(session)
            spans.append((t0 + MARGIN_S, time.perf_counter() - MARGIN_S))

    worker = threading.Thread(target=fit)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    inside = sum(1 for t in ticks for a, b in spans if a < t < b)
    assert sum(max(b - a, 0.0) for a, b in spans) > 0.2, spans
    assert inside > 0, "no other thread ran during any fit: the GIL was held"
