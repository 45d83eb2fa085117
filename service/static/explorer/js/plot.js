// A small SVG line plot: axes with round ticks, lines broken where a value is null,
// shaded bands, point markers, a legend and an optional vertical cursor. No library:
// the page needs only this, and every colour is an attribute so that the exported SVG
// stands alone.

const NS = "http://www.w3.org/2000/svg";
export const COLORS = ["#1f5fa8", "#c2410c", "#15803d", "#7e22ce", "#b91c1c", "#0e7490"];

function el(name, attrs = {}, parent) {
  const node = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) if (v !== undefined && v !== null) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

const finite = (v) => typeof v === "number" && Number.isFinite(v);

export function niceTicks(lo, hi, count = 6) {
  if (!(hi > lo)) { hi = lo + 1; }
  const raw = (hi - lo) / count;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
  const start = Math.floor(lo / step) * step;
  const end = Math.ceil(hi / step) * step;
  const ticks = [];
  for (let v = start; v <= end + step * 1e-9; v += step) ticks.push(Math.round(v / step) * step);
  return { ticks, lo: start, hi: end, step };
}

// A tick's label with as many decimals as its step needs (up to 6): a step of 2.5 (the
// narrow plot's four ticks over 0-10 s) keeps one, where the step's order of magnitude
// alone labelled 2.5 and 7.5 "3" and "8" (the audit of the forty-first session).
function fmtTick(v, step) {
  let digits = 0;
  while (digits < 6) {
    const scaled = step * 10 ** digits;
    if (Math.abs(scaled - Math.round(scaled)) <= 1e-6 * scaled) break;
    digits += 1;
  }
  return v.toFixed(digits);
}

// A label in lines of at most ``n`` characters, broken after a space (each line but the
// last keeps its space, so that the text's content is the label).
function wrap(label, n) {
  const out = [];
  let rest = label;
  while (rest.length > n) {
    const cut = rest.lastIndexOf(" ", n);
    if (cut <= 0) break;
    out.push(rest.slice(0, cut + 1));
    rest = rest.slice(cut + 1);
  }
  out.push(rest);
  return out;
}

// Runs of consecutive points where x and y are finite.
function segments(x, y) {
  const out = [];
  let cur = [];
  for (let i = 0; i < x.length; i++) {
    if (finite(x[i]) && finite(y[i])) cur.push(i);
    else if (cur.length) { out.push(cur); cur = []; }
  }
  if (cur.length) out.push(cur);
  return out;
}

// The drawing's width in user units: the width the SVG is shown at (1 unit = 1 CSS px,
// so its 12 px text stays 12 px on a narrow screen), 720 while it is not laid out.
export function shownWidth(svg, fallback = 720) {
  const w = svg.clientWidth || (svg.getBoundingClientRect ? svg.getBoundingClientRect().width : 0);
  return w > 0 ? Math.round(Math.max(280, Math.min(1200, w))) : fallback;
}

export function renderPlot(svg, series, opts = {}) {
  const W = opts.width || shownWidth(svg);
  // the height follows the width below 720 units, up to the asked (or 420) units
  const H = Math.round(Math.min(opts.height || 420, Math.max(240, W * 0.62)));
  const m = { l: 62, r: 16, t: 14, b: 48 };
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  svg.setAttribute("xmlns", NS);
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  svg.setAttribute("font-family", "system-ui, sans-serif");
  svg.setAttribute("font-size", "12");
  el("rect", { x: 0, y: 0, width: W, height: H, fill: "#ffffff" }, svg);

  let xs = [], ys = [];
  for (const s of series) {
    for (let i = 0; i < s.x.length; i++) {
      if (!finite(s.x[i])) continue;
      for (const arr of [s.y, s.lower, s.upper]) if (arr && finite(arr[i])) { xs.push(s.x[i]); ys.push(arr[i]); }
    }
  }
  const xr = opts.xRange || [Math.min(0, ...xs), xs.length ? Math.max(...xs) : 1];
  let yLo = ys.length ? Math.min(0, ...ys) : 0, yHi = ys.length ? Math.max(...ys) : 1;
  // a curve starting at 0 with round-off below it (-0.005 deg) keeps its axis at 0
  if (yLo < 0 && yLo > -0.01 * (yHi - yLo)) yLo = 0;
  if (opts.yClip) { yLo = Math.max(yLo, opts.yClip[0]); yHi = Math.min(yHi, opts.yClip[1]); }
  // fewer ticks on a narrow plot, so that their labels do not run into each other
  const xt = niceTicks(xr[0], xr[1], W < 560 ? 4 : 6), yt = niceTicks(yLo, yHi, H < 320 ? 4 : 6);
  const px = (v) => m.l + ((v - xt.lo) / (xt.hi - xt.lo)) * (W - m.l - m.r);
  const py = (v) => H - m.b - ((v - yt.lo) / (yt.hi - yt.lo)) * (H - m.t - m.b);
  const clipId = `clip-${svg.id || "plot"}`;
  const defs = el("defs", {}, svg);
  el("rect", { x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b }, el("clipPath", { id: clipId }, defs));

  const grid = el("g", { stroke: "#e5e7eb", "stroke-width": 1 }, svg);
  const labels = el("g", { fill: "#374151" }, svg);
  for (const v of xt.ticks) {
    el("line", { x1: px(v), x2: px(v), y1: m.t, y2: H - m.b }, grid);
    el("text", { x: px(v), y: H - m.b + 16, "text-anchor": "middle" }, labels).textContent = fmtTick(v, xt.step);
  }
  for (const v of yt.ticks) {
    el("line", { x1: m.l, x2: W - m.r, y1: py(v), y2: py(v) }, grid);
    el("text", { x: m.l - 6, y: py(v) + 4, "text-anchor": "end" }, labels).textContent = fmtTick(v, yt.step);
  }
  el("rect", { x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b, fill: "none", stroke: "#9ca3af" }, svg);
  el("text", { x: (m.l + W - m.r) / 2, y: H - 10, "text-anchor": "middle", fill: "#111827" }, svg).textContent = opts.xLabel || "";
  el("text", { x: 16, y: (m.t + H - m.b) / 2, "text-anchor": "middle", fill: "#111827",
    transform: `rotate(-90 16 ${(m.t + H - m.b) / 2})` }, svg).textContent = opts.yLabel || "";

  const body = el("g", { "clip-path": `url(#${clipId})` }, svg);
  for (const s of series) {
    const g = el("g", { "data-series": s.id, "data-label": s.label }, body);
    if (s.lower && s.upper) {
      for (const seg of segments(s.x, s.lower.map((v, i) => (finite(v) && finite(s.upper[i]) ? v : null)))) {
        const pts = seg.map((i) => `${px(s.x[i])},${py(s.upper[i])}`)
          .concat(seg.slice().reverse().map((i) => `${px(s.x[i])},${py(s.lower[i])}`));
        el("polygon", { points: pts.join(" "), fill: s.color, "fill-opacity": 0.16, stroke: "none", class: "band" }, g);
      }
    }
    if (!s.markersOnly) {
      for (const seg of segments(s.x, s.y)) {
        const d = seg.map((i, k) => `${k ? "L" : "M"}${px(s.x[i]).toFixed(2)},${py(s.y[i]).toFixed(2)}`).join("");
        el("path", { d, fill: "none", stroke: s.color, "stroke-width": s.width || 2,
          "stroke-dasharray": s.dash || null, class: "line" }, g);
      }
    }
    if (s.markers || s.markersOnly) {
      for (let i = 0; i < s.x.length; i++) {
        if (finite(s.x[i]) && finite(s.y[i])) el("circle", { cx: px(s.x[i]), cy: py(s.y[i]), r: 2.6, fill: s.color }, g);
      }
    }
    // the plotted numbers, for export and for tests that compare them with the API
    g.setAttribute("data-x", JSON.stringify(s.x));
    g.setAttribute("data-y", JSON.stringify(s.y));
  }
  if (finite(opts.cursorX)) {
    el("line", { x1: px(opts.cursorX), x2: px(opts.cursorX), y1: m.t, y2: H - m.b, stroke: "#111827",
      "stroke-dasharray": "3 3", "data-cursor": opts.cursorX }, svg);
  }
  // legend: top left inside the axes, or below them (the SVG grows to hold it)
  const shown = series.filter((s) => s.label);
  if (shown.length) {
    const lineH = 16;
    const below = opts.legend === "below";
    const left = below && W < 560 ? 4 : m.l;  // a narrow plot's legend uses its whole width
    const longest = Math.max(...shown.map((s) => s.label.length));
    const cols = below && 40 + 6.2 * longest < (W - left - m.r) / 2 ? 2 : 1;
    const colW = below ? (W - left - m.r) / cols : Math.min(360, 12 + 7 * Math.max(...shown.map((s) => s.label.length)));
    // a label longer than its column is wrapped at a space (about 6 units a character)
    const perLine = Math.max(12, Math.floor((colW - 34) / 6));
    const lines = shown.map((s) => wrap(s.label, below ? perLine : Infinity));
    const rowsOf = [];  // the first line of each entry, row by row of the columns
    let rows = 0;
    for (let k = 0; k < shown.length; k += cols) {
      const tall = Math.max(...lines.slice(k, k + cols).map((l) => l.length));
      for (let j = k; j < Math.min(k + cols, shown.length); j++) rowsOf[j] = rows;
      rows += tall;
    }
    let lg;
    if (below) {
      svg.setAttribute("viewBox", `0 0 ${W} ${H + rows * lineH + 8}`);
      svg.querySelector("rect").setAttribute("height", H + rows * lineH + 8);
      lg = el("g", { transform: `translate(${left},${H})` }, svg);
    } else {
      lg = el("g", { transform: `translate(${m.l + 8},${m.t + 8})` }, svg);
      el("rect", { x: 0, y: 0, width: colW, height: rows * lineH + 6, fill: "#ffffff", "fill-opacity": 0.85, stroke: "#d1d5db" }, lg);
    }
    shown.forEach((s, k) => {
      const x0 = (k % cols) * colW, y = 12 + rowsOf[k] * lineH;
      if (s.markersOnly) el("circle", { cx: x0 + 14, cy: y - 4, r: 3, fill: s.color }, lg);
      else el("line", { x1: x0 + 6, x2: x0 + 24, y1: y - 4, y2: y - 4, stroke: s.color, "stroke-width": s.width || 2, "stroke-dasharray": s.dash || null }, lg);
      const text = el("text", { x: x0 + 30, y, fill: "#111827", "font-size": 11 }, lg);
      if (lines[k].length === 1) text.textContent = s.label;
      else lines[k].forEach((line, j) => { el("tspan", { x: x0 + 30, dy: j ? lineH : 0 }, text).textContent = line; });
    });
  }
  if (opts.note) {
    el("text", { x: W - m.r - 6, y: m.t + 16, "text-anchor": "end", fill: "#b91c1c", "font-size": 11 }, svg).textContent = opts.note;
  }
  svg.dataset.renders = String(Number(svg.dataset.renders || 0) + 1);
}

export function svgText(svg) {
  const clone = svg.cloneNode(true);
  clone.setAttribute("xmlns", NS);
  const [, , w, h] = (svg.getAttribute("viewBox") || "0 0 720 420").split(" ");
  clone.setAttribute("width", w);
  clone.setAttribute("height", h);
  return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(clone);
}

// PNG of an SVG: drawn on a canvas at `scale` times its size (from a blob: URL, so
// nothing leaves the page).
export function svgToPngBlob(svg, scale = 2) {
  const [, , w, h] = (svg.getAttribute("viewBox") || "0 0 720 420").split(" ").map(Number);
  return new Promise((resolve, reject) => {
    const url = URL.createObjectURL(new Blob([svgText(svg)], { type: "image/svg+xml" }));
    const img = new Image();
    img.onload = () => {
      const canvas = document.createElement("canvas");
      canvas.width = w * scale; canvas.height = h * scale;
      const ctx = canvas.getContext("2d");
      ctx.scale(scale, scale);
      ctx.drawImage(img, 0, 0, w, h);
      URL.revokeObjectURL(url);
      canvas.toBlob((b) => (b ? resolve(b) : reject(new Error("PNG encoding failed"))), "image/png");
    };
    img.onerror = () => { URL.revokeObjectURL(url); reject(new Error("the SVG could not be drawn")); };
    img.src = url;
  });
}
