// The design explorer: design panel -> POST /v1/predict -> curve, band, validity,
// nearest FE curves (GET /v1/curves), readout at one point and sketch; pinned designs;
// the curve asked by chamber pressure, by injected volume, or by time at the pump's flow
// rate (the request's pressures_pa, volumes_ul or times_s with flow_ul_s);
// the FE solve of a refused design (POST /v1/solve, GET /v1/jobs/{id}); exports.
// The inverse form and the measured-data report live in inverse.js and calibration.js.

import { api, ApiError, clearMessage, clearProblems, fieldPath, isAbort, OfflineError, showMessage, showProblem } from "./api.js";
import { setupCalibration } from "./calibration.js";
import {
  FIELDS, PAIRS, W_FIELD, W_MM, axisGrid, defaultState, designBody, designLabel, fieldRange, materialId,
  materialLabel, pairLabel, scaledLengths, shown, stateOfDesign, takeScaleLimits,
} from "./design.js";
import { allowedWords, checkNumber, numberBoxes, rangeHints, readNumber } from "./fields.js";
import { setupInverse } from "./inverse.js";
import { curveEnd, jobText, readCurve } from "./job.js";
import { linkNote, readLink, writeLink } from "./link.js";
import { COLORS, renderPlot, svgText, svgToPngBlob } from "./plot.js";
import { renderSketch } from "./sketch.js";
import { $, csvCell, download, fmt, fmtSig, setTextWithCode } from "./util.js";

const N_POINTS = 81;
const LEVEL = 0.95;
const DEBOUNCE_MS = 16;  // one frame: a drag's inputs coalesce, a stale request is aborted
const MAX_PINNED = 4;
// What the curve is asked by: the request field, the input of its largest value, the unit.
const ASK = {
  pressure_pa: { field: "pressures_pa", input: "p_max", unit: "Pa", digits: 0, label: "pressure", fallback: 2000 },
  volume_ul: { field: "volumes_ul", input: "v_max", unit: "ul", digits: 2, label: "injected volume", fallback: 50 },
  time_s: { field: "times_s", input: "t_max", unit: "s", digits: 1, label: "time", fallback: 20 },
};
// The plot's axes as people read them (the x axis's pressure is the chamber's).
const X_LABELS = { pressure_pa: "chamber pressure (Pa)", volume_ul: "injected volume (ul)", time_s: "time (s)",
  pump_pressure_pa: "pump-gauge pressure (Pa)" };
const X_NAMES = { pressure_pa: "pressure", volume_ul: "volume", time_s: "time", pump_pressure_pa: "pump-gauge pressure" };
const RETRY_MS = 5000;  // a service that stopped answering is asked again this often
const FLAG_WORDS = {
  past_fe_range: "past the FE range",
  past_pressure_maximum: "past the pressure maximum (volume control)",
  angle_beyond_fe: "past the largest FE angle",
  pressure_beyond_fe: "past the FE pressure range",
  two_balloon_regime: "two-balloon regime",
  t_outside_fitted_range: "t outside the fitted box",
  L_outside_fitted_range: "L outside the fitted box",
  outside_box: "outside the design box",
  near_early_ended_fe_curves: "near FE curves that ended early",
  band_undercovers_random_designs: "band too narrow here (random designs)",
  force_past_fe_range: "force past the FE range",
  force_band_too_wide: "force band too wide",
  force_at_free_tip_pressure: "force: blocked tip at the free actuator's pressure",
  band_capped_at_fe_range: "band capped at the FE range",
  past_fe_pressure_stop: "past the FE's 20 kPa pressure stop",
  past_longest_pump_time: "past the longest pump time",
  pressures_look_like_kpa: "pressures look like kPa",
  near_stiffness_balance: "near the stiffness balance",
  curve_turns_back: "curve turns back: least reliable here",
  high_membrane_stretch: "membrane stretch where FE curves often fail",
};
export const flagWords = (f) => FLAG_WORDS[f] || String(f).replaceAll("_", " ");

const app = {
  presets: {},
  state: defaultState(),
  prediction: null,     // the last /v1/predict answer shown
  request: null,        // the request body it answers
  refused: null,        // ApiError of a refused design
  pinned: [],           // [{state, prediction, color}]
  feFamilies: new Map(),// family key -> summaries (GET /v1/curves)
  feDetails: new Map(), // curve id -> record (GET /v1/curves/{id})
  nearest: [],          // records shown
  health: null,         // the last GET /v1/health answer
  solved: new Map(),    // design key -> FE record from a finished solve
  stored: null,         // {key, record}: the stored FE record of the design shown (any status)
  job: null,            // {id, key, trace: [{pressure_pa, angle_deg, volume_ul, at_ms}]}
  inputErrors: new Map(),// error slot id -> the page's own message (an empty design field)
  opFraction: 0.5,      // the readout's place on the grid (kept when the grid's end changes)
  wantAxes: null,       // {x, y} of a link, applied once a prediction offers them
  linkHash: "",         // the fragment the page last wrote
  offline: false,       // the service stopped answering: retried on a timer, on focus, on a change
  retryMs: RETRY_MS,
  retryTimer: null,
  controller: null,
  timer: null,
  inputMark: null,
  timings: [],          // slider move -> redrawn curve, ms (performance.now)
  firstRenderMs: null,
};
window.explorer = app;

// ---------------------------------------------------------------- design panel
function addField(box, f, onValue) {
  const div = document.createElement("div");
  div.className = "field slider";
  const unit = f.unit === "x" ? "" : ` (${f.unit})`;
  div.innerHTML = `
    <label for="${f.name}">${f.label}${unit}</label>
    <div class="pair">
      <input type="range" id="${f.name}-range" step="${f.step}"
        value="${f.value}" aria-label="${f.label} slider" tabindex="-1">
      <input type="text" inputmode="decimal" id="${f.name}" name="${f.name}" step="${f.step}"
        value="${f.value}" required aria-describedby="${f.name}-range-text">
    </div>
    <span class="muted small" id="${f.name}-range-text"></span>
    <p class="field-error" id="err-${f.name}" data-for="${f.name}" hidden></p>`;
  box.appendChild(div);
  const range = div.querySelector(`#${f.name}-range`);
  const num = div.querySelector(`#${f.name}`);
  showRange(f, fieldRange(f, app.state.W_mm));
  range.tabIndex = 0;
  range.addEventListener("input", () => { num.value = range.value; app.inputErrors.delete(`err-${f.name}`); onValue(Number(range.value)); });
  num.addEventListener("input", () => {
    // an empty field is named beside it, never silently kept at its former value; a
    // number the server does not take (L 70, t -1) is sent, and its answer names the range.
    // A width or a stiffness scale <= 0 is no design at all: named here (a scale of -1 was
    // sent as a material of negative moduli and offered an FE solve the server refused)
    const text = num.value.trim();
    const allowed = fieldAllowed(f);
    const read = text === "" ? { error: `empty (${allowed})` } : readNumber(text, allowed);
    const v = read.value;
    if (read.error || ((f === W_FIELD || f.unit === "x") && !(v > 0))) {
      // text that is no number ("1e", "0x10") or too large for a double ("1e999")
      app.inputErrors.set(`err-${f.name}`, read.error || `${text} is not a usable value (${allowed})`);
      app.inputMark = performance.now();
      schedule(DEBOUNCE_MS);
      return;
    }
    app.inputErrors.delete(`err-${f.name}`);
    range.value = String(v);
    onValue(v);
  });
}

// "allowed: 4 to 18 mm": a design field's range at the design's width, in an error's words.
function fieldAllowed(f) {
  return `allowed: ${allowedText(f, fieldRange(f, app.state.W_mm))}`;
}

// A field's allowed values in an error's words.
function allowedText(f, r) {
  if (f.unit !== "x") return `${r.min} to ${r.max} ${f.unit}`;
  if (r.min === null || !f.ratio) return "more than 0 x preset moduli";
  return `${r.min} to ${r.max} x preset moduli, body / membrane ${f.ratio[0]} to ${f.ratio[1]}`;
}

function rangeText(f, r) {
  if (f.unit !== "x") return `${r.min} - ${r.max} ${f.unit}`;
  if (r.min === null || !f.ratio) return "x preset moduli";   // the server has not said yet
  return `${r.min} - ${r.max} x preset moduli; body / membrane ${f.ratio[0]} - ${f.ratio[1]}`;
}

// A field's range on its inputs and in its words: a length's at the design's width (the
// box scaled by W / 3 mm); a stiffness scale's number takes each layer's range, its slider
// spans the ratio's (one layer moved, the other at 1: every position in the box).
function showRange(f, r) {
  const slider = f.unit === "x" && f.ratio ? { min: f.ratio[0], max: f.ratio[1] } : r;
  for (const [id, lim] of [[f.name, r], [`${f.name}-range`, slider]]) {
    if (lim.min === null) continue;
    $(id).min = String(lim.min);
    $(id).max = String(lim.max);
  }
  $(`${f.name}-range-text`).textContent = rangeText(f, r);
}

function showRanges() {
  for (const f of FIELDS) showRange(f, fieldRange(f, app.state.W_mm));
}

// The state's values on the inputs of ``fields`` (all of them and the pair by default).
function showValues(fields = [W_FIELD, ...FIELDS]) {
  for (const f of fields) {
    // shown to 0.1 um; the state keeps full precision (a scaled copy stays in the box)
    $(f.name).value = shown(app.state[f.name]);
    $(`${f.name}-range`).value = String(app.state[f.name]);
  }
  $("pair").value = String(app.state.pair);
}

function buildFields() {
  const box = $("design-fields");
  addField(box, W_FIELD, onWidth);
  for (const f of FIELDS) addField(box, f, (v) => onInput(f.name, v));
  const pair = $("pair");
  PAIRS.forEach(([b, m], k) => pair.add(new Option(pairLabel(b, m), String(k))));
  pair.addEventListener("change", () => onInput("pair", Number(pair.value)));
  for (const id of ["p_max", "v_max", "t_max", "flow", "inlet", "tubing_length", "tubing_bore", "model", "nearby"]) {
    $(id).addEventListener("change", () => { $("view-note").textContent = ""; schedule(0); });
  }
  $("inlet").addEventListener("change", showInlet);
  $("ask_axis").addEventListener("change", onAskAxis);
  for (const id of ["x_axis", "y_axis"]) $(id).addEventListener("change", () => { redraw(); rewriteLink(); });
  $("p_op").addEventListener("input", () => {
    const max = Number($("p_op").max);
    if (max > 0) app.opFraction = Number($("p_op").value) / max;
    showOperatingPoint();
    redraw();
    rewriteLink();  // the readout's point is part of the view
  });
}

function onInput(name, value) {
  $("view-note").textContent = "";
  app.state[name] = value;
  app.inputMark = performance.now();
  schedule(DEBOUNCE_MS);
}

// A new width scales every length with it (a scaled copy bends alike at the same pressure)
// and the lengths' ranges with them; the user then changes any length within its range.
function onWidth(W) {
  Object.assign(app.state, scaledLengths(app.state, W));
  showRanges();
  showValues(FIELDS);  // not W's own input, which the user is typing in
  app.inputMark = performance.now();
  schedule(DEBOUNCE_MS);
}

// ``values``: any of the state's keys; a design without a width is at W = 3 mm (the
// design search's box, the stored records). ``at``: the readout's point on the asked axis
// (an inverse design's target pressure, injected volume or time): the curve's range grows
// to show it, with the readout on it.
export function loadDesign(values, { at } = {}) {
  Object.assign(app.state, { W_mm: W_MM }, values);
  for (const f of [W_FIELD, ...FIELDS]) app.inputErrors.delete(`err-${f.name}`);
  showRanges();
  showValues();
  if (Number.isFinite(at) && at > 0) showAt(at);
  app.inputMark = performance.now();
  schedule(0);
}

// The asked axis's grid (0 .. its largest value, N_POINTS points: Pa, ul or s) made to hold
// ``p`` on one of its points: kept when it does, else the largest value is raised (to
// 1.25 p at least, within the input's limit) to one that does; the readout is put on it.
function showAt(p) {
  const a = ASK[askAxis()];
  const input = $(a.input);
  const limit = Number(input.max) || Infinity;
  const n = N_POINTS - 1;
  const check = checkNumber(input);
  let max = check.value ?? a.fallback;
  const onGrid = (m) => p <= m && Math.abs((p * n) / m - Math.round((p * n) / m)) < 1e-9;
  if (!onGrid(max)) {
    const want = Math.min(limit, Math.max(max, 1.25 * p));
    let i = Math.max(1, Math.floor((p * n) / want));
    if ((p * n) / i > limit) i = Math.min(n, Math.ceil((p * n) / limit));
    const before = max;
    max = (p * n) / i;
    input.value = shown(max);
    clearMessage($(`err-${a.field}`));
    if (max > before) {
      const v = (x) => `${fmt(x, a.digits)} ${a.unit}`;
      $("view-note").textContent = `Largest ${a.label} raised from ${v(before)} to ${v(max)} to show the loaded design at ${v(p)}.`;
    }
  }
  app.opFraction = p / max;
}

function schedule(delay) {
  clearTimeout(app.timer);
  app.timer = setTimeout(update, delay);
}

function askAxis() {
  return $("ask_axis").value;
}

// The largest value of the asked axis (the grid runs from 0 to it); while its field holds
// no usable value (named beside it, see pageErrors) the last good one.
function gridMax() {
  const a = ASK[askAxis()];
  const v = checkNumber($(a.input)).value;
  if (v !== undefined && v !== null) { a.last = v; return v; }
  return a.last ?? a.fallback;
}

function flowRate() {
  const text = $("flow").value.trim();
  return text === "" ? null : Number(text);
}

// The page's own checks of the request's numbers: [[error slot, message]]; a field in
// error is named beside it with its range and no prediction is asked.
function pageErrors() {
  const out = [...app.inputErrors.entries()].map(([id, text]) => [$(id), text]);
  const a = ASK[askAxis()];
  const max = checkNumber($(a.input), { unit: a.unit });
  if (max.error) out.push([$(`err-${a.field}`), max.error]);
  const flow = checkNumber($("flow"), { optional: true, unit: "ul/s" });
  if (flow.error) out.push([$("err-flow_ul_s"), flow.error]);
  if ($("inlet").checked) {
    const length = checkNumber($("tubing_length"), { unit: "mm" });
    if (length.error) out.push([$("err-tubing_length"), length.error]);
    const bore = checkNumber($("tubing_bore"), { unit: "mm" });
    // the bore counts with tubing (length > 0) or where the length is itself in error:
    // both are named at once, not the bore only once the length is mended
    if ((length.error || length.value > 0) && bore.error) out.push([$("err-tubing_bore"), bore.error]);
  }
  return out;
}

// The request without its design: the asked axis, the flow rate, the inlet, the model.
function askPart(grid) {
  const body = { [ASK[askAxis()].field]: grid, model: $("model").value.trim() || "emulator", level: LEVEL };
  const q = flowRate();
  if (q !== null) body.flow_ul_s = q;
  if ($("inlet").checked) body.inlet = inletPart();
  return body;
}

// The inlet's hydraulic path: the paper's channel, and the tubing from the pump when its
// length is > 0 (Hagen-Poiseuille in series, surrogate/hydraulics.py). A field in error
// is named by pageErrors and nothing is asked.
function inletPart() {
  const length = checkNumber($("tubing_length")).value;
  if (!(length > 0)) return {};
  return { tubing_length_mm: length, tubing_bore_mm: checkNumber($("tubing_bore")).value };
}

// The tubing's fields with the inlet; the answer's resistance under them.
function showInlet() {
  for (const el of document.querySelectorAll("[data-inlet]")) el.hidden = !$("inlet").checked;
}

// The inlet's resistance R and, at the flow rate, its pressure drop R Q (the answer's).
function showInletNote() {
  const inlet = app.prediction && app.prediction.inlet;
  const R = inlet && inlet.resistance_pa_per_ul_s;
  $("inlet-note").textContent = typeof R !== "number" ? ""
    : `Inlet resistance R = ${fmtSig(R)} Pa per ul/s` +
      (typeof inlet.pressure_drop_pa === "number" ? `: R Q = ${fmtSig(inlet.pressure_drop_pa)} Pa at ${fmtSig(inlet.flow_ul_s)} ul/s.` : ".");
}

function predictBody(state, grid) {
  return { design: designBody(state, app.presets), ...askPart(grid) };
}

function onAskAxis() {
  showAskAxis();
  app.opFraction = 0.5;
  schedule(0);
}

// The inputs and headings of the asked axis.
function showAskAxis() {
  const axis = askAxis();
  for (const el of document.querySelectorAll("[data-ask]")) el.hidden = el.dataset.ask !== axis;
  const option = $("x_axis").querySelector(`option[value="${axis}"]`);
  option.disabled = false;
  $("x_axis").value = axis;
  const a = ASK[axis];
  $("p_op-h").textContent = `At one ${a.label}`;
  $("p_op-label").textContent = `${a.label[0].toUpperCase()}${a.label.slice(1)} (${a.unit})`;
}

// ---------------------------------------------------------------- the view's link
// The address's fragment holds the design, the curve request and the readout's point
// (link.js): each answer and each move of the readout rewrites it, a page opened with one
// starts from it.
function view() {
  const near = checkNumber($("nearby"), { integer: true });
  const inlet = $("inlet").checked ? inletPart() : {};
  return { ask: askAxis(), max: gridMax(), flow: flowRate(), inlet: $("inlet").checked,
           tubing: inlet.tubing_length_mm, bore: inlet.tubing_bore_mm,
           model: $("model").value.trim() || "emulator",
           x: app.wantAxes?.x ?? $("x_axis").value, y: app.wantAxes?.y ?? $("y_axis").value,
           near: near.value ?? undefined, at: (gridMax() * opIndex()) / (N_POINTS - 1) };
}

function rewriteLink() {
  app.linkHash = writeLink(app.state, view());
  history.replaceState(null, "", app.linkHash);
}

// ``reset``: a link pasted into the open page starts from the defaults, as a new page would.
function applyLink(hash, reset = false) {
  const link = readLink(hash);
  if (reset) {
    app.state = defaultState();
    app.inputErrors.clear();
    for (const el of $("design-form").querySelectorAll("input, select")) {
      if (el.type === "checkbox") el.checked = el.defaultChecked;
      else if (el.tagName === "SELECT") el.value = ([...el.options].find((o) => o.defaultSelected) || el.options[0]).value;
      else if (el.type !== "range") el.value = el.defaultValue;
    }
  }
  Object.assign(app.state, link.design);
  showRanges();
  showValues();
  const v = link.view;
  if (v.ask) $("ask_axis").value = v.ask;
  if (v.max) $(ASK[askAxis()].input).value = String(v.max);
  if (v.flow !== undefined) {
    $("flow").value = v.flow === null ? "" : String(v.flow);
    $("flow").dispatchEvent(new Event("input"));  // the time targets' flow box shows it too
  }
  if (v.inlet !== undefined) $("inlet").checked = v.inlet;
  if (v.tubing !== undefined) $("tubing_length").value = String(v.tubing);
  if (v.bore !== undefined) $("tubing_bore").value = String(v.bore);
  showInlet();
  if (v.model) $("model").value = v.model;
  if (v.near !== undefined) $("nearby").value = String(v.near);
  showAskAxis();
  app.wantAxes = v.x || v.y ? { x: v.x, y: v.y } : null;
  // the readout's point, on the curve's grid (one past its end is named, not moved)
  const max = gridMax();
  if (v.at !== undefined && v.at > max) link.ignored.push({ key: "at", value: String(v.at), why: "invalid" });
  app.opFraction = v.at !== undefined && v.at <= max ? v.at / max : 0.5;
  const note = $("link-note");
  note.hidden = link.ignored.length === 0;
  note.textContent = linkNote(link.ignored, linkAllowed);
}

// What a link's key read into a box allows, in the boxes' own words (null: no box).
function linkAllowed(key) {
  const field = [W_FIELD, ...FIELDS].find((f) => f.name === key);
  if (field) return fieldAllowed(field);
  const a = ASK[askAxis()];
  if (key === "at") return `allowed: from 0 to ${gridMax()} ${a.unit}`;
  const box = { max: [a.input, a.unit], flow: ["flow"], tubing: ["tubing_length"], bore: ["tubing_bore"],
    near: ["nearby"] }[key];
  return box ? allowedWords($(box[0]), { integer: key === "near", unit: box[1] }) : null;
}

const DESIGN_SLOTS = () => {
  const slots = {};
  for (const f of [W_FIELD, ...FIELDS]) if (f.name.endsWith("_mm")) slots[`design.${f.name}`] = $(`err-${f.name}`);
  slots["design.body_material"] = $("err-body_material");
  slots["design.membrane_material"] = $("err-membrane_material");
  slots.design = $("err-design");
  slots.pressures_pa = $("err-pressures_pa");
  slots.volumes_ul = $("err-volumes_ul");
  slots.times_s = $("err-times_s");
  slots.flow_ul_s = $("err-flow_ul_s");
  slots.inlet = $("err-inlet");
  slots["inlet.tubing_length_mm"] = $("err-tubing_length");
  slots["inlet.tubing_bore_mm"] = $("err-tubing_bore");
  slots.model = $("err-model");
  slots.ask_axis = $("err-ask_axis");
  return slots;
};

// A server's message in the page's words: each asked axis's request field as the "Ask by"
// choice that sends it (the paper's model asked by time said "allowed: pressures_pa", the
// API's name of what the page's "Ask by" chooses), a model by the "Model" box's name; the
// other fields are named by their boxes' labels (showProblem), with the ranges the
// server states in the user's units.
function inPageWords(text) {
  const choice = (field) => {
    const axis = Object.keys(ASK).find((k) => ASK[k].field === field);
    return `Ask by "${$("ask_axis").querySelector(`option[value="${axis}"]`).textContent}"`;
  };
  const fields = Object.values(ASK).map((a) => a.field).join("|");
  return text.replace(new RegExp(`(?<![\\w.])(${fields})(?![\\w.])`, "g"), choice)
    .replace(/\bmodel "([^"]+)"/g, 'Model "$1"');
}

// POST /v1/predict. Asked by pressure, the pump's flow rate only adds the time axis: a
// model that gives no injected volume (the paper's) refuses it, and is asked again without
// it, the answer saying so (the page's default 2.5 ul/s made the paper's model refuse
// every design by pressure, beside "Pump flow rate").
async function predictAnswer(body, signal) {
  try {
    return await api("/v1/predict", { method: "POST", body, signal });
  } catch (err) {
    const flowOnly = err instanceof ApiError && err.status === 422 && err.fieldErrors.length > 0 &&
      err.fieldErrors.every((e) => fieldPath(e) === "flow_ul_s");
    if (!flowOnly || !body.pressures_pa || body.flow_ul_s === undefined || body.inlet) throw err;
    const { flow_ul_s: _, ...without } = body;
    const answer = await api("/v1/predict", { method: "POST", body: without, signal });
    return { ...answer, flow_dropped: err.fieldErrors[0].message };
  }
}

// The slot of a refusal of the asked axis itself (a model that answers by pressure only,
// asked by volume or time: its "allowed" names another axis's field), not of its values:
// beside "Ask by", not "Largest time (s)".
function askSlot(path, e) {
  const fields = Object.values(ASK).map((a) => a.field);
  const other = fields.find((f) => f !== path && String(e.allowed || "").startsWith(f));
  return fields.includes(path) && other ? "ask_axis" : null;
}

async function update() {
  if (app.controller) app.controller.abort();  // a stale request is cancelled
  const controller = new AbortController();
  app.controller = controller;
  const mark = app.inputMark;
  const mine = pageErrors();
  if (mine.length) {  // said beside each field; nothing is asked with another value
    clearProblems($("design-form"));
    for (const [el, text] of mine) showMessage(el, text);
    app.prediction = null;
    app.refused = null;
    app.nearest = [];
    $("status").textContent = `No prediction: correct ${mine.map(([el]) => fieldName(el)).join(", ")} (beside the field).`;
    afterAnswer(null, mark);
    return;
  }
  const grid = axisGrid(gridMax(), N_POINTS);  // 0 .. the largest value, on any axis
  const p = $("p_op");
  p.max = String(gridMax());
  p.step = String(gridMax() / (N_POINTS - 1));
  p.value = String(app.opFraction * gridMax());  // the same place on the new grid
  let body = null;
  try {
    body = predictBody(app.state, grid);  // throws while a scaled layer's preset is unknown
    const prediction = await predictAnswer(body, controller.signal);
    if (controller.signal.aborted) return;
    clearProblems($("design-form"));
    app.prediction = prediction;
    app.request = body;
    app.refused = null;
    if (app.offline) backOnline();
    $("status").textContent = `${prediction.model} model${prediction.form ? ", " + prediction.form + " form" : ""}` +
      (prediction.flow_dropped ? `; no time axis: ${prediction.flow_dropped} (asked without the pump flow rate)` : "");
  } catch (err) {
    if (isAbort(err) || controller.signal.aborted) return;
    clearProblems($("design-form"));
    app.prediction = null;
    app.request = body;
    if (err instanceof OfflineError) {
      goOffline();
      afterAnswer(null, mark);
      return;
    }
    app.refused = (await offersSolve(err, body)) ? err : null;
    if (controller.signal.aborted) return;
    // a refusal of the design as a whole is shown once, in the FE solve box (not again
    // beside the field it names); a model the server does not know, beside the Model field
    const unknownModel = err instanceof ApiError && err.status === 404;
    showProblem(err, app.refused ? {} : DESIGN_SLOTS(), app.refused ? null : $(unknownModel ? "err-model" : "err-design"),
      { words: inPageWords, slot: askSlot });
    $("status").textContent = app.refused ? "No prediction: the model refuses this design (below)."
      : `No prediction: ${err instanceof ApiError ? `${err.problem.title || "error"} (${err.status})` : String(err)}`;
  }
  rewriteLink();
  refreshPinned(grid, controller);
  afterAnswer(controller, mark);
}

// What every answer (or page-side refusal) redraws; the nearest FE curves come after.
function afterAnswer(controller, mark) {
  showInletNote();
  $("pin").disabled = app.pinned.length >= MAX_PINNED || !app.prediction;
  $("pin").title = app.prediction ? "" : "nothing to pin: there is no prediction for this design";
  showRefused();
  showValidity();
  showOperatingPoint();
  redraw();
  if (mark !== null) {
    app.timings.push(performance.now() - mark);
    performance.measure?.("slider-to-redraw", { start: mark, end: performance.now() });
    app.inputMark = null;
  }
  if (app.firstRenderMs === null) app.firstRenderMs = performance.now();
  if (controller) loadNearest(controller);
}

// The page's name of an error slot's field ("Largest pressure (Pa)").
function fieldName(el) {
  const input = el.dataset.for && $(el.dataset.for);
  return (input && input.labels && input.labels[0] ? input.labels[0].textContent.trim() : el.id.replace(/^err-/, ""));
}

// ---------------------------------------------------------------- a service that stopped
function showHealth() {
  return api("/v1/health").then((h) => {
    app.health = h;   // the loaded model files' SHA-256, named in the CSV export
    // the default model first: the emulator; the exponential file is the named model
    const emulator = h.emulator && h.emulator.loaded ? "emulator (default model)" : "emulator not loaded";
    const exponential = h.surrogate && h.surrogate.loaded ? `; exponential model "${h.surrogate.name}"` : "";
    $("health").textContent = `service ${h.version}; ${h.database.records ?? 0} FE records; ${emulator}${exponential}`;
  }).catch((err) => {
    $("health").textContent = err instanceof OfflineError ? "service not answering" : "service health unknown";
    throw err;
  });
}

function goOffline() {
  app.offline = true;
  app.refused = null;
  app.nearest = [];
  app.stored = null;
  $("status").textContent = `No prediction: the service is not answering (is it running?). The page asks again every ${Math.round(app.retryMs / 1000)} s, when you return to this tab and at your next change.`;
  $("health").textContent = "service not answering";
  clearTimeout(app.retryTimer);
  app.retryTimer = setTimeout(retry, app.retryMs);
}

async function retry() {
  if (!app.offline) return;
  clearTimeout(app.retryTimer);
  try {
    await showHealth();
  } catch {
    app.retryTimer = setTimeout(retry, app.retryMs);
    return;
  }
  backOnline();
  schedule(0);
}

function backOnline() {
  app.offline = false;
  clearTimeout(app.retryTimer);
  showHealth().catch(() => {});
}

// A design the predictor refuses can still be solved by FE: a 422 whose errors all name
// the design (its family, the model's box: the emulator's "out-of-box" names the field), for a design the API's own schema accepts
// (DesignIn's limits in /openapi.json, which POST /v1/solve checks too). A value outside
// those limits is not offered a solve that would be refused the same way.
let designLimits = null;
let apiSpec = null;

async function openapi() {
  if (!apiSpec) apiSpec = api("/openapi.json").catch((err) => { apiSpec = null; throw err; });
  return apiSpec;
}

async function schemaLimits() {
  if (!designLimits) {
    try {
      const spec = await openapi();
      const props = spec.components.schemas.DesignIn.properties;
      designLimits = Object.fromEntries(Object.entries(props).map(([k, v]) => [k, [v.minimum ?? -Infinity, v.maximum ?? Infinity]]));
    } catch { return {}; }
  }
  return designLimits;
}

// The inputs' limits where the server's schema gives them: the solve's mesh level
// (SolveSettingsIn), each grid value and the flow rate (PredictRequest); a schema
// without them leaves the page's own.
async function applySchemaLimits() {
  let spec;
  try { spec = await openapi(); } catch { return; }
  applySpecLimits(spec);
  rangeHints();  // the boxes' hints say the limits just set
}

function applySpecLimits(spec) {
  const schemas = spec.components?.schemas || {};
  const set = (id, prop, { min = true } = {}) => {
    if (!prop) return;
    if (typeof prop.maximum === "number") $(id).max = String(prop.maximum);
    if (min && typeof prop.minimum === "number") $(id).min = String(prop.minimum);
  };
  set("mesh_level", schemas.SolveSettingsIn?.properties?.mesh_level);
  set("inv-n", schemas.InverseRequest?.properties?.n_results);
  set("cal-folds", schemas.CalibrateRequest?.properties?.folds);
  const predict = schemas.PredictRequest?.properties || {};
  // a list's items, also inside "anyOf" (a list or null)
  const items = (p) => p && (p.items || (p.anyOf || []).map((a) => a.items).find(Boolean));
  // the grid's ends: at most the largest value each point may take
  set("p_max", items(predict.pressures_pa), { min: false });
  set("v_max", items(predict.volumes_ul), { min: false });
  set("t_max", items(predict.times_s), { min: false });
  // the flow rate: a number or null (the page refused 0.001 ul/s, which the API takes)
  set("flow", (predict.flow_ul_s?.anyOf || []).find((a) => a.type === "number") || predict.flow_ul_s);
  const inlet = schemas.InletIn?.properties || {};
  set("tubing_length", inlet.tubing_length_mm);
  set("tubing_bore", inlet.tubing_bore_mm?.anyOf?.find((a) => a.type === "number") || inlet.tubing_bore_mm);
  // the design search's target (TargetIn): each field a number or null; an exclusive
  // minimum (volume_ul, time_s: more than 0) is left to the server, which names it
  const target = schemas.TargetIn?.properties || {};
  const number = (p) => (p?.anyOf || []).find((a) => a.type === "number") || p;
  for (const [id, name] of [["inv-pressure", "pressure_pa"], ["inv-volume", "volume_ul"], ["inv-time", "time_s"],
    ["inv-flow", "flow_ul_s"], ["inv-angle", "angle_deg"], ["inv-force", "force_mn"]]) set(id, number(target[name]));
}

async function offersSolve(err, body) {
  if (!(err instanceof ApiError) || err.status !== 422 || !body) return false;
  // the design itself refused (a chamber wider than the actuator, a material softer than
  // the FE's floor): the FE solve refuses it the same way
  if (err.problem && err.problem.fe_solvable === false) return false;
  const errs = err.fieldErrors;
  // the emulator's out-of-box refusal names the design field (["body", "design", "L_mm"];
  // servers before 2026-12-05 named it bare, ["body", "L_mm"])
  const inDesign = errs.length > 0 && errs.every((e) => {
    const loc = Array.isArray(e.loc) ? e.loc.slice(1).join(".") : String(e.field || "");
    return loc === "design" || loc.startsWith("design.") || Object.hasOwn(body.design, loc);
  });
  if (!inDesign) return false;
  const limits = await schemaLimits();
  return Object.entries(body.design).every(([k, v]) => typeof v !== "number" || !limits[k] || (v >= limits[k][0] && v <= limits[k][1]));
}

// ---------------------------------------------------------------- nearest FE curves
// The stored FE records are at W = 3 mm: a design at another width is compared with them
// as its copy scaled to W = 3 mm (lengths x 3 / W, to 1 um), and their curves are drawn
// scaled back (the same angle at the same pressure; volume x k^3, tip force x k^2).
function widthScale(state) {
  return (state.W_mm ?? W_MM) / W_MM;
}

function reduced(state, name) {
  return Math.round((state[name] / widthScale(state)) * 1e3) / 1e3;
}

function familyQuery(state) {
  const d = designBody(state, app.presets);
  return { body_material: materialId(d.body_material), membrane_material: materialId(d.membrane_material),
           T_mm: reduced(state, "T_mm"), b_mm: reduced(state, "b_mm"), h_mm: reduced(state, "h_mm") };
}

async function familySummaries(q, signal) {
  const key = JSON.stringify(q);
  if (app.feFamilies.has(key)) return app.feFamilies.get(key);
  const items = [];
  let offset = 0;
  while (offset !== null && offset !== undefined) {
    const params = new URLSearchParams({ body_material: q.body_material, membrane_material: q.membrane_material,
      T_mm: q.T_mm, b_mm: q.b_mm, h_mm: q.h_mm, limit: 500, offset });
    const page = await api(`/v1/curves?${params}`, { signal });
    items.push(...page.items);
    offset = page.next_offset;
  }
  // every status: a failed record is no neighbour, but it is this design's own curve
  const same = items.filter((r) => Math.abs(r.h_mm - q.h_mm) < 1e-6);
  app.feFamilies.set(key, same);
  return same;
}

async function record(id, signal) {
  if (!app.feDetails.has(id)) app.feDetails.set(id, await api(`/v1/curves/${id}`, { signal }));
  return app.feDetails.get(id);
}

async function loadNearest(controller) {
  const near = checkNumber($("nearby"), { integer: true });
  const count = near.value ?? 0;
  const state = { ...app.state };
  const key = designKey(state);
  const note = $("fe-note");
  const notes = [];
  clearMessage($("err-nearby"));
  if (near.error) showMessage($("err-nearby"), near.error);  // no curves rather than another count
  try {
    const q = familyQuery(state);
    const rows = await familySummaries(q, controller.signal);
    const L = reduced(state, "L_mm"), t = reduced(state, "t_mm");
    // this design's own stored record, of any status: a curve that ended early is drawn
    // up to where it stops (after a reload, or a solve by someone else)
    const own = rows.filter((r) => Math.abs(r.L_mm - L) < 1e-6 && Math.abs(r.t_mm - t) < 1e-6 && r.n_points > 1)
      .sort((a, b) => b.n_points - a.n_points)[0];
    const stored = own ? { key, record: await record(own.id, controller.signal) } : null;
    const neighbours = rows.filter((r) => r.status !== "failed");
    // nearest in (L, t), the same scales as the server's plot (10 mm, 0.5 mm)
    const ranked = neighbours.map((r) => [Math.hypot((r.L_mm - L) / 10, (r.t_mm - t) / 0.5), r])
      .sort((a, b) => a[0] - b[0]).slice(0, count).map(([, r]) => r);
    const records = [];
    for (const r of ranked) records.push(await record(r.id, controller.signal));
    if (controller !== app.controller) return;
    app.nearest = records;
    app.stored = stored;
    if (count > 0 && !neighbours.length) {
      notes.push(`No stored FE curves for this family (${materialLabel(q.body_material)} / ${materialLabel(q.membrane_material)}, ` +
        `T ${fmtSig(q.T_mm)} b ${fmtSig(q.b_mm)} h ${fmtSig(q.h_mm)} mm at W = 3 mm): none is drawn.`);
    }
    const shownRecord = app.solved.get(key) || stored?.record;
    if (shownRecord && shownRecord.curve.status && shownRecord.curve.status !== "complete") notes.push(endText(shownRecord, "The stored FE curve of this design"));
  } catch (err) {
    if (isAbort(err)) return;
    app.nearest = [];
    if (err instanceof OfflineError) { if (!app.offline) goOffline(); } else notes.push(`FE curves unavailable: ${err.message}`);
  }
  note.textContent = notes.join(" ");
  note.hidden = notes.length === 0;
  showOperatingPoint();
  redraw();
}

// "The stored FE curve of this design stops at 30.0 deg (3000 Pa): <why>."
function endText(rec, what) {
  const end = curveEnd(rec.curve);
  const why = rec.curve.reason ? `: ${rec.curve.reason}` : "";
  return end ? `${what} (curve ${rec.id.slice(0, 8)}) stops at ${fmt(end.angle_deg, 1)} deg (${fmt(end.pressure_pa, 0)} Pa)${why}.` : "";
}

// The FE record drawn for the design shown: its finished solve's, else its stored one
// when the model gives no curve or the record ended early (a complete one is already
// drawn first among the nearest FE curves). None while a design field is in error: the
// design shown is not the one whose fields were last good (an emptied L drew and read out
// "FE curve of this design" of the former L).
function ownRecord() {
  if (app.inputErrors.size) return null;
  const key = designKey(app.state);
  const stored = app.stored && app.stored.key === key ? app.stored.record : null;
  return app.solved.get(key) || (stored && (!app.prediction || stored.curve.status !== "complete") ? stored : null);
}

// ---------------------------------------------------------------- drawing
function designKey(state) {
  try { return JSON.stringify(designBody(state, app.presets)); } catch { return null; }
}

function axisKeys() {
  return { x: $("x_axis").value, y: $("y_axis").value };
}

function xOf(data) {
  const { x } = axisKeys();
  return data[x] && data[x].some((v) => v !== null && v !== undefined) ? data[x] : null;
}

// An FE record's curve on the page's axes, scaled to the design's width (kw = W / 3 mm:
// volume x kw^3, force x kw^2), its clock its own injected volume over the page's flow
// rate (none without one: the record's own 2.5 ul/s is not the user's pump).
function feData(rec, cutAt) {
  const kw = widthScale(app.state);
  const c = rec.curve;
  const volume = c.volume_ul ? c.volume_ul.map((v) => (v === null ? v : v * kw ** 3)) : null;
  const force = c.force_mn ? c.force_mn.map((f) => (f === null ? f : f * kw ** 2)) : c.force_mn;
  const q = flowRate();
  const time = q > 0 && volume ? volume.map((v) => (v === null ? v : v / q)) : null;
  const along = { pressure_pa: c.pressure_pa, volume_ul: volume, time_s: time }[askAxis()];
  if (!along) return null;
  const keep = along.map((x) => !cutAt || x <= gridMax() * 1.05);
  const cut = (a) => (a ? a.filter((_, i) => keep[i]) : a);
  return { pressure_pa: cut(c.pressure_pa), volume_ul: cut(volume), time_s: cut(time), angle_deg: cut(c.angle_deg), force_mn: cut(force) };
}

function curveSeries() {
  const { y } = axisKeys();
  const keys = y === "force" ? ["force_mn", "force_lower_mn", "force_upper_mn"] : ["angle_deg", "lower_deg", "upper_deg"];
  const out = [];
  // a series with no number to draw is left out, its legend entry too: by force, the
  // nearest free-tip FE curves (force null) were listed and never drawn
  const add = (id, label, data, color, extra = {}) => {
    const x = xOf(data);
    if (!x || !data[keys[0]] || !data[keys[0]].some((v) => Number.isFinite(v))) return;
    out.push({ id, label, color, x, y: data[keys[0]], lower: data[keys[1]], upper: data[keys[2]], ...extra });
  };
  const kw = widthScale(app.state);
  app.nearest.forEach((rec, k) => {
    const d = rec.design;
    const data = feData(rec, true);
    if (!data) return;  // by time without a flow rate: no clock for the records
    // labelled with its materials: the pooled PDMS group holds PDMS 1:10 and 1:15 records
    const pair = `${materialLabel(d.body_material, app.presets)} / ${materialLabel(d.membrane_material, app.presets)}`;
    const size = kw === 1 ? `L=${fmtSig(d.L_mm)} t=${fmtSig(d.t_mm)} mm` : `L=${fmtSig(d.L_mm)} t=${fmtSig(d.t_mm)} mm at W = 3 mm, scaled x${fmtSig(kw)}`;
    // a dash pattern of its own each: greys alone left two crossing curves alike
    add(`fe-${rec.id}`, `FE ${pair}, ${size}`, data, ["#6b7280", "#9ca3af", "#4b5563", "#a3a3a3", "#737373", "#525252"][k],
      { dash: ["5 4", "1.5 3", "9 3 2 3", "3 2", "12 4", "1.5 2 6 2"][k % 6], width: 1.4 });
  });
  // pinned curves without their bands (the table gives the band at the chosen pressure)
  app.pinned.forEach((pin) => {
    const pr = pinnedAnswer(pin);
    if (pr) add(`pin-${pin.n}`, `#${pin.n} ${designLabel(pin.state)}`, pr, pin.color, { width: 1.6, lower: null, upper: null });
  });
  const key = designKey(app.state);
  const own = ownRecord();
  const ownData = own && feData(own, false);
  if (ownData) {
    const end = curveEnd(own.curve);
    const early = own.curve.status && own.curve.status !== "complete" && end ? `, stops at ${fmt(end.angle_deg, 1)} deg` : "";
    add("fe-solve", `FE curve of this design ${own.id.slice(0, 8)}${early}`, ownData, "#111827", { width: 2, markers: true });
  }
  // the solve's converged steps while it runs; once its curve is stored, that curve (with
  // its steps marked): a step the solver replaced -- the overshoot past the 90-deg stop its
  // landing redoes -- is no point of the stored curve and was drawn past its end
  if (!ownData && app.job && app.job.key === key && app.job.trace.length) {
    const t = app.job.trace;
    add("fe-progress", "FE solve, converged steps", { pressure_pa: t.map((s) => s.pressure_pa), volume_ul: t.map((s) => s.volume_ul),
      angle_deg: t.map((s) => s.angle_deg) }, "#111827", { markersOnly: true });
  }
  if (app.prediction) add("prediction", `model (${Math.round(100 * app.prediction.level)} % band)`, app.prediction, COLORS[0], { width: 2.4 });
  return out;
}

export function redraw() {
  const { x, y } = axisKeys();
  const xLabel = X_LABELS[x];
  const yLabel = y === "force" ? "tip force (mN)" : "bending angle (deg)";
  const series = curveSeries();
  let cursor = null;
  const i = opIndex();
  if (app.prediction && i !== null) cursor = (xOf(app.prediction) || [])[i];
  const plot = $("plot");
  renderPlot(plot, series, {
    xLabel, yLabel, cursorX: cursor,
    xRange: x === askAxis() ? [0, gridMax()] : undefined, legend: "below",
    note: app.prediction ? "" : (app.offline ? "the service is not answering" : app.refused ? "the model refuses this design"
      : pageErrors().length ? "correct the marked field" : ""),
  });
  // the heading and the plot's name say what it shows
  const what = `${y === "force" ? "tip force" : "bending angle"} against ${xLabel.replace(/ \(.*\)$/, "")}`;
  plot.setAttribute("aria-label", `${app.prediction ? "Predicted " : "No prediction: "}${what}${app.prediction && y === "angle" ? " with its 95 % band" : ""}` +
    `${series.some((s) => s.id.startsWith("fe-")) ? ", and FE curves" : ""}`);
  const name = X_NAMES[x];
  $("curve-h").textContent = `${name[0].toUpperCase()}${name.slice(1)} - ${y === "force" ? "force" : "angle"} curve`;
  drawSketch();
}

function opIndex() {
  const p = Number($("p_op").value);
  return Math.round((p / gridMax()) * (N_POINTS - 1));
}

function showOperatingPoint() {
  const out = $("p_op-out");
  const i = opIndex();
  const pred = app.prediction;
  const axis = askAxis();
  const ask = ASK[axis];
  const p = (gridMax() * i) / (N_POINTS - 1);
  $("compare-p-h").textContent = `angle at ${fmt(p, ask.digits)} ${ask.unit}`;
  if (!pred) {
    // the design's own FE curve, when one is drawn: read at the readout's point
    const own = ownRecord();
    const data = own && feData(own, false);
    const read = data && readCurve(data, axis, p);
    const v = (x) => `${fmt(x, ask.digits)} ${ask.unit}`;
    let text = `${v(p)}: no model prediction`;
    if (read && read.beyondEnd) {
      text += `; past the FE curve's end: it stops at ${fmt(read.angle_deg, 1)} deg at ${v(read.at)}` +
        (axis === "pressure_pa" ? "" : ` (${fmt(read.pressure_pa, 0)} Pa)`);
    } else if (read) {
      text += `; FE curve: angle ${fmt(read.angle_deg, 1)} deg` +
        (read.between ? ` (read between its steps at ${fmt(read.between[0], ask.digits)} and ${v(read.between[1])})` : " (at its step)") +
        (axis === "pressure_pa" || !Number.isFinite(read.pressure_pa) ? "" : `; chamber pressure ${fmt(read.pressure_pa, 0)} Pa`);
    }
    out.textContent = text;
    renderCompare();
    return;
  }
  const a = pred.angle_deg[i];
  const at = axis === "pressure_pa" ? pred.pressure_pa[i] : (pred[axis] || [])[i];
  let text = `${fmt(at, ask.digits)} ${ask.unit}: angle ${a === null ? "not predicted (past the FE range)" : fmt(a, 1) + " deg"}`;
  if (a !== null) text += ` [${fmt(pred.lower_deg[i], 1)}, ${fmt(pred.upper_deg[i], 1)}] (${Math.round(pred.level * 100)} %)`;
  if (pred.force_mn && pred.force_mn[i] !== null && pred.force_mn[i] !== undefined) {
    // forces, volumes and times to 3 significant digits: they scale with the design's size
    // (a corner of the box read "force 0.00 mN [0.00, 0.00]" for 0.0030 [0.0017, 0.0048])
    text += `; force ${fmtSig(pred.force_mn[i])} mN`;
    if (pred.force_lower_mn && pred.force_upper_mn) text += ` [${fmtSig(pred.force_lower_mn[i])}, ${fmtSig(pred.force_upper_mn[i])}]`;
  }
  const has = (k) => Array.isArray(pred[k]) && pred[k][i] !== null && pred[k][i] !== undefined;
  if (axis !== "pressure_pa" && has("pressure_pa")) text += `; chamber pressure ${fmt(pred.pressure_pa[i], 0)} Pa`;
  if (has("pump_pressure_pa")) text += `; pump gauge ${fmt(pred.pump_pressure_pa[i], 0)} Pa`;
  if (axis !== "volume_ul" && has("volume_ul")) text += `; volume ${fmtSig(pred.volume_ul[i])} ul`;
  if (axis !== "time_s" && has("time_s")) text += `; time ${fmtSig(pred.time_s[i])} s`;
  out.textContent = text;
  renderCompare();
}

function drawSketch() {
  const pred = app.prediction;
  const i = opIndex();
  const design = pred ? pred.design : { ...app.state };
  let angle = pred ? pred.angle_deg[i] : null;
  let source = "predicted";
  if (!pred) {  // the design's own FE curve, read at the readout's point
    const own = ownRecord();
    const data = own && feData(own, false);
    const read = data && readCurve(data, askAxis(), (gridMax() * i) / (N_POINTS - 1));
    if (read && !read.beyondEnd) { angle = read.angle_deg; source = "FE"; }
  }
  renderSketch($("sketch"), design, angle === null || angle === undefined ? NaN : angle,
    angle === null ? 0 : i / (N_POINTS - 1), { at: ASK[askAxis()].label, source });
}

function showValidity() {
  const box = $("validity");
  box.innerHTML = "";
  const pred = app.prediction;
  if (!pred) return;
  const v = pred.validity || {};
  const head = document.createElement("p");
  const cautions = (v.flags || []).length > 0;
  head.className = v.in_domain && !cautions ? "ok" : "warn";
  head.textContent = !v.in_domain ? "Outside the model's fitted domain:"
    : (cautions ? "Inside the model's fitted domain, with these cautions:" : "Inside the model's fitted domain.");
  box.appendChild(head);
  const flags = document.createElement("p");
  for (const f of v.flags || []) {
    const chip = document.createElement("span");
    chip.className = "chip";
    chip.dataset.flag = f;
    chip.textContent = flagWords(f);
    flags.appendChild(chip);
  }
  if (flags.childNodes.length) box.appendChild(flags);
  const ul = document.createElement("ul");
  const messages = [...(v.messages || [])];
  const firstNull = pred.angle_deg.findIndex((a) => a === null);
  const asked = app.request ? app.request[ASK[askAxis()].field] : null;
  if (firstNull > 0 && asked) {
    // the FE range's end in the asked axis, as the server states it (the first empty grid
    // point after it said "39.38 ul" beside the server's "38.8 ul"), where the curve ends
    // there: between its last answered point and its first empty one (an exponential
    // model's curve ends earlier, at the family's largest FE angle, than the family's
    // last FE pressure, which the page had called the curve's end)
    const flow = app.request && app.request.flow_ul_s;
    const end = { pressure_pa: v.fe_limit_pa, volume_ul: v.fe_limit_volume_ul,
      time_s: typeof v.fe_limit_volume_ul === "number" && flow ? v.fe_limit_volume_ul / flow : null }[askAxis()];
    const { unit, digits } = ASK[askAxis()];
    const [last, first] = [asked[firstNull - 1], asked[firstNull]];
    const atEnd = typeof end === "number" && end >= last - 1e-9 * first && end <= first * (1 + 1e-9);
    messages.push(atEnd
      ? `The curve ends at ${fmt(end, digits)} ${unit}, where the FE's range ends: the answer is capped there, no angle is given beyond it.`
      : `The curve ends at ${fmt(last, digits)} ${unit}: the answer is capped there, no angle is given from ${fmt(first, digits)} ${unit} on (past the FE's range, above).`);
  }
  for (const m of messages) {
    const li = document.createElement("li");
    li.textContent = m;
    ul.appendChild(li);
  }
  if (messages.length) box.appendChild(ul);
  const hasForce = Array.isArray(pred.force_mn) && pred.force_mn.some((f) => f !== null);
  $("y_axis").querySelector('option[value="force"]').disabled = !hasForce;
  for (const k of ["volume_ul", "time_s", "pump_pressure_pa"]) {
    $("x_axis").querySelector(`option[value="${k}"]`).disabled = !(Array.isArray(pred[k]) && pred[k].some((x) => x !== null));
  }
  // a link's axes, once the answer offers them
  const want = app.wantAxes;
  app.wantAxes = null;
  for (const [id, v] of [["x_axis", want?.x], ["y_axis", want?.y]]) {
    const option = v && $(id).querySelector(`option[value="${v}"]`);
    if (option && !option.disabled) $(id).value = v;
  }
  if ($("x_axis").selectedOptions[0]?.disabled) $("x_axis").value = "pressure_pa";
  if ($("y_axis").selectedOptions[0]?.disabled) $("y_axis").value = "angle";
}

// ---------------------------------------------------------------- compare
function pin() {
  if (app.pinned.length >= MAX_PINNED || !app.prediction) return;
  const used = new Set(app.pinned.map((p) => p.n));
  let n = 1;
  while (used.has(n)) n++;
  // the answer shown is this design's unless a change is still being asked (a pin made
  // then kept the former design's curve under the new design's name): then the pinned
  // design waits for its own answer, which the pending change's refreshPinned asks
  const own = designKey(app.state) === JSON.stringify(app.request.design);
  app.pinned.push({ n, state: { ...app.state }, prediction: own ? app.prediction : null, color: COLORS[n],
                    ask: own ? askOf(app.request) : null });
  renderCompare();
  redraw();
}

// A predict request's question without its design (the asked axis's grid, flow rate,
// inlet, model), as text; ``currentAsk``: the one the page asks now.
function askOf(body) {
  const { design: _, ...ask } = body;
  return JSON.stringify(ask);
}

function currentAsk() {
  return JSON.stringify(askPart(axisGrid(gridMax(), N_POINTS)));
}

// A pinned design's answer to the page's question now; null while it answers another
// (its row and curve wait for the answer rather than read a former grid's points).
function pinnedAnswer(pin) {
  return pin.prediction && pin.ask === currentAsk() ? pin.prediction : null;
}

// The pinned designs asked the question of the answer shown (``controller``'s): a newer
// question aborts it, and an answer to an older one is never kept (it set a pinned row's
// "angle at 500 Pa" to its angle at 1500 Pa of the former 3000 Pa grid).
async function refreshPinned(grid, controller) {
  const ask = JSON.stringify(askPart(grid));  // the same question of every pinned design
  for (const pin of app.pinned) {
    if (pin.prediction && pin.ask === ask) continue;
    let prediction = null;
    try {
      prediction = await predictAnswer(predictBody(pin.state, grid), controller.signal);
    } catch (err) { if (isAbort(err)) return; }
    if (controller.signal.aborted) return;
    pin.prediction = prediction;
    pin.ask = prediction ? ask : null;
    renderCompare();
    redraw();
  }
}

function renderCompare() {
  const table = $("compare-table");
  const tbody = table.querySelector("tbody");
  tbody.innerHTML = "";
  table.hidden = app.pinned.length === 0;
  $("compare-empty").hidden = app.pinned.length > 0;
  $("pin").disabled = app.pinned.length >= MAX_PINNED || !app.prediction;
  const i = opIndex();
  for (const pin of app.pinned) {
    const tr = document.createElement("tr");
    const pr = pinnedAnswer(pin);
    const a = pr ? pr.angle_deg[i] : null;
    const force = pr && pr.force_mn ? pr.force_mn[i] : null;
    const cells = [
      `<span class="swatch" style="background:${pin.color}"></span>#${pin.n}`,
      designLabel(pin.state),
      a === null || a === undefined ? "-" : `${fmt(a, 1)} deg`,
      pr && a !== null ? `${fmt(pr.lower_deg[i], 1)} - ${fmt(pr.upper_deg[i], 1)}` : "-",
      force === null || force === undefined ? "-" : `${fmtSig(force)} mN`,
      pr ? ((pr.validity.flags || []).length ? pr.validity.flags.map(flagWords).join(", ")
        : (pr.validity.in_domain ? "in domain" : "outside the fitted domain")) : "no prediction",
    ];
    tr.innerHTML = cells.map((c) => `<td>${c}</td>`).join("") +
      `<td><button type="button" data-load="${pin.n}" aria-label="Load pinned design #${pin.n}">Load</button> ` +
      `<button type="button" data-unpin="${pin.n}" aria-label="Remove pinned design #${pin.n}">Remove</button></td>`;
    tbody.appendChild(tr);
  }
}

// ---------------------------------------------------------------- FE solve
function showRefused() {
  const box = $("refused");
  box.hidden = !app.refused;
  if (app.refused) setTextWithCode($("refused-detail"), app.refused.message);
  // the server's nearest design inside the box (an out-of-box refusal), one click away
  const near = app.refused && app.refused.problem.nearest_design ? stateOfDesign(app.refused.problem.nearest_design) : null;
  const button = $("load-nearest");
  button.hidden = !near;
  button.textContent = near ? `Load the nearest design in the box: ${designLabel(near)}` : "";
  button.onclick = near ? () => loadDesign(near) : null;
}

async function solve() {
  clearProblems($("refused"));
  const key = $("api_key").value.trim();
  if (!key) { showProblem(new Error("the server's API key is needed to queue a solve"), {}, $("err-api_key")); return; }
  sessionStorage.setItem("balloon-api-key", key);
  const level = checkNumber($("mesh_level"), { integer: true });
  if (level.error) { showMessage($("err-settings"), level.error); return; }  // the server's limit, from its schema
  const design = designBody(app.state, app.presets);
  const designKey = JSON.stringify(design);
  const body = { design, settings: { mesh_level: level.value } };
  let job;
  try {
    job = await api("/v1/solve", { method: "POST", body, key });
  } catch (err) {
    if (err instanceof ApiError && err.status === 409 && err.problem.curve_id) {
      $("job").textContent = "Already in the database: loading the stored FE curve.";
      const rec = await showStoredCurve(designKey, err.problem.curve_id);
      if (rec) $("job").textContent = `Already in the database: the stored FE curve is drawn. ${endText(rec, "It") || ""}`.trim();
      return;
    }
    const slots = { ...DESIGN_SLOTS(), settings: $("err-settings"), design: $("err-solve") };
    const target = err instanceof ApiError && (err.status === 401 || err.status === 403) ? $("err-api_key") : $("err-solve");
    showProblem(err, slots, target);
    return;
  }
  app.job = { id: job.id, key: designKey, trace: [] };
  $("cancel-solve").hidden = false;
  poll(job);
}

async function poll(job) {
  const mine = app.job;
  if (!mine || mine.id !== job.id) return;
  const pr = job.progress || {};
  if (pr.step && !mine.trace.some((s) => s.step === pr.step) && pr.angle_deg !== null) mine.trace.push({ ...pr, at_ms: Date.now() });
  $("job").textContent = jobText(job, mine.trace, null);
  // "finished" once its curve is loaded and said
  if (job.status !== "finished") $("job").dataset.status = job.status;
  redraw();
  if (job.status === "queued" || job.status === "running") {
    const again = async () => {
      try { poll(await api(`/v1/jobs/${job.id}`)); } catch (err) {
        // a service that stopped answering may come back: the job is asked again
        if (err instanceof OfflineError) { $("job").textContent = `FE solve: ${err.message}; asking again.`; setTimeout(again, app.retryMs); }
        else $("job").textContent = `Lost the job: ${err.message}`;
      }
    };
    setTimeout(again, 1000);
    return;
  }
  $("cancel-solve").hidden = true;
  if (job.status === "finished" && job.curve_id) {
    const rec = await showStoredCurve(mine.key, job.curve_id);
    $("job").textContent = jobText(job, mine.trace, rec ? curveEnd(rec.curve) : null);
    $("job").dataset.status = "finished";
    $("job").dataset.curveId = job.curve_id;
    showHealth().catch(() => {});  // the record count has grown
  } else {
    $("job").textContent = jobText(job, mine.trace, null);
  }
}

async function showStoredCurve(designKey, curveId) {
  try {
    const record = await api(`/v1/curves/${curveId}`);
    app.solved.set(designKey, record);
    app.feFamilies.clear();  // the database has a new record
    app.feDetails.set(curveId, record);
    showOperatingPoint();
    redraw();
    return record;
  } catch (err) {
    $("job").textContent = `Could not load curve ${curveId}: ${err.message}`;
    return null;
  }
}

async function cancelSolve() {
  if (!app.job) return;
  try {
    poll(await api(`/v1/jobs/${app.job.id}`, { method: "DELETE", key: $("api_key").value.trim() }));
  } catch (err) { showProblem(err, {}, $("err-solve")); }
}

// ---------------------------------------------------------------- export
function shownCurves() {
  const series = curveSeries();
  return series.map((s) => ({ id: s.id, label: s.label, x_axis: axisKeys().x, x: s.x, y_axis: axisKeys().y, y: s.y, lower: s.lower || null, upper: s.upper || null }));
}

// The model a curve of the page came from, for a CSV row: its name, file and the SHA-256
// of the file the server loaded (GET /v1/health), and the service's version. An FE curve
// is a database record (its id in the series' label); a saved calibrated model's file is
// not named by the health answer, nor the built-in paper model's (it has none).
function modelColumns(seriesId) {
  const h = app.health || {};
  if (seriesId.startsWith("fe-")) return ["FE", h.database?.name ?? "", "", h.version ?? ""];
  const name = app.prediction?.model ?? $("model").value.trim();
  const loaded = { emulator: h.emulator, exponential: h.surrogate, fitted: h.surrogate }[name];
  return [name, loaded?.file ?? "", loaded?.sha256 ?? "", h.version ?? ""];
}

function exportCsv() {
  const { x, y } = axisKeys();
  const yName = y === "force" ? "force_mn" : "angle_deg";
  const lines = [["series", x, yName, `lower_${yName}`, `upper_${yName}`, "model", "model_file", "model_sha256", "balloon_version"].join(",")];
  for (const s of shownCurves()) {
    const model = modelColumns(s.id);
    s.x.forEach((xv, i) => lines.push([s.label, xv, s.y[i], s.lower ? s.lower[i] : "", s.upper ? s.upper[i] : "", ...model].map(csvCell).join(",")));
  }
  download("balloon-curves.csv", lines.join("\n") + "\n", "text/csv");
}

function exportJson() {
  const h = app.health || {};
  const data = { exported_utc: new Date().toISOString(),
    service: { version: h.version, emulator: h.emulator, surrogate: h.surrogate },  // the model files by SHA-256
    request: app.request, prediction: app.prediction,
    pinned: app.pinned.map((p) => ({ design: designBody(p.state, app.presets), prediction: pinnedAnswer(p) })),
    fe_curves: app.nearest.map((r) => ({ id: r.id, design: r.design, curve: { pressure_pa: r.curve.pressure_pa, volume_ul: r.curve.volume_ul, angle_deg: r.curve.angle_deg, force_mn: r.curve.force_mn } })),
    shown: shownCurves() };
  download("balloon-curves.json", JSON.stringify(data, null, 1), "application/json");
}

// ---------------------------------------------------------------- start
async function start() {
  buildFields();
  const stored = sessionStorage.getItem("balloon-api-key");
  if (stored) { $("api_key").value = stored; $("save-key").value = stored; }
  $("pin").addEventListener("click", pin);
  $("reset").addEventListener("click", () => loadDesign(defaultState()));
  $("solve").addEventListener("click", solve);
  $("refused").addEventListener("submit", (ev) => { ev.preventDefault(); solve(); });
  $("cancel-solve").addEventListener("click", cancelSolve);
  $("compare-table").addEventListener("click", (ev) => {
    const load = ev.target.dataset.load, unpin = ev.target.dataset.unpin;
    if (load) loadDesign({ ...app.pinned.find((p) => String(p.n) === load).state });
    if (unpin) { app.pinned = app.pinned.filter((p) => String(p.n) !== unpin); renderCompare(); redraw(); }
  });
  $("design-form").addEventListener("submit", (ev) => ev.preventDefault());
  $("export-csv").addEventListener("click", exportCsv);
  $("export-json").addEventListener("click", exportJson);
  $("export-svg").addEventListener("click", () => download("balloon-curves.svg", svgText($("plot")), "image/svg+xml"));
  $("export-png").addEventListener("click", async () => download("balloon-curves.png", await svgToPngBlob($("plot"))));
  // the presets are needed only for a stiffness scale != 1: the first curve does not wait
  const materials = api("/v1/materials").then((list) => {
    for (const m of list.items) app.presets[m.id] = m;
    takeScaleLimits(list.stiffness_scale);   // the limits the server answers within
    showRanges();
    showValues(FIELDS.filter((f) => f.unit === "x"));
  }).catch((err) => {
    $("err-design").textContent = `Materials unavailable: ${err.message}`;
    $("err-design").hidden = false;
  });
  showHealth().catch(() => {});
  applySchemaLimits();
  setupInverse({ loadDesign, presets: app.presets });
  setupCalibration({ presets: app.presets });
  numberBoxes();
  rangeHints();   // the page's own limits until the schema's are read
  applyLink(location.hash);
  // a link pasted into this open page (the browser does not reload for a new fragment)
  window.addEventListener("hashchange", () => {
    if (location.hash === app.linkHash) return;
    applyLink(location.hash, true);
    schedule(0);
  });
  // a service that stopped answering is asked again when the tab is back in front
  window.addEventListener("focus", retry);
  window.addEventListener("online", retry);
  document.addEventListener("visibilitychange", () => { if (!document.hidden) retry(); });
  // the plot and the sketch are drawn at the width they are shown at (legible text)
  let resizeTimer = null;
  window.addEventListener("resize", () => { clearTimeout(resizeTimer); resizeTimer = setTimeout(redraw, 100); });
  // a stiffness scale != 1 needs the presets to send its inline material
  if (app.state.body_scale !== 1 || app.state.membrane_scale !== 1) await materials;
  await Promise.all([update(), materials]);
  document.body.dataset.ready = "true";
}

start();
