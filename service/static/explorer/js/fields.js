// Page-side checks of the numbers the page itself turns into a request (the largest value
// of the curve's grid, the flow rate, the nearest-curves count, a design field, the mesh
// level): an empty or out-of-range value is named beside its field with its allowed range
// (the input's min and max, set from the server's schema where it gives them), never
// replaced by another value.

// A number as the service reads one written as text (service/number_text.py): ASCII
// decimal digits, as 1000, 2.5 or 1e-3 (JavaScript's Number also reads "0x10" and " ").
export const NUMBER_TEXT = /^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$/;

// {value} or {error}: `optional` takes an empty field as null, `integer` whole numbers only.
// A decimal too large for a double ("1e999") is out of range, not "not a number": a text
// box (the flow rate's) keeps its text, where a number box only says badInput.
export function checkNumber(input, { integer = false, optional = false, unit = "" } = {}) {
  const text = String(input.value).trim();
  const min = input.min === "" ? -Infinity : Number(input.min);
  const max = input.max === "" ? Infinity : Number(input.max);
  const bounds = [Number.isFinite(min) ? `from ${min}` : "", Number.isFinite(max) ? `to ${max}` : ""].filter(Boolean).join(" ");
  const allowed = `allowed: ${integer ? "a whole number " : ""}${bounds}${unit ? " " + unit : ""}`.trim();
  if (text === "") {
    // a number box holding text that is no number reads as empty (validity.badInput)
    if (input.validity && input.validity.badInput) return { error: `not a number (${allowed})` };
    return optional ? { value: null } : { error: `empty (${allowed})` };
  }
  const v = Number(text);
  if (!NUMBER_TEXT.test(text)) return { error: `"${text.slice(0, 20)}" is not a number (${allowed})` };
  if (!Number.isFinite(v)) return { error: `${text.slice(0, 20)} is outside the allowed range (${allowed})` };
  if (integer && !Number.isInteger(v)) return { error: `${v} is not a whole number (${allowed})` };
  if (v < min || v > max) return { error: `${v} is outside the allowed range (${allowed})` };
  return { value: v };
}

// A text box holding a number (the flow rate's: a number box reads "1e999" as empty, and
// copied that emptiness into the box sharing its value) stepped by the arrow keys, as a
// number box is: by 1 from the value shown, within the box's min and max.
export function stepByArrows(input) {
  input.addEventListener("keydown", (event) => {
    const dir = { ArrowUp: 1, ArrowDown: -1 }[event.key];
    const text = input.value.trim();
    if (!dir || !NUMBER_TEXT.test(text) || !Number.isFinite(Number(text))) return;
    event.preventDefault();
    const lo = input.min === "" ? -Infinity : Number(input.min);
    const hi = input.max === "" ? Infinity : Number(input.max);
    input.value = String(Math.min(hi, Math.max(lo, Number(text) + dir)));
    input.dispatchEvent(new Event("input"));
    input.dispatchEvent(new Event("change"));
  });
}
