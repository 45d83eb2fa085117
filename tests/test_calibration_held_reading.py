"""The falling readings read a second way, as a hold, when no pump log gives the history
(surrogate/calibration/_held_reading.py): the mechanism. The lab set it was made for
(a leak in a hold, read as creep) is in tests/test_calibration_history.py."""

from __future__ import annotations

import numpy as np

from surrogate.calibration import observations_from_rows
from surrogate.calibration._held_reading import (
    held_instead,
    reads_better,
    sentence,
    wants_held_reading,
)


def _rows() -> list[dict]:
    """Two curves pumped at 2 ul/s for 4 s, then the bend and the gauge falling for 3 s."""
    rows = []
    for c, s in enumerate((1.0, 1.05)):
        for k in range(8):
            load = k <= 4
            p = s * (300.0 * k if load else 1200.0 - 300.0 * (k - 4))
            rows.append({"curve_id": f"c{c}", "L_mm": 9.3, "t_mm": 0.63, "T_mm": 1.27,
                         "b_mm": 1.55, "h_mm": 0.17, "body_material": "pdms_1_10",
                         "membrane_material": "ecoflex_00_30", "time_s": float(k),
                         "flow_ul_s": 2.0, "pressure_pa": p,
                         "angle_deg": 10.0 * k if load else 40.0 - 10.0 * (k - 4)})
    return rows


def test_the_falling_readings_held_keep_the_pumps_volume():
    """Read off the readings the falling ones are unloading and the injected volume falls
    at 2 ul/s; read as a hold it stays at the top (8 ul) and the pump's switch is later."""
    obs = observations_from_rows(_rows())
    assert np.sum(obs.direction < 0) > 0
    held = held_instead(obs)
    assert np.sum(held.direction < 0) == 0
    assert np.array_equal(held.direction, np.where(obs.direction < 0, 0, obs.direction))
    top = held.volume_ul[(held.curve == 0) & (held.time_s >= 4.0)]
    assert np.allclose(top, top[0]) and top[0] > 0.0
    assert np.min(obs.volume_ul[(obs.curve == 0) & (obs.time_s == 7.0)]) < top[0]
    assert np.array_equal(held.pressure_pa, obs.pressure_pa)   # the readings themselves


def _report(timed: bool, structured: bool, logged: bool = False, unloading: int = 6) -> dict:
    return {"data": {"pump_logged": logged, "has_time_s": True, "has_flow_ul_s": True,
                     "injected_volume": "pump history",
                     "readings": {"loading": 10, "unloading": unloading, "hold": 0}},
            "selected_effects": ["viscoelastic_creep"] if timed else ["angle_offset"],
            "residual_structured_after": structured}


def test_the_second_reading_is_asked_only_where_a_misread_hold_would_show():
    assert wants_held_reading(_report(timed=True, structured=False))
    assert wants_held_reading(_report(timed=False, structured=True))
    assert not wants_held_reading(_report(timed=False, structured=False))
    assert not wants_held_reading(_report(timed=True, structured=False, logged=True))
    assert not wants_held_reading(_report(timed=True, structured=False, unloading=0))


def _read(sel, angle, joint, structured=False, unloading=12):
    return {"readings": {"loading": 30, "unloading": unloading, "hold": 3},
            "selected_effects": sel, "params": {}, "rmse_after_deg": angle,
            "rmse_pressure_after_pa": 200.0, "rmse_cv_joint": joint, "structured": structured}


def test_the_hold_reading_is_taken_only_where_it_explains_the_data_better():
    """L6's figures (benchmarks/RESULTS.md, forty-second session, s42-cal2): the leak read
    as a hold 1.93 deg (both channels 1.68) against creep read as unloading 2.14 (1.80)."""
    unloading = _read(["viscoelastic_creep"], 2.14, 1.80)
    assert reads_better(_read(["chamber_leak"], 1.93, 1.68, unloading=0), unloading)
    assert not reads_better(_read(["chamber_leak"], 1.93, 1.90, unloading=0), unloading)
    assert not reads_better(_read(["chamber_leak"], 2.20, 1.68, unloading=0), unloading)
    assert not reads_better(_read([], 1.50, None, unloading=0), unloading)
    assert not reads_better(_read(["chamber_leak"], 1.5, 1.2, True, unloading=0), unloading)
    said = sentence({"taken": False, "unloading": unloading,
                     "hold": _read([], 10.33, None, True, unloading=0)})
    assert "the data chose the unloading" in said and "left structured" in said
    assert sentence(None) is None
