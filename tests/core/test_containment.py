"""What a contained plugin call runs under."""

import numpy  # noqa: F401  (loads the BLAS whose threads are limited)

from forensics_core.containment import can_fork, run_forked


def _threads():
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info()]


def test_a_contained_call_runs_with_one_blas_thread():
    assert can_fork()
    (kind, threads), _ = run_forked(_threads, 30)
    assert kind == "value" and threads and set(threads) == {1}
