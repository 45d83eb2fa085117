"""The augmented model at every observation: baseline + effects, stage by stage.

    p_chamber = pressure effects (p_gauge, flow, direction)
    static    = k_A,f x baseline(design + physical effects, p_chamber / k_p,f)
    angle     = time effects that lag the bend (static along each curve's time; 4
                substeps per interval)
    observed  = angle effects (angle)

or, where the injected volume V of every reading is known (time_s and flow_ul_s) and the
baseline gives V(p) (``pressure_weight`` > 0: the two observables of a syringe pump):

    V         = volume effects (V_pump, the changed design's p(V))  what the chamber got
    static    = baseline angle(design + physical effects, V)        its answer by volume
    p_chamber = baseline p_chamber(design + physical effects, V)
    angle     = time effects;  observed = angle effects            as above
    gauge     = pressure effects' inverses (p_chamber delayed by the time effects that
                lag the gauge, along each curve's time)            ``gauge_pressures``

A gauge effect moves only the gauge against volume; a camera effect only the angle
against volume; a physical change both, the FE's coupled way (docs/calibration.md).

k_A,f and k_p,f (amplitude and pressure scale per family) exist only when the baseline
leaves them open (the exponential and paper models: their per-family constants); the
emulator leaves nothing open (its material constants are the stiffness effects).

By volume the data may leave one more thing open, whatever the baseline: when the pump
changed state (stopped, restarted, reversed) between two readings, as a program that ends
at a volume or a time does, every later reading's injected volume is off
(``_history.pump_switches``). With ``switches`` each such change gets a shift s (reading
intervals, within +-SWITCH_BOUND; 0 = at the reading the data put it at), shared by the
replicates of one design and flow rate (one pump program), fitted with the baseline and
with every candidate set alike. The loop frees them only where they explain the data
(_pump_switches.py, ``pump_switches_open``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration._history import line_direction
from surrogate.calibration._response import Responses, design_key
from surrogate.calibration._specimens import SpecimenScatter
from surrogate.calibration.effects import Effect

SUBSTEPS = 4
OPEN_BOUND = 0.7  # |log k| for the open amplitude and pressure scales
SWITCH_BOUND = 0.75  # |s|, reading intervals: a state held for most of an interval gives
                     # the interval its direction (_history.directions)


@dataclass(frozen=True)
class Layout:
    """The free numbers: open baseline scales per family, then the effects' parameters."""

    names: tuple[str, ...]
    units: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    start: np.ndarray
    n_open: int

    @property
    def k(self) -> int:
        return len(self.names)


class AugmentedModel:
    """Evaluates angles at the rows of ``obs`` for parameter vectors of ``layout``."""

    def __init__(self, obs: Observations, responses: Responses, effects: tuple[Effect, ...],
                 open_parameters: tuple[str, ...], pressure_weight: float = 0.0,
                 switches: bool = False, scatter: SpecimenScatter | None = None) -> None:
        """``pressure_weight`` (deg per Pa): the pressure-by-volume channel's residuals
        count as ``pressure_weight`` x (predicted - read gauge pressure) beside the angle's
        (the ratio of the two noise floors); 0 leaves the channel out. ``switches``: fit
        the pump switches' shifts (by volume only). ``scatter``: the specimens' pressure
        scale as a random effect, the residuals weighted by it (``whiten``,
        _specimens.py); None: ordinary least squares."""
        self.obs = obs
        # the pressure effects' flow direction: none yet at a reading at the pump's start
        self.flow_direction = line_direction(obs.time_s, obs.direction)
        self.scatter = scatter
        self._scale_direction: np.ndarray | None = None
        self.pressure_weight = float(pressure_weight)
        self.by_volume = self.pressure_weight > 0.0
        self.responses = responses
        self.effects = effects
        self.physical = tuple(e for e in effects if e.stage == "design")
        self.pressure = tuple(e for e in effects if e.stage == "pressure")
        self.volume = tuple(e for e in effects if e.stage == "volume")
        # time effects that act on the volume the pump put in (a leak): by volume only
        self._leaks = tuple(e for e in effects if e.stage == "time" and e.lags == "volume"
                            and self.by_volume)
        self.time = tuple(e for e in effects if e.stage == "time")
        self.angle = tuple(e for e in effects if e.stage == "angle")
        self.families = sorted(set(obs.family.tolist()))
        self.open = open_parameters
        names, units, lo, hi, x0 = [], [], [], [], []
        for f in self.families:
            for o in open_parameters:
                names.append(f"log_{o}[{f}]")
                units.append("-")
                lo.append(-OPEN_BOUND)
                hi.append(OPEN_BOUND)
                x0.append(0.0)
        n_open = len(names)
        # the pump switches' shifts: by volume only (by pressure the gauge is read)
        self.switch_cols = (np.flatnonzero(np.any(obs.switch_after != 0, axis=0)
                                           | np.any(obs.switch_at != 0, axis=0))
                            if switches and self.by_volume else np.zeros(0, int))
        for j in self.switch_cols:
            names.append(obs.switch_names[j])
            units.append("reading intervals")
            lo.append(-SWITCH_BOUND)
            hi.append(SWITCH_BOUND)
            x0.append(0.0)
        for e in effects:
            for p in e.parameters:
                # a physical effect stays where the baseline answers (its reach)
                b = responses.reach(e).bounds if e.stage == "design" else p.fit_bounds
                names.append(p.name)
                units.append(p.unit)
                lo.append(b[0])
                hi.append(b[1])
                x0.append(min(max(p.start, b[0]), b[1]))
        self.layout = Layout(tuple(names), tuple(units), np.array(lo, float),
                             np.array(hi, float), np.array(x0, float), n_open)
        per_curve = np.array([responses.index[design_key(obs.design(c))]
                              for c in range(obs.n_curves)], dtype=int)
        self.design_index = per_curve[obs.curve]
        fam_pos = {f: i for i, f in enumerate(self.families)}
        self.family_pos = np.array([fam_pos[f] for f in obs.family])
        if self.time:
            self._prepare_substeps()
        self._last_volumes: tuple[bytes | None, np.ndarray | None] = (None, None)
        # each curve's design (its rows share it): what a leak's pressure is read on
        self._curve_design = np.array([self.design_index[self.obs.curve == c][0]
                                       for c in range(obs.n_curves)], dtype=int)

    def switch_shifts(self, x: np.ndarray) -> np.ndarray:
        """The pump switches' fitted shifts (reading intervals) in ``x``."""
        n = self.layout.n_open
        return x[n:n + self.switch_cols.size] if x.size else np.zeros(self.switch_cols.size)

    def volume_shift(self, x: np.ndarray) -> np.ndarray:
        """How much the pump switches' shifts move each row's injected volume (ul)."""
        o = self.obs
        if not self.switch_cols.size:
            return np.zeros(o.n)
        s = self.switch_shifts(x)
        return (o.switch_after[:, self.switch_cols] @ s
                + o.switch_at[:, self.switch_cols] @ np.minimum(s, 0.0))

    def volumes(self, x: np.ndarray) -> np.ndarray:
        """Injected volume (ul) at every row, the pump switches' shifts applied."""
        return np.maximum(self.obs.volume_ul + self.volume_shift(x), 0.0)

    def gauge_pressures(self, x: np.ndarray) -> np.ndarray:
        """Predicted gauge reading (Pa) at every row's injected volume: the baseline's
        chamber pressure at that volume for the changed design, delayed along each
        curve's time by the time effects that lag the gauge, through the pressure
        effects' inverses (last applied first)."""
        values = self.values(x)
        o = self.obs
        lags = tuple(e for e in self.time if e.lags == "gauge")
        if lags or self._leaks:
            s = self._sub
            static = self._chamber_at_volume(values, self.design_index[s["rows"]],
                                             self._substep_volumes(x))
            grid = np.full(s["shape"], np.nan)
            grid[s["valid"]] = static
            known = np.isfinite(grid[s["sample_pos"]])
            tgrid = s["tgrid"]
            grid = np.nan_to_num(grid)
            for e in lags:
                grid = e.lag(grid, tgrid, s["valid"], values)
            p = np.full(o.n, np.nan)
            p[s["sample_rows"]] = np.where(known, grid[s["sample_pos"]], np.nan)
        else:
            p = self._chamber_at_volume(values, self.design_index, self.volumes(x))
        q = np.nan_to_num(o.flow_ul_s)
        for e in reversed(self.pressure):
            p = e.gauge_pressure(p, q, self.flow_direction, values)
        return p

    def _by_volume(self, what, values, design_index, v_ul):
        """The baseline's angle ("angle_v") or chamber pressure ("pressure_v") at injected
        volume ``v_ul`` (the pump's, less any leak) of the changed design (its table by
        volume, interpolated), at the volume the chamber got from it (the volume
        effects')."""
        thetas = [values[e.parameters[0].name] for e in self.physical]
        if self.volume:
            p_table = self.responses.curves(self.physical, thetas, what="pressure_v")
            v_ul = self._in_chamber(values, p_table, design_index, v_ul)
        table = self.responses.curves(self.physical, thetas, what=what)
        return self.responses.lookup_volume(table, design_index, v_ul)

    def _in_chamber(self, values, p_table, design_index, v_ul):
        """The chamber's volume (ul) at line volumes ``v_ul`` through the volume effects,
        ``p_table`` the changed designs' chamber pressure by volume."""
        for e in self.volume:
            v_ul = e.chamber_volume(v_ul, self.responses.v_grid, p_table, design_index,
                                    values)
        return v_ul

    def _pressure_at(self, values, design: np.ndarray):
        """line volume ul (one per curve) -> chamber pressure (Pa) of each curve's
        changed design ``design`` (n_curves,), its tables interpolated once: what a leak
        integrates along the readings, so the lookup is lean (NaN past the table)."""
        thetas = [values[e.parameters[0].name] for e in self.physical]
        p_table = self.responses.curves(self.physical, thetas, what="pressure_v")
        rows = p_table[design]
        n, dv, curve = rows.shape[1], self.responses.dv, np.arange(design.size)

        def at(v_ul: np.ndarray) -> np.ndarray:
            if self.volume:
                v_ul = self._in_chamber(values, p_table, design, v_ul)
            f = np.maximum(v_ul, 0.0) / dv
            i0 = np.minimum(f.astype(int), n - 2)
            a = rows[curve, i0]
            out = a + (f - i0) * (rows[curve, i0 + 1] - a)
            return np.where(f <= n - 1, out, np.nan)
        return at

    def _chamber_at_volume(self, values, design_index, v_ul):
        return self._by_volume("pressure_v", values, design_index, v_ul)

    def reading_pressure(self, x: np.ndarray) -> np.ndarray:
        """The chamber pressure (Pa) at which each row's angle is read off the baseline:
        the gauge's, or by volume the baseline's at the injected volume."""
        if self.by_volume:
            return self._chamber_at_volume(self.values(x), self.design_index,
                                           self.volumes(x))
        return np.clip(self.obs.pressure_pa, 0.0, None)

    def values(self, x: np.ndarray) -> dict[str, float]:
        """The effects' parameters by name."""
        n = self.layout.n_open + self.switch_cols.size
        return {name: float(v) for name, v in zip(self.layout.names[n:], x[n:], strict=True)}

    def _scales(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k_a = np.ones(len(self.families))
        k_p = np.ones(len(self.families))
        i = 0
        for fi in range(len(self.families)):
            for o in self.open:
                if o == "amplitude":
                    k_a[fi] = np.exp(x[i])
                else:
                    k_p[fi] = np.exp(x[i])
                i += 1
        return k_a[self.family_pos], k_p[self.family_pos]

    def _static(self, values, design_index, p_gauge, flow, direction, k_a, k_p, v_ul):
        if self.by_volume:  # the gauge's effects do not move the actuator
            return k_a * self._by_volume("angle_v", values, design_index, v_ul)
        p = p_gauge
        for e in self.pressure:
            p = e.chamber_pressure(p, flow, direction, values)
        curves = self.responses.curves(self.physical,
                                       [values[e.parameters[0].name] for e in self.physical])
        return k_a * self.responses.lookup(curves, design_index, p / k_p)

    def angles(self, x: np.ndarray, amp: float = 1.0, pscale: float = 1.0) -> np.ndarray:
        """Predicted angle (deg) at every row; ``amp``/``pscale`` multiply every curve's
        amplitude / pressure scale (for the structure test's nuisance directions)."""
        values = self.values(x)
        k_a, k_p = self._scales(x)
        k_a, k_p = k_a * amp, k_p * pscale
        o = self.obs
        if not (self._leaks or any(e.lags == "angle" for e in self.time)):
            out = self._static(values, self.design_index, o.pressure_pa, o.flow_ul_s,
                               self.flow_direction, k_a, k_p, self.volumes(x))
        else:
            s = self._sub
            static = self._static(values, self.design_index[s["rows"]], s["p"], s["q"],
                                  s["d"], k_a[s["rows"]], k_p[s["rows"]],
                                  self._substep_volumes(x))
            grid = np.full(s["shape"], np.nan)
            grid[s["valid"]] = static
            tgrid = s["tgrid"]
            for e in self.time:
                if e.lags == "angle":
                    grid = e.lag(np.nan_to_num(grid), tgrid, s["valid"], values)
            out = np.empty(o.n)
            out[s["sample_rows"]] = grid[s["sample_pos"]]
        for e in self.angle:
            out = e.observed(out, values)
        return out

    def _substep_volumes(self, x: np.ndarray) -> np.ndarray:
        """The volume (ul) in the line at every substep: the pump's, linear between the
        readings' volumes with the pump switches' shifts applied, less what leaked out
        along the curve's time (the time effects that act on the volume). With a leak,
        the last ``x``'s answer is kept (read-only): a residual asks for it twice, for the
        angles and for the gauge, and the leak's integration along every curve is most of
        a fit's time."""
        if not self._leaks:
            return self._line_volumes(x)
        key = x.tobytes()
        if self._last_volumes[0] != key:
            v = self._line_volumes(x)
            v.flags.writeable = False
            self._last_volumes = (key, v)
        return self._last_volumes[1]

    def _line_volumes(self, x: np.ndarray) -> np.ndarray:
        s = self._sub
        v = s["v"]
        if self.switch_cols.size:
            shift = np.concatenate([self.volume_shift(x), [0.0]])  # [-1]: at rest
            v = np.maximum(v + (1.0 - s["w"]) * shift[s["prev"]]
                           + s["w"] * shift[s["rows"]], 0.0)
        if self._leaks:
            v = v - self._leaked(x, v)
        return v

    def _leaked(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """What the leaks took (ul) by every substep from the line volumes ``v`` there:
        integrated by the effects along the readings (and rest, the substeps' first
        column), linear in time between them (a leak changes over many readings; a
        quarter of the cost of every substep)."""
        s = self._sub
        values = self.values(x)
        grid = np.zeros(s["shape"])
        grid[s["valid"]] = v
        tgrid = s["tgrid"]
        at = slice(0, None, SUBSTEPS)                    # rest, then every reading
        pressure_at = self._pressure_at(values, self._curve_design)
        kept = grid[:, at]
        for e in self._leaks:
            kept = e.delivered_volume(kept, tgrid[:, at], s["valid"][:, at], pressure_at,
                                      values)
        lost = grid[:, at] - kept
        k = np.arange(s["shape"][1])
        w = (k % SUBSTEPS) / SUBSTEPS
        left = k // SUBSTEPS
        right = np.minimum(left + 1, lost.shape[1] - 1)
        return ((1.0 - w) * lost[:, left] + w * lost[:, right])[s["valid"]]

    def pressure_scale_direction(self, x: np.ndarray) -> np.ndarray:
        """d residual / d e at every residual row for a pressure scale (1 + e) of the
        baseline's curves (what scaling both layers' stiffness does): by pressure the
        angle's change when each curve is read at p / (1 + e); by injected volume 0 for
        the angle (the invariance leaves angle(V) unchanged) and the weighted chamber
        pressure for the gauge channel. NaN (past the baseline's range) as 0."""
        if self.by_volume:
            dp = self.pressure_weight * self.reading_pressure(x)
            return np.nan_to_num(np.concatenate([np.zeros(self.obs.n), dp]))
        h = 1e-3
        base = self.angles(x)
        return np.nan_to_num((self.angles(x, pscale=1.0 + h) - base) / h)

    def residual_specimens(self) -> np.ndarray:
        """The specimen of every residual row (the pressure channel's rows repeat the
        angles'): a specimen's runs share its scatter (the curve without runs)."""
        c = self.obs.specimen
        return np.concatenate([c, c]) if self.by_volume else c

    def whiten(self, r: np.ndarray) -> np.ndarray:
        """The residual rows ``r`` weighted for the specimens' scatter (_specimens.py),
        along the pressure-scale direction at the layout's start (every candidate set
        starts at the recalibrated baseline, so all are weighted alike); ``r`` itself
        without ``scatter``."""
        if self.scatter is None or self.scatter.tau <= 0.0:
            return r
        if self._scale_direction is None:
            self._scale_direction = self.pressure_scale_direction(self.layout.start)
        return self.scatter.whiten(r, self._scale_direction, self.residual_specimens())

    def _prepare_substeps(self) -> None:
        """Pressure (and injected volume) linear in time between readings, SUBSTEPS per
        interval; the lag is integrated exactly for a static angle linear between
        substeps. ``time_s`` counts from the start of the pump with the chamber at rest
        (docs/measured-data.md), so each curve starts at rest at t = 0 (pressure, volume
        and bend 0), SUBSTEPS before its first reading: a first reading taken seconds
        into the pumping already lags (a curve whose clock starts at its first reading
        adds nothing: those substeps last 0 s)."""
        o = self.obs
        order = o.padded_order()
        n_curves, m = order.shape
        width = m * SUBSTEPS + 1
        valid = np.zeros((n_curves, width), bool)
        rows, p, q, d, t, v, prev_rows, weights = [], [], [], [], [], [], [], []
        sample_rows, sample_pos = [], []
        ramp = np.arange(0, SUBSTEPS + 1) / SUBSTEPS
        for c in range(n_curves):
            idx = order[c][order[c] >= 0]
            for j, r in enumerate(idx):
                if j == 0:  # from rest at t = 0 to the first reading
                    fr, p0, v0 = ramp, 0.0, 0.0
                    t0 = min(0.0, float(o.time_s[r]))
                    prev = -1
                else:
                    prev = idx[j - 1]
                    fr = ramp[1:]
                    t0, p0, v0 = o.time_s[prev], o.pressure_pa[prev], o.volume_ul[prev]
                for k, w in enumerate(fr):
                    pos = k if j == 0 else j * SUBSTEPS + k + 1
                    valid[c, pos] = True
                    rows.append(r)
                    p.append(p0 + w * (o.pressure_pa[r] - p0))
                    t.append(t0 + w * (o.time_s[r] - t0))
                    v.append(v0 + w * (o.volume_ul[r] - v0) if np.isfinite(v0)
                             else o.volume_ul[r])
                    q.append(o.flow_ul_s[r])
                    d.append(self.flow_direction[r])
                    prev_rows.append(prev)
                    weights.append(w)
                sample_rows.append(r)
                sample_pos.append((c, (j + 1) * SUBSTEPS))
        # rows of a curve fill its first positions contiguously
        self._sub = {"rows": np.array(rows), "p": np.array(p), "q": np.nan_to_num(np.array(q)),
                     "d": np.array(d), "t": np.array(t), "v": np.array(v), "valid": valid,
                     "prev": np.array(prev_rows, int), "w": np.array(weights, float),
                     "shape": (n_curves, width), "sample_rows": np.array(sample_rows),
                     "sample_pos": tuple(np.array(sample_pos).T)}
        # each curve's substep times as a grid (0 in the padding): what every time effect
        # integrates along, the same at every evaluation
        tgrid = np.zeros((n_curves, width))
        tgrid[valid] = self._sub["t"]
        tgrid.flags.writeable = False
        self._sub["tgrid"] = tgrid
