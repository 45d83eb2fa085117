// Small helpers shared by the page's modules: numbers as a person reads them, downloads.

import { NUMBER_TEXT } from "./fields.js";

export const $ = (id) => document.getElementById(id);

// A message's text into `el`, each `quoted` span (a command the server's words name, as
// `balloon solve`) shown as code rather than with its backticks; text nodes only, so
// nothing in a message is read as HTML.
export function setTextWithCode(el, text) {
  el.replaceChildren();
  String(text).split(/`([^`\n]+)`/).forEach((part, i) => {
    if (!part) return;
    if (i % 2) {
      const code = document.createElement("code");
      code.textContent = part;
      el.append(code);
    } else el.append(document.createTextNode(part));
  });
}

export function fmt(v, digits = 1) {
  return typeof v === "number" && Number.isFinite(v) ? v.toFixed(digits) : "-";
}

export function fmtSig(v, sig = 3) {
  if (typeof v !== "number" || !Number.isFinite(v)) return "-";
  if (v === 0) return "0";
  if (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e6) return v.toExponential(sig - 1);
  const d = Math.max(0, sig - 1 - Math.floor(Math.log10(Math.abs(v))));
  return v.toFixed(Math.min(d, 6));
}

export function download(name, blobOrText, type = "text/plain") {
  const blob = blobOrText instanceof Blob ? blobOrText : new Blob([blobOrText], { type });
  const url = URL.createObjectURL(blob);
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

// A number box's value, null when empty; text that is no number in the service's form
// ("0x10", which Number reads; "1e999", too large for a double) is sent as text, which
// the server refuses naming the field, never as null (a missing value, a default, a
// bound at the box's edge). The page names such text itself first (fields.js).
export function numberOrNull(input) {
  const text = String(input.value).trim();
  if (text === "") return null;
  const v = Number(text);
  // a non-number ("0x10", which Number reads) goes to the server, which names it
  return NUMBER_TEXT.test(text) && Number.isFinite(v) ? v : text;
}

// One CSV cell: quoted when it holds a comma, a quote or a line break.
export function csvCell(v) {
  if (v === null || v === undefined) return "";
  const s = String(v);
  return /[",\n]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s;
}
