// The page's design and curve request in the address's fragment ("#W_mm=3&L_mm=7.1&..."),
// so that a view can be bookmarked, shared and reopened as it was. Pure functions: the
// fragment is text from anywhere, so only known keys with valid values are taken (numbers
// finite and > 0, the readout's point and the tubing length finite and >= 0, the pair an
// index, the axis one of three, the model a name; an empty flow rate, none); the others
// are returned as ignored, never interpreted.

import { FIELDS, PAIRS, W_FIELD } from "./design.js";

export const ASK_AXES = ["pressure_pa", "volume_ul", "time_s"];
export const X_AXES = [...ASK_AXES, "pump_pressure_pa"];
export const Y_AXES = ["angle", "force"];
const MAX_NEAR = 6;  // the "Nearest FE curves" field's largest count
const NUMBER_KEYS = [W_FIELD.name, ...FIELDS.map((f) => f.name)];
const MODEL = /^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$/;

function positive(text) {
  const v = Number(text);
  return text.trim() !== "" && Number.isFinite(v) && v > 0 ? v : null;
}

function nonNegative(text) {
  const v = Number(text);
  return text.trim() !== "" && Number.isFinite(v) && v >= 0 ? v : null;
}

// {design: {...state keys}, view: {ask, max, flow, inlet, tubing, bore, model, x, y, near, at},
//  ignored: ["key", ...]}; view.flow null: the link's flow rate is none ("flow=").
export function readLink(hash) {
  const out = { design: {}, view: {}, ignored: [] };
  const text = String(hash || "").replace(/^#/, "");
  if (!text) return out;
  let params;
  try { params = new URLSearchParams(text); } catch { out.ignored.push("the whole fragment"); return out; }
  for (const [key, value] of params) {
    let ok = true;
    if (NUMBER_KEYS.includes(key)) {
      const v = positive(value);
      if (v === null) ok = false; else out.design[key] = v;
    } else if (key === "pair") {
      const k = Number(value);
      if (Number.isInteger(k) && k >= 0 && k < PAIRS.length && value.trim() !== "") out.design.pair = k; else ok = false;
    } else if (key === "ask") {
      if (ASK_AXES.includes(value)) out.view.ask = value; else ok = false;
    } else if (key === "flow" && value.trim() === "") {
      out.view.flow = null;
    } else if (key === "max" || key === "flow") {
      const v = positive(value);
      if (v === null) ok = false; else out.view[key] = v;
    } else if (key === "at" || key === "tubing") {
      const v = nonNegative(value);
      if (v === null) ok = false; else out.view[key] = v;
    } else if (key === "bore") {
      const v = positive(value);
      if (v === null) ok = false; else out.view.bore = v;
    } else if (key === "inlet") {
      if (value === "1" || value === "0") out.view.inlet = value === "1"; else ok = false;
    } else if (key === "model") {
      if (MODEL.test(value)) out.view.model = value; else ok = false;
    } else if (key === "x" || key === "y") {
      if ((key === "x" ? X_AXES : Y_AXES).includes(value)) out.view[key] = value; else ok = false;
    } else if (key === "near") {
      const k = Number(value);
      if (value.trim() !== "" && Number.isInteger(k) && k >= 0 && k <= MAX_NEAR) out.view.near = k; else ok = false;
    } else {
      ok = false;
    }
    if (!ok) out.ignored.push(key.slice(0, 40));
  }
  return out;
}

// The fragment of a state (design keys) and view ({ask, max, flow, inlet, tubing, bore
// (the inlet's tubing length and bore, mm), model, x, y, near, at: the readout's point on
// the asked axis;
// flow null: none, written "flow=" so that the link does not reopen at the page's default).
export function writeLink(state, view) {
  const params = new URLSearchParams();
  for (const key of NUMBER_KEYS) if (Number.isFinite(state[key])) params.set(key, String(state[key]));
  params.set("pair", String(state.pair));
  params.set("ask", view.ask);
  if (Number.isFinite(view.max)) params.set("max", String(view.max));
  if (Number.isFinite(view.flow)) params.set("flow", String(view.flow));
  else if (view.flow === null) params.set("flow", "");
  if (Number.isFinite(view.at)) params.set("at", String(view.at));
  if (view.inlet) params.set("inlet", "1");
  if (view.inlet && view.tubing > 0 && Number.isFinite(view.bore)) {
    params.set("tubing", String(view.tubing));
    params.set("bore", String(view.bore));
  }
  if (view.model) params.set("model", view.model);
  if (view.x && view.x !== view.ask) params.set("x", view.x);
  if (view.y && view.y !== "angle") params.set("y", view.y);
  if (Number.isInteger(view.near)) params.set("near", String(view.near));
  return `#${params}`;
}
