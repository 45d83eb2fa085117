// An FE solve job and an FE curve as people read them (pure functions): the progress
// line, the solver cutting its step back, where a curve that ended early stops, and the
// curve read at a point of the readout.

import { fmt } from "./util.js";

const CUT_FRACTION = 0.25;  // a step this much smaller than the largest so far is a cut-back
const STALL_MS = 15000;     // this long without a converged step: the solver is struggling

// The last point of a curve with a finite angle: {angle_deg, pressure_pa, index}, or null.
export function curveEnd(curve) {
  const a = curve.angle_deg || [];
  for (let i = a.length - 1; i >= 0; i--) {
    if (typeof a[i] === "number" && Number.isFinite(a[i])) return { angle_deg: a[i], pressure_pa: (curve.pressure_pa || [])[i], index: i };
  }
  return null;
}

// ``data``'s angle and pressure at ``value`` on ``axis`` (pressure_pa, volume_ul or time_s
// arrays beside angle_deg), read linearly between the two steps that bracket it: the first
// such pair along the curve (past a pressure maximum a volume-controlled curve's pressure
// falls, and a pressure is read on the loading branch). {at, angle_deg, pressure_pa,
// between: [x0, x1]} (no ``between`` at a step itself); past the curve's end (its largest
// value on the axis), that end with beyondEnd; null when the curve has no such axis or
// does not reach down to ``value``. The readout had shown the nearest step's angle (10.0
// deg "at its step of 1000 Pa" for 1500 Pa on a curve at 40 deg by 2000 Pa).
export function readCurve(data, axis, value) {
  const xs = data[axis];
  if (!Array.isArray(xs)) return null;
  const points = [];
  xs.forEach((x, i) => {
    const a = data.angle_deg[i];
    if (Number.isFinite(x) && Number.isFinite(a)) points.push({ at: x, angle_deg: a, pressure_pa: (data.pressure_pa || [])[i] ?? null });
  });
  if (!points.length) return null;
  const end = points.reduce((m, q) => (q.at > m.at ? q : m));
  if (value > end.at) return { ...end, beyondEnd: true };
  for (let k = 0; k < points.length; k++) {
    const [p, q] = [points[k], points[k + 1]];
    if (p.at === value) return p;
    if (q && (p.at - value) * (q.at - value) < 0) {
      const w = (value - p.at) / (q.at - p.at);
      const lerp = (u, v) => (Number.isFinite(u) && Number.isFinite(v) ? u + w * (v - u) : null);
      return { at: value, angle_deg: lerp(p.angle_deg, q.angle_deg), pressure_pa: lerp(p.pressure_pa, q.pressure_pa),
               between: [p.at, q.at] };
    }
  }
  return null;
}

// What the progress says of the step size: a progress field the server may add
// (cutbacks, step_cut) or, from the converged steps, a last step much smaller than the
// largest (in pressure and in volume) or a long wait for the next one.
export function cutBackText(trace, progress = {}, nowMs = Date.now()) {
  if (typeof progress.cutbacks === "number" && progress.cutbacks > 0) return `the solver has cut its step back ${progress.cutbacks} times`;
  if (progress.step_cut === true) return "the solver is cutting its step back";
  const parts = [];
  if (trace.length >= 4) {
    const inc = (k) => trace.slice(1).map((s, i) => s[k] - trace[i][k]).filter(Number.isFinite);
    const dp = inc("pressure_pa"), dv = inc("volume_ul");
    const small = (d) => d.length >= 3 && d.at(-1) < CUT_FRACTION * Math.max(...d);
    if (small(dp) && (!dv.length || small(dv))) {
      parts.push(`the solver is cutting its step back: the last step added ${fmt(dp.at(-1), 1)} Pa, earlier ones up to ${fmt(Math.max(...dp), 0)} Pa`);
    }
  }
  const last = trace.at(-1);
  if (last && last.at_ms && nowMs - last.at_ms > STALL_MS) {
    parts.push(`no new converged step for ${Math.round((nowMs - last.at_ms) / 1000)} s (the solver is retrying smaller steps or iterating)`);
  }
  return parts.join("; ");
}

// The job's line: queued / running with the last converged step; at the end, where the
// curve stops and why when it ended early (never "finished" and "failed" together).
export function jobText(job, trace, end, nowMs = Date.now()) {
  const pr = job.progress || {};
  if (job.status === "queued" || job.status === "running") {
    let text = `FE solve ${job.status}`;
    if (pr.step) {
      text += `: step ${pr.step}, ${fmt(pr.pressure_pa, 0)} Pa, ${fmt(pr.volume_ul, 3)} ul, ${fmt(pr.angle_deg, 1)} deg` +
        (pr.newton_iterations ? ` (${pr.newton_iterations} Newton iterations)` : "");
    }
    const cut = job.status === "running" ? cutBackText(trace, pr, nowMs) : "";
    return cut ? `${text}; ${cut}.` : text;
  }
  if (job.status === "finished" && job.curve_id) {
    const stored = `stored in the database as curve ${job.curve_id}`;
    const where = end ? `${fmt(end.angle_deg, 1)} deg (${fmt(end.pressure_pa, 0)} Pa)` : "its last converged step";
    if (!job.curve_status || job.curve_status === "complete") return `FE solve done: the curve reaches ${where}, ${stored}.`;
    return `FE solve done, the curve ended early: it stops at ${where}` +
      `${job.curve_reason ? ` because ${job.curve_reason}` : ""}. The steps up to there are usable and ${stored}.`;
  }
  const words = { failed: "failed", cancelled: "cancelled", timed_out: "stopped at the time limit", parked: "done but not yet stored" };
  return `FE solve ${words[job.status] || job.status}${job.error ? ": " + job.error : ""}`;
}
