"""The emulator's memo of designs asked before (surrogate/emulator/design_memo.py): a
design asked again is answered from its kept curve -- no GP evaluated -- with exactly the
numbers a fresh emulator gives, and nothing a caller does to an answer changes the next."""

from __future__ import annotations

import dataclasses
import threading
from pathlib import Path

import numpy as np
import pytest

from solver.design import Design
from solver.design_space import scaled_material
from surrogate.emulator import load_emulator
from surrogate.emulator import vector_gp as vector_gp_module
from surrogate.emulator.design_memo import DesignMemo

EMULATOR = Path(__file__).resolve().parents[1] / "service" / "data" / "emulator.json"


@dataclasses.dataclass(frozen=True)
class Kept:
    values: np.ndarray
    pair: tuple[np.ndarray, np.ndarray]
    note: str


def test_the_memo_keeps_the_last_designs_read_only_and_nothing_that_failed():
    memo = DesignMemo(size=2)
    made: list[str] = []

    def make(name: str) -> Kept:
        made.append(name)
        return Kept(np.arange(3.0), (np.ones(2), np.zeros(2)), name)

    a = memo.get_or_make("a", lambda: make("a"))
    assert memo.get_or_make("a", lambda: make("again")) is a and made == ["a"]
    with pytest.raises(ValueError, match="read-only"):
        a.values[0] = 7.0
    with pytest.raises(ValueError, match="read-only"):
        a.pair[1][0] = 7.0
    memo.get_or_make("b", lambda: make("b"))
    memo.get_or_make("a", lambda: make("again"))         # "a" used last: "b" goes first
    memo.get_or_make("c", lambda: make("c"))
    assert len(memo) == 2 and made == ["a", "b", "c"]
    memo.get_or_make("b", lambda: make("b"))
    assert made == ["a", "b", "c", "b"]

    def fail() -> Kept:
        raise RuntimeError("no curve")

    with pytest.raises(RuntimeError):
        memo.get_or_make("d", fail)
    memo.get_or_make("d", lambda: make("d"))
    assert made[-1] == "d"
    memo.clear()
    assert len(memo) == 0


def test_threads_asking_one_design_all_get_its_value():
    memo = DesignMemo()
    out: list[object] = []

    def ask() -> None:
        out.append(memo.get_or_make("k", lambda: Kept(np.arange(4.0), (), "v")))

    threads = [threading.Thread(target=ask) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(out) == 8 and len(memo) == 1
    for v in out:
        np.testing.assert_array_equal(v.values, np.arange(4.0))


@pytest.fixture(scope="module")
def shipped():
    return load_emulator(EMULATOR)


def _answers(e, design: Design, level: float) -> list[np.ndarray]:
    p = e.predict(design, np.linspace(50.0, 4000.0, 40), level=level)
    v = e.predict_volume(design, np.linspace(0.5, 60.0, 30), level=level)
    return [np.asarray(a, float) for a in (
        p.angle_deg, p.lower_deg, p.upper_deg, p.volume_ul, p.force_mn, p.force_lower_mn,
        v.angle_deg, v.lower_deg, v.upper_deg, v.pressure_pa, v.force_mn)]


DESIGNS = {
    "standard": Design(),
    # the standard design's unit coordinates, three times its size: the FE's 500 ul
    # volume stop comes 27x sooner in its reduced volume, so its range ends sooner
    "a scaled copy, W 9 mm": Design(W_mm=9.0, L_mm=21.3, t_mm=1.5, T_mm=3.0, b_mm=5.4,
                                    h_mm=0.45),
    "both layers 1.5x stiffer": Design(
        body_material=scaled_material("pdms_1_10", 1.5),
        membrane_material=scaled_material("ecoflex_00_30", 1.5)),
    "reversed pair": Design(L_mm=12.0, t_mm=0.9, body_material="ecoflex_00_30",
                            membrane_material="pdms_1_15"),
    "soft pair": Design(L_mm=9.0, t_mm=0.6, T_mm=1.4, body_material="ecoflex_00_30",
                        membrane_material=scaled_material("ecoflex_00_30", 0.6)),
}


def test_a_design_asked_again_gives_a_fresh_emulators_numbers_and_evaluates_no_gp(
        shipped, monkeypatch):
    """Each design, asked by pressure and by volume at two band levels, in an order where
    designs that share unit coordinates (the W-scaled copy and the standard design, the
    stiffness-scaled one) follow each other: every answer equals that of an emulator
    with an empty memo, and asking all of it again evaluates no GP."""
    e = dataclasses.replace(shipped)          # the same GPs, its own (empty) memo
    first = {(name, level): _answers(e, d, level)
             for level in (0.95, 0.9) for name, d in DESIGNS.items()}
    calls = []
    real = vector_gp_module.VectorGP.predict

    def counted(self, *args, **kwargs):
        calls.append(1)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(vector_gp_module.VectorGP, "predict", counted)
    again = {key: _answers(e, DESIGNS[key[0]], key[1]) for key in first}
    assert calls == []
    monkeypatch.setattr(vector_gp_module.VectorGP, "predict", real)
    for key, answers in first.items():
        fresh = _answers(dataclasses.replace(shipped), DESIGNS[key[0]], key[1])
        for a, b, c in zip(answers, again[key], fresh, strict=True):
            np.testing.assert_array_equal(a, b, err_msg=str(key))
            np.testing.assert_array_equal(a, c, err_msg=str(key))
    # the length scale is part of the key: the scaled copy's range ends at another angle
    std, big = (e.predict(DESIGNS[k], [100.0]).validity["fe_limit_pa"]
                for k in ("standard", "a scaled copy, W 9 mm"))
    assert big < 0.9 * std
    # the band's level is part of the key: the 90 % band is narrower
    std95, std90 = first[("standard", 0.95)], first[("standard", 0.9)]
    assert np.nanmax(std95[2] - std95[1]) > np.nanmax(std90[2] - std90[1])


def test_what_a_caller_does_to_an_answer_does_not_change_the_next(shipped):
    e = dataclasses.replace(shipped)
    d = Design(L_mm=10.0, t_mm=0.7)
    p = np.linspace(100.0, 2500.0, 25)
    a = e.predict(d, p)
    expected = a.angle_deg.copy()
    a.angle_deg[:] = -1.0
    a.lower_deg[:] = -1.0
    np.testing.assert_array_equal(e.predict(d, p).angle_deg, expected)
