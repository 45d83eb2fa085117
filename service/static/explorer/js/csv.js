// Measured data files (docs/measured-data.md) -> the rows of POST /v1/calibrate.
// CSV: a header line, '#' lines are comments, an empty cell means "absent". Cells of
// the text columns stay text; the others become numbers when they read as one and are
// otherwise sent as written, so that the server's check names the row and the column.
// The dialect is the server's (surrogate/calibration/_csv_dialect.py): ',' between
// fields, or ';' or tabs with ',' as the decimal mark when the numbers have one (a
// German Excel's CSV), or ',' with quoted decimal commas ("8,60") where no number has a
// '.' and some comma cannot be a thousands separator; rows of separators only are blank;
// a column without a name in the header is dropped when empty (a trailing separator),
// else named by its place; a line of text after the last reading is refused by its line;
// a first line 'sep=;' (Excel's hint) names the separator.

const TEXT_COLUMNS = new Set(["curve_id", "body_material", "membrane_material"]);

function splitLine(line, sep) {
  const out = [];
  let cur = "", quoted = false;
  for (let i = 0; i < line.length; i++) {
    const c = line[i];
    if (quoted) {
      if (c === '"' && line[i + 1] === '"') { cur += '"'; i++; }
      else if (c === '"') quoted = false;
      else cur += c;
    } else if (c === '"') quoted = true;
    else if (c === sep) { out.push(cur); cur = ""; }
    else cur += c;
  }
  out.push(cur);
  return out.map((s) => s.trim());
}

function separatorOf(header) {
  if (header.includes(",")) return ",";
  if (header.includes(";")) return ";";
  return header.includes("\t") ? "\t" : ",";
}

// a number with one comma that no thousands separator writes: not three digits after
// it, or a whole part of 0 ("8,60", "0,030"; not "1,500")
function onlyDecimal(cell) {
  const m = /^[+-]?([0-9]+),([0-9]+)$/.exec(cell);
  return m !== null && (m[2].length !== 3 || Number(m[1]) === 0);
}

function isNumberText(cell) {
  return cell !== "" && Number.isFinite(Number(cell));
}

export function parseCsv(text) {
  const numbered = text.replace(/^\uFEFF/, "").split(/\r\n|\r|\n/)
    .map((l, k) => [k + 1, l])
    .filter(([, l]) => l.replace(/[\s,;]/g, "") !== "" && !l.trimStart().startsWith("#"));
  const lines = numbered.map(([, l]) => l);
  if (!lines.length) throw new Error("the file is empty");
  // Excel's 'sep=;' (',', a tab) above the header names the separator, as the server
  // reads it (_csv_dialect.named_separator)
  const named = /^"?sep=(.?)"?[,;\t]*$/i.exec(lines[0]);
  if (named && !",;\t".includes(named[1] || "x")) {
    throw new Error(`the first line '${lines[0].slice(0, 40)}' names '${named[1]}' as the ` +
      "field separator (allowed: sep=, sep=; or sep= and a tab, or no sep= line)");
  }
  if (named) { lines.shift(); numbered.shift(); }   // the header's line numbers as before
  if (!lines.length) throw new Error("the file holds only its 'sep=' line");
  const sep = named ? named[1] : separatorOf(lines[0]);
  const header = splitLine(lines[0], sep).map((name, k) => name || `column ${k + 1}`);
  const cells = lines.slice(1).map((line) => splitLine(line, sep));
  // a logger's text after the last reading: its first cell text, the others empty
  let last = cells.length;
  const textOnly = (r) => r[0] !== "" && !isNumberText(r[0]) && r.slice(1).every((c) => c === "");
  while (last && textOnly(cells[last - 1])) last--;
  if (last < cells.length) {
    const first = cells[last][0];
    const shown = first.length <= 60 ? first : `${first.slice(0, 57)}...`;
    throw new Error(`line ${numbered[last + 1][0]} holds text after the last reading `
      + `('${shown}'), which is not a reading: start it with '#' (a comment), or delete it`);
  }
  // with ';' or tabs, ',' is the decimal mark when any number has one; a cell that
  // also has a '.' goes as written, and the server names its row and column; with ','
  // only where no number has a '.' and some comma cannot be a thousands separator
  const numeric = cells.flatMap((r) => r.filter((c, k) => !TEXT_COLUMNS.has(header[k])));
  const commas = numeric.filter((c) => c.includes(","));
  const decimalComma = commas.length > 0 && (sep !== "," || (
    !numeric.some((c) => c.includes(".")) && commas.some(onlyDecimal)));
  return cells.map((line) => {
    const row = {};
    header.forEach((name, k) => {
      let cell = line[k] ?? "";
      if (cell === "") return;
      if (TEXT_COLUMNS.has(name)) { row[name] = cell; return; }
      if (decimalComma && cell.includes(".")) { row[name] = cell; return; }
      if (decimalComma) cell = cell.replace(",", ".");
      const v = Number(cell);
      row[name] = Number.isFinite(v) ? v : cell;
    });
    return row;
  });
}

// A data file's bytes as text, as the server reads them (surrogate/calibration/_data.py
// decode_text, solver/byte_order_mark.py): UTF-8, or UTF-16 with a byte-order mark (Excel's
// "Unicode Text", tab-separated); anything else is refused, never read with its bytes
// replaced (file.text() made a latin-1 "90°" into "90\uFFFD" and UTF-16 into NULs).
const BOMS = [[[0xEF, 0xBB, 0xBF], "utf-8"], [[0xFF, 0xFE], "utf-16le"], [[0xFE, 0xFF], "utf-16be"]];

export function decodeMeasured(bytes) {
  const [, encoding] = BOMS.find(([bom]) => bom.every((b, i) => bytes[i] === b)) ?? [null, "utf-8"];
  try {
    return new TextDecoder(encoding, { fatal: true }).decode(bytes);   // drops the mark
  } catch {
    const lossy = new TextDecoder(encoding).decode(bytes);    // where the first bad byte is
    const line = lossy.slice(0, lossy.indexOf("\uFFFD")).split("\n").length;
    throw new Error(`line ${line}: not ${encoding === "utf-8" ? "UTF-8" : encoding} text` +
      (encoding === "utf-8" ? " (latin-1 or Windows-1252 from a spreadsheet?)" : "") +
      " (allowed: UTF-8 text, or UTF-16 with a byte-order mark: save the file as CSV UTF-8)");
  }
}

export function parseMeasured(name, text) {
  if (/\.json$/i.test(name) || text.trimStart().startsWith("[") || text.trimStart().startsWith("{")) {
    const data = JSON.parse(text);
    return Array.isArray(data) ? data : data.rows;
  }
  return parseCsv(text);
}

// The rows as the server read them: the report's data.columns_read says which header was
// read as which column and by what factor ("Pressure (kPa)" as pressure_pa x 1000:
// surrogate/calibration/_headers.py), so the page draws what was calibrated, in Pa and
// degrees, from the server's own reading rather than one of its own.
export function asRead(rows, readings) {
  if (!Array.isArray(readings) || !readings.length) return rows;
  const by = new Map(readings.map((r) => [r.header, r]));
  return rows.map((row) => {
    const out = {};
    for (const [k, v] of Object.entries(row)) {
      const r = by.get(k);
      if (!r) out[k] = v;
      else out[r.column] = typeof v === "number" ? v * r.factor : v;
    }
    return out;
  });
}
