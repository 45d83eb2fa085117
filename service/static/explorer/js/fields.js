// Page-side checks of the numbers the page itself turns into a request (the largest value
// of the curve's grid, the flow rate, the nearest-curves count, a design field, the mesh
// level): an empty or out-of-range value is named beside its field with its allowed range
// (the input's min and max, set from the server's schema where it gives them), never
// replaced by another value.

// A number as the service reads one written as text (service/number_text.py): ASCII
// decimal digits, as 1000, 2.5 or 1e-3 (JavaScript's Number also reads "0x10" and " ").
export const NUMBER_TEXT = /^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$/;

// A box's text as a number ({value}), or why it is none in the page's words ({error}):
// text not in the service's form is "not a number"; a decimal too large for a double
// ("1e999") is out of range, with the box's allowed range. Every number box of the page
// is a text box (numberBoxes): a number box read such text as "" (badInput) and said
// "not a number", or sent the search's target as "not a number".
export function readNumber(text, allowed) {
  const shown = text.slice(0, 20);
  if (!NUMBER_TEXT.test(text)) return { error: `"${shown}" is not a number (${allowed})` };
  const v = Number(text);
  if (!Number.isFinite(v)) return { error: `${shown} is outside the allowed range (${allowed})` };
  return { value: v };
}

// A box's min and max as numbers (-Infinity and Infinity where it has none).
function boxRange(input) {
  return [input.min === "" ? -Infinity : Number(input.min),
          input.max === "" ? Infinity : Number(input.max)];
}

// "allowed: a whole number from 1 to 20 ul": the box's min and max in words, in the
// unit given or the box's own (its data-unit).
export function allowedWords(input, { integer = false, unit = input.dataset?.unit || "" } = {}) {
  const [min, max] = boxRange(input);
  const bounds = [Number.isFinite(min) ? `from ${min}` : "", Number.isFinite(max) ? `to ${max}` : ""].filter(Boolean).join(" ");
  return `allowed: ${integer ? "a whole number " : ""}${bounds}${unit ? " " + unit : ""}`.trim();
}

// {value} or {error}: `optional` takes an empty field as null, `integer` whole numbers only.
export function checkNumber(input, { integer = false, optional = false, unit = input.dataset?.unit || "" } = {}) {
  const text = String(input.value).trim();
  const [min, max] = boxRange(input);
  const allowed = allowedWords(input, { integer, unit });
  if (text === "") return optional ? { value: null } : { error: `empty (${allowed})` };
  const read = readNumber(text, allowed);
  if (read.error) return read;
  const v = read.value;
  if (integer && !Number.isInteger(v)) return { error: `${v} is not a whole number (${allowed})` };
  if (v < min || v > max) return { error: `${v} is outside the allowed range (${allowed})` };
  return { value: v };
}

// Every number box of the page (index.html's and the design fields': text boxes with
// inputmode "decimal", so that their text stays readable) stepped by the arrow keys, as
// a number box is: by its step (1 without one) from the value shown, within its min and
// max. Called once, when the page's boxes exist.
export function numberBoxes(root = document) {
  for (const input of root.querySelectorAll("input[inputmode=decimal]")) {
    input.addEventListener("keydown", (event) => {
      const dir = { ArrowUp: 1, ArrowDown: -1 }[event.key];
      const text = input.value.trim();
      if (!dir || !NUMBER_TEXT.test(text) || !Number.isFinite(Number(text))) return;
      event.preventDefault();
      const step = Number(input.step) > 0 ? Number(input.step) : 1;
      const [lo, hi] = boxRange(input);
      // to the step's digits: 0.1 + 0.2 shows 0.3
      const digits = Math.max(0, -Math.floor(Math.log10(step)) + 1);
      const next = Number((Number(text) + dir * step).toFixed(Math.min(digits + 6, 15)));
      input.value = String(Math.min(hi, Math.max(lo, next)));
      input.dispatchEvent(new Event("input"));
      input.dispatchEvent(new Event("change"));
    });
  }
}

// Each marked box's allowed range beside it before anything is typed ("from 0 to 6";
// data-hint="integer": "a whole number from 0 to 6"), from its min and max: the limits
// the page checks it against, the server's schema's where applySchemaLimits set them.
// The hint is tied to its box (aria-describedby); called again when the limits change.
// Until 2026-12-08 "Nearest FE curves" and "Mesh level" showed their range only in the
// error of a value out of it.
export function rangeHints(root = document) {
  for (const input of root.querySelectorAll("input[data-hint]")) {
    const id = `${input.id}-hint`;
    let hint = document.getElementById(id);
    if (!hint) {
      hint = document.createElement("span");
      hint.id = id;
      hint.className = "muted small hint";
      input.after(hint);
      const ids = (input.getAttribute("aria-describedby") || "").split(/\s+/).filter(Boolean);
      input.setAttribute("aria-describedby", [...ids, id].join(" "));
    }
    hint.textContent = allowedWords(input, { integer: input.dataset.hint === "integer" }).replace(/^allowed: /, "");
  }
}
