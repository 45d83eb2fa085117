// Measured data files (docs/measured-data.md) -> the rows of POST /v1/calibrate.
// CSV: a header line, '#' lines are comments, an empty cell means "absent". Cells of
// the text columns stay text; the others become numbers when they read as one and are
// otherwise sent as written, so that the server's check names the row and the column.

const TEXT_COLUMNS = new Set(["curve_id", "body_material", "membrane_material"]);

function splitLine(line) {
  const out = [];
  let cur = "", quoted = false;
  for (let i = 0; i < line.length; i++) {
    const c = line[i];
    if (quoted) {
      if (c === '"' && line[i + 1] === '"') { cur += '"'; i++; }
      else if (c === '"') quoted = false;
      else cur += c;
    } else if (c === '"') quoted = true;
    else if (c === ",") { out.push(cur); cur = ""; }
    else cur += c;
  }
  out.push(cur);
  return out.map((s) => s.trim());
}

export function parseCsv(text) {
  const lines = text.split(/\r\n|\r|\n/).filter((l) => l.trim() !== "" && !l.trimStart().startsWith("#"));
  if (!lines.length) throw new Error("the file is empty");
  const header = splitLine(lines[0].replace(/^\uFEFF/, ""));
  if (header.length === 1 && /[;\t]/.test(header[0])) {
    // a spreadsheet's export where the decimal mark is a comma: not comma-separated
    const sep = header[0].includes(";") ? "';'" : "tabs";
    throw new Error(`the header is one column separated by ${sep}: save the file as ` +
      "comma-separated values with '.' as the decimal mark (CSV UTF-8, comma-delimited)");
  }
  return lines.slice(1).map((line) => {
    const cells = splitLine(line);
    const row = {};
    header.forEach((name, k) => {
      const cell = cells[k] ?? "";
      if (cell === "") return;
      if (TEXT_COLUMNS.has(name)) { row[name] = cell; return; }
      const v = Number(cell);
      row[name] = Number.isFinite(v) ? v : cell;
    });
    return row;
  });
}

export function parseMeasured(name, text) {
  if (/\.json$/i.test(name) || text.trimStart().startsWith("[") || text.trimStart().startsWith("{")) {
    const data = JSON.parse(text);
    return Array.isArray(data) ? data : data.rows;
  }
  return parseCsv(text);
}
