// Measures msii view's page in headless Chromium (software WebGL, as the browser test runs
// it): the first frame after loading, the work of a change of radius and of a click (the
// page's own figures, window.msiiViewTimings), medians over several of each.
//
//   build/tools/msii view scan.msii.ply        # prints http://127.0.0.1:PORT/
//   node tools/view/measure.mjs http://127.0.0.1:PORT/ [--loads 3] [--changes 9] [--clicks 9]
//        [--chromium /usr/bin/chromium] [--size 1280x800]
import { chromium } from 'playwright-core';

const argv = process.argv.slice(2);
const url = argv.find((a) => a.startsWith('http'));
const option = (name, fallback) => {
  const k = argv.indexOf(`--${name}`);
  return k >= 0 ? argv[k + 1] : fallback;
};
if (!url) {
  console.error('usage: node tools/view/measure.mjs URL [--loads N] [--changes N] [--clicks N] [--chromium PATH] [--size WxH]');
  process.exit(2);
}
const loads = Number(option('loads', 3)), changes = Number(option('changes', 9)), clicks = Number(option('clicks', 9));
const [width, height] = option('size', '1280x800').split('x').map(Number);
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader'];

const median = (v) => {
  const s = [...v].sort((a, b) => a - b);
  return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN;
};

const browser = await chromium.launch({ executablePath: option('chromium', '/usr/bin/chromium'), headless: true, args: FLAGS });
const first = [], all = [], fetched = [], decoded = [], radius = [], radiusFrame = [], click = [], clickPick = [], clickMetric = [], clickKernel = [], clickFrame = [];
let header = null;
try {
  for (let run = 0; run < loads; run++) {
    const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
    await page.goto(url);
    await page.waitForFunction(() => window.msiiViewTimings?.firstFrame !== null, null, { timeout: 120000, polling: 50 });
    await page.evaluate(() => window.msiiView.ready);
    const t = await page.evaluate(() => window.msiiViewTimings);
    first.push(t.firstFrame);
    all.push(t.allColumns);
    fetched.push(t.fetched);
    decoded.push(t.decoded);
    header = await page.evaluate(() => ({ items: window.msiiView.header.items, kind: window.msiiView.header.kind, columns: window.msiiView.header.columns.length }));
    if (run === loads - 1) {
      // Changes of radius through the slider, as a user drags it.
      const max = Number(await page.getAttribute('#radius', 'max'));
      for (let k = 0; k < changes; k++) {
        const n = await page.evaluate(() => window.msiiViewTimings.radiusChanges.length);
        await page.evaluate((v) => {
          const s = document.getElementById('radius');
          s.value = String(v);
          s.dispatchEvent(new Event('input'));
        }, 1 + ((k * 5) % max));
        await page.waitForFunction((m) => window.msiiViewTimings.radiusChanges.length > m, n);
      }
      // Clicks on vertices (or cells) spread over the object, those that are in sight.
      const picked = [];
      for (let k = 0, tries = 0; k < clicks && tries < 50 * clicks; tries++) {
        const i = Math.floor(((tries * 0.618034) % 1) * header.items);
        const at = await page.evaluate((j) => window.msiiView.screenOf(j), i);
        if (!(await page.evaluate((p) => window.msiiView.itemAt(p.x, p.y) !== null, at))) continue;
        k++;
        const n = await page.evaluate(() => window.msiiViewTimings.clicks.length);
        await page.mouse.click(at.x, at.y);
        await page.waitForFunction((m) => window.msiiViewTimings.clicks.length > m, n, { timeout: 60000 });
        picked.push(await page.evaluate(() => window.msiiView.state().sel));
      }
      const u = await page.evaluate(() => window.msiiViewTimings);
      for (const c of u.radiusChanges) radius.push(c.work), radiusFrame.push(c.frame);
      for (const c of u.clicks) click.push(c.work), clickPick.push(c.pick), clickMetric.push(c.metric), clickKernel.push(c.kernel), clickFrame.push(c.frame);
    }
    await page.close();
  }
} finally {
  await browser.close();
}
const f = (v) => v.toFixed(0);
const result = {
  url, items: header.items, kind: header.kind, columns: header.columns, viewport: `${width}x${height}`,
  firstFrameMs: first, firstFrameMedianMs: median(first), fetchedMedianMs: median(fetched), decodedMedianMs: median(decoded),
  allColumnsMedianMs: median(all),
  radiusChangeWorkMedianMs: median(radius), radiusChangeFrameMedianMs: median(radiusFrame), radiusChanges: radius.length,
  clickWorkMedianMs: median(click), clickPickMedianMs: median(clickPick), clickMetricMedianMs: median(clickMetric),
  clickKernelMedianMs: median(clickKernel), clickWorkMs: click, clickKernelMs: clickKernel, clickPickMs: clickPick, clickMetricMs: clickMetric,
  clickFrameMedianMs: median(clickFrame), clicks: click.length,
};
console.log(JSON.stringify(result, null, 1));
console.log(`first frame ${f(result.firstFrameMedianMs)} ms (median of ${first.length} loads; fetched ${f(result.fetchedMedianMs)}, decoded ${f(result.decodedMedianMs)}, all columns ${f(result.allColumnsMedianMs)} ms); ` +
  `radius change ${f(result.radiusChangeWorkMedianMs)} ms of work + ${f(result.radiusChangeFrameMedianMs)} ms frame (median of ${radius.length}); ` +
  `click ${f(result.clickWorkMedianMs)} ms of work (pick ${f(result.clickPickMedianMs)}, metric ${f(result.clickMetricMedianMs)} of which the kernel ${f(result.clickKernelMedianMs)}) + ${f(result.clickFrameMedianMs)} ms frame (median of ${click.length})`);
