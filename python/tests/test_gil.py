"""The fit releases the GIL: another Python thread runs while `calibrate` works."""

import bisect
import sys
import threading
import time

import accelcal
from conftest import UNIT_ID

# Python may hand the GIL over one switch interval after a thread asks (set to 0.1 ms here, so
# that a fit of a few ms leaves room to look inside it: a hand session's fit takes about 7 ms). A
# call that holds the GIL lets another thread run only once it has returned (measured with the GIL
# held: none in the first half of any call, some just after each, while the caller waits to take
# the GIL back); a call that releases it lets it run from the start. The margin, ten switch
# intervals, covers a hand-over between taking the start time and entering the call.
SWITCH_INTERVAL_S = 0.0001
MARGIN_S = 0.001


def test_other_threads_run_during_calibrate(hand):
    session = accelcal.segment_file(
        hand["csv"], acc_unit="m/s2", gyro_unit="deg/s", time_column="t", unit_id=UNIT_ID
    )
    spans = []

    def looked_inside():
        return sum(max(b - a, 0.0) for a, b in spans)

    def fit():
        # Fits until their first halves add up to enough time to look inside (a faster build or
        # machine runs more fits), for at most 20 s.
        start = time.perf_counter()
        while looked_inside() < 0.12 and time.perf_counter() - start < 20.0:
            t0 = time.perf_counter()
            accelcal.calibrate(session)
            spans.append((t0 + MARGIN_S, (t0 + time.perf_counter()) / 2))

    worker = threading.Thread(target=fit)
    ticks = []
    interval = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    try:
        worker.start()
        while worker.is_alive():
            ticks.append(time.perf_counter())
        worker.join()
    finally:
        sys.setswitchinterval(interval)
    # The ticks are in time order: those inside a span are one slice of them.
    inside = sum(bisect.bisect_left(ticks, b) - bisect.bisect_right(ticks, a) for a, b in spans if a < b)
    assert looked_inside() > 0.1, spans
    assert inside > 0, "no other thread ran during any fit: the GIL was held"
