// The design search's target kinds as the page shows them (POST /v1/inverse's
// target.kind): the fields each kind takes, the rankings it allows, the result table's
// columns and the curve axis a listed design is loaded on. By chamber pressure (Pa):
// angle_at_pressure, pressure_budget, force_at_pressure; by a syringe pump, from the empty
// actuator: angle_at_volume, volume_budget (injected volume, ul), angle_at_time,
// time_budget (time s at the flow rate ul/s; volume = flow x time).

import { fmt, fmtSig } from "./util.js";

// kind -> what its target is given by ("pressure" | "volume" | "time"): the form's fields
// with data-by="<by>" are shown for it, and a listed design is loaded on that axis
export const TARGET_BY = {
  angle_at_pressure: "pressure", pressure_budget: "pressure", force_at_pressure: "pressure",
  angle_at_volume: "volume", volume_budget: "volume", angle_at_time: "time", time_budget: "time",
};

// The rankings each target kind takes (the server refuses the others, saying which it
// allows: a refusal's "allowed" list replaces this one for that kind).
export const OBJECTIVES = {
  angle_at_pressure: ["certainty", "compact"],
  force_at_pressure: ["certainty", "compact"],
  pressure_budget: ["certainty", "pressure", "margin", "compact"],
  angle_at_volume: ["certainty", "compact"],
  volume_budget: ["certainty", "volume", "margin", "compact"],
  angle_at_time: ["certainty", "compact"],
  time_budget: ["certainty", "volume", "margin", "compact"],
};

// The Curve panel's "Ask by" axis a listed design is shown on, per what the target is by.
export const ASK_AXIS = { pressure: "pressure_pa", volume: "volume_ul", time: "time_s" };

// The target's fields as the form sends them: [form input id, target field].
export const TARGET_INPUTS = {
  pressure: [["inv-pressure", "pressure_pa"]],
  volume: [["inv-volume", "volume_ul"]],
  time: [["inv-time", "time_s"], ["inv-flow", "flow_ul_s"]],
};

// "v [lo, hi]" (the band left out where the answer has none or it is one point)
function banded(v, lo, hi, format) {
  const band = typeof lo === "number" && typeof hi === "number" && lo !== hi ? ` [${format(lo)}, ${format(hi)}]` : "";
  return `${format(v)}${band}`;
}

const angle = (v) => fmt(v, 1);
const pressure = (v) => fmt(v, 0);
// volumes and times to 3 significant digits: they scale with the design's size
const sig = (v) => fmtSig(v);

// The kind's own columns of the result table for the target searched ({kind, pressure_pa,
// volume_ul, time_s, flow_ul_s}): [{head, key, cell(candidate)}]; a column whose key no
// listed design gives a number for is left out (a budget's designs may all be past their
// FE range at the budget's volume: no angle there).
export function targetColumns(searched) {
  const by = TARGET_BY[searched.kind];
  if (by === "pressure") {
    const force = searched.kind === "force_at_pressure";
    const value = force ? sig : angle;
    return [
      { head: force ? "force at the pressure (mN)" : "angle at the pressure (deg)", key: "value_at_pressure",
        cell: (c) => banded(c.value_at_pressure, c.value_lower, c.value_upper, value) },
      { head: "pressure needed (Pa)", key: "pressure_needed_pa",
        cell: (c) => banded(c.pressure_needed_pa, c.pressure_lower_pa, c.pressure_upper_pa, pressure) },
    ];
  }
  // the target's volume or time as the user gave it
  const volume = by === "volume" ? `${searched.volume_ul} ul` : `${searched.time_s} s`;
  const needed = [
    { head: "volume needed (ul)", key: "volume_needed_ul",
      cell: (c) => banded(c.volume_needed_ul, c.volume_lower_ul, c.volume_upper_ul, sig) },
  ];
  if (by === "time") {
    needed.unshift({ head: `time needed at ${searched.flow_ul_s} ul/s (s)`, key: "time_needed_s",
      cell: (c) => banded(c.time_needed_s, c.time_lower_s, c.time_upper_s, sig) });
  }
  // a budget's design reaches the angle before the budget's end: the chamber's pressure
  // there (for an exact target it is the pressure at the target volume)
  if (searched.kind.endsWith("_budget")) {
    needed.push({ head: "chamber pressure needed (Pa)", key: "pressure_needed_pa",
      cell: (c) => banded(c.pressure_needed_pa, c.pressure_lower_pa, c.pressure_upper_pa, pressure) });
  }
  return [
    ...needed,
    { head: `angle at ${volume} (deg)`, key: "angle_at_volume_deg",
      cell: (c) => banded(c.angle_at_volume_deg, c.angle_at_volume_lower_deg, c.angle_at_volume_upper_deg, angle) },
    { head: `chamber pressure at ${volume} (Pa)`, key: "pressure_at_volume_pa",
      cell: (c) => pressure(c.pressure_at_volume_pa) },
  ];
}

// The unit of a listed design's change per 0.01 mm (change_per_0_01_mm): the angle's at
// the target's pressure or volume, the force's for a force target.
export function changeUnit(kind) {
  return kind === "force_at_pressure" ? "mN" : "deg";
}

// Where on its curve a listed design is shown (the readout's point, on the target's axis):
// an exact target's pressure, volume or time; a budget's: what the design needs.
export function readoutAt(searched, c) {
  switch (searched.kind) {
    case "pressure_budget": return c.pressure_needed_pa ?? c.target_pressure_pa;
    case "angle_at_volume": return searched.volume_ul;
    case "volume_budget": return c.volume_needed_ul;
    case "angle_at_time": return searched.time_s;
    case "time_budget": return c.time_needed_s;
    default: return searched.pressure_pa ?? c.pressure_needed_pa ?? c.target_pressure_pa;
  }
}

// A listed design's messages that are about its target: an angle target's designs leave
// out the force's (force_past_fe_range "force is given up to ...", force_band_too_wide "no
// force at ..."): its curve's blocked-tip force, which no column of the table shows (the
// design loaded shows it with its own flags).
export function targetNotes(searched, messages) {
  if (searched.kind === "force_at_pressure") return messages;
  return messages.filter((m) => !/^(no )?force\b/.test(m));
}
