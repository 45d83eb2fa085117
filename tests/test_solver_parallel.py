"""solver/parallel.py: the assembly's two-thread map keeps order and errors, and follows
the thread budget (MKL_NUM_THREADS, else OMP_NUM_THREADS)."""

import os
import threading

import pytest

from solver.parallel import map_pair, thread_budget


def test_budget_follows_mkl_then_omp(monkeypatch):
    monkeypatch.setenv("MKL_NUM_THREADS", "3")
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    assert thread_budget() == 3
    monkeypatch.delenv("MKL_NUM_THREADS")
    assert thread_budget() == 1


@pytest.mark.parametrize("threads", ["1", "2"])
def test_order_and_the_helper(monkeypatch, threads):
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", threads)
    names = {}

    def square(x):
        names[x] = threading.current_thread().name
        return x * x

    assert map_pair(square, range(5), split=3) == [0, 1, 4, 9, 16]
    on_helper = {x for x, name in names.items() if name != threading.current_thread().name}
    assert on_helper == ({3, 4} if threads == "2" else set())


def test_an_error_on_either_thread_is_raised(monkeypatch):
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "2")

    def fail_at(bad):
        def f(x):
            if x == bad:
                raise FloatingPointError(f"item {x}")
            return x
        return f

    for bad in (0, 2):               # the caller's part, the helper's part
        with pytest.raises(FloatingPointError, match=f"item {bad}"):
            map_pair(fail_at(bad), [0, 1, 2])


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_a_forked_child_gets_its_own_helper(monkeypatch):
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    assert map_pair(abs, [-1, -2]) == [1, 2]          # the parent's helper exists now
    pid = os.fork()
    if pid == 0:                                       # child: would hang without a new helper
        os._exit(0 if map_pair(abs, [-3, -4]) == [3, 4] else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
