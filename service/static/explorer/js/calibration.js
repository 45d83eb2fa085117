// Measured data -> POST /v1/calibrate -> the report as a person reads it: the
// interpretation, the errors before and after, the selected effects with their values,
// every candidate, the data with the model as it was and (once saved, or when the report
// carries them) as augmented, the residuals; download the report; save the model (key).
//
// The report format may grow (docs/calibration.md): every field is read defensively and
// a missing one is left out, never invented.

import { ApiError, api, clearProblems, showMessage, showProblem } from "./api.js";
import { asRead, decodeMeasured, parseMeasured } from "./csv.js";
import { checkNumber } from "./fields.js";
import { COLORS, renderPlot } from "./plot.js";
import { $, download, fmt, fmtSig } from "./util.js";

const DESIGN_KEYS = ["L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "body_material", "membrane_material"];

function designOf(row) {
  const d = {};
  for (const k of DESIGN_KEYS) if (row[k] !== undefined) d[k] = row[k];
  return d;
}

function groupByDesign(rows) {
  const groups = new Map();
  for (const r of rows) {
    const key = JSON.stringify(designOf(r));
    if (!groups.has(key)) groups.set(key, { design: designOf(r), rows: [] });
    groups.get(key).rows.push(r);
  }
  return [...groups.values()];
}

// Per-observation model values the report may carry (a later report format): an array of
// objects with pressure_pa and a field whose name says "after" (and perhaps "before").
function reportPoints(report) {
  for (const key of ["observations", "residuals", "points", "predictions"]) {
    const v = report[key];
    if (Array.isArray(v) && v.length && typeof v[0] === "object" && "pressure_pa" in v[0]) {
      const after = Object.keys(v[0]).find((k) => /after/.test(k) && /deg/.test(k));
      const before = Object.keys(v[0]).find((k) => /before|model/.test(k) && /deg/.test(k));
      if (after) return { items: v, after, before };
    }
  }
  return null;
}

// The model's angles at the given pressures; a measured pressure below 0 Pa (a gauge
// reading at rest) has no model value: null, and it is not sent.
async function modelValues(model, group, pressures) {
  const keep = pressures.map((p, i) => [p, i]).filter(([p]) => Number.isFinite(p) && p >= 0);
  const out = pressures.map(() => null);
  if (!keep.length) return out;
  const res = await api("/v1/predict", { method: "POST", body: { design: group.design, pressures_pa: keep.map(([p]) => p), model } });
  keep.forEach(([, i], k) => { out[i] = res.angle_deg[k]; });
  return out;
}

function effectLines(report) {
  const fitted = (report.fitted && report.fitted.effects) || {};
  const lines = [];
  for (const name of report.selected_effects || []) {
    const params = Object.entries(fitted).filter(([, p]) => p && p.effect === name);
    const cand = (report.candidates || []).find((c) => c.effect === name);
    const list = params.length ? params : Object.entries((cand && cand.params) || {});
    const text = list.map(([pname, p]) => {
      if (typeof p !== "object" || p === null) return `${pname} = ${fmtSig(p)}`;
      const range = Array.isArray(p.plausible_range) ? ` (plausible ${p.plausible_range.map((x) => fmtSig(x)).join(" to ")})` : "";
      return `${pname} = ${fmtSig(p.value)}${typeof p.sd === "number" ? " +/- " + fmtSig(p.sd, 2) : ""} ${p.unit || ""}${range}`;
    }).join("; ");
    lines.push(`${name.replaceAll("_", " ")}: ${text || "(no parameters reported)"}`);
  }
  return lines;
}

function paramText(params) {
  return Object.entries(params || {}).map(([k, p]) => (p && typeof p === "object"
    ? `${k} = ${fmtSig(p.value)}${typeof p.sd === "number" ? " +/- " + fmtSig(p.sd, 2) : ""} ${p.unit || ""}`.trim()
    : `${k} = ${fmtSig(p)}`)).join("; ");
}

function effectNames(effects) {
  return (effects || []).map((e) => String(e).replaceAll("_", " ")).join(" + ") || "nothing";
}

// What else the data allow: explanations they cannot tell from the selection
// (`indistinguishable`), a better fit the baseline cannot back (`unbacked_better`), and with
// nothing selected the closest rejected set (`closest_rejected`). Read defensively.
export function alternativeLines(report) {
  const out = [];
  for (const a of report.indistinguishable || []) {
    const measure = (Array.isArray(a.measure) ? a.measure : [a.measure]).filter(Boolean).join("; ");
    if (a.exact) {  // the same readings by the physics (a gauge gain, a uniformly stiffer batch)
      out.push({ warn: true, text: `The same readings exactly: ${effectNames(a.effects)} (${paramText(a.params)})`
        + `${a.why ? ": " + a.why : ""}. No reading of bend or gauge tells them apart`
        + `${measure ? "; to tell them apart: " + measure : ""}.` });
      continue;
    }
    out.push({ warn: true, text: `Equally consistent with the data: ${effectNames(a.effects)} (${paramText(a.params)}; `
      + `CV error ${fmt(a.rmse_cv_deg, 2)} deg, paired z ${fmt(a.paired_z, 2)}${a.backed === false ? ", not backed by the baseline" : ""}). `
      + `The selection is the lowest BIC, not evidence against it${measure ? "; to tell them apart: " + measure : ""}.` });
  }
  const u = report.unbacked_better;
  if (u && typeof u === "object") {
    out.push({ warn: true, text: `Fits better but cannot be backed by the baseline: ${effectNames(u.effects)} (${paramText(u.params)}); an FE solve of the fitted design would decide.` });
  }
  const c = report.closest_rejected;
  if (c && typeof c === "object") {
    const why = Array.isArray(c.why_not) ? c.why_not.join("; ") : (c.why_not || "");
    out.push({ warn: false, text: `Closest catalogued explanation, rejected: ${effectNames(c.effects)} (${paramText(c.params)}; CV error ${fmt(c.rmse_cv_deg, 2)} deg)${why ? ": " + why : ""}.` });
  }
  return out;
}

// "rows" + "1.angle_deg" -> "angle_deg" (the column first, as docs/measured-data.md's
// messages read; the message names the row); "angle_deg" -> "angle_deg".
export function rowWords(rest, error) {
  const parts = rest.split(".");
  const column = parts.filter((p) => !/^\d+$/.test(p)).join(".");
  const index = parts.find((p) => /^\d+$/.test(p));
  const row = index !== undefined && !/\brow \d+/.test(String(error.message || "")) ? `row ${Number(index) + 1}` : "";
  return [column && `column ${column}`, row].filter(Boolean).join(", ");
}

// Starting models whose calibrations the server cannot save: learned from a refused save,
// with the server's words; kept for the session.
const UNSAVEABLE_KEY = "balloon-unsaveable-models";
function unsaveable() {
  try { return JSON.parse(sessionStorage.getItem(UNSAVEABLE_KEY) || "{}"); } catch { return {}; }
}
function noteUnsaveable(model, why) {
  const known = unsaveable();
  known[model] = why;
  sessionStorage.setItem(UNSAVEABLE_KEY, JSON.stringify(known));
}

export function setupCalibration() {
  const form = $("cal-form");
  let rows = null, report = null, lastBody = null;

  // before calibrating: a starting model known not to give a saveable calibration is said
  const showSaveability = () => {
    const model = $("cal-model").value.trim() || "emulator";
    const why = unsaveable()[model];
    const note = $("cal-save-note");
    note.hidden = !why;
    note.textContent = why ? `A calibration against "${model}" cannot be saved as a model (the server says: ${why}). ` +
      "Its report is still shown; to save the augmented model, choose another starting model." : "";
    // the report shown: its Save is greyed out, saying why, when it cannot be saved (the
    // report says so itself; older servers' refusals were learned per starting model)
    const said = report && report.saveable && report.saveable.ok === false ? report.saveable.why : null;
    const shownWhy = lastBody ? (said || unsaveable()[lastBody.model]) : null;
    $("save-run").disabled = !!shownWhy;
    $("save-note").hidden = !shownWhy;
    $("save-note").textContent = shownWhy ? `This calibration against "${lastBody.model}" cannot be saved: ${shownWhy}.` : "";
  };
  $("cal-model").addEventListener("input", showSaveability);
  showSaveability();

  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    clearProblems(form);
    const file = $("cal-file").files[0];
    if (!file) { showProblem(new Error("choose a CSV or JSON file of measured rows"), {}, $("err-cal-rows")); return; }
    try {
      rows = parseMeasured(file.name, decodeMeasured(new Uint8Array(await file.arrayBuffer())));
    } catch (err) {
      showProblem(new Error(`${file.name}: ${err.message}`), {}, $("err-cal-rows"));
      return;
    }
    // the report of an earlier file is not left on screen as if it were this one's
    $("cal-report").hidden = true;
    report = null;
    lastBody = null;
    // the folds' box as every number box: "abc" or "1e999" named beside it, never read as 5
    const folds = checkNumber($("cal-folds"), { integer: true, optional: true });
    if (folds.error) { showMessage($("err-cal-folds"), folds.error); return; }
    const body = { rows, model: $("cal-model").value.trim() || "emulator", folds: folds.value ?? 5 };
    if (await run(body, form, { rows: $("err-cal-rows"), model: $("err-cal-model"), folds: $("err-cal-folds") }, $("err-calibrate"))) lastBody = body;
    showSaveability();
  });

  $("save-form").addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const sf = $("save-form");
    clearProblems(sf);
    if (!lastBody) return;
    const key = $("save-key").value.trim();
    const missing = [];
    if (!$("save-name").value.trim()) missing.push([$("err-save"), "give the new model a name"]);
    if (!key) missing.push([$("err-save-key"), "saving a model needs the server's API key"]);
    if (missing.length) { for (const [el, text] of missing) showProblem(new Error(text), {}, el); return; }
    sessionStorage.setItem("balloon-api-key", key);
    await run({ ...lastBody, save: $("save-name").value.trim() }, sf, { save: $("err-save"), rows: $("err-save-form") },
      $("err-save-form"), key);
  });

  $("cal-download").addEventListener("click", () => {
    if (report) download("calibration-report.json", JSON.stringify(report, null, 1), "application/json");
  });

  // true when the server answered with a report
  async function run(body, root, slots, fallback, key) {
    $("cal-status").textContent = `Calibrating ${body.rows.length} rows...`;
    $("cal-run").disabled = true;
    try {
      report = await api("/v1/calibrate", { method: "POST", body, key });
      $("cal-status").textContent = report.saved_model ? `Saved the augmented model as "${report.saved_model}": use it as the model in the design panel.` : "";
      if (report.saved_model) $("model-list").appendChild(new Option(report.saved_model, report.saved_model));
      showSaveability();
      await render(report, body);
      return true;
    } catch (err) {
      $("cal-status").textContent = "";
      const target = err.status === 401 || err.status === 403 ? ($("err-save-key"))
        : (err instanceof ApiError && err.status === 404 ? $("err-cal-model") : fallback);  // an unknown starting model
      showProblem(err, slots, target, { rest: rowWords });
      const refusal = err instanceof ApiError && err.fieldErrors.find((e) => e.field === "save" && /cannot be saved/.test(e.message || ""));
      if (refusal) { noteUnsaveable(body.model, refusal.message); showSaveability(); }
      return false;
    } finally {
      $("cal-run").disabled = false;
    }
  }

  async function render(rep, body) {
    $("cal-report").hidden = false;
    $("cal-interpretation").textContent = rep.interpretation || "";
    const errors = $("cal-errors").querySelector("tbody");
    errors.innerHTML = "";
    // by curve, or by specimen when the data have runs (docs/measured-data.md, "Runs")
    const by = /specimen/.test((rep.cross_validation && rep.cross_validation.method) || "") ? "by specimen" : "by curve";
    const rowsOut = [
      ["starting model as is", rep.rmse_model_deg],
      [(rep.baseline?.open_parameters || []).length
        ? `recalibrated constants, cross-validated ${by}`
        : `starting model, cross-validated ${by} (nothing to recalibrate)`, rep.rmse_before_deg],
      [`with the selected effects, cross-validated ${by}`, rep.rmse_after_deg],
      [`noise floor${rep.noise_floor_source ? " (" + rep.noise_floor_source + ")" : ""}`, rep.noise_floor_deg],
    ];
    for (const [label, v] of rowsOut) {
      if (v === undefined) continue;
      const tr = document.createElement("tr");
      tr.innerHTML = "<th scope=\"row\"></th><td></td>";
      tr.children[0].textContent = label;
      tr.children[1].textContent = v === null ? "not available" : fmt(v, 2);
      errors.appendChild(tr);
    }
    const eff = $("cal-effects");
    eff.innerHTML = "";
    const lines = effectLines(rep);
    if (!lines.length) lines.push("none: no catalogued effect explains the data better than the recalibrated model");
    for (const line of lines) { const li = document.createElement("li"); li.textContent = line; eff.appendChild(li); }
    for (const line of alternativeLines(rep)) {
      const li = document.createElement("li");
      li.className = line.warn ? "warn" : "";
      li.textContent = line.text;
      eff.appendChild(li);
    }
    if (rep.residual_structured_after) {
      const li = document.createElement("li");
      li.className = "warn";
      li.textContent = "Structure remains in the residuals after the selected effects: an effect outside the catalogue acts.";
      eff.appendChild(li);
    }
    const cand = $("cal-candidates").querySelector("tbody");
    cand.innerHTML = "";
    for (const c of rep.candidates || []) {
      const tr = document.createElement("tr");
      const params = Object.entries(c.params || {}).map(([k, p]) => (p && typeof p === "object" ? `${k} = ${fmtSig(p.value)} ${p.unit || ""}` : `${k} = ${fmtSig(p)}`)).join("; ");
      const cells = [c.effect, fmt(c.rmse_cv_deg, 2), fmt(c.delta_bic, 1), params, c.selectable === undefined ? "" : (c.selectable ? "yes" : "no"),
        Array.isArray(c.why_not) ? c.why_not.join("; ") : (c.why_not || "")];
      tr.innerHTML = cells.map(() => "<td></td>").join("");
      cells.forEach((v, i) => { tr.children[i].textContent = String(v); });
      cand.appendChild(tr);
    }
    await plots(rep, body);
  }

  async function plots(rep, body) {
    const groups = groupByDesign(asRead(body.rows, rep.data && rep.data.columns_read));
    const start = (rep.model && rep.model.name) || body.model;
    const after = rep.saved_model || null;
    const points = reportPoints(rep);
    const data = [], resid = [];
    const notes = [];
    for (const [k, g] of groups.entries()) {
      const color = COLORS[k % COLORS.length];
      const label = `L=${fmtSig(g.design.L_mm)} t=${fmtSig(g.design.t_mm)} mm`;
      data.push({ id: `data-${k}`, label: `measured ${label}`, color, x: g.rows.map((r) => r.pressure_pa), y: g.rows.map((r) => r.angle_deg), markersOnly: true });
      const pMax = Math.max(...g.rows.map((r) => r.pressure_pa).filter(Number.isFinite));
      const grid = Array.from({ length: 41 }, (_, i) => (pMax * i) / 40);
      const measuredP = g.rows.map((r) => r.pressure_pa);
      try {
        data.push({ id: `before-${k}`, label: k === 0 ? `model "${start}" as is (dashed, colour of its design)` : "", color, x: grid, y: await modelValues(start, g, grid), dash: "5 4", width: 1.4 });
        const atData = await modelValues(start, g, measuredP);
        resid.push({ id: `rb-${k}`, label: k === 0 ? `model "${start}" as is (colour: design as above)` : "", color, x: measuredP, y: g.rows.map((r, i) => (atData[i] === null ? null : r.angle_deg - atData[i])), markersOnly: true });
      } catch (err) { notes.push(`model "${start}" for ${label}: ${err.message}`); }
      if (after) {
        try {
          data.push({ id: `after-${k}`, label: k === 0 ? `augmented "${after}" from /v1/predict (solid)` : "", color, x: grid, y: await modelValues(after, g, grid), width: 2 });
          const atData = await modelValues(after, g, measuredP);
          resid.push({ id: `ra-${k}`, label: k === 0 ? `augmented "${after}"` : "", color: "#111827", x: measuredP, y: g.rows.map((r, i) => (atData[i] === null ? null : r.angle_deg - atData[i])), markersOnly: true });
        } catch (err) { notes.push(`augmented model for ${label}: ${err.message}`); }
      }
    }
    if (points && !after) {
      // the report's own fit at each reading (its flow rate and time); by injected volume
      // at the gauge pressure the fit gives there (once saved, the saved model's curves
      // stand for it)
      data.push({ id: "fit-report", label: "with the selected effects (the report's fit at each reading)", color: "#111827",
        x: points.items.map((p) => (typeof p.pressure_after_pa === "number" ? p.pressure_after_pa : p.pressure_pa)),
        y: points.items.map((p) => (typeof p[points.after] === "number" ? p[points.after] : null)), markersOnly: true });
      resid.push({ id: "ra-report", label: "with the selected effects (report)", color: "#111827", x: points.items.map((p) => p.pressure_pa),
        y: points.items.map((p) => (typeof p.angle_deg === "number" && typeof p[points.after] === "number" ? p.angle_deg - p[points.after] : null)), markersOnly: true });
    }
    renderPlot($("cal-plot"), data, { xLabel: "pressure (Pa)", yLabel: "bending angle (deg)", height: 360, legend: "below" });
    renderPlot($("cal-resid"), resid, { xLabel: "pressure (Pa)", yLabel: "measured - model (deg)", height: 260, legend: "below" });
    const cannotSave = unsaveable()[body.model];
    const msg = after
      ? `The augmented curves come from /v1/predict with model "${after}": quasi-static, at the calibration's median flow rate, so they differ from the report's own fit (${fmt(rep.rmse_after_deg, 2)} deg, each curve at its own flow rate and time) where flow rates or creep matter.`
      : (points || cannotSave ? "" : "The augmented model's curves are drawn once it is saved (below).");
    $("cal-status").textContent = [$("cal-status").textContent, msg, ...notes].filter(Boolean).join(" ");
  }
}
