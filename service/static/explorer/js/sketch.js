// Side view of the bent actuator, to scale in mm: a SKETCH, not a solution. The body is
// clamped at x = 0; over the chamber (length L, from the chamber offset) it bends as a
// circular arc whose total turn is the bending angle (positive away from the membrane);
// before and after the chamber it stays straight. Layers through the thickness, from
// the membrane's outer face: membrane t, chamber h (over the chamber only), body T.
// The balloon's bulge is drawn schematically (its height is not computed here).

const NS = "http://www.w3.org/2000/svg";

function el(name, attrs, parent) {
  const node = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  parent.appendChild(node);
  return node;
}

// Centre-line frame at arc length s: position (x, y) and the unit normal (towards the body).
function frame(s, L, c0, kappa) {
  const sA = Math.min(s, c0);
  const sB = Math.min(Math.max(s - c0, 0), L);
  const sC = Math.max(s - c0 - L, 0);
  let x = sA, y = 0;
  if (kappa !== 0) {
    const phi = kappa * sB;
    x += Math.sin(phi) / kappa;
    y += (1 - Math.cos(phi)) / kappa;
  } else {
    x += sB;
  }
  const phi = kappa * sB;
  x += sC * Math.cos(phi);
  y += sC * Math.sin(phi);
  return { x, y, nx: -Math.sin(phi), ny: Math.cos(phi) };
}

// ``at``: what the readout steps on ("pressure", "injected volume", "time"); ``source``:
// where the angle comes from ("predicted", or "FE" for the design's own FE curve).
export function renderSketch(svg, design, angleDeg, pressureFraction = 0, { at: stepsOn = "pressure", source = "predicted" } = {}) {
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  // drawn at the width it is shown at (1 unit = 1 CSS px: legible text on a narrow screen)
  const shownW = svg.clientWidth || 0;
  const W = shownW > 0 ? Math.round(Math.max(280, Math.min(1200, shownW))) : 720;
  const Hpx = W < 560 ? 200 : 250;
  svg.setAttribute("viewBox", `0 0 ${W} ${Hpx}`);
  svg.setAttribute("font-family", "system-ui, sans-serif");
  el("rect", { x: 0, y: 0, width: W, height: Hpx, fill: "#ffffff" }, svg);
  const L = design.L_mm, t = design.t_mm, h = design.h_mm, T = design.T_mm;
  const k = (design.W_mm || 3) / 3;  // the body-length rule scales with W (solver/design.py)
  const Lb = design.body_length_mm || Math.max(12 * k, L + 2 * k);
  const c0 = design.chamber_offset_mm ?? (Lb - L) / 2;
  const angle = Number.isFinite(angleDeg) ? angleDeg : 0;
  const kappa = (angle * Math.PI / 180) / L;
  const Ht = t + h + T;
  const n0 = -Ht / 2;  // centre line in the middle of the thickness

  const N = 120;
  const ss = Array.from({ length: N + 1 }, (_, i) => (Lb * i) / N);
  const chamberS = Array.from({ length: 41 }, (_, i) => c0 + (L * i) / 40);
  const at = (s, n) => { const f = frame(s, L, c0, kappa); return [f.x + (n + n0) * f.nx, f.y + (n + n0) * f.ny]; };
  const band = (sList, nLo, nHi) => sList.map((s) => at(s, nLo)).concat(sList.slice().reverse().map((s) => at(s, nHi)));
  // balloon: the membrane bulges outwards over the chamber (schematic height)
  const bulgeMax = Math.min(0.2 * L, 1.2, 4 * h + 2 * t) * Math.min(1, Math.max(0, pressureFraction));
  const bulge = (s) => bulgeMax * Math.sin(Math.PI * (s - c0) / L);
  const balloonOuter = chamberS.map((s) => at(s, -bulge(s)));
  const balloonInner = chamberS.slice().reverse().map((s) => at(s, t - bulge(s) * 0.9));

  const shapes = {
    body: band(ss, t, Ht),
    membrane: band(ss, 0, t),
    chamber: band(chamberS, t, t + h),
    balloon: balloonOuter.concat(balloonInner),
  };
  // fit all points (and the clamp) in the frame, equal scale in x and y
  const all = Object.values(shapes).flat().concat([[-1.5, -Ht], [0, Ht]]);
  const xs = all.map((p) => p[0]), ys = all.map((p) => p[1]);
  const minX = Math.min(...xs), maxX = Math.max(...xs), minY = Math.min(...ys), maxY = Math.max(...ys);
  const pad = 30;
  const scale = Math.min((W - 2 * pad) / (maxX - minX), (Hpx - 2 * pad - 20) / (maxY - minY));
  const X = (x) => pad + (x - minX) * scale;
  const Y = (y) => Hpx - pad - 10 - (y - minY) * scale;  // y up
  const poly = (pts, attrs) => el("polygon", { points: pts.map(([x, y]) => `${X(x).toFixed(1)},${Y(y).toFixed(1)}`).join(" "), ...attrs }, svg);

  // clamp
  const clampTop = Y(Ht), clampBottom = Y(-Ht);
  el("rect", { x: X(-1.5), y: clampTop, width: X(0) - X(-1.5), height: clampBottom - clampTop, fill: "#9ca3af", stroke: "#4b5563" }, svg);
  poly(shapes.body, { fill: "#cbd5e1", stroke: "#475569", "stroke-width": 1, "data-part": "body" });
  if (bulgeMax > 0) poly(shapes.balloon, { fill: "#fde68a", stroke: "#b45309", "stroke-width": 1, "data-part": "balloon" });
  poly(shapes.membrane, { fill: "#fbbf24", stroke: "#b45309", "stroke-width": 1, "data-part": "membrane" });
  poly(shapes.chamber, { fill: "#bfdbfe", stroke: "#1d4ed8", "stroke-width": 0.8, "data-part": "chamber" });

  // scale bar: 5 mm (or 2 mm when the drawing is small)
  const barMm = (maxX - minX) > 15 ? 5 : 2;
  const bx = W - pad - barMm * scale, by = Hpx - 12;
  el("line", { x1: bx, x2: bx + barMm * scale, y1: by, y2: by, stroke: "#111827", "stroke-width": 2 }, svg);
  el("text", { x: bx + barMm * scale / 2, y: by - 5, "text-anchor": "middle", "font-size": 11, fill: "#111827" }, svg).textContent = `${barMm} mm`;
  const caption = Number.isFinite(angleDeg)
    ? `sketch: ${angle.toFixed(1)} deg bend${source === "FE" ? " (FE curve)" : ""} as a circular arc over the chamber (balloon height schematic)`
    : `sketch: no ${source === "FE" ? "FE" : "predicted"} angle at this ${stepsOn}`;
  // in lines that fit the width (about 6.6 units a character at 12 px)
  const x0 = W < 560 ? 8 : pad;
  const perLine = Math.max(20, Math.floor((W - 2 * x0) / 6.6));
  const lines = [];
  for (const word of caption.split(" ")) {
    if (lines.length && (lines.at(-1) + " " + word).length <= perLine) lines[lines.length - 1] += " " + word;
    else lines.push(word);
  }
  lines.forEach((line, k) => { el("text", { x: x0, y: 16 + 15 * k, "font-size": 12, fill: "#374151" }, svg).textContent = line; });
  svg.dataset.angle = String(angle);
}
