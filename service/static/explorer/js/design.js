// The design box the explorer offers and the request a design becomes.
//
// Ranges: the design box of the whole-box emulator (geometry L 4-18 mm, t 0.5-1.2 mm,
// T 0.6-2.0 mm, b 1.0-2.4 mm, h 0.10-0.30 mm at W = 3 mm; four material pairs; the
// stiffness scales the server's: GET /v1/materials `stiffness_scale`, each layer's own s
// and the ratio s_body / s_membrane, from solver/design_space.py -- scaling both layers by
// one factor only scales the pressure axis). At another width W the lengths' ranges are the
// box scaled by W / 3 mm: a design with every length scaled by one factor bends alike at the
// same pressure (solver/design_space.py), so the emulator answers every scaled copy of the
// box. Defaults: the paper's standard design (Table 3), which is also what the API assumes
// for an omitted field. The server, not this table, decides what it can answer: a design
// it refuses comes back as a problem document.

export const FIELDS = [
  { name: "L_mm", label: "Chamber length L", unit: "mm", min: 4, max: 18, step: 0.1, value: 7.1 },
  { name: "t_mm", label: "Membrane thickness t", unit: "mm", min: 0.5, max: 1.2, step: 0.01, value: 0.5 },
  { name: "T_mm", label: "Body thickness above chamber T", unit: "mm", min: 0.6, max: 2.0, step: 0.05, value: 1.0 },
  { name: "b_mm", label: "Chamber width b", unit: "mm", min: 1.0, max: 2.4, step: 0.05, value: 1.8 },
  { name: "h_mm", label: "Chamber height h", unit: "mm", min: 0.1, max: 0.3, step: 0.01, value: 0.15 },
  // min, max: each layer's s; ratio: s_body / s_membrane (the slider's span: one layer
  // alone, the other at 1). Until GET /v1/materials answers, none is known.
  { name: "body_scale", label: "Body stiffness scale s", unit: "x", min: null, max: null, ratio: null, step: 0.05, value: 1 },
  { name: "membrane_scale", label: "Membrane stiffness scale s", unit: "x", min: null, max: null, ratio: null, step: 0.05, value: 1 },
];

// The stiffness scales' limits as the server states them (GET /v1/materials'
// `stiffness_scale`: {layer: [low, high], ratio: [low, high]}), onto FIELDS.
export function takeScaleLimits(limits) {
  if (!limits || !Array.isArray(limits.layer) || !Array.isArray(limits.ratio)) return;
  for (const f of FIELDS) {
    if (f.unit !== "x") continue;
    [f.min, f.max] = limits.layer;
    f.ratio = limits.ratio;
  }
}
export const W_MM = 3.0;  // the paper's width, at which FIELDS give the box
// The width: 1-10 mm keeps the scaled box inside the API's length limits (L <= 60 mm).
export const W_FIELD = { name: "W_mm", label: "Actuator width W", unit: "mm", min: 1, max: 10, step: 0.1, value: W_MM };

// A length field's range at width W (mm): the box's, scaled by W / 3 mm; the stiffness
// scales' ranges do not change with W.
export function fieldRange(f, W) {
  if (!f.name.endsWith("_mm") || f.name === W_FIELD.name) return { min: f.min, max: f.max };
  const k = W / W_MM;
  const r = (v) => Math.round(v * k * 1e4) / 1e4;
  return { min: r(f.min), max: r(f.max) };
}

// The design's lengths scaled by W_new / W_old (a scaled copy: the same angle-pressure
// curve), at full precision: a length rounded here (0.5 x 3.2 / 3 -> 0.5333) is no longer
// the scaled copy and can leave the box once scaled back. Only the inputs show them rounded.
export function scaledLengths(state, W) {
  const k = W / (state.W_mm || W_MM);
  const out = { W_mm: W };
  for (const f of FIELDS) if (f.name.endsWith("_mm")) out[f.name] = state[f.name] * k;
  return out;
}

// A value as the inputs and labels show it: to 0.1 um (or 1e-4 of a stiffness scale), or to
// 4 significant digits where that rounding is off by more than 1 % (a scale of 1e-300 had
// read "0" and 1e305 "Infinity": another number than the one typed).
export function shown(v) {
  if (typeof v !== "number" || !Number.isFinite(v)) return String(v);
  const rounded = Math.round(v * 1e4) / 1e4;
  return String(Math.abs(rounded - v) <= 0.01 * Math.abs(v) ? rounded : Number(v.toPrecision(4)));
}
export const PAIRS = [
  ["pdms_1_10", "ecoflex_00_30"],
  ["pdms_1_15", "ecoflex_00_30"],
  ["ecoflex_00_30", "pdms_1_15"],
  ["ecoflex_00_30", "ecoflex_00_30"],
];
export const MATERIAL_NAMES = { pdms_1_10: "PDMS 1:10", pdms_1_15: "PDMS 1:15", ecoflex_00_30: "Ecoflex 00-30" };

export function pairLabel(body, membrane) {
  return `${MATERIAL_NAMES[body] || body} / ${MATERIAL_NAMES[membrane] || membrane}`;
}

export function defaultState() {
  const s = { pair: 0, W_mm: W_MM };
  for (const f of FIELDS) s[f.name] = f.value;
  return s;
}

// "1.5" for 1.5, "0.75" for 0.75: the scale as written in an inline material's id.
function scaleText(s) {
  return String(Math.round(s * 1000) / 1000);
}

// A layer's material: the preset id, or at a stiffness scale s != 1 the inline Ogden
// material with every modulus times s (same exponents): {id: "<preset>_x<s>", mu_kpa, alpha}.
export function material(presetId, scale, presets) {
  if (Math.abs(scale - 1) < 1e-9) return presetId;
  const preset = presets[presetId];
  if (!preset) throw new Error(`material ${presetId} is not in GET /v1/materials`);
  return {
    id: `${presetId}_x${scaleText(scale)}`,
    mu_kpa: preset.mu_kpa.map((mu) => mu * scale),
    alpha: [...preset.alpha],
  };
}

export function designBody(state, presets) {
  const [body, membrane] = PAIRS[state.pair];
  return {
    L_mm: state.L_mm, t_mm: state.t_mm, T_mm: state.T_mm, b_mm: state.b_mm, h_mm: state.h_mm,
    W_mm: state.W_mm ?? W_MM,
    body_material: material(body, state.body_scale, presets),
    membrane_material: material(membrane, state.membrane_scale, presets),
  };
}

export function materialId(m) {
  return typeof m === "string" ? m : m.id;
}

// A layer's id as [preset, stiffness scale]: "<preset>*<s>" (the store's and the server's
// name of a scaled preset, solver.design_space.scaled_material) or "<preset>_x<s>" (this
// page's inline material); any other id at scale 1.
export function presetAndScale(id) {
  const match = String(id).match(/^(.*?)(?:\*([0-9.eE+-]+)|_x([0-9.]+))$/);
  return match ? [match[1], Number(match[2] || match[3])] : [String(id), 1];
}

// A design as the server writes it (an out-of-box refusal's ``nearest_design``: lengths
// in mm, each layer by id) as the page's state; null for a pair this page does not offer.
export function stateOfDesign(d) {
  const [body, bodyScale] = presetAndScale(d.body_material);
  const [membrane, membraneScale] = presetAndScale(d.membrane_material);
  const pair = PAIRS.findIndex(([b, m]) => b === body && m === membrane);
  const lengths = [W_FIELD, ...FIELDS].filter((f) => f.name.endsWith("_mm")).map((f) => f.name);
  if (pair < 0 || !(bodyScale > 0 && membraneScale > 0) || !lengths.every((n) => d[n] > 0)) return null;
  const state = { pair, body_scale: bodyScale, membrane_scale: membraneScale };
  for (const n of lengths) state[n] = d[n];
  return state;
}

// A stored record's layer as people read it: the preset's name, and its stiffness scale
// when not 1 ("PDMS 1:15 x0.968"). The store names a scaled layer "<preset>*<s>", an
// inline one sent by this page "<preset>_x<s>"; with the presets (GET /v1/materials) the
// scale is read off the moduli instead.
export function materialLabel(m, presets) {
  const id = materialId(m);
  const [base, idScale] = presetAndScale(id);
  let scale = idScale;
  const preset = presets && presets[base];
  if (preset && typeof m === "object" && m.mu_kpa && preset.mu_kpa[0]) scale = m.mu_kpa[0] / preset.mu_kpa[0];
  const name = MATERIAL_NAMES[base] || base;
  return Math.abs(scale - 1) < 1e-3 ? name : `${name} x${scaleText(scale)}`;
}

export function designLabel(state) {
  const [body, membrane] = PAIRS[state.pair];
  const sc = (s) => (Math.abs(s - 1) < 1e-9 ? "" : ` x${scaleText(s)}`);
  const W = state.W_mm ?? W_MM;
  return `L ${shown(state.L_mm)} t ${shown(state.t_mm)} T ${shown(state.T_mm)} b ${shown(state.b_mm)} h ${shown(state.h_mm)}${W === W_MM ? "" : ` W ${shown(W)}`} mm, ` +
    `${MATERIAL_NAMES[body] || body}${sc(state.body_scale)} / ${MATERIAL_NAMES[membrane] || membrane}${sc(state.membrane_scale)}`;
}

// The points of a curve request on the asked axis (pressures, Pa; volumes, ul; or times,
// s): n points from 0 to max (the readout slider steps on them, so the value it shows is
// one the server computed, never an interpolation).
export function axisGrid(max, n = 81) {
  return Array.from({ length: n }, (_, i) => (max * i) / (n - 1));
}
