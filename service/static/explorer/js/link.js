// The page's design and curve request in the address's fragment ("#W_mm=3&L_mm=7.1&..."),
// so that a view can be bookmarked, shared and reopened as it was. Pure functions: the
// fragment is text from anywhere, so only known keys with valid values are taken (numbers
// finite and > 0, the readout's point and the tubing length finite and >= 0, the pair an
// index, the axis one of three, the model a name; an empty flow rate, none; each key
// once); the others are returned as ignored, with their text, never interpreted, and
// named on the page with what each allows (``linkNote``: at most MAX_NAMED of them, their
// text cut and its hidden characters escaped).

import { FIELDS, PAIRS, W_FIELD } from "./design.js";

export const ASK_AXES = ["pressure_pa", "volume_ul", "time_s"];
export const X_AXES = [...ASK_AXES, "pump_pressure_pa"];
export const Y_AXES = ["angle", "force"];
const MAX_NEAR = 6;  // the "Nearest FE curves" field's largest count
const NUMBER_KEYS = [W_FIELD.name, ...FIELDS.map((f) => f.name)];
const MODEL = /^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$/;
export const MAX_NAMED = 8;  // ignored keys named in the note; the rest counted
const KEY_CHARS = 40;        // a key's and a value's text as the note shows it, at most
const VALUE_CHARS = 20;
// What the keys not read from a box allow, in the note's words (the boxes' own ranges,
// which depend on the page's state, come from the page: ``linkNote``'s ``boxAllowed``).
const ALLOWED = {
  pair: `allowed: a whole number from 0 to ${PAIRS.length - 1}`,
  ask: `allowed: ${ASK_AXES.join(", ")}`,
  x: `allowed: ${X_AXES.join(", ")}`,
  y: `allowed: ${Y_AXES.join(", ")}`,
  inlet: "allowed: 0 or 1",
  model: "allowed: a model's name, up to 64 letters, digits, _ . -",
};

function positive(text) {
  const v = Number(text);
  return text.trim() !== "" && Number.isFinite(v) && v > 0 ? v : null;
}

function nonNegative(text) {
  const v = Number(text);
  return text.trim() !== "" && Number.isFinite(v) && v >= 0 ? v : null;
}

// {design: {...state keys}, view: {ask, max, flow, inlet, tubing, bore, model, x, y, near, at},
//  ignored: [{key, value, why}, ...]} (why: "unknown", "repeated" or "invalid"); view.flow
// null: the link's flow rate is none ("flow=").
export function readLink(hash) {
  const out = { design: {}, view: {}, ignored: [] };
  const text = String(hash || "").replace(/^#/, "");
  if (!text) return out;
  const params = new URLSearchParams(text);
  const counts = new Map();
  for (const key of params.keys()) counts.set(key, (counts.get(key) || 0) + 1);
  const named = new Set();
  for (const [key, value] of params) {
    let ok = true;
    const times = counts.get(key);
    if (times > 1) {  // which one was meant is unknown (HTTP refuses a repeated key too)
      if (!named.has(key)) out.ignored.push({ key, value: "", why: "repeated", times });
      named.add(key);
      continue;
    }
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
      out.ignored.push({ key, value, why: "unknown" });
      continue;
    }
    if (!ok) out.ignored.push({ key, value, why: "invalid" });
  }
  return out;
}

// Text from the address as the page shows it: cut to ``n`` characters, and each control,
// bidi-override, zero-width or other invisible character written as its escape (U+202E as
// \u202e), as the service writes a user's text in its problems (solver/plain_text.py).
export function shownText(text, n) {
  const cut = [...String(text)];
  const head = cut.slice(0, n).join("");
  const escaped = head.replace(/[\p{Cc}\p{Cf}\p{Cs}\p{Zl}\p{Zp}\p{Cn}]|[^\P{Zs} ]/gu,
    (c) => `\\u${c.codePointAt(0).toString(16).padStart(4, "0")}`);
  return cut.length > n ? `${escaped}...` : escaped;
}

// The note naming the link's ignored keys, each with its text and what it allows (a
// box's range from ``boxAllowed(key)``, which returns null for a key of no box), the
// first MAX_NAMED of them, then how many more; "" when none.
export function linkNote(ignored, boxAllowed) {
  if (!ignored.length) return "";
  const named = ignored.slice(0, MAX_NAMED).map(({ key, value, why, times }) => {
    const k = shownText(key, KEY_CHARS);
    if (why === "unknown") return `${k} (not a key of a view)`;
    if (why === "repeated") return `${k} (given ${times} times: allowed once)`;
    const allowed = ALLOWED[key] || boxAllowed(key) || "allowed: a number above 0";
    return `${k}=${shownText(value, VALUE_CHARS)} (${allowed})`;
  });
  const more = ignored.length - named.length;
  return `The link's ${named.join("; ")}${more ? `; and ${more} more` : ""}: ignored, the `
    + "page's own values kept.";
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
