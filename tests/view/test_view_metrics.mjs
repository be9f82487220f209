// The page's metrics (tools/view/web/metrics.js) against `msii metric`, for every metric,
// at every vertex of a generated tablet, on the data of the view folder as the page reads
// it (data.js, run by node: the same inflating and decoding); and the kernels compiled per
// click against the plain loops, which must agree bit for bit.
//
//   node tests/view/test_view_metrics.mjs --msii build/tools/msii --samples build/samples/msii-samples
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { decodeSection } from '../../tools/view/web/data.js';
import { METRICS, MISSING, compiling, computeMetric, featureTable, vertexReference } from '../../tools/view/web/metrics.js';
import { Checks, readPly, run } from './support.mjs';

const args = Object.fromEntries(process.argv.slice(2).join(' ').split(/\s*--/).filter(Boolean).map((a) => a.split(' ')));
const msii = path.resolve(args.msii), samples = path.resolve(args.samples);
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'msii-view-metrics-'));
const checks = new Checks();

/**
 * How far the page's f may be from msii metric's for the norms and Eq. 11, given that each
 * element is within step_e/2 of the file's value (so x − o within step_e): ‖δ‖_p ≤ ‖δ‖_1
 * (weights ≤ 1), and for Eq. 11 √λmax(S)·‖δ‖₂ with λmax(S) < 4 for the W of N = 16
 * (Gershgorin; S the symmetric part of W).
 */
function tolerance(metric, steps) {
  if (metric === 'mahalanobis') return 2 * Math.sqrt(steps.reduce((s, v) => s + v * v, 0)) + 1e-6;
  return steps.reduce((s, v) => s + v, 0) + 1e-6;
}

try {
  run(samples, ['tablet', '--width', '8', '--height', '6', '--spacing', '0.06', '-q', '-o', path.join(work, 'scan.ply')]);
  run(msii, ['compute', path.join(work, 'scan.ply'), '-r', '1', '-q', '-o', path.join(work, 'scan.msii.ply')]);
  run(msii, ['view', path.join(work, 'scan.msii.ply'), '--no-serve', '-q']);
  const folder = path.join(work, 'scan.msii.view');
  const header = JSON.parse(fs.readFileSync(path.join(folder, 'data.json'), 'utf8'));
  const bin = fs.readFileSync(path.join(folder, 'data.bin'));
  const buffer = bin.buffer.slice(bin.byteOffset, bin.byteOffset + bin.length);
  const columns = new Map();
  for (const c of header.columns) columns.set(c.name, { q: await decodeSection(header, buffer, c.section), lo: c.lo, step: c.step });
  const ply = readPly(path.join(work, 'scan.msii.ply'));
  checks.ok(ply.count === header.items, `the view has the PLY's ${ply.count} vertices`);
  // Every decoded value within the stated precision of the PLY's.
  let values = 0;
  for (const c of header.columns) {
    const q = columns.get(c.name).q, v = ply.columns[c.name];
    let worst = 0;
    for (let i = 0; i < ply.count; i++) {
      if (Number.isNaN(v[i])) checks.ok(q[i] === 65535, `${c.name} at ${i}: NaN is coded 65535`);
      else worst = Math.max(worst, Math.abs(c.lo + q[i] * c.step - v[i]));
      values++;
    }
    checks.ok(worst <= c.max_error * (1 + 1e-9) + 1e-12, `${c.name}: decoded within ${c.max_error} (worst ${worst})`);
  }
  checks.note(`${values} decoded values within their column's max_error`);

  // The reference: the deepest point of a wedge, inside the tablet.
  const q = ply.columns.quality;
  let ref = 0;
  for (let i = 0; i < ply.count; i++) if (q[i] > q[ref]) ref = i;
  const names = METRICS.map(([k]) => k);
  for (const letters of ['V', 'VSPL']) {
    const table = featureTable(letters, columns, ply.count);
    const reference = vertexReference(table, ref);
    const steps = Array.from(table.step);
    run(msii, ['metric', path.join(work, 'scan.msii.ply'), '--reference', `vertex:${ref}`, '--metric', names.join(','),
      '--p', '3', '--invariants', [...letters].join(','), '-q', '--overwrite', '-o', path.join(work, `${letters}.metric.ply`)]);
    const expected = readPly(path.join(work, `${letters}.metric.ply`)).columns;
    for (const metric of names) {
      const a = new Float32Array(ply.count), sa = new Float32Array(ply.count);
      const b = new Float32Array(ply.count), sb = new Float32Array(ply.count);
      compiling.allowed = true;
      const undefinedA = computeMetric(table, reference, metric, 3, a, sa, {});
      compiling.allowed = false;
      const undefinedB = computeMetric(table, reference, metric, 3, b, sb, {});
      compiling.allowed = true;
      checks.ok(undefinedA === undefinedB, `${metric} of ${letters}: as many undefined from the kernel as from the loops (${undefinedA}, ${undefinedB})`);
      let same = 0, compared = 0, worst = 0, worstRelative = 0;
      const f = expected[`f_${metric}`];
      const diffs = [];
      for (let i = 0; i < ply.count; i++) {
        if ((Object.is(a[i], b[i]) || a[i] === b[i]) && sa[i] === sb[i]) same++;
        checks.ok(Number.isNaN(a[i]) ? sa[i] === Math.fround(MISSING) : sa[i] === a[i], `${metric} of ${letters} at ${i}: the GPU's copy holds f (or MISSING)`);
        if (Number.isNaN(f[i]) || Number.isNaN(a[i])) {
          checks.ok(Number.isNaN(f[i]) === Number.isNaN(a[i]) || Math.abs(f[i]) < 1e-3, `${metric} of ${letters} at ${i}: NaN in both (${a[i]}, ${f[i]})`);
          continue;
        }
        const d = Math.abs(a[i] - f[i]);
        diffs.push(d);
        worst = Math.max(worst, d);
        worstRelative = Math.max(worstRelative, d / Math.max(1e-3, Math.abs(f[i])));
        if (/^(mahalanobis|l(1|2|inf|p)w?)$/.test(metric)) {
          const bound = tolerance(metric, steps) + 1e-6 * Math.abs(f[i]);
          checks.ok(d <= bound, `${metric} of ${letters} at vertex ${i}: ${a[i]} vs ${f[i]} (bound ${bound})`);
        }
        compared++;
      }
      checks.ok(same === ply.count, `${metric} of ${letters}: the compiled kernel equals the loops at all ${ply.count} vertices (${same})`);
      diffs.sort((x, y) => x - y);
      const median = diffs[Math.floor(diffs.length / 2)];
      // The similarities and the normalised distance have no simple bound (centring cancels
      // most of a flat vertex's value, and its quantization error remains): their typical
      // difference is that error's, below 10⁻³; a wrong formula gives differences near 1.
      checks.ok(median < 1e-3, `${metric} of ${letters}: median difference ${median}`);
      checks.ok(compared > 0.9 * ply.count, `${metric} of ${letters}: ${compared} vertices compared`);
      checks.note(`${metric.padEnd(15)} ${letters.padEnd(4)} ${compared} vertices: median |diff| ${median.toExponential(1)}, largest ${worst.toExponential(1)} (relative ${worstRelative.toExponential(1)})`);
    }
  }
  console.log(`ok: ${checks.count} checks`);
} catch (e) {
  console.error(e.message);
  process.exitCode = 1;
} finally {
  fs.rmSync(work, { recursive: true, force: true });
}
