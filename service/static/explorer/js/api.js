// The only door to the server: JSON over the documented /v1 API.
// Every error answer is an RFC 9457 problem document (application/problem+json);
// ApiError keeps it whole so that the page can show each message beside its field.

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

export async function api(path, { method = "GET", body, key, signal } = {}) {
  const headers = { Accept: "application/json, application/problem+json" };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  if (key) headers["X-API-Key"] = key;
  const response = await fetch(path, {
    method, headers, signal,
    body: body === undefined ? undefined : JSON.stringify(body),
  });
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

// Show a problem beside the fields it names. `slots` maps a field path to the element
// that shows its message; an error goes to the longest matching path, else to `fallback`.
export function showProblem(err, slots, fallback) {
  const messages = new Map();
  const put = (el, text) => { messages.set(el, [...(messages.get(el) || []), text]); };
  const errors = err instanceof ApiError ? err.fieldErrors : [];
  for (const e of errors) {
    const path = fieldPath(e);
    let best = null;
    for (const name of Object.keys(slots)) {
      if ((path === name || path.startsWith(name + ".")) && (!best || name.length > best.length)) best = name;
    }
    const text = e.allowed ? `${e.message} (allowed: ${e.allowed})` : e.message;
    put(best ? slots[best] : fallback, best ? text : `${path}: ${text}`);
  }
  if (!errors.length) put(fallback, err.message || String(err));
  for (const [el, texts] of messages) {
    if (!el) continue;
    el.textContent = texts.join(" ");
    el.hidden = false;
    const input = el.dataset.for && document.getElementById(el.dataset.for);
    if (input) input.setAttribute("aria-invalid", "true");
  }
}

export function clearProblems(root) {
  for (const el of root.querySelectorAll(".field-error, .form-error")) {
    el.textContent = "";
    el.hidden = true;
  }
  for (const el of root.querySelectorAll("[aria-invalid]")) el.removeAttribute("aria-invalid");
}
