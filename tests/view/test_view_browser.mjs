// The page of `msii view` in a real browser (Debian's Chromium, software WebGL), on a small
// generated tablet and a generated DEM: it draws them in msii render's colours, a click
// shows the feature vector of the file, the distances equal `msii metric`'s, a link keeps
// the view, the PNG is saved, and the server gives nothing outside its folder.
//
//   node tests/view/test_view_browser.mjs --msii build/tools/msii --samples build/samples/msii-samples
//        [--chromium /usr/bin/chromium] [--screenshots DIR] [--keep]
//        [--browser firefox [--firefox /usr/bin/firefox-esr]]   (Debian's firefox-esr, under xvfb-run -a)
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { Checks, decodePng, launchBrowser, pixel, readPly, run, startView, tableColor } from './support.mjs';

const args = Object.fromEntries(process.argv.slice(2).join(' ').split(/\s*--/).filter(Boolean).map((a) => {
  const [k, ...v] = a.split(' ');
  return [k, v.join(' ') || true];
}));
const msii = path.resolve(args.msii);
const samples = path.resolve(args.samples);
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'msii-view-test-'));
const shots = args.screenshots ? path.resolve(args.screenshots) : null;
if (shots) fs.mkdirSync(shots, { recursive: true });
const checks = new Checks();
const VIEWPORT = { width: 1100, height: 720 };

/** The page, ready: every column read and the link's state applied. */
async function openPage(browser, url) {
  const page = await browser.newPage({ viewport: VIEWPORT, deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(url);
  await page.evaluate(() => window.msiiView.ready);
  page.errors = errors;
  return page;
}

async function screenshot(page, name) {
  const png = await page.screenshot();
  if (shots && name) fs.writeFileSync(path.join(shots, name), png);
  return decodePng(png);
}

/** Not blank: most of the drawing area is drawn, in many colours. */
function checkDrawn(img, what) {
  let drawn = 0;
  const colours = new Set();
  const width = img.width - 330; // left of the panel
  for (let y = 0; y < img.height; y += 2) {
    for (let x = 0; x < width; x += 2) {
      const [r, g, b] = pixel(img, x, y);
      if (r < 250 || g < 250 || b < 250) drawn++;
      colours.add((r << 16) | (g << 8) | b);
    }
  }
  const share = drawn / ((img.height / 2) * (width / 2));
  checks.note(`${what}: ${(100 * share).toFixed(0)} % of the view drawn, ${colours.size} colours`);
  checks.ok(share > 0.3, `${what}: the view is drawn (${share})`);
  checks.ok(colours.size > 50, `${what}: in many colours (${colours.size})`);
}

function near3(actual, expected, tolerance, what) {
  checks.ok(actual.every((v, k) => Math.abs(v - expected[k]) <= tolerance), `${what}: colour ${actual} vs ${expected.map((v) => v.toFixed(1))}`);
}

/** Waits until the page has computed a distance after `before` with this state. */
async function waitForDistance(page, before, wanted) {
  await page.waitForFunction(([v, w]) => {
    const s = window.msiiView.state();
    return window.msiiView.distanceVersion > v && Object.entries(w).every(([k, x]) => s[k] === x);
  }, [before, wanted]);
}

/** An upper bound of |f(x̂, ô) − f(x, o)| for values within step/2 of the file's (so δ_e ≤ step_e). */
function metricBound(metric, letters, header) {
  const blocks = [...letters].map((l) => header.columns.filter((c) => new RegExp(`^${l}_\\d+$`).test(c.name)));
  if (metric === 'l2w') {
    let s = 0;
    blocks.forEach((cols, b) => {
      const n = cols.length, l = letters[b];
      cols.forEach((c, k) => {
        const j = k + 1;
        const w = l === 'V' ? (3 * j * j - 3 * j + 1) / n ** 3 : l === 'P' ? (2 * j - 1) / n ** 2 : 1 / n;
        s += w * c.step * c.step;
      });
    });
    return Math.sqrt(s);
  }
  // Mahalanobis: f = |S^½ d| with S the symmetric part of W (Eq. 9–11), so the error is at
  // most √λmax(S)·|δ|; λmax by Gershgorin.
  let lambda = 0, delta = 0;
  blocks.forEach((cols, b) => {
    const n = cols.length, l = letters[b];
    const w = (j, k) => (j > k ? 0 : l === 'V' ? (3 * j * j - 3 * j + 1) / k ** 3 : l === 'P' ? (2 * j - 1) / k ** 2 : j === k ? 1 : 0);
    for (let j = 1; j <= n; j++) {
      let row = 0;
      for (let k = 1; k <= n; k++) row += Math.abs((w(j, k) + w(k, j)) / 2);
      lambda = Math.max(lambda, row);
    }
    for (const c of cols) delta += c.step * c.step;
  });
  return Math.sqrt(lambda) * Math.sqrt(delta);
}

/** GET or another method of a raw path (not normalised, as a browser would) from the server. */
function request(url, rawPath, { method = 'GET', host } = {}) {
  const u = new URL(url);
  return new Promise((resolve, reject) => {
    const headers = host ? { Host: host } : {};
    const req = http.request({ host: u.hostname, port: u.port, path: rawPath, method, headers }, (res) => {
      let size = 0;
      res.on('data', (d) => { size += d.length; });
      res.on('end', () => resolve({ status: res.statusCode, type: res.headers['content-type'], size, length: res.headers['content-length'] }));
    });
    req.on('error', reject);
    req.end();
  });
}

async function testServer(url, folder) {
  const outside = path.join(work, 'scan.msii.ply');
  fs.symlinkSync(outside, path.join(folder, 'link-out'));
  fs.symlinkSync('../scan.msii.ply', path.join(folder, 'link-relative'));
  fs.symlinkSync(work, path.join(folder, 'dir-out'));
  fs.symlinkSync('data.json', path.join(folder, 'link-in'));
  const refused = ['/../scan.msii.ply', '/%2e%2e/scan.msii.ply', '/%2E%2E%2Fscan.msii.ply', '/three/..%2f..%2fscan.msii.ply',
    '//etc/passwd', '/%2fetc/passwd', `/${outside}`, '/link-out', '/link-relative', '/dir-out/scan.msii.ply',
    '/no-such-file', '/three', '/index.html%00.png', '/..\\scan.msii.ply'];
  for (const p of refused) {
    const r = await request(url, p);
    checks.ok(r.status === 404, `${p} is refused with 404 (got ${r.status})`);
  }
  const types = { '/': 'text/html; charset=utf-8', '/viewer.js': 'text/javascript; charset=utf-8', '/viewer.css': 'text/css; charset=utf-8',
    '/data.json': 'application/json', '/data.bin': 'application/octet-stream', '/link-in': 'application/json' };
  for (const [p, type] of Object.entries(types)) {
    const r = await request(url, p);
    checks.ok(r.status === 200 && r.type === type, `${p}: 200 ${type} (got ${r.status} ${r.type})`);
  }
  const head = await request(url, '/data.bin', { method: 'HEAD' });
  checks.ok(head.status === 200 && head.size === 0 && Number(head.length) === fs.statSync(path.join(folder, 'data.bin')).size,
    `HEAD /data.bin: 200 with the length and no body (${head.status}, ${head.length}, ${head.size})`);
  for (const method of ['POST', 'PUT', 'DELETE']) {
    const r = await request(url, '/data.json', { method });
    checks.ok(r.status === 405, `${method} is refused with 405 (got ${r.status})`);
  }
  const rebound = await request(url, '/data.json', { host: 'attacker.example:80' });
  checks.ok(rebound.status === 403, `a request for another host name gets 403 (got ${rebound.status})`);
  for (const f of ['link-out', 'link-relative', 'dir-out', 'link-in']) fs.unlinkSync(path.join(folder, f));
  checks.note(`server: ${refused.length} paths outside the folder refused`);
}

async function testMesh(browser) {
  run(samples, ['tablet', '--width', '12', '--height', '9', '--spacing', '0.06', '-q', '-o', path.join(work, 'scan.ply')]);
  run(msii, ['compute', path.join(work, 'scan.ply'), '-r', '1', '-q', '-o', path.join(work, 'scan.msii.ply')]);
  const ply = readPly(path.join(work, 'scan.msii.ply'));
  const server = await startView(msii, [path.join(work, 'scan.msii.ply'), '-q']);
  const folder = path.join(work, 'scan.msii.view');
  try {
    await testServer(server.url, folder);
    const header = JSON.parse(fs.readFileSync(path.join(folder, 'data.json'), 'utf8'));
    const plySize = fs.statSync(path.join(work, 'scan.msii.ply')).size;
    const folderSize = fs.readdirSync(folder, { recursive: true }).map((f) => fs.statSync(path.join(folder, f)))
      .filter((s) => s.isFile()).reduce((s, f) => s + f.size, 0);
    checks.note(`mesh: ${ply.count} vertices; PLY ${(plySize / 1e6).toFixed(1)} MB, folder ${(folderSize / 1e6).toFixed(1)} MB`);

    // Vertices to look at: the deepest wedge point inside the tablet, a flat one, one in between.
    const { x, y, z, quality } = ply.columns;
    const [x0, y0] = [Math.min(...x), Math.min(...y)], [x1, y1] = [Math.max(...x), Math.max(...y)];
    const inner = [];
    for (let i = 0; i < ply.count; i++) {
      if (x[i] > x0 + 0.25 * (x1 - x0) && x[i] < x1 - 0.25 * (x1 - x0) && y[i] > y0 + 0.25 * (y1 - y0) && y[i] < y1 - 0.25 * (y1 - y0)) inner.push(i);
    }
    inner.sort((a, b) => quality[a] - quality[b]);
    const wedge = inner[inner.length - 1], flat = inner[Math.floor(inner.length / 2)], between = inner[Math.floor(inner.length * 0.97)];

    // 1. The page draws the scan, and the pixel of a vertex has the colour of its value.
    let page = await openPage(browser, `${server.url}#shade=0`);
    checkDrawn(await screenshot(page, null), 'tablet, quality');
    const c = header.mesh.center, v = header.mesh.view;
    const diag = Math.hypot(...header.mesh.bbox_max.map((m, k) => m - header.mesh.bbox_min[k]));
    const range = await page.evaluate(() => window.msiiView.range());
    const expectedRange = header.columns.find((col) => col.name === 'quality').percentiles;
    checks.near(range[0], expectedRange[0], 1e-12, 'the colour range is the 1st percentile');
    checks.near(range[1], expectedRange[1], 1e-12, 'the colour range is the 99th percentile');
    for (const i of [wedge, flat, between]) {
      const t = [x[i] - c[0], y[i] - c[1], z[i] - c[2]];
      const cam = [...t.map((tk, k) => tk + 3 * diag * v.normal[k]), ...t, 20];
      await page.evaluate((h) => { location.hash = h; }, `cam=${cam.join(',')}&shade=0&show=quality`);
      await page.waitForFunction((target) => window.msiiView.state().camera.slice(3, 6)
        .every((v, k) => Math.abs(v - target[k]) < 1e-6), t);
      await page.evaluate(() => window.msiiView.render());
      const at = await page.evaluate((k) => window.msiiView.screenOf(k), i);
      const img = await screenshot(page, null);
      const want = tableColor(header.colormaps.viridis, (quality[i] - range[0]) / (range[1] - range[0]));
      near3(pixel(img, at.x, at.y), want, 3, `vertex ${i}'s pixel (${at.x.toFixed(1)}, ${at.y.toFixed(1)}), quality ${quality[i]}`);
    }
    checks.note('mesh: 3 vertices drawn in the colour of their value');
    await page.close();

    // 2. A click on a vertex shows its feature vector, that of the PLY within the quantization.
    page = await openPage(browser, `${server.url}`);
    checkDrawn(await screenshot(page, 'view-tablet-quality.png'), 'tablet, quality, shaded');
    const before = await page.evaluate(() => window.msiiView.distanceVersion);
    const at = await page.evaluate((k) => window.msiiView.screenOf(k), wedge);
    await page.mouse.click(at.x, at.y);
    await waitForDistance(page, before, { sel: wedge, metric: 'mahalanobis', inv: 'V' });
    const shown = await page.$$eval('#vector td[data-name]', (tds) => tds.map((td) => [td.dataset.name, Number(td.dataset.value)]));
    let compared = 0;
    for (const [name, value] of shown) {
      const col = header.columns.find((cl) => cl.name === name);
      checks.near(value, ply.columns[name][wedge], col.max_error + 1e-9, `vertex ${wedge}'s ${name}`);
      compared++;
    }
    const features = ply.names.filter((n) => /^[VSPL]_\d\d$/.test(n)).length;
    checks.ok(compared >= features && features === 64, `the click showed all ${features} feature values (${compared} compared)`);
    const curves = await page.$$eval('#curves svg path.vector', (ps) => ps.map((p) => p.getAttribute('d').split(/[ML]/).filter(Boolean).length));
    checks.ok(curves.length === 4 && curves.every((n) => n === 16), `four curves of 16 points are drawn (${curves})`);
    checks.note(`mesh: a click on vertex ${wedge} showed its ${compared} values within the quantization`);
    await screenshot(page, 'view-tablet-click.png');

    // 3. The distance colouring equals msii metric's values at 10 vertices.
    const sample = Array.from({ length: 10 }, (_, k) => Math.floor(((k + 0.5) / 10) * ply.count));
    sample[0] = wedge;
    const compare = async (metric, letters, file) => {
      run(msii, ['metric', path.join(work, 'scan.msii.ply'), '--reference', `vertex:${wedge}`, '--metric', metric,
        '--invariants', [...letters].join(','), '-q', '--overwrite', '-o', path.join(work, file)]);
      const f = readPly(path.join(work, file)).columns[`f_${metric}`];
      const bound = metricBound(metric, letters, header) + 1e-6;
      const page_ = await page.evaluate((s) => s.map((i) => window.msiiView.distanceAt(i)), sample);
      sample.forEach((i, k) => checks.near(page_[k], f[i], bound + 1e-6 * Math.abs(f[i]), `${metric} of ${letters} at vertex ${i}`));
      checks.note(`mesh: ${metric} of ${letters} equals msii metric's at ${sample.length} vertices (within ${bound.toExponential(1)})`);
    };
    await compare('mahalanobis', 'V', 'm1.metric.ply');
    let version = await page.evaluate(() => window.msiiView.distanceVersion);
    await page.selectOption('#metric', 'l2w');
    await waitForDistance(page, version, { metric: 'l2w' });
    for (const l of 'SPL') {
      version = await page.evaluate(() => window.msiiView.distanceVersion);
      await page.check(`#inv input[value="${l}"]`);
      await waitForDistance(page, version, { inv: `V${'SPL'.slice(0, 'SPL'.indexOf(l) + 1)}` });
    }
    await compare('l2w', 'VSPL', 'm2.metric.ply');
    await screenshot(page, 'view-tablet-distance.png');

    // 4. The link keeps the view: the same state and the same picture in a new page.
    await page.waitForTimeout(600); // the address follows the view within 300 ms
    const link = page.url();
    const first = await screenshot(page, null);
    const again = await openPage(browser, link);
    const s1 = await page.evaluate(() => window.msiiView.state()), s2 = await again.evaluate(() => window.msiiView.state());
    for (const k of ['sel', 'metric', 'inv', 'show', 'cmap']) checks.ok(s1[k] === s2[k], `the link keeps ${k} (${s1[k]} / ${s2[k]})`);
    checks.near(s2.thr, s1.thr, 1e-6 * Math.abs(s1.thr), 'the link keeps the threshold');
    checks.ok(s1.camera.every((vv, k) => Math.abs(vv - s2.camera[k]) <= 1e-5 * (1 + Math.abs(vv))), 'the link keeps the camera');
    const second = await screenshot(again, null);
    let differ = 0, pixels = 0;
    for (let y = 0; y < first.height; y++) {
      for (let x = 0; x < first.width - 330; x++, pixels++) {  // the view, not the panel (focus rings)
        const k = (y * first.width + x) * 4;
        if ([0, 1, 2].some((c) => Math.abs(first.rgba[k + c] - second.rgba[k + c]) > 2)) differ++;
      }
    }
    checks.ok(differ < 0.001 * pixels, `the link's view looks the same (${differ} of ${pixels} pixels differ)`);
    checks.note(`mesh: the link ${link.slice(link.indexOf('#'))} gives the same view`);
    await again.close();

    // 5. The PNG of the view.
    let name, png;
    if (args.browser !== 'firefox') {
      const [download] = await Promise.all([page.waitForEvent('download'), page.click('#png')]);
      name = download.suggestedFilename();
      png = decodePng(fs.readFileSync(await download.path()));
    } else {  // WebDriver BiDi reports no downloads: the link the page clicks, caught in the page
      const got = await page.evaluate(() => new Promise((resolve) => {
        HTMLAnchorElement.prototype.click = function click() {
          fetch(this.href).then((r) => r.arrayBuffer()).then((b) => resolve({ name: this.download, bytes: Array.from(new Uint8Array(b)) }));
        };
        document.getElementById('png').click();
      }));
      name = got.name;
      png = decodePng(Buffer.from(got.bytes));
    }
    checks.ok(name === 'scan.msii.view.png', `the PNG is named ${name}`);
    checks.ok(png.width === VIEWPORT.width - 330 && png.height > 600, `the PNG has the view's size (${png.width} x ${png.height})`);
    checks.ok(page.errors.length === 0, `no errors on the page (${page.errors.join('; ')})`);
    const timings = await page.evaluate(() => window.msiiViewTimings);
    checks.note(`mesh timings (ms): first frame ${timings.firstFrame.toFixed(0)}, clicks ${timings.clicks.map((t) => t.work.toFixed(0)).join(' ')}`);
    await page.close();
  } finally {
    const { code } = await server.stop();
    checks.ok(code === 0, `msii view ends with status 0 on Ctrl-C (got ${code})`);
  }
}

/** gdallocationinfo's values of band `band` of `file` at cells [col, row] (unscaled by `scale`). */
function cellValues(file, band, cells, scale = 1) {
  const out = run('gdallocationinfo', ['-valonly', '-b', String(band), file], { input: cells.map(([cl, rw]) => `${cl} ${rw}`).join('\n') + '\n' });
  const values = out.trim().split('\n').map((s) => Number(s) * scale);
  checks.ok(values.length === cells.length && values.every(Number.isFinite), `gdallocationinfo read ${cells.length} values of ${path.basename(file)}`);
  return values;
}

async function testDem(browser) {
  const dem = path.join(work, 'dem.tif');
  run(samples, ['terrain', '--geotiff', '--width', '40', '--height', '30', '--spacing', '0.5', '--relief', '3', '--hill-width', '5', '-q', '-o', dem]);
  run(msii, ['compute', dem, '-r', '4', '--bands', 'quality,V', '-q']);
  const features = path.join(work, 'dem.msii.tif');
  const info = JSON.parse(run('gdalinfo', ['-json', features]));
  const bandOf = Object.fromEntries(info.bands.map((b, k) => [b.description, { band: k + 1, scale: b.scale ?? 1 }]));
  const server = await startView(msii, [features, '-q']);
  try {
    const header = JSON.parse(fs.readFileSync(path.join(work, 'dem.msii.view', 'data.json'), 'utf8'));
    const { width, height, transform: t } = header.raster;
    checks.ok(header.kind === 'raster' && header.raster.heights, 'the DEM view is a raster with heights');
    let page = await openPage(browser, `${server.url}#shade=0`);
    checkDrawn(await screenshot(page, null), 'DEM, quality');
    const range = await page.evaluate(() => window.msiiView.range());
    const cells = [[10, 7], [40, 30], [61, 44], [25, 50]];
    const quality = cellValues(features, bandOf.quality.band, cells, bandOf.quality.scale);
    for (const [k, [col, row]] of cells.entries()) {
      const at = await page.evaluate((i) => window.msiiView.screenOf(i), row * width + col);
      const img = await screenshot(page, null);
      near3(pixel(img, at.x, at.y), tableColor(header.colormaps.viridis, (quality[k] - range[0]) / (range[1] - range[0])), 3,
        `cell (${col}, ${row})'s pixel, quality ${quality[k]}`);
    }
    checks.note(`DEM: ${cells.length} cells drawn in the colour of their value`);
    await page.close();

    page = await openPage(browser, server.url);
    await screenshot(page, 'view-dem-quality.png');
    const [col, row] = [40, 30];
    const cell = row * width + col;
    const before = await page.evaluate(() => window.msiiView.distanceVersion);
    const at = await page.evaluate((i) => window.msiiView.screenOf(i), cell);
    await page.mouse.click(at.x, at.y);
    await waitForDistance(page, before, { sel: cell });
    const shown = await page.$$eval('#vector td[data-name]', (tds) => tds.map((td) => [td.dataset.name, Number(td.dataset.value)]));
    let compared = 0;
    for (const [name, value] of shown) {
      const b = bandOf[name];
      const [want] = cellValues(features, b.band, [[col, row]], b.scale);
      const step = header.columns.find((cl) => cl.name === name).max_error;
      checks.near(value, want, step + 1e-6, `cell (${col}, ${row})'s ${name}`);
      compared++;
    }
    checks.ok(compared === 9, `the click on a cell showed quality and V at 8 radii (${compared} compared)`);
    await screenshot(page, 'view-dem-click.png');
    // The distance to that cell, against msii metric with the cell's point as the reference.
    const [z] = cellValues(dem, 1, [[col, row]]);
    const X = t[0] + (col + 0.5) * t[1] + (row + 0.5) * t[2], Y = t[3] + (col + 0.5) * t[4] + (row + 0.5) * t[5];
    run(msii, ['metric', features, '--reference', `point:${X},${Y},${z}`, '-q', '-o', path.join(work, 'dem.metric.tif')]);
    const sample = Array.from({ length: 10 }, (_, k) => [Math.floor((k * 7 + 3) % width), Math.floor((k * 11 + 5) % height)]);
    const want = cellValues(path.join(work, 'dem.metric.tif'), 2, sample);
    const got = await page.evaluate(([s, w]) => s.map(([cl, rw]) => window.msiiView.distanceAt(rw * w + cl)), [sample, width]);
    const bound = metricBound('mahalanobis', 'V', header) + 1e-5;
    sample.forEach(([cl, rw], k) => checks.near(got[k], want[k], bound + 1e-6 * Math.abs(want[k]), `DEM mahalanobis at cell (${cl}, ${rw})`));
    checks.note(`DEM: a click on cell (${col}, ${row}) showed its ${compared} values; the distances equal msii metric's at ${sample.length} cells`);
    checks.ok(page.errors.length === 0, `no errors on the DEM's page (${page.errors.join('; ')})`);
    await page.close();
  } finally {
    await server.stop();
  }

  // The default bands (V at R/4, R/2, 3R/4 and R) open too; a click says, as msii metric
  // does, that the metrics need every radius.
  run(msii, ['compute', dem, '-r', '4', '-q', '--raster-output', path.join(work, 'default.msii.tif')]);
  const other = await startView(msii, [path.join(work, 'default.msii.tif'), '-q']);
  try {
    const page = await openPage(browser, other.url);
    const at = await page.evaluate((i) => window.msiiView.screenOf(i), 30 * 80 + 40);
    await page.mouse.click(at.x, at.y);
    await page.waitForFunction(() => window.msiiView.state().sel !== null && document.getElementById('metric-note').textContent !== '');
    const note = await page.evaluate(() => document.getElementById('metric-note').textContent);
    checks.ok(/some radii only \(V_02, V_04, V_06, V_08\)/.test(note), `the default bands: a click explains the metrics (${note})`);
    checks.ok(page.errors.length === 0, `no errors on the page of the default bands (${page.errors.join('; ')})`);
    checks.note('DEM: the default bands open, and a click says the metrics need every radius');
    await page.close();
  } finally {
    await other.stop();
  }
}

const browser = await launchBrowser(args.browser || 'chromium', args.browser === 'firefox' ? args.firefox : args.chromium);
try {
  await testMesh(browser);
  await testDem(browser);
  console.log(`ok: ${checks.count} checks`);
} catch (e) {
  console.error(e.message);
  process.exitCode = 1;
} finally {
  await browser.close();
  if (!args.keep) fs.rmSync(work, { recursive: true, force: true });
  else console.log(`kept ${work}`);
}
