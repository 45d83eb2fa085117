"""The calibration loop on the forty-fifth session's fresh lab sets
(benchmarks/lab_rig_sets.py N14-N21, made from FE solves of designs D14-D16, their truths
fixed before any calibration; tests/data/lab_gauge_noise_*.csv from its ``--test-data``,
read here without the pump's log, as a lab writes them).

* a gauge in inches of water (a differential gauge's unit, ``Pressure (inH2O)``) was
  refused: the loader knew cmH2O but not inH2O, mmH2O or inWC;
"""

from __future__ import annotations

import pytest
from test_calibration_history import lab_rows

from surrogate.calibration import observations_from_rows

INCH_OF_WATER_PA = 25.4 * 9.80665   # 25.4 mm of water at 1000 kg/m^3 and standard gravity


def test_a_gauge_in_inches_of_water_is_read():
    """N15 writes its gauge in inH2O. Before: ``Pressure (inH2O): read as pressure_pa, but
    'inH2O' is not a unit of pressure`` and the set was refused whole. Now the column is
    read x 249.089 Pa, and mmH2O and inWC with it."""
    rows, _ = lab_rows("membrane_softer_inh2o")
    header = "Pressure (inH2O)"
    obs = observations_from_rows(rows)
    assert obs.pressure_pa == pytest.approx(
        [float(r[header].replace(",", ".")) * INCH_OF_WATER_PA for r in rows], abs=1e-9)
    for unit, pa in (("inWC", INCH_OF_WATER_PA), ("mmH2O", 9.80665)):
        other = [{**{k: v for k, v in r.items() if k != header}, f"p ({unit})": r[header]}
                 for r in rows]
        assert observations_from_rows(other).pressure_pa == pytest.approx(
            [float(r[header].replace(",", ".")) * pa for r in rows], abs=1e-9)

