// Inverse design: a target (by chamber pressure: angle at a pressure, angle within a
// pressure budget, force at a pressure; by a syringe pump: angle at or within an injected
// volume, or a time at the flow rate: js/targets.js), bounds on the lengths and the allowed
// material pairs -> POST /v1/inverse -> ranked designs; "Load" puts one in the design
// panel, its curve asked on the target's axis (pressure, injected volume or time).

import { ApiError, api, clearProblems, showMessage, showProblem } from "./api.js";
import { FIELDS, PAIRS, W_FIELD, W_MM, pairLabel } from "./design.js";
import { allowedWords, checkNumber, readNumber } from "./fields.js";
import { ASK_AXIS, OBJECTIVES, TARGET_BY, TARGET_INPUTS, changeUnit, readoutAt, targetColumns, targetNotes } from "./targets.js";
import { $, fmt, fmtSig, numberOrNull } from "./util.js";

// The pump's flow rate is one value on the page: the Curve panel's "Pump flow rate"
// (#flow, which the "Ask by" switch's time axis uses) and the time targets' flow box
// (#inv-flow) show it, and typing in either changes the other. Being the page's value, it
// is checked by the page's one check (fields.js), as the Curve panel checks it: a bad
// flow rate is named in the same words beside both boxes, and no search is sent with it
// (the server's refusal was a second wording of the same error).
// Both are text boxes (index.html): a number box read "1e999" as "" and the other box
// was wiped with it; the text is now one value in both, named out of range beside both.
function shareFlowRate() {
  const page = $("flow"), form = $("inv-flow");
  form.value = page.value;
  page.addEventListener("input", () => { form.value = page.value; });
  page.addEventListener("change", () => { form.value = page.value; });
  form.addEventListener("input", () => { page.value = form.value; });
  form.addEventListener("change", () => { page.value = form.value; page.dispatchEvent(new Event("change")); });
}

// The result table's first columns, whatever the target.
const FIXED_HEADS = ["rank", "body / membrane", "stiffness scales (body, membrane)", "L (mm)", "t (mm)",
  "T (mm)", "b (mm)", "h (mm)"];

// "pdms_1_15/ecoflex_00_30 T=1 b=1.8 h=0.15" -> {T_mm: 1, b_mm: 1.8, h_mm: 0.15}
export function familyGeometry(candidate) {
  const out = {};
  for (const k of ["T", "b", "h"]) {
    if (typeof candidate[`${k}_mm`] === "number") { out[`${k}_mm`] = candidate[`${k}_mm`]; continue; }
    const m = new RegExp(`\\b${k}=([0-9.eE+-]+)`).exec(candidate.family || "");
    if (m) out[`${k}_mm`] = Number(m[1]);
  }
  return out;
}

// [lo, hi] of a range's two boxes; an empty one is the design box's edge (as its
// placeholder "box" says): the box at W = 3 mm, where the search runs.
function bounds(lo, hi, name) {
  const a = numberOrNull($(lo)), b = numberOrNull($(hi));
  if (a === null && b === null) return undefined;
  const f = FIELDS.find((x) => x.name === name);
  return [a ?? f.min, b ?? f.max];
}

// The lengths whose range the form bounds (inv-X-lo, inv-X-hi -> X_bounds_mm): every
// length of the box, so a lab with one body mould can pin T, b and h (the page offered L
// and t only: its designs came back with any T, b and h, which that mould cannot make).
const RANGED = ["L", "t", "T", "b", "h"];
// what each box reads before the server checks it (solver.design.LIMITS_MM; the search
// itself stays within the box, and a bound outside it is the server's to name)
const LENGTH_LIMITS_MM = { L: [0.5, 60], t: [0.05, 5], T: [0.1, 10], b: [0.1, 20], h: [0.02, 5] };

// A length's two range boxes, "box" (the design box's edge) when empty, and its error slot.
function rangeField(k) {
  const [min, max] = LENGTH_LIMITS_MM[k];
  const step = FIELDS.find((f) => f.name === `${k}_mm`).step;
  const box = (end, words) => `<input id="inv-${k}-${end}" type="text" inputmode="decimal" data-unit="mm" ` +
    `min="${min}" max="${max}" step="${step}" placeholder="box" aria-label="${k} ${words} (mm)">`;
  const field = document.createElement("div");
  field.className = "field";
  field.innerHTML = `<label for="inv-${k}-lo">${k} range (mm)</label>` +
    `<span class="range2">${box("lo", "from")} to ${box("hi", "to")}</span>` +
    `<p class="field-error" id="err-inv-${k}" data-for="inv-${k}-lo" hidden></p>`;
  return field;
}

// The design panel's body mould (T, b, h) as ranges pinned to it, at W = 3 mm where the
// search runs (a scaled copy's lengths scaled back by 3 mm / W).
function pinMould() {
  const W = Number($(W_FIELD.name).value);
  for (const k of ["T", "b", "h"]) {
    const v = Number($(`${k}_mm`).value) * W_MM / W;
    if (!Number.isFinite(v)) continue;
    const text = String(Math.round(v * 1e4) / 1e4);
    $(`inv-${k}-lo`).value = text;
    $(`inv-${k}-hi`).value = text;
  }
}

// The form's shown boxes hold numbers or nothing: text that is none ("0x10") or too
// large for a double ("1e999") is named beside its box with the box's range, and no
// search is sent (a number box read "1e999" as "", which was sent as "not a number" and
// refused by the server as "Input should be a valid number"). The ranges stay the
// server's to check.
function numbersReadable(form) {
  let readable = true;
  for (const box of form.querySelectorAll("input[inputmode=decimal]")) {
    const text = box.value.trim();
    if (!text || box.closest("[hidden]")) continue;
    const read = readNumber(text, allowedWords(box));
    if (!read.error) continue;
    const slot = form.querySelector(`.field-error[data-for="${box.id}"]`)
      || form.querySelector(`.field-error[data-for="${box.id.replace(/-hi$/, "-lo")}"]`);
    showMessage(slot, read.error);
    readable = false;
  }
  return readable;
}

export function setupInverse({ loadDesign }) {
  const form = $("inverse-form");
  const pairs = $("inv-pairs");
  PAIRS.forEach(([b, m], k) => {
    const id = `inv-pair-${k}`;
    const label = document.createElement("label");
    label.className = "check";
    label.innerHTML = `<input type="checkbox" id="${id}" value="${k}" checked> ${pairLabel(b, m)}`;
    pairs.appendChild(label);
  });
  for (const k of RANGED) $("inv-ranges").appendChild(rangeField(k));
  const kind = $("inv-kind");
  shareFlowRate();
  $("inv-mould").addEventListener("click", pinMould);
  const showKind = () => {
    const force = kind.value === "force_at_pressure";
    $("inv-angle-field").hidden = force;
    $("inv-force-field").hidden = !force;
    // the fields of what the target is given by: a pressure, a volume, a time and flow rate
    for (const el of form.querySelectorAll("[data-by]")) el.hidden = el.dataset.by !== TARGET_BY[kind.value];
    const budget = kind.value.endsWith("_budget");
    $("inv-volume-label").textContent = budget ? "Volume budget, at most (ul)" : "Injected volume (ul)";
    $("inv-time-label").textContent = budget ? "Time budget from empty, at most (s)" : "Time from empty (s)";
    // only the rankings the server takes for this target are offered
    const allowed = OBJECTIVES[kind.value];
    const select = $("inv-objective");
    for (const option of select.options) option.hidden = option.disabled = !!option.value && !!allowed && !allowed.includes(option.value);
    if (select.selectedOptions[0]?.disabled) select.value = "";
  };
  kind.addEventListener("change", showKind);
  showKind();
  let candidates = [];
  let searched = null;  // the target of the candidates shown: {kind, pressure_pa, ...}
  $("inv-pairs").addEventListener("change", () => { $("err-inv-pairs").hidden = true; });

  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    clearProblems(form);
    if (!numbersReadable(form)) return;
    const target = { kind: kind.value };
    for (const [id, name] of TARGET_INPUTS[TARGET_BY[kind.value]]) target[name] = numberOrNull($(id));
    if (kind.value === "force_at_pressure") target.force_mn = numberOrNull($("inv-force"));
    else target.angle_deg = numberOrNull($("inv-angle"));
    const body = { target, n_results: numberOrNull($("inv-n")) ?? 5 };
    for (const k of RANGED) {
      const range = bounds(`inv-${k}-lo`, `inv-${k}-hi`, `${k}_mm`);
      if (range) body[`${k}_bounds_mm`] = range;
    }
    if (TARGET_BY[kind.value] === "time") {
      const flow = checkNumber($("inv-flow"), { unit: "ul/s" });
      if (flow.error) {
        showMessage($("err-inv-flow"), flow.error);
        return;
      }
    }
    const chosen = [...pairs.querySelectorAll("input:checked")].map((i) => PAIRS[Number(i.value)]);
    if (!chosen.length) {
      showMessage($("err-inv-pairs"), "Material pairs: tick at least one pair to search.");
      return;
    }
    if (chosen.length < PAIRS.length) body.material_pairs = chosen.map(([b, m]) => ({ body_material: b, membrane_material: m }));
    if ($("inv-objective").value) body.objective = $("inv-objective").value;
    const slots = {
      "target.kind": $("err-inv-kind"), "target.pressure_pa": $("err-inv-pressure"),
      "target.volume_ul": $("err-inv-volume"), "target.time_s": $("err-inv-time"),
      "target.flow_ul_s": $("err-inv-flow"),
      "target.angle_deg": $("err-inv-angle"), "target.force_mn": $("err-inv-force"),
      ...Object.fromEntries(RANGED.map((k) => [`${k}_bounds_mm`, $(`err-inv-${k}`)])),
      material_pairs: $("err-inv-pairs"),
      objective: $("err-inv-objective"), n_results: $("err-inv-n"), target: $("err-inv-kind"),
    };
    $("inv-explanation").textContent = "Searching...";
    // the last search's rows are not this target's: hidden until the answer, so a row
    // clicked while searching cannot load a design listed for another target
    $("inv-table").hidden = true;
    $("inv-run").disabled = true;
    try {
      const res = await api("/v1/inverse", { method: "POST", body });
      candidates = res.candidates || [];
      searched = { ...target };
      render(res);
    } catch (err) {
      $("inv-explanation").textContent = "";
      $("inv-table").hidden = true;
      showProblem(err, slots, $("err-inverse"));
      // a ranking refused for this target: the server's list is offered from now on
      const objective = err instanceof ApiError && err.fieldErrors.find((e) => String(e.field || "").startsWith("objective") && e.allowed);
      if (objective) {
        OBJECTIVES[target.kind] = objective.allowed.split("|").map((s) => s.trim()).filter(Boolean);
        showKind();
      }
    } finally {
      $("inv-run").disabled = false;
    }
  });

  function render(res) {
    let text = res.explanation || (res.feasible ? "" : "No design meets the target.");
    const best = res.best_reachable || {};
    if (!res.feasible && typeof best.value === "number") {
      text += ` Best reachable: ${fmtSig(best.value)} at L = ${fmtSig(best.L_mm)} mm, t = ${fmtSig(best.t_mm)} mm (${best.family || ""}).`;
    }
    // the count, unless the explanation already gives it
    if (typeof res.n_evaluated === "number" && !text.includes(String(res.n_evaluated))) text += ` (${res.n_evaluated} designs evaluated)`;
    // a message every candidate carries is said once, under the explanation, not in each row
    const messagesOf = (c) => targetNotes(searched, (c.validity && c.validity.messages) || []);
    const common = candidates.length > 1
      ? messagesOf(candidates[0]).filter((m) => candidates.every((c) => messagesOf(c).includes(m)))
      : [];
    // a sentence of its own: the server's explanation may end without a full stop
    if (common.length) text += `${/[.!?]$/.test(text) ? "" : "."} Every design listed: ${common.join(" ")}`;
    $("inv-explanation").textContent = text;
    // the target kind's columns (a column no listed design has a number for left out)
    const columns = targetColumns(searched).filter((col) => candidates.some((c) => typeof c[col.key] === "number"));
    const head = $("inv-table").querySelector("thead tr");
    head.innerHTML = "";
    for (const text of [...FIXED_HEADS, ...columns.map((col) => col.head), "notes", ""]) {
      const th = document.createElement("th");
      th.scope = "col";
      th.textContent = text;
      head.appendChild(th);
    }
    const tbody = $("inv-table").querySelector("tbody");
    tbody.innerHTML = "";
    $("inv-table").hidden = candidates.length === 0;
    candidates.forEach((c, k) => {
      const tr = document.createElement("tr");
      // what a mould's tolerance does: the length whose 0.01 mm moves the value most
      const tol = Object.entries(c.change_per_0_01_mm || {}).sort((a, b) => Math.abs(b[1]) - Math.abs(a[1]))[0];
      const tolNote = tol ? `0.01 mm more ${tol[0].replace(/_mm$/, "")}: ${tol[1] >= 0 ? "+" : ""}${fmtSig(tol[1], 2)} ${changeUnit(searched.kind)}.` : "";
      const notes = [tolNote, ...messagesOf(c).filter((m) => !common.includes(m))].filter(Boolean).join(" ");
      const geometry = familyGeometry(c);
      const scale = (s) => (typeof s === "number" ? `x${fmtSig(s)}` : "x1");
      const cells = [c.rank, pairLabel(c.body_material, c.membrane_material),
        `${scale(c.body_stiffness_scale)}, ${scale(c.membrane_stiffness_scale)}`,
        fmt(c.L_mm, 2), fmt(c.t_mm, 3),
        ...["T_mm", "b_mm", "h_mm"].map((k) => (typeof geometry[k] === "number" ? fmt(geometry[k], 3) : "")),
        ...columns.map((col) => col.cell(c)), notes || (c.validity?.in_domain === false ? "outside the fitted domain" : "")];
      tr.innerHTML = cells.map(() => "<td></td>").join("") + `<td><button type="button" data-candidate="${k}">Load</button></td>`;
      tr.querySelector("button").setAttribute("aria-label", `Load rank ${c.rank}: L ${fmt(c.L_mm, 2)} mm, t ${fmt(c.t_mm, 3)} mm, ${pairLabel(c.body_material, c.membrane_material)}`);
      cells.forEach((v, i) => { tr.children[i].textContent = String(v); });
      tbody.appendChild(tr);
    });
  }

  $("inv-table").addEventListener("click", (ev) => {
    const k = ev.target.dataset.candidate;
    if (k === undefined) return;
    const c = candidates[Number(k)];
    const pair = PAIRS.findIndex(([b, m]) => b === c.body_material && m === c.membrane_material);
    // the candidate's whole design: L, t, T, b, h (to 0.1 um) and each layer's stiffness scale
    const round = (v) => Math.round(v * 1e4) / 1e4;
    const geometry = Object.fromEntries(Object.entries(familyGeometry(c)).map(([k, v]) => [k, round(v)]));
    // the design search's box is at W = 3 mm (loadDesign's width when none is given)
    const values = { L_mm: round(c.L_mm), t_mm: round(c.t_mm), ...geometry,
      body_scale: c.body_stiffness_scale ?? 1, membrane_scale: c.membrane_stiffness_scale ?? 1 };
    if (pair >= 0) values.pair = pair;
    // the curve on the target's axis: by pressure, by injected volume, or by time at the
    // flow rate searched (the page's flow rate set to it)
    const by = TARGET_BY[searched.kind];
    if (by === "time" && Number($("flow").value) !== searched.flow_ul_s) {
      $("flow").value = String(searched.flow_ul_s);
      $("flow").dispatchEvent(new Event("input"));
    }
    if ($("ask_axis").value !== ASK_AXIS[by]) {
      $("ask_axis").value = ASK_AXIS[by];
      $("ask_axis").dispatchEvent(new Event("change"));
    }
    // the readout at the target's pressure, volume or time (a budget's: what the design
    // needs), the curve's range grown to show it
    const at = readoutAt(searched, c);
    loadDesign(values, { at: typeof at === "number" ? at : undefined });
    $("explore").scrollIntoView({ behavior: "instant", block: "start" });
  });
}
