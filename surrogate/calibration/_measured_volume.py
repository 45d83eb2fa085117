"""A measured injected volume (the ``volume_ul`` column: a syringe pump's dispensed
volume, ul) read against the pump's history.

A pump's log is its own record of the volume it has moved into the chamber since the
start, the chamber at rest (empty of injected fluid). Read against the volume the loop
computes from ``time_s`` and ``flow_ul_s`` (``_history.injected_volume_ul``: Q x time,
with the pump's state read off the readings), the two agree to the pump's accuracy:
``VOLUME_ACCURACY`` (1 %) of the volume plus one step of the log's last written digit
(``written_step_ul``: a log of 0.001 ml is read to 1 ul). Where they agree, the computed
volume is used and nothing changes. Where they do not, the measured volume is used for
that curve (the pump's own record of what it moved: it holds where the program switched
between readings and what a misread history or a pump not running at its nominal rate
put elsewhere), its rises and falls are the history (loading / unloading / holds), the
fitted pump-switch shifts are off for it, and a warning names the curve and the
disagreement. Without ``time_s`` and ``flow_ul_s`` the measured volume is the injected
volume and its rises and falls are the history.

A measured volume is refused (``check_runs``) where it reverses for a single reading
inside a run (rising, falling, rising again by more than the log's resolution): no pump
program withdraws for one reading interval; a typo or a column of another quantity.
"""

from __future__ import annotations

import numpy as np

from surrogate.calibration._errors import DataError

#: a syringe pump's volume accuracy, as a fraction of the volume it has moved
VOLUME_ACCURACY = 0.01
#: the finest last digit read off a log (a volume written to 10^-6 of its unit or finer)
FINEST_DIGIT = 1e-6
ALLOWED = ("a syringe pump's dispensed volume since the start (the chamber at rest), >= 0 "
           "in ul (or a volume unit): rising while loading, standing in holds, falling "
           "while unloading")


def written_step_ul(written: list[float], factor: float) -> float:
    """The step of a volume log's last written digit, in ul: the largest power of ten
    (in the column's own unit, x ``factor`` to ul) that every value is a whole multiple
    of, ``FINEST_DIGIT`` at the finest."""
    step = 1.0
    while step > FINEST_DIGIT:
        if all(abs(x / step - round(x / step)) <= 1e-6 * max(1.0, abs(x / step))
               for x in written):
            break
        step /= 10.0
    return step * factor


def tolerance_ul(volume_ul: np.ndarray, step_ul: float) -> np.ndarray:
    """How far two records of one pump's volume may differ at each reading: the pump's
    accuracy (``VOLUME_ACCURACY`` of the volume) plus one step of the log's last digit."""
    return VOLUME_ACCURACY * np.abs(volume_ul) + step_ul + 1e-9


def volume_steps(volume_ul: np.ndarray, step_ul: float) -> np.ndarray:
    """+1 / 0 / -1 per interval of one curve's measured volume: a rise, a stand (within
    the log's resolution) or a fall."""
    dv = np.diff(volume_ul)
    return np.where(np.abs(dv) <= step_ul + 1e-9, 0.0, np.sign(dv))


def volume_directions(curve: np.ndarray, volume_ul: np.ndarray, step_ul: float
                      ) -> np.ndarray:
    """The pump's state per reading (+1 loading, 0 hold, -1 unloading; rows sorted by
    curve, then history) from the measured volume's change since the previous reading;
    the first reading takes the next interval's (as ``_history.directions`` does)."""
    out = np.zeros(volume_ul.size)
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        d = volume_steps(volume_ul[rows], step_ul)
        out[rows[1:]] = d
        out[rows[0]] = d[0] if d.size else 0.0
    return out


def check_runs(curve_id: str, volume_ul: list[float], file_rows: list[int], step_ul: float,
               logged: list[float] | None = None) -> None:
    """A DataError naming ``volume_ul`` and the file row where one curve's measured
    volume (in history order, from 0 at rest before its first reading) reverses for a
    single reading inside a run: up, down, up (or down, up, down) by more than the log's
    resolution; or, with the pump's logged states (``logged``: +1 load, 0 hold, -1
    unload since the previous reading), moves against them by more than
    ``tolerance_ul``."""
    v = [0.0] + list(volume_ul)
    if logged is not None:
        _check_against_log(curve_id, np.asarray(v), file_rows, step_ul, logged)
    s = volume_steps(np.asarray(v), step_ul)
    for k in range(1, s.size - 1):
        if s[k] != 0 and s[k - 1] == s[k + 1] == -s[k]:
            run = "loading" if s[k - 1] > 0 else "unloading"
            raise DataError("volume_ul", f"curve_id {curve_id!r} goes {v[k]:g}, "
                            f"{v[k + 1]:g}, {v[k + 2]:g} ul inside a {run} run: no pump "
                            "reverses for one reading (a typo, or a column of another "
                            "quantity?)", file_rows[k], ALLOWED)


def _check_against_log(curve_id: str, v: np.ndarray, file_rows: list[int], step_ul: float,
                       logged: list[float]) -> None:
    """The measured volume ``v`` (0 at rest first) against the pump's logged states."""
    dv = np.diff(v)
    tol = tolerance_ul(v[1:], step_ul)
    words = {1.0: ("load", "falls"), 0.0: ("hold", "moves"), -1.0: ("unload", "rises")}
    for k, d in enumerate(logged):
        if (d > 0 and dv[k] < -tol[k]) or (d == 0 and abs(dv[k]) > tol[k]) or (
                d < 0 and dv[k] > tol[k]):
            state, verb = words[float(d)]
            raise DataError("volume_ul", f"curve_id {curve_id!r} {verb} from {v[k]:g} to "
                            f"{v[k + 1]:g} ul where the pump column logs {state!r}: no "
                            "pump does that", file_rows[k], ALLOWED)


def disagreements(curve: np.ndarray, curve_ids: tuple[str, ...], measured_ul: np.ndarray,
                  pump_ul: np.ndarray, step_ul: float) -> tuple[np.ndarray, list[str]]:
    """The curves (bool per row) whose measured volume differs from the pump history's
    by more than ``tolerance_ul`` at some reading, and one warning naming them, the
    largest difference and the volume used (the measured one)."""
    off = np.zeros(curve.size, bool)
    worst: list[tuple[float, float, str]] = []
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        diff = measured_ul[rows] - pump_ul[rows]
        if np.all(np.abs(diff) <= tolerance_ul(pump_ul[rows], step_ul)):
            continue
        off[rows] = True
        k = int(np.argmax(np.abs(diff)))
        worst.append((float(diff[k]), float(pump_ul[rows][k]), curve_ids[int(c)]))
    if not worst:
        return off, []
    worst.sort(key=lambda w: -abs(w[0]))
    named = "; ".join(f"curve_id {cid!r} by up to {diff:+.3g} ul at {pump:.3g} ul"
                      + (f" ({100 * diff / pump:+.0f} %)" if pump > 0 else "")
                      for diff, pump, cid in worst[:3])
    more = f"; and {len(worst) - 3} more curves" if len(worst) > 3 else ""
    return off, [f"volume_ul: the measured volume differs from the pump history's "
                 f"(flow_ul_s x time_s) past a pump's {100 * VOLUME_ACCURACY:g} % + "
                 f"{step_ul:.3g} ul on {len(worst)} curve(s): {named}{more}; the measured "
                 "volume is used there (its rises and falls the history, no pump-switch "
                 "shift fitted): check flow_ul_s, time_s and the pump's log"]


def is_absent(measured_ul: np.ndarray | None) -> bool:
    """No measured volume (no column, or the rows of an older Observations)."""
    return measured_ul is None or not np.all(np.isfinite(measured_ul))
