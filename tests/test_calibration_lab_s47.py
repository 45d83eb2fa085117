"""The calibration loop on the forty-seventh session's fresh lab sets
(benchmarks/lab_rig_sets.py N30-N37, made from FE solves of designs D20-D22, their truths
fixed before any calibration; tests/data/lab_gauge_noise_*.csv from its ``--test-data``).

* a logger's lines of text above the header (N30) were refused as ``curve_id: required
  column is missing``, naming neither the text nor the header below it;
* a pair that holds the selection and fails only for want of specimens went unsaid, while
  its added member was significant and the fit far better (N34: the mount's tilt beside
  air in the line);
* a set that fits better but whose size is within replicate scatter did not block the
  set that would stand in for it (N23's offset; the rule decided on 47 lab sets), and the
  reasons a set gives way said "BIC -31 lower".
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from surrogate.calibration import DataError, load_observations, observations_from_rows
from surrogate.calibration._data import decode_text, read_csv_rows

DATA = Path(__file__).parent / "data"


def test_text_above_the_header_is_refused_naming_the_header_below_it(tmp_path):
    """N30: a logger writes two lines of text (its name and the batch) between the file's
    comment and the header. The file is refused on one line that names the header's line,
    the text above it and how to convert (a '#' before each line); the rows the explorer
    sends (the first line taken as the header) are refused alike. Before (2026-12-07):
    ``curve_id: required column is missing``."""
    path = DATA / "lab_gauge_noise_text_above_header.csv"
    with pytest.raises(DataError) as err:
        load_observations(path)
    said = str(err.value)
    assert err.value.column == "header"
    assert "line 4 holds the header below text ('RigLogger 2.3 export" in said
    assert "starting with '#' (a comment), or deleted" in said
    assert "\n" not in said and str(DATA) not in said
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    keys = [k.strip() for k in lines[0].split(",")]
    as_sent = [dict(zip(keys, (c.strip() for c in ln.split(",")))) for ln in lines[1:]]
    with pytest.raises(DataError, match=r"^header: the header stands below text "
                       r"\('RigLogger 2.3 export, 2026-12-05 14:02', ...\)"):
        observations_from_rows(as_sent)
    # commented out, the same lines are read: three specimens of 12 readings each
    text = path.read_text().replace("RigLogger", "# RigLogger").replace("Sample", "# Sample")
    (tmp_path / "commented.csv").write_text(text)
    assert len(load_observations(tmp_path / "commented.csv").curve_ids) == 3


def test_a_larger_set_that_wants_only_a_specimen_more_is_said_beside_the_selection():
    """N34: 2.5 ul/kPa of air in the line and the mount tilted -1.5 deg on the deep
    chamber D22, three specimens at 2 and 5 ul/s, angles in radians. Three specimens back
    one tested parameter (k + 2), so line_compliance alone is selected; the pair with the
    tilt fits far better (BIC 48 lower, the tilt's z 3.7, cross-validated 1.48 against
    1.66 deg) and is now said beside it, with its sizes and what would back it. Before
    (2026-12-07) the report left the tilt unsaid: "What remains is consistent with
    replicate scatter"."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration

    path = DATA / "lab_gauge_noise_air_tilt_two_flows_rad.csv"
    report = run_calibration(read_csv_rows(decode_text(path.read_bytes(), path.name)),
                             emulator()).report
    assert report["selected_effects"] == ["line_compliance"]
    beyond = report["wants_specimens_beyond"]
    assert beyond["effects"] == ["line_compliance", "angle_offset"]
    assert beyond["added"] == ["angle_offset"] and beyond["z"]["offset_deg"] > 3.0
    offset = beyond["params"]["offset_deg"]
    assert abs(offset["value"] + 1.5) < 3 * offset["sd"]       # the truth, -1.5 deg
    assert "needs 4 curves to back them" in beyond["why_not"][0]
    assert "with more specimens the data may show angle_offset acting too" in report[
        "interpretation"]


def test_a_better_fit_within_replicate_scatter_blocks_the_set_that_would_stand_in_for_it():
    """N23 (the forty-sixth session's set, the units row converted as its error says): the
    membrane of D18 0.08 mm thicker than drawn. An angle offset of 0.84 +/- 0.24 deg,
    which the three readings at rest (0.7, 0.0, -1.6 deg) do not show, was selected while
    a stiffer membrane and a shorter chamber fitted 27-31 lower in BIC and as well held
    out, their sizes within replicate scatter (z 1.7-2.0). Such a better fit now blocks
    the offset as an unbacked one does, and the report says so plainly: nothing selected.
    Decided on 47 lab sets (benchmarks/RESULTS.md, the forty-seventh session): N23 is the
    only selection the rule changes."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration

    path = DATA / "lab_gauge_noise_units_row.csv"
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    names, units = lines[0].split(","), lines[1].split(",")
    header = [f"{n} ({u})" if u and not n.endswith("_mm") else n
              for n, u in zip(names, units, strict=True)]
    rows = read_csv_rows("\n".join([",".join(header), *lines[2:]]))
    report = run_calibration(rows, emulator()).report
    assert report["selected_effects"] == []
    offset = next(c for c in report["candidates"] if c["effects"] == ["angle_offset"])
    assert offset["stands_in_for"] and offset["stands_in_because"] == "replicate scatter"
    assert "within what replicate scatter explains (z " in offset["why_not"][-1]
    assert re.match(r"\w+ explains the data better \(BIC \d+ lower", offset["why_not"][-1])
    assert ("angle_offset fits with plausible, significant values, but "
            in report["interpretation"])
    # the better fit with its size (the forty-eighth session: it was named without one)
    assert re.search(r"values, but [\w ]+ \(\w+ = -?[\d.]+(e[-+]?\d+)? \+/- [\d.e+-]+[^)]*\) "
                     r"fits better while its size", report["interpretation"]), (
        report["interpretation"])
    assert "No catalogued effect is warranted" in report["interpretation"]


def test_a_fit_that_explains_the_data_better_is_said_so_many_bic_units_lower():
    """The words a set gives way in: the BIC difference is a positive count of units
    lower. N23's figures (the forty-sixth session: the thicker membrane's BIC 38.7 below
    the recalibrated baseline's, the selected offset's 6.6 below it). Before (2026-12-07)
    the reason read "BIC -32 lower" (chamber_length's in benchmarks/RESULTS.md: "BIC -20
    lower")."""
    from surrogate.calibration._selection import explains_better_words

    said = explains_better_words({"effects": ["membrane_thickness"], "bic": -38.7,
                                  "rmse_cv_joint": 0.941}, {"bic": -6.6, "rmse_cv_joint":
                                                            0.945}, True)
    assert said == ("membrane_thickness explains the data better (BIC 32 lower, "
                    "cross-validated 0.94 vs 0.94 deg, angle and gauge pressure together)")
