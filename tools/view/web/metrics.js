// The metrics of `msii metric` (engine/src/metrics/feature_metrics.cpp, paper §3.1), on the
// quantized feature values of a view: the same formulas, weights, blocks and NaN rules,
// vertex by vertex in double precision as there. The table holds the codes row by row
// (each vertex's vector together, as the C++ table does), so a vertex's elements are read
// from one place in memory.

import { NAN_CODE } from './data.js';

/** Metric names as `msii metric --metric` takes them, with what the menu says. */
export const METRICS = [
  ['mahalanobis', 'Mahalanobis (Eq. 11)'],
  ['l1', 'L1'],
  ['l2', 'L2 (Euclidean)'],
  ['linf', 'L∞ (maximum)'],
  ['lp', 'Lp'],
  ['l1w', 'L1, scale-weighted (Eq. 4–6)'],
  ['l2w', 'L2, scale-weighted'],
  ['linfw', 'L∞, scale-weighted'],
  ['lpw', 'Lp, scale-weighted'],
  ['neuclid', 'normalised Euclidean'],
  ['cosine', 'cosine similarity'],
  ['correlation', 'correlation'],
  ['autocorrelation', 'auto-correlation (lag 1)'],
  ['tanimoto', 'Tanimoto similarity'],
];

/** Similarities grow with likeness; the others are distances. */
export function isSimilarity(name) {
  return ['cosine', 'correlation', 'autocorrelation', 'tanimoto'].includes(name);
}

/** The value of the ideal flat surface: 0.5 for V and S, 1 for P and L. */
export function flatValue(letter) {
  return letter === 'V' || letter === 'S' ? 0.5 : 1.0;
}

/** Scale weights of Eq. 4–6 for n elements of invariant `letter`. */
export function scaleWeights(letter, n) {
  const w = [];
  for (let j = 1; j <= n; j++) {
    if (letter === 'V') w.push((3 * j * j - 3 * j + 1) / (n * n * n)); // Eq. 4
    else if (letter === 'P') w.push((2 * j - 1) / (n * n)); // Eq. 6
    else w.push(1.0 / n); // Eq. 5: S and L, uniform
  }
  return w;
}

/** Options of a metric name, as metricOptionsByName(). Throws for an unknown name. */
export function metricOptions(name, p = 2) {
  if (!(p > 0)) throw new Error('the p of a p-norm must be a positive number (or infinity)');
  const o = { kind: 'pnorm', p: 2, weighted: false };
  let base = name;
  if (base.length > 1 && base[0] === 'l' && base.endsWith('w')) {
    o.weighted = true;
    base = base.slice(0, -1);
  }
  if (base === 'l1') o.p = 1;
  else if (base === 'l2') o.p = 2;
  else if (base === 'linf') o.p = Infinity;
  else if (base === 'lp') o.p = p;
  else if (!o.weighted && ['mahalanobis', 'cosine', 'correlation', 'autocorrelation', 'tanimoto', 'neuclid'].includes(name)) o.kind = name;
  else throw new Error(`unknown metric '${name}'`);
  return o;
}

const featureName = (letter, j) => `${letter}_${String(j).padStart(2, '0')}`;

/**
 * The feature table of `letters` (e.g. "V" or "VP"), as featureTableOf(): for each, the
 * columns <letter>_01, <letter>_02, … up to the first missing, concatenated. `columns` maps
 * a column name to {q: Uint16Array, lo, step}. Throws, in msii metric's words, where one
 * is missing.
 */
export function featureTable(letters, columns, n) {
  const blocks = [];
  const cols = [];
  for (const letter of letters) {
    let count = 0;
    while (columns.has(featureName(letter, count + 1))) count++;
    if (count === 0) {
      const some = [...columns.keys()].filter((k) => k.length > 2 && k[0] === letter && k[1] === '_' && /\d/.test(k[2]));
      if (some.length) {
        throw new Error(`the input has ${letter} at some radii only (${some.join(', ')}); the metrics need it at every radius, from ${featureName(letter, 1)} (msii compute --bands quality,${letter} writes every radius)`);
      }
      throw new Error(`the input has no ${letter} features (${featureName(letter, 1)} …)`);
    }
    for (let j = 1; j <= count; j++) cols.push(columns.get(featureName(letter, j)));
    blocks.push({ letter, count });
  }
  const dim = cols.length;
  const codes = new Uint16Array(n * dim);
  const nan = new Uint8Array(n); // a vertex with a NaN element: its f is NaN
  // In blocks of vertices, so that the rows being filled stay in the cache.
  const block = 4096;
  for (let i0 = 0; i0 < n; i0 += block) {
    const i1 = Math.min(n, i0 + block);
    for (let e = 0; e < dim; e++) {
      const q = cols[e].q;
      for (let i = i0, k = i0 * dim + e; i < i1; i++, k += dim) {
        const v = q[i];
        codes[k] = v;
        if (v === NAN_CODE) nan[i] = 1;
      }
    }
  }
  return {
    n, dim, blocks, letters, codes, nan,
    lo: Float64Array.from(cols, (c) => c.lo),
    step: Float64Array.from(cols, (c) => c.step),
  };
}

/** The feature vector of vertex `i` (dequantized); NaN where an element is missing. */
export function rowOf(table, i) {
  const out = [];
  for (let e = 0; e < table.dim; e++) {
    const q = table.codes[i * table.dim + e];
    out.push(q === NAN_CODE ? NaN : table.lo[e] + q * table.step[e]);
  }
  return out;
}

function elementLabel(table, e) {
  for (const b of table.blocks) {
    if (e < b.count) return featureName(b.letter, e + 1);
    e -= b.count;
  }
  return `element ${e + 1}`;
}

/** The reference vector of vertex `i`; throws, as vertexReference(), if it holds a NaN. */
export function vertexReference(table, i) {
  const o = rowOf(table, i);
  const e = o.findIndex((v) => Number.isNaN(v));
  if (e >= 0) throw new Error(`vertex ${i} cannot be the reference: its ${elementLabel(table, e)} is NaN (masked near a border)`);
  return o;
}

function flatReference(table) {
  const f = [];
  for (const b of table.blocks) for (let j = 0; j < b.count; j++) f.push(flatValue(b.letter));
  return f;
}

/**
 * |d|^p for whole and half-whole p ≤ 64 as msii metric computes it: by squaring (and one
 * square root for the half), which is also far faster than Math.pow.
 */
function powerBySquaring(d, p) {
  const whole = Math.floor(p);
  let power = whole !== p ? Math.sqrt(d) : 1.0, base = d;
  for (let k = whole; k !== 0; k >>= 1) {
    if (k & 1) power *= base;
    base *= base;
  }
  return power;
}

/** The code of powerBySquaring(a, p), unrolled for one p (a: the name of a variable ≥ 0). */
function powerSource(a, p) {
  const whole = Math.floor(p);
  let power = whole !== p ? `Math.sqrt(${a})` : '1.0', base = a;
  for (let k = whole; k !== 0; k >>= 1) {
    if (k & 1) power = `(${power} * ${base})`;
    base = `(${base} * ${base})`;
  }
  return power;
}

/** c0[e] = lo_e − o_e, so that x_e − o_e = c0[e] + step_e · code. */
function offsets(table, o) {
  return Float64Array.from(o, (v, e) => table.lo[e] - v);
}

/** (Σ_e w_e |x_e − o_e|^p)^(1/p), w_e = 1 or the weights of Eq. 4–6; p = ∞: the maximum of w_e |x_e − o_e|. */
function pNorm(t, o, opt, out) {
  const { n, dim, codes, nan, step } = t;
  const w = Float64Array.from(opt.weighted ? t.blocks.flatMap((b) => scaleWeights(b.letter, b.count)) : new Array(dim).fill(1));
  const c0 = offsets(t, o);
  const p = opt.p;
  const integral = p <= 64 && Math.floor(2 * p) === 2 * p;
  const pf = Math.fround(p);
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    let s = 0;
    if (p === Infinity) {
      for (let e = 0; e < dim; e++) s = Math.max(s, w[e] * Math.abs(c0[e] + step[e] * codes[b + e]));
      out[i] = s;
    } else if (p === 1) {
      for (let e = 0; e < dim; e++) s += w[e] * Math.abs(c0[e] + step[e] * codes[b + e]);
      out[i] = s;
    } else if (p === 2) {
      for (let e = 0; e < dim; e++) {
        const d = c0[e] + step[e] * codes[b + e];
        s += w[e] * d * d;
      }
      out[i] = Math.sqrt(s);
    } else if (integral) {
      for (let e = 0; e < dim; e++) s += w[e] * powerBySquaring(Math.abs(c0[e] + step[e] * codes[b + e]), p);
      out[i] = s ** (1 / p);
    } else {
      // msii metric raises |d| to p in single precision here (powf).
      for (let e = 0; e < dim; e++) s += w[e] * Math.fround(Math.fround(Math.abs(c0[e] + step[e] * codes[b + e])) ** pf);
      out[i] = s ** (1 / p);
    }
  }
}

/**
 * Eq. 11, sqrt((x − o) W (x − o)ᵀ), W block-diagonal: Eq. 9 (V) and Eq. 10 (P), the identity
 * for S and L; by suffix sums as in C++: Σ_{k≥j} w_jk d_k = a_j · Σ_{k≥j} d_k / b_k.
 */
function mahalanobis(t, o, out) {
  const { n, dim, codes, nan, step } = t;
  const c0 = offsets(t, o);
  const a = new Float64Array(dim).fill(1), ib = new Float64Array(dim).fill(1);
  const spans = [];
  let offset = 0;
  for (const bl of t.blocks) {
    const triangular = bl.letter === 'V' || bl.letter === 'P';
    for (let j = 1; triangular && j <= bl.count; j++) {
      a[offset + j - 1] = bl.letter === 'V' ? 3 * j * j - 3 * j + 1 : 2 * j - 1;
      ib[offset + j - 1] = 1 / (bl.letter === 'V' ? j * j * j : j * j);
    }
    spans.push([offset, offset + bl.count, triangular]);
    offset += bl.count;
  }
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    let q = 0;
    for (const [begin, end, triangular] of spans) {
      if (triangular) {
        let suffix = 0;
        for (let j = end - 1; j >= begin; j--) {
          const d = c0[j] + step[j] * codes[b + j];
          suffix += d * ib[j];
          q += d * a[j] * suffix;
        }
      } else {
        for (let j = begin; j < end; j++) {
          const d = c0[j] + step[j] * codes[b + j];
          q += d * d;
        }
      }
    }
    // W is not symmetric: a negative form keeps its sign (f = −sqrt(−q)), as in C++.
    out[i] = q >= 0 ? Math.sqrt(q) : -Math.sqrt(-q);
  }
}

/** A similarity of centred values (x − flat), from x̃·õ, |x̃|², |õ|²; throws if õ = 0. */
function centredSimilarity(t, o, metric, out, combine) {
  const { n, dim, codes, nan, step, lo } = t;
  const flat = flatReference(t);
  const oc = o.map((v, e) => v - flat[e]);
  if (oc.every((v) => v === 0)) {
    throw new Error(`${metric} needs a reference other than the flat surface (it is the origin of the centred values, so the similarity to it is undefined)`);
  }
  let oo = 0;
  for (const v of oc) oo += v * v;
  const c0 = Float64Array.from(lo, (l, e) => l - flat[e]);
  const ocv = Float64Array.from(oc);
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    let xo = 0, xx = 0;
    for (let e = 0; e < dim; e++) {
      const xc = c0[e] + step[e] * codes[b + e];
      xo += xc * ocv[e];
      xx += xc * xc;
    }
    out[i] = combine(xo, xx, oo);
  }
}

/** Pearson correlation of the elements of x and o; NaN for a vertex whose elements are all equal. */
function correlation(t, o, out) {
  const { n, dim, codes, nan, step, lo } = t;
  if (o.every((v) => v === o[0])) {
    throw new Error(`the correlation needs a reference whose values are not all equal (all are ${o[0]}, a zero variance)`);
  }
  let mo = 0;
  for (const v of o) mo += v;
  mo /= dim;
  const oc = Float64Array.from(o, (v) => v - mo);
  let oo = 0;
  for (const v of oc) oo += v * v;
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    // Two passes over the row, as in C++ (one pass Σx² − n·x̄² cancels).
    let sum = 0;
    let constant = true;
    const x0 = lo[0] + step[0] * codes[b];
    for (let e = 0; e < dim; e++) {
      const x = lo[e] + step[e] * codes[b + e];
      sum += x;
      constant = constant && x === x0;
    }
    if (constant) {
      out[i] = NaN;
      continue;
    }
    const mx = sum / dim;
    let xo = 0, xx = 0;
    for (let e = 0; e < dim; e++) {
      const xc = lo[e] + step[e] * codes[b + e] - mx;
      xo += xc * oc[e];
      xx += xc * xc;
    }
    out[i] = xo / Math.sqrt(xx * oo);
  }
}

/** Lag-1 autocorrelation of d = x − o within each block of n ≥ 2, the mean over blocks; NaN if d is constant in one. */
function autoCorrelation(t, o, out) {
  const { n, dim, codes, nan, step } = t;
  const c0 = offsets(t, o);
  const spans = [];
  let offset = 0;
  for (const bl of t.blocks) {
    if (bl.count >= 2) spans.push([offset, offset + bl.count]);
    offset += bl.count;
  }
  if (!spans.length) {
    throw new Error(`the auto-correlation needs a feature block of at least 2 elements (${t.blocks.map((bl) => `${bl.letter}×${bl.count}`).join(', ')} given)`);
  }
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    let sumR = 0;
    let undefinedHere = false;
    for (const [begin, end] of spans) {
      let sum = 0;
      let constant = true;
      const d0 = c0[begin] + step[begin] * codes[b + begin];
      for (let j = begin; j < end; j++) {
        const d = c0[j] + step[j] * codes[b + j];
        sum += d;
        constant = constant && d === d0;
      }
      if (constant) {
        undefinedHere = true;
        break;
      }
      const mean = sum / (end - begin);
      let prev = d0 - mean;
      let num = 0, den = prev * prev;
      for (let j = begin + 1; j < end; j++) {
        const cur = c0[j] + step[j] * codes[b + j] - mean;
        num += prev * cur;
        den += cur * cur;
        prev = cur;
      }
      sumR += num / den;
    }
    out[i] = undefinedHere ? NaN : sumR / spans.length;
  }
}

/** 1/σ_e² of each element over the vertices without NaN (0 where σ_e = 0), population variance. */
export function inverseVariances(t) {
  const { n, dim, codes, nan, step, lo } = t;
  const mean = new Float64Array(dim), m2 = new Float64Array(dim);
  let total = 0;
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) continue;
    total++;
    for (let e = 0; e < dim; e++) mean[e] += lo[e] + step[e] * codes[b + e];
  }
  for (let e = 0; e < dim; e++) mean[e] /= total;
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) continue;
    for (let e = 0; e < dim; e++) {
      const d = lo[e] + step[e] * codes[b + e] - mean[e];
      m2[e] += d * d;
    }
  }
  return Float64Array.from(m2, (v) => (total > 0 && v > 0 ? total / v : 0));
}

function normalizedEuclidean(t, o, out, inv) {
  const { n, dim, codes, nan, step } = t;
  const c0 = offsets(t, o);
  for (let i = 0, b = 0; i < n; i++, b += dim) {
    if (nan[i]) {
      out[i] = NaN;
      continue;
    }
    let s = 0;
    for (let e = 0; e < dim; e++) {
      const d = c0[e] + step[e] * codes[b + e];
      s += d * d * inv[e]; // inv[e] = 0 skips a constant element
    }
    out[i] = Math.sqrt(s);
  }
}

// ---------------------------------------------------------------------------------------
// The same kernels compiled for one click: the loop over a vertex's elements unrolled and
// every constant (weights, the reference, the quantization) written into the code. The
// arithmetic is that of the loops above, operation for operation; a JavaScript engine runs
// it two to three times faster, which is what lets a click on a million vertices stay
// within 100 ms. A page whose Content-Security-Policy forbids compiling code gets the loops.

const literal = (v) => String(v); // the shortest text that reads back as the same double

/** The code of the kernel of `opt` for `reference`, or null where the loops serve as well. */
function kernelSource(t, o, opt, cache) {
  const { dim, step, lo } = t;
  const x = (e, c) => `(${literal(c)} + ${literal(step[e])} * codes[b + ${e}])`; // c + step·code
  const c0 = offsets(t, o);
  // Where o_e lies on the column's grid (the clicked vertex's own value does; the steps are
  // powers of two), x_e − o_e is (code − o's code)·step, with the step folded into the
  // constants that multiply it: the same numbers bit for bit (scaling by a power of two is
  // exact), two operations fewer per element.
  const gridCode = (e) => {
    if (!(step[e] > 0) || !Number.isInteger(Math.log2(step[e])) || !Number.isInteger(lo[e] / step[e])) return null;
    const k = (o[e] - lo[e]) / step[e];
    return Number.isInteger(k) && Math.abs(k) < 2 ** 31 ? k : null;
  };
  const xo = (e) => (gridCode(e) === null ? x(e, c0[e]) : `(codes[b + ${e}] - ${gridCode(e)}) * ${literal(step[e])}`);
  const lines = [];
  let result;
  if (opt.kind === 'pnorm') {
    const w = opt.weighted ? t.blocks.flatMap((bl) => scaleWeights(bl.letter, bl.count)) : new Array(dim).fill(1);
    const p = opt.p;
    lines.push('let s = 0, d;');
    for (let e = 0; e < dim; e++) {
      const d = xo(e), we = literal(w[e]), k = gridCode(e);
      if (p === Infinity) lines.push(`s = Math.max(s, ${we} * Math.abs(${d}));`);
      else if (p === 1) lines.push(`s += ${we} * Math.abs(${d});`);
      else if (p === 2 && k !== null) lines.push(`d = codes[b + ${e}] - ${k}; s += ${literal(w[e] * step[e] * step[e])} * d * d;`);
      else if (p === 2) lines.push(`d = ${d}; s += ${we} * d * d;`);
      else if (p <= 64 && Math.floor(2 * p) === 2 * p) lines.push(`d = Math.abs(${d}); s += ${we} * ${powerSource('d', p)};`);
      else lines.push(`s += ${we} * Math.fround(Math.fround(Math.abs(${d})) ** ${literal(Math.fround(p))});`);
    }
    result = p === Infinity || p === 1 ? 's' : p === 2 ? 'Math.sqrt(s)' : `s ** ${literal(1 / p)}`;
  } else if (opt.kind === 'mahalanobis') {
    lines.push('let q = 0, t, d;');
    let offset = 0;
    for (const bl of t.blocks) {
      if (bl.letter === 'V' || bl.letter === 'P') {
        lines.push('t = 0;');
        for (let j = bl.count; j >= 1; j--) {
          const e = offset + j - 1;
          const a = bl.letter === 'V' ? 3 * j * j - 3 * j + 1 : 2 * j - 1;
          const ib = 1 / (bl.letter === 'V' ? j * j * j : j * j);
          const k = gridCode(e);
          if (k === null) lines.push(`d = ${x(e, c0[e])}; t += d * ${literal(ib)}; q += d * ${literal(a)} * t;`);
          else lines.push(`d = codes[b + ${e}] - ${k}; t += d * ${literal(step[e] * ib)}; q += d * ${literal(step[e] * a)} * t;`);
        }
      } else {
        for (let e = offset; e < offset + bl.count; e++) lines.push(`d = ${xo(e)}; q += d * d;`);
      }
      offset += bl.count;
    }
    result = 'q >= 0 ? Math.sqrt(q) : -Math.sqrt(-q)';
  } else if (opt.kind === 'cosine' || opt.kind === 'tanimoto') {
    const flat = flatReference(t);
    const oc = o.map((v, e) => v - flat[e]);
    if (oc.every((v) => v === 0)) return null; // the loops say why it is undefined
    let oo = 0;
    for (const v of oc) oo += v * v;
    lines.push('let xo = 0, xx = 0, c;');
    for (let e = 0; e < dim; e++) lines.push(`c = ${x(e, lo[e] - flat[e])}; xo += c * ${literal(oc[e])}; xx += c * c;`);
    result = opt.kind === 'cosine' ? `xx > 0 ? xo / (Math.sqrt(xx) * ${literal(Math.sqrt(oo))}) : NaN`
      : `(xx + ${literal(oo)} - xo) > 0 ? xo / (xx + ${literal(oo)} - xo) : NaN`;
  } else if (opt.kind === 'neuclid') {
    if (!cache.inverseVariances) cache.inverseVariances = inverseVariances(t);
    const inv = cache.inverseVariances;
    lines.push('let s = 0, d;');
    for (let e = 0; e < dim; e++) if (inv[e] !== 0) lines.push(`d = ${xo(e)}; s += d * d * ${literal(inv[e])};`);
    result = 'Math.sqrt(s)';
  } else if (opt.kind === 'correlation') {
    if (o.every((v) => v === o[0])) return null;
    let mo = 0;
    for (const v of o) mo += v;
    mo /= dim;
    const oc = o.map((v) => v - mo);
    let oo = 0;
    for (const v of oc) oo += v * v;
    for (let e = 0; e < dim; e++) lines.push(`const x${e} = ${x(e, lo[e])};`);
    lines.push(`if (${Array.from({ length: dim - 1 }, (_, e) => `x${e + 1} === x0`).join(' && ') || 'true'}) { out[i] = NaN; shown[i] = ${literal(MISSING)}; undefinedCount++; continue; }`);
    lines.push(`let sum = 0; ${Array.from({ length: dim }, (_, e) => `sum += x${e};`).join(' ')}`);
    lines.push(`const mx = sum / ${dim}; let xo = 0, xx = 0, c;`);
    for (let e = 0; e < dim; e++) lines.push(`c = x${e} - mx; xo += c * ${literal(oc[e])}; xx += c * c;`);
    result = `xo / Math.sqrt(xx * ${literal(oo)})`;
  } else if (opt.kind === 'autocorrelation') {
    const spans = [];
    let offset = 0;
    for (const bl of t.blocks) {
      if (bl.count >= 2) spans.push([offset, offset + bl.count]);
      offset += bl.count;
    }
    if (!spans.length) return null;
    lines.push('let sumR = 0, sum, mean, prev, cur, num, den;');
    for (const [begin, end] of spans) {
      for (let j = begin; j < end; j++) lines.push(`const d${j} = ${xo(j)};`);
      lines.push(`if (${Array.from({ length: end - begin - 1 }, (_, k) => `d${begin + k + 1} === d${begin}`).join(' && ')}) { out[i] = NaN; shown[i] = ${literal(MISSING)}; undefinedCount++; continue; }`);
      lines.push(`sum = 0; ${Array.from({ length: end - begin }, (_, k) => `sum += d${begin + k};`).join(' ')}`);
      lines.push(`mean = sum / ${end - begin}; prev = d${begin} - mean; num = 0; den = prev * prev;`);
      for (let j = begin + 1; j < end; j++) lines.push(`cur = d${j} - mean; num += prev * cur; den += cur * cur; prev = cur;`);
      lines.push('sumR += num / den;');
    }
    result = `sumR / ${spans.length}`;
  } else {
    return null;
  }
  return `let undefinedCount = 0;
for (let i = 0, b = 0; i < ${t.n}; i++, b += ${dim}) {
  if (nan[i] === 1) { out[i] = NaN; shown[i] = ${literal(MISSING)}; undefinedCount++; continue; }
  ${lines.join('\n  ')}
  const f = ${result};
  out[i] = f;
  if (f === f) shown[i] = f;
  else { shown[i] = ${literal(MISSING)}; undefinedCount++; }
}
return undefinedCount;`;
}

/** Whether kernels may be compiled (false: a Content-Security-Policy forbids it, or a test asks for the loops). */
export const compiling = { allowed: true };

/** What stands in for NaN in `shown` (a GPU's shader cannot be relied on to test for NaN). */
export const MISSING = 3.0e38;

/**
 * f per vertex into `out` (a Float32Array, as msii metric writes it), NaN where a vertex
 * has a NaN element or the metric is undefined there, and the same into `shown` with
 * MISSING for NaN. Returns how many are NaN. `cache` keeps what does not depend on the
 * reference (the variances) for this table.
 */
export function computeMetric(table, reference, name, p, out, shown, cache) {
  const opt = metricOptions(name, p);
  if (reference.length !== table.dim) throw new Error('the reference does not fit the feature table');
  if (compiling.allowed) {
    const source = kernelSource(table, reference, opt, cache);
    if (source) {
      let kernel = null;
      try {
        kernel = new Function('codes', 'nan', 'out', 'shown', source); // eslint-disable-line no-new-func
      } catch {
        compiling.allowed = false;
      }
      if (kernel) return kernel(table.codes, table.nan, out, shown);
    }
  }
  computeWithLoops(table, reference, opt, out, cache);
  let undefinedCount = 0;
  for (let i = 0; i < out.length; i++) {
    const f = out[i];
    if (f === f) shown[i] = f;
    else {
      shown[i] = MISSING;
      undefinedCount++;
    }
  }
  return undefinedCount;
}

function computeWithLoops(table, reference, opt, out, cache) {
  switch (opt.kind) {
    case 'pnorm': pNorm(table, reference, opt, out); break;
    case 'mahalanobis': mahalanobis(table, reference, out); break;
    case 'cosine':
      // A flat vertex (x̃ = 0) has no direction: NaN.
      centredSimilarity(table, reference, 'the cosine similarity', out, (xo, xx, oo) => (xx > 0 ? xo / (Math.sqrt(xx) * Math.sqrt(oo)) : NaN));
      break;
    case 'tanimoto':
      centredSimilarity(table, reference, 'the Tanimoto similarity', out, (xo, xx, oo) => {
        const den = xx + oo - xo;
        return den > 0 ? xo / den : NaN;
      });
      break;
    case 'correlation': correlation(table, reference, out); break;
    case 'autocorrelation': autoCorrelation(table, reference, out); break;
    case 'neuclid':
      if (!cache.inverseVariances) cache.inverseVariances = inverseVariances(table);
      normalizedEuclidean(table, reference, out, cache.inverseVariances);
      break;
    default: throw new Error(`unknown metric kind ${opt.kind}`);
  }
}
