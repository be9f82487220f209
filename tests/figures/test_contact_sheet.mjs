// The contact sheet of a collection (`msii render A B C --layout fat-cross --output-dir D`,
// D/index.html) in a real browser (Debian's Chromium): it names the three scans and their
// sizes, its thumbnails load and share one scale (their sizes compare as the sheets' do),
// and each links to its full sheet, which loads too.
//
//   node tests/figures/test_contact_sheet.mjs --msii build/tools/msii --samples build/samples/msii-samples
//        [--chromium /usr/bin/chromium] [--screenshot FILE] [--keep]
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { Checks, launchBrowser, run } from '../view/support.mjs';

const args = Object.fromEntries(process.argv.slice(2).join(' ').split(/\s*--/).filter(Boolean).map((a) => {
  const [k, ...v] = a.split(' ');
  return [k, v.join(' ') || true];
}));
const msii = path.resolve(args.msii);
const samples = path.resolve(args.samples);
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'msii-sheets-test-'));
const checks = new Checks();

const scans = [
  ['small.ply', ['--width', '14', '--height', '20', '--thickness', '8']],
  ['middle.ply', ['--width', '20', '--height', '28']],
  ['large.ply', ['--width', '28', '--height', '40', '--thickness', '12']],
];
for (const [name, size] of scans)
  run(samples, ['rounded-tablet', '--spacing', '0.6', '--marks', '2,2,1,1,1,1', ...size, '-q', '-o', path.join(work, name)]);
const out = path.join(work, 'sheets');
run(msii, ['render', ...scans.map(([n]) => path.join(work, n)), '--layout', 'fat-cross', '--dpi', '100', '--labels',
  '-q', '--output-dir', out]);

const browser = await launchBrowser('chromium', args.chromium || null);
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(pathToFileURL(path.join(out, 'index.html')).href);
  await page.waitForLoadState('load');
  const entries = await page.$$eval('figure', (figures) => figures.map((f) => {
    const img = f.querySelector('img');
    return {
      caption: f.querySelector('figcaption').textContent,
      href: f.querySelector('a').getAttribute('href'),
      loaded: img.complete && img.naturalWidth > 0,
      width: img.naturalWidth,
      height: img.naturalHeight,
    };
  }));
  checks.ok(errors.length === 0, `no errors on the page: ${errors.join('; ')}`);
  checks.ok(entries.length === 3, `three scans listed (${entries.length})`);
  const sizes = {};
  for (const [name] of scans) {
    const e = entries.find((x) => x.caption.includes(name));
    checks.ok(e, `${name} is named`);
    checks.ok(e.loaded, `${name}: its thumbnail loads`);
    checks.ok(/\d+(\.\d+)? × \d+(\.\d+)? × \d+(\.\d+)? mm/.test(e.caption), `${name}: its size in mm (${e.caption})`);
    const sheet = path.join(out, e.href);
    checks.ok(fs.existsSync(sheet), `${name}: its link ${e.href} is a file`);
    const record = JSON.parse(fs.readFileSync(sheet.replace(/\.png$/, '.json'), 'utf8'));
    sizes[name] = { thumb: e.height, sheet: record.height, pixelSize: record.pixel_size };
    // The full sheet opens from the link.
    const full = await browser.newPage();
    await full.goto(pathToFileURL(sheet).href);
    const natural = await full.$eval('img', (img) => [img.naturalWidth, img.naturalHeight]);
    checks.ok(natural[0] === record.width && natural[1] === record.height, `${name}: the sheet loads at its size`);
    await full.close();
  }
  // One scale: the sheets share their pixel size, and the thumbnails keep their proportions.
  checks.ok(new Set(Object.values(sizes).map((s) => s.pixelSize)).size === 1, 'the sheets share one pixel size');
  const ratio = (a, b) => sizes[a].thumb / sizes[b].thumb;
  const sheetRatio = (a, b) => sizes[a].sheet / sizes[b].sheet;
  checks.near(ratio('large.ply', 'small.ply'), sheetRatio('large.ply', 'small.ply'), 0.05, 'thumbnails at one scale');
  checks.ok(sizes['large.ply'].thumb > sizes['small.ply'].thumb, 'the larger scan has the larger thumbnail');
  if (args.screenshot) fs.writeFileSync(path.resolve(args.screenshot), await page.screenshot());
  console.log(`contact sheet: ${checks.count} checks passed`);
} finally {
  await browser.close();
  if (!args.keep) fs.rmSync(work, { recursive: true, force: true });
}
