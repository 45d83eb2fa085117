"""How each reading was taken: loading, unloading or hold, from the pressure sequence.

Labs record a curve in time (or file) order; the pressure's change from the previous
reading says what the pump did: rising = loading (fluid in, direction +1), falling =
unloading (withdrawn, -1), pressure and angle unchanged = hold (pump stopped, 0). The
first reading takes the direction of the next interval; a drop into a flat stretch is the
start of a hold (the gauge loses the inlet's R Q when the pump stops). The noise floor,
the time effects' identifiability and the inlet pressure drop (R Q x direction) use it,
and so does the injected volume (``injected_volume_ul``: the syringe pump's volume, from
time, flow rate and direction).
"""

from __future__ import annotations

import numpy as np

HOLD_FRACTION = 0.01  # a constant-flow inflation near its pressure maximum still rises
HOLD_MIN_PA = 8.0     # faster (1 % of the range per reading at 1 s, 2.5 ul/s)
#: holds below this fraction of a curve's top pressure are the actuator at rest, not holds
REST_FRACTION = 0.1


def directions(curve: np.ndarray, pressure_pa: np.ndarray, angle_deg: np.ndarray,
               time_s: np.ndarray | None = None, group: np.ndarray | None = None,
               untrusted: np.ndarray | None = None) -> np.ndarray:
    """+1 / -1 / 0 per row; rows sorted by curve, then history. A reading is classified
    by the pressure's change from the previous one (the pump's state since then): within
    HOLD_FRACTION of the curve's pressure range (at least HOLD_MIN_PA, above a pressure
    sensor's noise) it is a hold, and a drop followed by a flat interval is the step into
    a hold (the inlet's R Q vanishing when the pump stops), not unloading. Where the
    pressure cannot tell, the bend does (``_by_bend``). Replicates taken with one pump
    program (``group``, with the same reading times ``time_s``) share it: each reading
    takes the majority of theirs (``_vote``). An interval with an ``untrusted`` angle
    at either end (a sensor at its stop: _angle_stop.py) is read by the pressure
    alone."""
    out = np.zeros(pressure_pa.size)
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        p = pressure_pa[rows]
        tol = max(HOLD_FRACTION * float(np.ptp(p)), HOLD_MIN_PA)
        dp = np.diff(p)
        flat = np.abs(dp) <= tol
        back = np.where(flat, 0.0, np.sign(dp))
        fwd_flat = np.append(flat[1:], False)
        d = np.where((back < 0) & fwd_flat, 0.0, back)
        t = time_s[rows] if time_s is not None and np.all(np.isfinite(time_s[rows])) \
            else np.arange(rows.size, dtype=float)
        a = angle_deg[rows]
        bend = a * (1.0 if a[np.argmax(np.abs(a))] >= 0 else -1.0)  # reversed pairs too
        d = _by_bend(d, dp, bend, t, tol, None if untrusted is None else untrusted[rows])
        out[rows[1:]] = d
        out[rows[0]] = d[0] if d.size else 0.0
    if time_s is not None and group is not None and np.all(np.isfinite(time_s)):
        _vote(out, curve, time_s, group)
    return out


#: the bend decides an interval where a moving one bends by more than this fraction of
#: the curve's bend (at least BEND_MIN_DEG: 3.5 x the difference of two readings with a
#: camera's 0.7 deg noise); a still interval is told only where twice that. 0.05 until
#: 2026-12-06: on a short stiff curve read every 4 s (L 4.1 mm, 96 deg, intervals of
#: 4.4-6 deg at the top, where the gauge rises by 13 Pa, under 1 % of its range) a
#: loading reading fell below it and read as a hold; the three replicates' vote took it,
#: and every later volume of the curves was one interval off (clean data flagged 2.2 x
#: the floor, the unseen set clean-past-fe-range at seed offset 300)
BEND_INFORMATIVE = 0.04
BEND_MIN_DEG = 2.5
#: below this fraction of the top bend the actuator may be straight while the pump runs
BEND_LOW = 0.2
MOVING_SHARE = 0.5   # of the pump's bend rate at that bend: the pump ran
STILL_SHARE = 0.25   # below: it stood (creep of g = 0.25 bends at most g x the rate)


def _by_bend(d: np.ndarray, dp: np.ndarray, bend: np.ndarray, t: np.ndarray,
             tol_p: float, untrusted: np.ndarray | None = None) -> np.ndarray:
    """Directions of a curve's intervals checked against its bend (the angle, signed so
    that the curve bends positive: a camera offset may take it below 0). The chamber's
    bend follows its volume, so a pump running at a constant rate bends it at about the
    rate its other running intervals show at the same bend (loading and unloading
    alike; not near the bottom, where an emptied actuator may stay straight; the rate is
    read off running intervals that bend beyond the camera's noise, so that a hold whose
    noisy gauge read some of its intervals as running is not its own reference). Where
    that rate is well above the camera's noise, an interval bending by at least
    MOVING_SHARE of it, the way its pressure goes (beyond HOLD_MIN_PA) or, bending beyond
    the camera's noise, with its pressure within the hold tolerance (near a pressure
    maximum the gauge cannot tell: until 2026-12-07 such a loading reading at 80 deg was a
    hold; a precise gauge's flat hold keeps its noisy bend), ran: at the top of a
    stiff curve the pressure rises by < 1 % of its range per reading while the angle
    still moves by 5-8 % of the bend. So did one whose gauge says the pump ran the other way:
    a pump withdrawing cannot bend the actuator on at half its loading rate (creep of
    g < 0.75 makes unloading's bend fall or rise at most (2g - 1) x the rate), while a
    gauge read to 1-2 % falls by its noise where a curve's pressure flattens near its
    top (until 2026-12-06 such a reading was unloading, the replicates' vote made it
    theirs, and every later volume was two intervals off). One bending by less than
    STILL_SHARE of it stood -- its pressure within twice the hold tolerance, or within
    what the pump moves it in the running intervals at that bend, or falling, or its bend
    falling while its gauge rose (a pump running in raises both, and by a full interval's
    bend): a hold whose gauge noise exceeds 1 % of a soft curve's range (a gauge read to
    1.5 % rises by 50-85 Pa at 2.3 kPa in a hold: until 2026-12-06 that read as loading
    where the pump moves it by 250), or the inlet's R Q vanishing when the pump stops
    (the pressure drops, the bend stays). At a flat top the pump moves the gauge by
    70-110 Pa a reading, less than twice a 1.5 % gauge's noise there (47 Pa a reading):
    until 2026-12-07 a hold reading whose gauge rose by more than half of that read as
    loading, the replicates' vote made it theirs (benchmarks/lab_rig_sets.py N22, N24:
    a clean hold's volume 11 ul high, a measured volume said to disagree with the pump's
    log, a staircase's last hold fitted as a pump switch 0.3 of an interval late)."""
    if d.size < 3:
        return d
    da = np.diff(bend)
    dt = np.maximum(np.diff(t), 1e-9)
    rate = np.abs(da) / dt
    level = 0.5 * (bend[1:] + bend[:-1])
    floor = max(BEND_INFORMATIVE * float(np.ptp(bend)), BEND_MIN_DEG)
    out = d.copy()
    # an interval with a reading the sensor could not read (at its stop) is no reference
    # for the others, and is read by its gauge: running where it moves by MOVING_SHARE of
    # the pump's pressure per interval nearby, else a hold
    read = np.ones(d.size, bool) if untrusted is None else ~(untrusted[1:] | untrusted[:-1])
    for i in range(d.size):
        ran = np.flatnonzero((d != 0) & (np.arange(d.size) != i) & read)
        if ran.size < 2:
            return d
        moving = ran[np.abs(da[ran]) > floor]     # a hold's gauge noise is no pump rate
        near = (moving if moving.size >= 2 else ran)
        near = near[np.argsort(np.abs(level[near] - level[i]))[:3]]
        expected = float(np.median(rate[near])) * dt[i]
        pumped_pa = float(np.median(np.abs(dp[near] / dt[near]))) * dt[i]
        if not read[i]:      # the bend cannot tell: read with its run (_unread_run)
            continue
        if expected <= floor or level[i] < BEND_LOW * float(np.max(bend)):
            continue
        agrees = np.sign(da[i]) == np.sign(dp[i]) and abs(dp[i]) > HOLD_MIN_PA
        against = d[i] == -np.sign(da[i])  # the gauge read the pump running backwards
        flat = d[i] == 0 and abs(da[i]) > floor   # or could not tell (a flat top: p max)
        if abs(da[i]) >= MOVING_SHARE * expected and (agrees or against or flat):
            out[i] = np.sign(da[i])
        elif (abs(da[i]) <= STILL_SHARE * expected and expected > 2 * floor
              and (abs(dp[i]) <= max(2 * tol_p, pumped_pa) or dp[i] < 0 or da[i] < 0)):
            out[i] = 0.0
    return out if untrusted is None else _unread_runs(out, dp, read)


def _unread_runs(d: np.ndarray, dp: np.ndarray, read: np.ndarray) -> np.ndarray:
    """The intervals the bend cannot tell (``read`` False: a sensor at its stop), run by
    run, read as the pump's program runs at the top of a curve: loading, then standing,
    then withdrawing (each possibly empty). The gauge moves over the run are split
    where they fit that best: a mean rise while loading, none while standing, a mean
    fall while withdrawing, each moving segment's mean a parameter (least squares,
    BIC: one parameter per moving segment). The pump's pace at the top of a curve is
    not the pace below it (the pressure flattens there), and one reading's noise must
    not flip a lone interval."""
    out = d.copy()
    i = 0
    while i < d.size:
        if read[i]:
            i += 1
            continue
        j = i
        while j < d.size and not read[j]:
            j += 1
        moves = dp[i:j]
        n = moves.size
        best, split = np.inf, (0, 0)
        for a in range(n + 1):
            for b in range(a, n + 1):
                up, still, down = moves[:a], moves[a:b], moves[b:]
                if (up.size and up.mean() <= 0) or (down.size and down.mean() >= 0):
                    continue
                rss = (float(np.sum((up - up.mean()) ** 2)) if up.size else 0.0) + float(
                    np.sum(still ** 2)) + (float(np.sum((down - down.mean()) ** 2))
                                           if down.size else 0.0)
                score = n * np.log(rss / n + 1e-9) + (bool(up.size) + bool(down.size)) \
                    * np.log(n)
                if score < best:
                    best, split = score, (a, b)
        a, b = split
        out[i:i + a], out[i + a:i + b], out[i + b:j] = 1.0, 0.0, -1.0
        i = j
    return out


def _vote(out: np.ndarray, curve: np.ndarray, time_s: np.ndarray, group: np.ndarray) -> None:
    """In place: replicates of one group read at the same times (within a tenth of their
    reading interval) ran the same pump program; at each reading the direction most of
    them show (a strict majority) is every one's. One specimen's noisy hold or a flat
    step at the top of its curve then does not cut its history differently from the
    others' (the noise floor compares replicates segment by segment). Where no state has
    a majority and some replicates show the pump running in, others out, one program
    did neither there: it stood (a hold's first reading whose bend still moves, read as
    loading on one specimen, unloading on another and a hold on the third, cut the three
    histories apart and the floor from them rose 4.7 x: a camera 0.5 s late,
    benchmarks/lab_rig_sets.py N13)."""
    for g in np.unique(group):
        curves = np.unique(curve[group == g])
        if curves.size < 3:
            continue
        rows = [np.flatnonzero(curve == c) for c in curves]
        by_times: dict[tuple, list[np.ndarray]] = {}
        for r in rows:
            t = time_s[r]
            step = float(np.median(np.diff(t))) if t.size > 1 else 1.0
            key = (t.size, *np.round(t / max(step, 1e-9) * 10).astype(int) // 10)
            by_times.setdefault(key, []).append(r)
        for same in by_times.values():
            if len(same) < 3:
                continue
            d = np.array([out[r] for r in same])
            for k in range(d.shape[1]):
                values, counts = np.unique(d[:, k], return_counts=True)
                if counts.max() * 2 > len(same):
                    d[:, k] = values[np.argmax(counts)]
                elif values[0] < 0 < values[-1]:
                    d[:, k] = 0.0
            for r, dk in zip(same, d, strict=True):
                out[r] = dk


def history_traits(curve: np.ndarray, pressure_pa: np.ndarray, direction: np.ndarray
                   ) -> dict[str, int]:
    """Counts of loading, unloading and hold readings (holds at rest not counted)."""
    top = np.zeros(int(curve.max()) + 1)
    np.maximum.at(top, curve, pressure_pa)
    hold = (direction == 0) & (pressure_pa > REST_FRACTION * top[curve])
    return {"loading": int(np.sum(direction > 0)), "unloading": int(np.sum(direction < 0)),
            "hold": int(np.sum(hold))}


def line_direction(time_s: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The pump's state over the interval that ends at each reading, as the fluid in the
    inlet line moves (the inlet's R Q x direction): ``direction``, but 0 at a reading
    taken at the pump's start (``time_s`` 0, the chamber at rest): no fluid has flowed
    through the line before it, so the gauge there reads the chamber, not R Q above it
    (``directions`` gives such a reading the next interval's state). Without time_s the
    readings cannot say when the pump started: ``direction``."""
    return np.where(time_s == 0.0, 0.0, direction)


def injected_volume_ul(curve: np.ndarray, time_s: np.ndarray, flow_ul_s: np.ndarray,
                       direction: np.ndarray) -> np.ndarray:
    """The volume the pump has put into the chamber at each reading (ul): V_0 = Q d t_0,
    V_k = V_(k-1) + Q d_k (t_k - t_(k-1)) along each curve (rows sorted by curve, then
    time; d the pump's state since the previous reading). ``time_s`` counts from the start
    of the pump with the chamber at rest (empty of injected fluid); NaN without time or
    flow. An incompressible fluid and stiff tubing are assumed: the pump's volume is the
    chamber's."""
    out = np.full(time_s.size, np.nan)
    if not (np.all(np.isfinite(time_s)) and np.all(np.isfinite(flow_ul_s))):
        return out
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        t = time_s[rows]
        dt = np.diff(np.concatenate([[0.0], t]))
        out[rows] = np.maximum(np.cumsum(flow_ul_s[rows] * direction[rows] * dt), 0.0)
    return out


#: a switch of the pump's state is fitted only where the chamber holds at least this
#: fraction of the curve's largest injected volume (at rest the actuator cannot tell)
SWITCH_MIN_VOLUME = 0.1


def pump_switches(curve: np.ndarray, time_s: np.ndarray, flow_ul_s: np.ndarray,
                  direction: np.ndarray, volume_ul: np.ndarray, keys: list[str]
                  ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Where the pump changed state between readings, and what that does to the injected
    volume. ``injected_volume_ul`` puts each change at a reading (the direction of an
    interval is the pump's state over all of it), but a lab's pump program switches when
    its volume or time is reached, anywhere between two readings. A switch from state d
    to d' assumed at reading j, really at t_j + s dt (s in reading intervals dt; s < 0:
    before reading j), leaves every later reading's volume off by s dt Q (d - d'), and
    reading j's by min(s, 0) dt Q (d - d').

    Returns ``after`` and ``at`` (n rows x S switches: dt Q (d - d') where the shift acts
    in full and at the switch's own reading) and the switches' names. Replicates of one
    design and flow rate (``keys[curve]``) ran the same program: their i-th switches share
    one name (one fitted shift). Switches where the chamber holds less than
    SWITCH_MIN_VOLUME of the curve's largest volume are left out (the actuator at rest
    cannot tell when the pump stopped)."""
    names: list[str] = []
    cols: dict[str, int] = {}
    entries: list[tuple[int, np.ndarray, int, float]] = []
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        if rows.size < 3:
            continue
        t, d = time_s[rows], direction[rows]
        dt = float(np.median(np.diff(t)))
        top = float(np.max(volume_ul[rows]))
        ordinal = 0
        for j in range(rows.size - 1):
            if d[j] == d[j + 1]:
                continue
            if volume_ul[rows[j]] < SWITCH_MIN_VOLUME * top:
                continue
            name = f"pump_switch_shift[{keys[int(c)]}#{ordinal}]"
            ordinal += 1
            if name not in cols:
                cols[name] = len(names)
                names.append(name)
            amount = dt * float(flow_ul_s[rows[j]]) * float(d[j] - d[j + 1])
            entries.append((cols[name], rows, j, amount))
    after = np.zeros((curve.size, len(names)))
    at = np.zeros((curve.size, len(names)))
    for col, rows, j, amount in entries:
        after[rows[j + 1:], col] += amount
        at[rows[j], col] += amount
    return after, at, tuple(names)
