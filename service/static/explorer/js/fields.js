// Page-side checks of the numbers the page itself turns into a request (the largest value
// of the curve's grid, the flow rate, the nearest-curves count, a design field, the mesh
// level): an empty or out-of-range value is named beside its field with its allowed range
// (the input's min and max, set from the server's schema where it gives them), never
// replaced by another value.

// {value} or {error}: `optional` takes an empty field as null, `integer` whole numbers only.
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
  if (!Number.isFinite(v)) return { error: `"${text.slice(0, 20)}" is not a number (${allowed})` };
  if (integer && !Number.isInteger(v)) return { error: `${v} is not a whole number (${allowed})` };
  if (v < min || v > max) return { error: `${v} is outside the allowed range (${allowed})` };
  return { value: v };
}
