// The only door to the server: JSON over the documented /v1 API.
// Every error answer is an RFC 9457 problem document (application/problem+json);
// ApiError keeps it whole so that the page can show each message beside its field.

import { setTextWithCode } from "./util.js";

export class ApiError extends Error {
  constructor(status, problem) {
    super(problem.detail || problem.title || `HTTP ${status}`);
    this.status = status;
    this.problem = problem;
    // [{loc: [...], field: "design.t_mm", message, allowed}], possibly empty
    this.fieldErrors = Array.isArray(problem.errors) ? problem.errors : [];
  }
  get kind() {  // "out-of-family", "invalid-input", ... (the type's last part)
    return String(this.problem.type || "").split(":").pop();
  }
}

// No answer at all (the server stopped, the network down): fetch's TypeError, said plainly.
export class OfflineError extends Error {
  constructor() {
    super("the service is not answering (is it running?)");
    this.name = "OfflineError";
  }
}

export async function api(path, { method = "GET", body, key, signal } = {}) {
  const headers = { Accept: "application/json, application/problem+json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  if (key) headers["X-API-Key"] = key;
  let response;
  try {
    response = await fetch(path, {
      method, headers, signal,
      body: body === undefined ? undefined : JSON.stringify(body),
    });
  } catch (err) {
    if (isAbort(err)) throw err;
    throw new OfflineError();
  }
  const text = await response.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch { data = { detail: text.slice(0, 300) }; }
  if (!response.ok) throw new ApiError(response.status, data || {});
  return data;
}

export function isAbort(err) {
  return err && err.name === "AbortError";
}

// A field path of a problem error without its request part: ["body", "design", "t_mm"]
// -> "design.t_mm"; list indices stay ("rows.3.t_mm").
export function fieldPath(error) {
  if (Array.isArray(error.loc) && error.loc.length) {
    const loc = ["body", "query", "path"].includes(error.loc[0]) ? error.loc.slice(1) : error.loc;
    return loc.join(".");
  }
  return String(error.field || "");
}

// The page's name of the field an error slot stands beside: its input's label
// ("Largest pressure (Pa)"), or the slot's data-label.
function slotLabel(el) {
  if (el.dataset.label) return el.dataset.label;
  const input = el.dataset.for && document.getElementById(el.dataset.for);
  const label = input && input.labels && input.labels[0];
  return label ? label.textContent.trim() : "";
}

// Show a problem beside the fields it names. `slots` maps a field path to the element
// that shows its message; an error goes to the longest matching path, else to `fallback`.
// The same message for several items of one list (each grid point over a limit) is said
// once, named by the page's field. `options.rest(rest, error)`: the words for the part of
// the path below the slot ("rows" + "1.angle_deg" -> "angle_deg"), by default none.
// `options.words(text)`: the message in the page's words (a request field the server's
// words name, "allowed: pressures_pa", as the page's control that sets it), by default as
// the server wrote it. `options.slot(path, error)`: the slot's path where the error's own
// field is not the one to show it beside (a model refusing the asked axis: "Ask by").
export function showProblem(err, slots, fallback, options = {}) {
  const messages = new Map();
  const put = (el, text) => {
    const list = messages.get(el) || [];
    if (!list.includes(text)) list.push(text);
    messages.set(el, list);
  };
  const errors = err instanceof ApiError ? err.fieldErrors : [];
  const named = slotNames(slots);
  const pageWords = (text) => named(options.words ? options.words(text) : text);
  for (const e of errors) {
    const path = (options.slot && options.slot(fieldPath(e), e)) || fieldPath(e);
    let best = null;
    for (const name of Object.keys(slots)) {
      if ((path === name || path.startsWith(name + ".")) && (!best || name.length > best.length)) best = name;
    }
    let text = pageWords(e.allowed ? `${e.message} (allowed: ${e.allowed})` : e.message);
    if (best && path !== best && options.rest) {
      const words = options.rest(path.slice(best.length + 1), e);
      if (words) text = `${words}: ${text}`;
    }
    put(best ? slots[best] : fallback, best ? text : `${path}: ${text}`);
  }
  if (!errors.length) put(fallback, err.message || String(err));
  for (const [el, texts] of messages) {
    if (!el) continue;
    showMessage(el, texts.join(" "));
  }
}

// A message with each request field of ``slots`` it names (a path's last part written
// as the API writes it, with an underscore: "volume_ul", "flow_ul_s") as the label of the
// page's control that sets it: "allowed: 0 < volume_ul <= 500" beside "Injected volume
// (ul)" reads "allowed: 0 < Injected volume (ul) <= 500".
function slotNames(slots) {
  const names = Object.entries(slots).map(([path, el]) => [path.split(".").pop(), el ? slotLabel(el) : ""])
    .filter(([name, label]) => label && name.includes("_"));
  return (text) => names.reduce((t, [name, label]) =>
    t.replace(new RegExp(`(?<![\\w.])${name}(?!\\w|\\.\\d)`, "g"), label), text);
}

// One message in an error slot, named by its field when the slot has one, announced
// (role alert) and tied to its input (aria-invalid, aria-describedby).
export function showMessage(el, text) {
  const label = el.classList.contains("field-error") ? slotLabel(el) : "";
  setTextWithCode(el, label && !text.startsWith(label) ? `${label}: ${text}` : text);
  el.hidden = false;
  el.setAttribute("role", "alert");
  const input = el.dataset.for && document.getElementById(el.dataset.for);
  if (input) {
    input.setAttribute("aria-invalid", "true");
    const ids = (input.getAttribute("aria-describedby") || "").split(/\s+/).filter(Boolean);
    if (!ids.includes(el.id)) input.setAttribute("aria-describedby", [...ids, el.id].join(" "));
  }
}

export function clearMessage(el) {
  el.textContent = "";
  el.hidden = true;
  const input = el.dataset.for && document.getElementById(el.dataset.for);
  if (input) {
    input.removeAttribute("aria-invalid");
    const ids = (input.getAttribute("aria-describedby") || "").split(/\s+/).filter((id) => id && id !== el.id);
    if (ids.length) input.setAttribute("aria-describedby", ids.join(" ")); else input.removeAttribute("aria-describedby");
  }
}

export function clearProblems(root) {
  for (const el of root.querySelectorAll(".field-error, .form-error")) clearMessage(el);
  for (const el of root.querySelectorAll("[aria-invalid]")) el.removeAttribute("aria-invalid");
}
