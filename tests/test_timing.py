"""``sgb.timing``: a piece of work's wall time counts a wait, its CPU time does not."""

import time

from sgb.timing import timed


def test_a_wait_counts_in_the_wall_time_and_work_in_both():
    with timed() as waited:
        time.sleep(0.3)
    assert waited["wall_time_s"] >= 0.3 > waited["cpu_time_s"] + 0.2
    with timed() as worked:
        sum(i * i for i in range(2_000_000))
    assert worked["cpu_time_s"] > 0 and worked["wall_time_s"] > 0
