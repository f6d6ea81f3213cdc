"""The provenance record names what a result depends on, the compiled kernels' thread count too."""

import numba

from mlsgalerkin.io.provenance import provenance


def test_provenance_records_the_thread_count_the_parallel_sums_used():
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert provenance("a study")["numba_threads"] == 1
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        assert provenance("a study")["numba_threads"] == numba.config.NUMBA_NUM_THREADS
    finally:
        numba.set_num_threads(before)


def test_provenance_extra_items_override_the_recorded_ones():
    record = provenance("a study", mode="quick", extra={"numba_threads": 7, "note": "x"})
    assert record["mode"] == "quick"
    assert record["numba_threads"] == 7
    assert record["note"] == "x"
    assert list(record)[:2] == ["study", "command"]
