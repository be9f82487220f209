// Feature vectors as curves over the radius, one small chart per invariant, as the paper's
// figures draw them: r on the x axis (mesh units), the normalised invariant on the y axis,
// the flat surface's value dashed.

const SVG = 'http://www.w3.org/2000/svg';

const LABELS = {
  V: { symbol: 'V̂', name: 'V / |B_r|', flat: 0.5 },
  S: { symbol: 'Ŝ', name: 'S / 4πr²', flat: 0.5 },
  P: { symbol: 'P̂', name: 'P / πr²', flat: 1 },
  L: { symbol: 'L̂', name: 'L / 2πr', flat: 1 },
};

function el(name, attrs = {}, text) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

/** About `count` round tick values spanning [lo, hi]. */
export function niceTicks(lo, hi, count = 4) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / count;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw);
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) ticks.push(Number(t.toPrecision(12)));
  return ticks;
}

/** A number with at most `digits` significant digits, without trailing zeros. */
export function formatNumber(v, digits = 4) {
  if (!Number.isFinite(v)) return String(v);
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-4) return v.toExponential(digits - 1).replace(/\.?0+e/, 'e');
  return String(Number(v.toPrecision(digits)));
}

/**
 * Draws one chart per invariant into `container` (an element, emptied first).
 * `curves`: [{letter, radii: [r_j], values: [x_j], reference?: [o_j]}], `units`: "mm".
 */
export function drawFeatureCurves(container, curves, units) {
  container.textContent = '';
  const W = 151, H = 124, left = 36, right = 7, top = 18, bottom = 28;
  for (const c of curves) {
    const info = LABELS[c.letter] || { symbol: c.letter, name: c.letter, flat: NaN };
    const svg = el('svg', { width: W, height: H, viewBox: `0 0 ${W} ${H}`, class: 'curve', 'data-letter': c.letter });
    const finite = c.values.filter(Number.isFinite);
    if (Number.isFinite(info.flat)) finite.push(info.flat);
    let lo = Math.min(...finite), hi = Math.max(...finite);
    const pad = Math.max((hi - lo) * 0.08, 1e-3);
    lo -= pad;
    hi += pad;
    const rMax = Math.max(...c.radii);
    const x = (r) => left + (r / rMax) * (W - left - right);
    const y = (v) => top + (1 - (v - lo) / (hi - lo)) * (H - top - bottom);
    svg.append(el('text', { x: left, y: 12, class: 'title' }, `${info.symbol} = ${info.name}`));
    // Axes with ticks.
    svg.append(el('line', { x1: left, y1: H - bottom, x2: W - right, y2: H - bottom, class: 'axis' }));
    svg.append(el('line', { x1: left, y1: top, x2: left, y2: H - bottom, class: 'axis' }));
    for (const t of niceTicks(0, rMax, 3)) {
      svg.append(el('line', { x1: x(t), y1: H - bottom, x2: x(t), y2: H - bottom + 3, class: 'axis' }));
      svg.append(el('text', { x: x(t), y: H - bottom + 12, class: 'tick', 'text-anchor': 'middle' }, formatNumber(t)));
    }
    svg.append(el('text', { x: (left + W - right) / 2, y: H - 3, class: 'label', 'text-anchor': 'middle' }, `r (${units})`));
    for (const t of niceTicks(lo, hi, 4)) {
      svg.append(el('line', { x1: left - 3, y1: y(t), x2: left, y2: y(t), class: 'axis' }));
      svg.append(el('text', { x: left - 5, y: y(t) + 3, class: 'tick', 'text-anchor': 'end' }, formatNumber(t, 3)));
    }
    if (Number.isFinite(info.flat)) {
      svg.append(el('line', { x1: left, y1: y(info.flat), x2: W - right, y2: y(info.flat), class: 'flat' }));
    }
    // The curve, broken where a value is missing (NaN: masked near a border).
    let d = '';
    let pen = 'M';
    c.radii.forEach((r, j) => {
      const v = c.values[j];
      if (!Number.isFinite(v)) {
        pen = 'M';
        return;
      }
      d += `${pen}${x(r).toFixed(1)},${y(v).toFixed(1)}`;
      pen = 'L';
    });
    svg.append(el('path', { d, class: 'vector' }));
    c.radii.forEach((r, j) => {
      const v = c.values[j];
      if (Number.isFinite(v)) svg.append(el('circle', { cx: x(r).toFixed(1), cy: y(v).toFixed(1), r: 1.8, class: 'point' }));
    });
    container.append(svg);
  }
}
