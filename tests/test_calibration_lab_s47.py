"""The calibration loop on the forty-seventh session's fresh lab sets
(benchmarks/lab_rig_sets.py N30-N37, made from FE solves of designs D20-D22, their truths
fixed before any calibration; tests/data/lab_gauge_noise_*.csv from its ``--test-data``).

* a logger's lines of text above the header (N30) were refused as ``curve_id: required
  column is missing``, naming neither the text nor the header below it;
"""

from __future__ import annotations

from pathlib import Path

import pytest

from surrogate.calibration import DataError, load_observations, observations_from_rows

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
