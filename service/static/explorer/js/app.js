// The design explorer: design panel -> POST /v1/predict -> curve, band, validity,
// nearest FE curves (GET /v1/curves), readout at one point and sketch; pinned designs;
// the curve asked by chamber pressure, by injected volume, or by time at the pump's flow
// rate (the request's pressures_pa, volumes_ul or times_s with flow_ul_s);
// the FE solve of a refused design (POST /v1/solve, GET /v1/jobs/{id}); exports.
// The inverse form and the measured-data report live in inverse.js and calibration.js.

import { api, ApiError, clearProblems, isAbort, showProblem } from "./api.js";
import { setupCalibration } from "./calibration.js";
import {
  FIELDS, PAIRS, W_FIELD, W_MM, axisGrid, defaultState, designBody, designLabel, fieldRange, materialId,
  materialLabel, pairLabel, scaledLengths,
} from "./design.js";
import { setupInverse } from "./inverse.js";
import { readLink, writeLink } from "./link.js";
import { COLORS, renderPlot, svgText, svgToPngBlob } from "./plot.js";
import { renderSketch } from "./sketch.js";
import { $, csvCell, download, fmt, fmtSig } from "./util.js";

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
};

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
  solved: new Map(),    // design key -> FE record from a finished solve
  job: null,            // {id, key, trace: [{pressure_pa, angle_deg, volume_ul}]}
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
      <input type="range" id="${f.name}-range" min="${f.min}" max="${f.max}" step="${f.step}"
        value="${f.value}" aria-label="${f.label} slider" tabindex="-1">
      <input type="number" id="${f.name}" name="${f.name}" min="${f.min}" max="${f.max}" step="${f.step}"
        value="${f.value}" required aria-describedby="${f.name}-range-text">
    </div>
    <span class="muted small" id="${f.name}-range-text">${rangeText(f, f)}</span>
    <p class="field-error" id="err-${f.name}" data-for="${f.name}" hidden></p>`;
  box.appendChild(div);
  const range = div.querySelector(`#${f.name}-range`);
  const num = div.querySelector(`#${f.name}`);
  range.tabIndex = 0;
  range.addEventListener("input", () => { num.value = range.value; onValue(Number(range.value)); });
  num.addEventListener("input", () => {
    const v = Number(num.value);
    if (num.value.trim() === "" || !Number.isFinite(v)) return;
    range.value = String(v);
    onValue(v);
  });
}

function rangeText(f, r) {
  return `${r.min} - ${r.max}${f.unit === "x" ? " x preset moduli" : " " + f.unit}`;
}

// The lengths' ranges at the design's width (the box scaled by W / 3 mm), on both inputs.
function showRanges() {
  for (const f of FIELDS) {
    const r = fieldRange(f, app.state.W_mm);
    for (const id of [f.name, `${f.name}-range`]) { $(id).min = String(r.min); $(id).max = String(r.max); }
    $(`${f.name}-range-text`).textContent = rangeText(f, r);
  }
}

// The state's values on the inputs of ``fields`` (all of them and the pair by default).
function showValues(fields = [W_FIELD, ...FIELDS]) {
  for (const f of fields) {
    $(f.name).value = String(app.state[f.name]);
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
  for (const id of ["p_max", "v_max", "t_max", "flow", "inlet", "model", "nearby"]) $(id).addEventListener("change", () => schedule(0));
  $("ask_axis").addEventListener("change", onAskAxis);
  for (const id of ["x_axis", "y_axis"]) $(id).addEventListener("change", redraw);
  $("p_op").addEventListener("input", () => { showOperatingPoint(); redraw(); });
}

function onInput(name, value) {
  app.state[name] = value;
  app.inputMark = performance.now();
  schedule(DEBOUNCE_MS);
}

// A new width scales every length with it (a scaled copy bends alike at the same pressure)
// and the lengths' ranges with them; the user then changes any length within its range.
function onWidth(W) {
  if (!(W > 0)) return;
  Object.assign(app.state, scaledLengths(app.state, W));
  showRanges();
  showValues(FIELDS);  // not W's own input, which the user is typing in
  app.inputMark = performance.now();
  schedule(DEBOUNCE_MS);
}

// ``values``: any of the state's keys; a design without a width is at W = 3 mm (the
// design search's box, the stored records).
export function loadDesign(values) {
  Object.assign(app.state, { W_mm: W_MM }, values);
  showRanges();
  showValues();
  app.inputMark = performance.now();
  schedule(0);
}

function schedule(delay) {
  clearTimeout(app.timer);
  app.timer = setTimeout(update, delay);
}

function askAxis() {
  return $("ask_axis").value;
}

// The largest value of the asked axis (the grid runs from 0 to it).
function gridMax() {
  const a = ASK[askAxis()];
  const v = Number($(a.input).value);
  return Number.isFinite(v) && v > 0 ? v : a.fallback;
}

function flowRate() {
  const text = $("flow").value.trim();
  return text === "" ? null : Number(text);
}

// The request without its design: the asked axis, the flow rate, the inlet, the model.
function askPart(grid) {
  const body = { [ASK[askAxis()].field]: grid, model: $("model").value.trim() || "emulator", level: LEVEL };
  const q = flowRate();
  if (q !== null) body.flow_ul_s = q;
  if ($("inlet").checked) body.inlet = {};
  return body;
}

function predictBody(state, grid) {
  return { design: designBody(state, app.presets), ...askPart(grid) };
}

function onAskAxis() {
  showAskAxis();
  $("p_op").value = String(gridMax() / 2);
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
  $("curve-h").textContent = `${a.label[0].toUpperCase()}${a.label.slice(1)} - angle curve`;
}

// ---------------------------------------------------------------- the view's link
// The address's fragment holds the design and the curve request (link.js): each answer
// rewrites it, a page opened with one starts from it.
function view() {
  return { ask: askAxis(), max: gridMax(), flow: flowRate() ?? undefined, inlet: $("inlet").checked,
           model: $("model").value.trim() || "emulator" };
}

function applyLink(hash) {
  const link = readLink(hash);
  Object.assign(app.state, link.design);
  showRanges();
  showValues();
  const v = link.view;
  if (v.ask) $("ask_axis").value = v.ask;
  if (v.max) $(ASK[askAxis()].input).value = String(v.max);
  if (v.flow) $("flow").value = String(v.flow);
  if (v.inlet !== undefined) $("inlet").checked = v.inlet;
  if (v.model) $("model").value = v.model;
  showAskAxis();
  $("p_op").value = String(gridMax() / 2);
  const note = $("link-note");
  note.hidden = link.ignored.length === 0;
  note.textContent = link.ignored.length ? `The link's ${link.ignored.join(", ")} ignored (unknown or not a valid value).` : "";
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
  slots.model = $("err-model");
  return slots;
};

async function update() {
  if (app.controller) app.controller.abort();  // a stale request is cancelled
  const controller = new AbortController();
  app.controller = controller;
  const grid = axisGrid(gridMax(), N_POINTS);  // 0 .. the largest value, on any axis
  const p = $("p_op");
  p.max = String(gridMax());
  p.step = String(gridMax() / (N_POINTS - 1));
  const mark = app.inputMark;
  let body = null;
  try {
    body = predictBody(app.state, grid);  // throws while a scaled layer's preset is unknown
    const prediction = await api("/v1/predict", { method: "POST", body, signal: controller.signal });
    if (controller.signal.aborted) return;
    clearProblems($("design-form"));
    app.prediction = prediction;
    app.request = body;
    app.refused = null;
    $("status").textContent = `${prediction.model} model${prediction.form ? ", " + prediction.form + " form" : ""}`;
  } catch (err) {
    if (isAbort(err) || controller.signal.aborted) return;
    clearProblems($("design-form"));
    app.prediction = null;
    app.request = body;
    app.refused = (await offersSolve(err, body)) ? err : null;
    if (controller.signal.aborted) return;
    // a refusal of the design as a whole is shown once, in the FE solve box (not again
    // beside the field it names)
    showProblem(err, app.refused ? {} : DESIGN_SLOTS(), app.refused ? null : $("err-design"));
    $("status").textContent = app.refused ? "No prediction: the model refuses this design (below)."
      : `No prediction: ${err instanceof ApiError ? `${err.problem.title || "error"} (${err.status})` : String(err)}`;
  }
  history.replaceState(null, "", writeLink(app.state, view()));
  refreshPinned(grid);
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
  loadNearest(controller);
}

// A design the predictor refuses can still be solved by FE: a 422 whose errors all name
// the design (its family, the model's box: the emulator's "out-of-box" names the field), for a design the API's own schema accepts
// (DesignIn's limits in /openapi.json, which POST /v1/solve checks too). A value outside
// those limits is not offered a solve that would be refused the same way.
let designLimits = null;

async function schemaLimits() {
  if (!designLimits) {
    try {
      const spec = await api("/openapi.json");
      const props = spec.components.schemas.DesignIn.properties;
      designLimits = Object.fromEntries(Object.entries(props).map(([k, v]) => [k, [v.minimum ?? -Infinity, v.maximum ?? Infinity]]));
    } catch { designLimits = {}; }
  }
  return designLimits;
}

async function offersSolve(err, body) {
  if (!(err instanceof ApiError) || err.status !== 422 || !body) return false;
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
  const same = items.filter((r) => Math.abs(r.h_mm - q.h_mm) < 1e-6 && r.status !== "failed");
  app.feFamilies.set(key, same);
  return same;
}

async function loadNearest(controller) {
  const count = Math.max(0, Math.min(6, Number($("nearby").value) || 0));
  const state = { ...app.state };
  try {
    const rows = count ? await familySummaries(familyQuery(state), controller.signal) : [];
    // nearest in (L, t), the same scales as the server's plot (10 mm, 0.5 mm)
    const ranked = rows.map((r) => [Math.hypot((r.L_mm - reduced(state, "L_mm")) / 10, (r.t_mm - reduced(state, "t_mm")) / 0.5), r])
      .sort((a, b) => a[0] - b[0]).slice(0, count).map(([, r]) => r);
    const records = [];
    for (const r of ranked) {
      if (!app.feDetails.has(r.id)) app.feDetails.set(r.id, await api(`/v1/curves/${r.id}`, { signal: controller.signal }));
      records.push(app.feDetails.get(r.id));
    }
    if (controller !== app.controller) return;
    app.nearest = records;
  } catch (err) {
    if (isAbort(err)) return;
    app.nearest = [];
    $("status").textContent += ` (FE curves unavailable: ${err.message})`;
  }
  redraw();
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
  return data[x] && data[x].some((v) => v !== null) ? data[x] : null;
}

function curveSeries() {
  const { y } = axisKeys();
  const keys = y === "force" ? ["force_mn", "force_lower_mn", "force_upper_mn"] : ["angle_deg", "lower_deg", "upper_deg"];
  const out = [];
  const add = (id, label, data, color, extra = {}) => {
    const x = xOf(data);
    if (!x || !data[keys[0]]) return;
    out.push({ id, label, color, x, y: data[keys[0]], lower: data[keys[1]], upper: data[keys[2]], ...extra });
  };
  // the records scaled to the design's width (kw = W / 3 mm): volume x kw^3, force x kw^2
  const kw = widthScale(app.state);
  app.nearest.forEach((rec, k) => {
    const d = rec.design;
    const c = rec.curve;
    const volume = c.volume_ul ? c.volume_ul.map((v) => v * kw ** 3) : c.volume_ul;
    const force = c.force_mn ? c.force_mn.map((f) => (f === null ? f : f * kw ** 2)) : c.force_mn;
    // an FE record's clock at the page's flow rate: its own injected volume over the flow
    const q = flowRate();
    const time = q > 0 && volume ? volume.map((v) => v / q) : (c.time_s && c.time_s.map((t) => t * kw ** 3));
    const along = { pressure_pa: c.pressure_pa, volume_ul: volume, time_s: time }[askAxis()] || c.pressure_pa;
    const keep = along.map((x) => x <= gridMax() * 1.05);
    const cut = (a) => (a ? a.filter((_, i) => keep[i]) : a);
    const data = { pressure_pa: cut(c.pressure_pa), volume_ul: cut(volume), time_s: cut(time),
      angle_deg: cut(c.angle_deg), force_mn: cut(force) };
    // labelled with its materials: the pooled PDMS group holds PDMS 1:10 and 1:15 records
    const pair = `${materialLabel(d.body_material, app.presets)} / ${materialLabel(d.membrane_material, app.presets)}`;
    const size = kw === 1 ? `L=${fmtSig(d.L_mm)} t=${fmtSig(d.t_mm)} mm` : `L=${fmtSig(d.L_mm)} t=${fmtSig(d.t_mm)} mm at W = 3 mm, scaled x${fmtSig(kw)}`;
    add(`fe-${rec.id}`, `FE ${pair}, ${size}`, data, ["#6b7280", "#9ca3af", "#4b5563", "#a3a3a3", "#737373", "#525252"][k], { dash: "5 4", width: 1.4 });
  });
  // pinned curves without their bands (the table gives the band at the chosen pressure)
  app.pinned.forEach((pin) => { if (pin.prediction) add(`pin-${pin.n}`, `#${pin.n} ${designLabel(pin.state)}`, pin.prediction, pin.color, { width: 1.6, lower: null, upper: null }); });
  const key = designKey(app.state);
  const solved = app.solved.get(key);
  if (solved) add("fe-solve", `FE solve ${solved.id.slice(0, 8)}`, solved.curve, "#111827", { width: 2, markers: true });
  if (app.job && app.job.key === key && app.job.trace.length) {
    const t = app.job.trace;
    add("fe-progress", "FE solve, converged steps", { pressure_pa: t.map((s) => s.pressure_pa), volume_ul: t.map((s) => s.volume_ul),
      angle_deg: t.map((s) => s.angle_deg) }, "#111827", { markersOnly: true });
  }
  if (app.prediction) add("prediction", `model (${Math.round(100 * app.prediction.level)} % band)`, app.prediction, COLORS[0], { width: 2.4 });
  return out;
}

export function redraw() {
  const { x, y } = axisKeys();
  const xLabel = { pressure_pa: "pressure (Pa)", volume_ul: "injected volume (ul)", time_s: "time (s)" }[x];
  const yLabel = y === "force" ? "tip force (mN)" : "bending angle (deg)";
  const series = curveSeries();
  let cursor = null;
  const i = opIndex();
  if (app.prediction && i !== null) cursor = (xOf(app.prediction) || [])[i];
  renderPlot($("plot"), series, {
    xLabel, yLabel, cursorX: cursor,
    xRange: x === askAxis() ? [0, gridMax()] : undefined, legend: "below",
    note: app.prediction ? "" : (app.refused ? "the model refuses this design" : ""),
  });
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
  if (!pred) { out.textContent = `${fmt(p, ask.digits)} ${ask.unit}: no prediction`; return; }
  const a = pred.angle_deg[i];
  const at = axis === "pressure_pa" ? pred.pressure_pa[i] : (pred[axis] || [])[i];
  let text = `${fmt(at, ask.digits)} ${ask.unit}: angle ${a === null ? "not predicted (past the FE range)" : fmt(a, 1) + " deg"}`;
  if (a !== null) text += ` [${fmt(pred.lower_deg[i], 1)}, ${fmt(pred.upper_deg[i], 1)}] (${Math.round(pred.level * 100)} %)`;
  if (pred.force_mn && pred.force_mn[i] !== null && pred.force_mn[i] !== undefined) {
    text += `; force ${fmt(pred.force_mn[i], 2)} mN`;
    if (pred.force_lower_mn && pred.force_upper_mn) text += ` [${fmt(pred.force_lower_mn[i], 2)}, ${fmt(pred.force_upper_mn[i], 2)}]`;
  }
  const has = (k) => Array.isArray(pred[k]) && pred[k][i] !== null && pred[k][i] !== undefined;
  if (axis !== "pressure_pa" && has("pressure_pa")) text += `; chamber pressure ${fmt(pred.pressure_pa[i], 0)} Pa`;
  if (has("pump_pressure_pa")) text += `; pump gauge ${fmt(pred.pump_pressure_pa[i], 0)} Pa`;
  if (axis !== "volume_ul" && has("volume_ul")) text += `; volume ${fmt(pred.volume_ul[i], 2)} ul`;
  if (axis !== "time_s" && has("time_s")) text += `; time ${fmt(pred.time_s[i], 1)} s`;
  out.textContent = text;
  $("compare-p-h").textContent = `angle at ${fmt(p, ask.digits)} ${ask.unit}`;
  renderCompare();
}

function drawSketch() {
  const pred = app.prediction;
  const i = opIndex();
  const design = pred ? pred.design : { ...app.state };
  const angle = pred ? pred.angle_deg[i] : null;
  renderSketch($("sketch"), design, angle === null ? NaN : angle, angle === null ? 0 : i / (N_POINTS - 1));
}

function showValidity() {
  const box = $("validity");
  box.innerHTML = "";
  const pred = app.prediction;
  if (!pred) return;
  const v = pred.validity || {};
  const head = document.createElement("p");
  head.className = v.in_domain ? "ok" : "warn";
  head.textContent = v.in_domain ? "Inside the model's fitted domain." : "Outside the model's fitted domain:";
  box.appendChild(head);
  const flags = document.createElement("p");
  for (const f of v.flags || []) {
    const chip = document.createElement("span");
    chip.className = "chip";
    chip.dataset.flag = f;
    chip.textContent = FLAG_WORDS[f] || f.replaceAll("_", " ");
    flags.appendChild(chip);
  }
  if (flags.childNodes.length) box.appendChild(flags);
  const ul = document.createElement("ul");
  const messages = [...(v.messages || [])];
  const firstNull = pred.angle_deg.findIndex((a) => a === null);
  const asked = app.request ? app.request[ASK[askAxis()].field] : null;
  if (firstNull > 0 && asked) messages.push(`No angle is given from ${fmt(asked[firstNull], ASK[askAxis()].digits)} ${ASK[askAxis()].unit} on: past the FE's range the answer is capped there.`);
  for (const m of messages) {
    const li = document.createElement("li");
    li.textContent = m;
    ul.appendChild(li);
  }
  if (messages.length) box.appendChild(ul);
  const hasForce = Array.isArray(pred.force_mn) && pred.force_mn.some((f) => f !== null);
  $("y_axis").querySelector('option[value="force"]').disabled = !hasForce;
  for (const k of ["volume_ul", "time_s"]) {
    $("x_axis").querySelector(`option[value="${k}"]`).disabled = !(Array.isArray(pred[k]) && pred[k].some((x) => x !== null));
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
  app.pinned.push({ n, state: { ...app.state }, prediction: app.prediction, color: COLORS[n], ask: JSON.stringify(askPart(axisGrid(gridMax(), N_POINTS))) });
  renderCompare();
  redraw();
}

async function refreshPinned(grid) {
  const ask = JSON.stringify(askPart(grid));  // the same question of every pinned design
  for (const pin of app.pinned) {
    if (pin.prediction && pin.ask === ask) continue;
    try {
      pin.prediction = await api("/v1/predict", { method: "POST", body: predictBody(pin.state, grid) });
      pin.ask = ask;
    } catch { pin.prediction = null; }
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
  $("pin").disabled = app.pinned.length >= MAX_PINNED;
  const i = opIndex();
  for (const pin of app.pinned) {
    const tr = document.createElement("tr");
    const pr = pin.prediction;
    const a = pr ? pr.angle_deg[i] : null;
    const force = pr && pr.force_mn ? pr.force_mn[i] : null;
    const cells = [
      `<span class="swatch" style="background:${pin.color}"></span>#${pin.n}`,
      designLabel(pin.state),
      a === null || a === undefined ? "-" : `${fmt(a, 1)} deg`,
      pr && a !== null ? `${fmt(pr.lower_deg[i], 1)} - ${fmt(pr.upper_deg[i], 1)}` : "-",
      force === null || force === undefined ? "-" : `${fmt(force, 2)} mN`,
      pr ? (pr.validity.in_domain ? "in domain" : (pr.validity.flags || []).map((f) => FLAG_WORDS[f] || f).join(", ")) : "no prediction",
    ];
    tr.innerHTML = cells.map((c) => `<td>${c}</td>`).join("") +
      `<td><button type="button" data-load="${pin.n}">Load</button> <button type="button" data-unpin="${pin.n}">Remove</button></td>`;
    tbody.appendChild(tr);
  }
}

// ---------------------------------------------------------------- FE solve
function showRefused() {
  const box = $("refused");
  box.hidden = !app.refused;
  if (app.refused) $("refused-detail").textContent = app.refused.message;
}

async function solve() {
  clearProblems($("refused"));
  const key = $("api_key").value.trim();
  if (!key) { showProblem(new Error("the server's API key is needed to queue a solve"), {}, $("err-api_key")); return; }
  sessionStorage.setItem("balloon-api-key", key);
  const design = designBody(app.state, app.presets);
  const designKey = JSON.stringify(design);
  const body = { design, settings: { mesh_level: Number($("mesh_level").value) || 0 } };
  let job;
  try {
    job = await api("/v1/solve", { method: "POST", body, key });
  } catch (err) {
    if (err instanceof ApiError && err.status === 409 && err.problem.curve_id) {
      $("job").textContent = "Already in the database: loading the stored FE curve.";
      await showStoredCurve(designKey, err.problem.curve_id);
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
  if (pr.step && !mine.trace.some((s) => s.step === pr.step) && pr.angle_deg !== null) mine.trace.push({ ...pr });
  $("job").textContent = `FE solve ${job.status}` + (pr.step ? `: step ${pr.step}, ${fmt(pr.pressure_pa, 0)} Pa, ${fmt(pr.volume_ul, 3)} ul, ${fmt(pr.angle_deg, 1)} deg` +
    (pr.newton_iterations ? ` (${pr.newton_iterations} Newton iterations)` : "") : "");
  $("job").dataset.status = job.status;
  redraw();
  if (job.status === "queued" || job.status === "running") {
    setTimeout(async () => {
      try { poll(await api(`/v1/jobs/${job.id}`)); } catch (err) { $("job").textContent = `Lost the job: ${err.message}`; }
    }, 1000);
    return;
  }
  $("cancel-solve").hidden = true;
  if (job.status === "finished" && job.curve_id) {
    await showStoredCurve(mine.key, job.curve_id);
    $("job").textContent = `FE solve finished: curve ${job.curve_id} (${job.curve_status}${job.curve_reason ? ": " + job.curve_reason : ""}), stored in the database.`;
    $("job").dataset.status = "finished";
  } else {
    $("job").textContent = `FE solve ${job.status}${job.error ? ": " + job.error : ""}`;
  }
}

async function showStoredCurve(designKey, curveId) {
  try {
    const record = await api(`/v1/curves/${curveId}`);
    app.solved.set(designKey, record);
    app.feFamilies.clear();  // the database has a new record
    redraw();
  } catch (err) {
    $("job").textContent = `Could not load curve ${curveId}: ${err.message}`;
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

function exportCsv() {
  const { x, y } = axisKeys();
  const yName = y === "force" ? "force_mn" : "angle_deg";
  const lines = [["series", x, yName, `lower_${yName}`, `upper_${yName}`].join(",")];
  for (const s of shownCurves()) {
    s.x.forEach((xv, i) => lines.push([s.label, xv, s.y[i], s.lower ? s.lower[i] : "", s.upper ? s.upper[i] : ""].map(csvCell).join(",")));
  }
  download("balloon-curves.csv", lines.join("\n") + "\n", "text/csv");
}

function exportJson() {
  const data = { exported_utc: new Date().toISOString(), request: app.request, prediction: app.prediction,
    pinned: app.pinned.map((p) => ({ design: designBody(p.state, app.presets), prediction: p.prediction })),
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
  }).catch((err) => {
    $("err-design").textContent = `Materials unavailable: ${err.message}`;
    $("err-design").hidden = false;
  });
  api("/v1/health").then((h) => {
    $("health").textContent = `service ${h.version}; ${h.database.records ?? 0} FE records; surrogate ${h.surrogate.loaded ? h.surrogate.name : "not loaded"}`;
  }).catch(() => { $("health").textContent = "service health unknown"; });
  setupInverse({ loadDesign, presets: app.presets });
  setupCalibration({ presets: app.presets });
  applyLink(location.hash);
  // a stiffness scale != 1 needs the presets to send its inline material
  if (app.state.body_scale !== 1 || app.state.membrane_scale !== 1) await materials;
  await Promise.all([update(), materials]);
  document.body.dataset.ready = "true";
}

start();
