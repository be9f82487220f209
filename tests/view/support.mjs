// What the browser tests of msii view share: running the programs, reading the files they
// write (binary PLY, PNG) and driving Debian's Chromium through playwright-core.
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { chromium, firefox } from 'playwright-core';

/** The flags of headless Chromium with software WebGL (SwiftShader), no network of its own. */
export const CHROMIUM_FLAGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
];

/**
 * Launches Debian's chromium (`executable`, default /usr/bin/chromium), or with `name`
 * "firefox" Debian's firefox-esr through WebDriver BiDi (playwright's moz-firefox
 * channel, for a stock Firefox). Firefox draws WebGL with Mesa only on a display, so it
 * runs in a window: under `xvfb-run -a` on a machine without one. Playwright gives either
 * browser a fresh profile folder.
 */
export async function launchBrowser(name = 'chromium', executable = null) {
  if (name === 'firefox') {
    if (!process.env.DISPLAY) throw new Error('--browser firefox needs a display for WebGL: run it under xvfb-run -a');
    return firefox.launch({
      channel: 'moz-firefox', executablePath: executable || '/usr/bin/firefox-esr', headless: false,
      firefoxUserPrefs: { 'webgl.force-enabled': true }, // software GL is off by default
    });
  }
  return chromium.launch({ executablePath: executable || '/usr/bin/chromium', headless: true, args: CHROMIUM_FLAGS });
}

/** Runs a program to its end; throws with its stderr if it fails. */
export function run(program, args, options = {}) {
  try {
    return execFileSync(program, args, { encoding: 'utf8', stdio: [options.input ? 'pipe' : 'ignore', 'pipe', 'pipe'], ...options });
  } catch (e) {
    throw new Error(`${path.basename(program)} ${args.join(' ')} failed: ${e.stderr || e.message}`);
  }
}

/**
 * Starts `msii view INPUT` (serving) and resolves with {url, child} once it prints its
 * address; `stop()` ends it with SIGINT as Ctrl-C does and resolves with its exit code.
 */
export function startView(msii, args) {
  return new Promise((resolve, reject) => {
    const child = spawn(msii, ['view', ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '', err = '';
    const exited = new Promise((r) => child.on('exit', (code, signal) => r({ code, signal })));
    child.stdout.on('data', (d) => {
      out += d;
      const m = /^(http:\/\/127\.0\.0\.1:\d+\/)$/m.exec(out);
      if (m) resolve({ url: m[1], child, stderr: () => err, stop: () => { child.kill('SIGINT'); return exited; } });
    });
    child.stderr.on('data', (d) => { err += d; });
    child.on('exit', (code) => reject(new Error(`msii view ended (${code}) before serving: ${err}`)));
  });
}

/** The vertex properties of a binary little-endian PLY: {count, names, columns: {name: Float64Array}, comments}. */
export function readPly(file) {
  const buf = fs.readFileSync(file);
  const end = buf.indexOf('end_header\n');
  const lines = buf.subarray(0, end).toString('latin1').split('\n');
  if (!lines.some((l) => l.startsWith('format binary_little_endian'))) throw new Error(`${file}: not a binary little-endian PLY`);
  const sizes = { char: 1, uchar: 1, int8: 1, uint8: 1, short: 2, ushort: 2, int16: 2, uint16: 2, int: 4, uint: 4, int32: 4, uint32: 4, float: 4, float32: 4, double: 8, float64: 8 };
  let count = 0, inVertex = false;
  const props = [];
  const comments = [];
  for (const l of lines) {
    const w = l.trim().split(/\s+/);
    if (w[0] === 'comment') comments.push(l.slice(8));
    if (w[0] === 'element') {
      inVertex = w[1] === 'vertex';
      if (inVertex) count = Number(w[2]);
    } else if (w[0] === 'property' && inVertex) {
      if (w[1] === 'list') throw new Error('vertex lists are not read here');
      props.push({ type: w[1], name: w[2], size: sizes[w[1]] });
    }
  }
  const stride = props.reduce((s, p) => s + p.size, 0);
  const view = new DataView(buf.buffer, buf.byteOffset + end + 'end_header\n'.length, count * stride);
  const columns = {};
  let offset = 0;
  for (const p of props) {
    const a = new Float64Array(count);
    const get = {
      char: 'getInt8', int8: 'getInt8', uchar: 'getUint8', uint8: 'getUint8', short: 'getInt16', int16: 'getInt16',
      ushort: 'getUint16', uint16: 'getUint16', int: 'getInt32', int32: 'getInt32', uint: 'getUint32', uint32: 'getUint32',
      float: 'getFloat32', float32: 'getFloat32', double: 'getFloat64', float64: 'getFloat64',
    }[p.type];
    for (let i = 0; i < count; i++) a[i] = view[get](i * stride + offset, true);
    columns[p.name] = a;
    offset += p.size;
  }
  return { count, names: props.map((p) => p.name), columns, comments };
}

/** The pixels of an 8-bit RGB or RGBA PNG (as Playwright's screenshots are): {width, height, rgba: Uint8Array}. */
export function decodePng(bytes) {
  const signature = '89504e470d0a1a0a';
  if (bytes.subarray(0, 8).toString('hex') !== signature) throw new Error('not a PNG');
  let width = 0, height = 0, colorType = 0;
  const idat = [];
  for (let p = 8; p < bytes.length;) {
    const length = bytes.readUInt32BE(p);
    const type = bytes.toString('latin1', p + 4, p + 8);
    const data = bytes.subarray(p + 8, p + 8 + length);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      if (data[8] !== 8 || data[12] !== 0) throw new Error('only 8-bit, non-interlaced PNGs are read here');
      colorType = data[9];
    } else if (type === 'IDAT') idat.push(data);
    p += 12 + length;
  }
  const channels = { 2: 3, 6: 4 }[colorType];
  if (!channels) throw new Error(`PNG colour type ${colorType} is not read here`);
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const out = new Uint8Array(width * height * 4);
  const prev = new Uint8Array(stride), cur = new Uint8Array(stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let x = 0; x < stride; x++) {
      const a = x >= channels ? cur[x - channels] : 0, b = prev[x], c = x >= channels ? prev[x - channels] : 0;
      let v = line[x];
      if (filter === 1) v += a;
      else if (filter === 2) v += b;
      else if (filter === 3) v += (a + b) >> 1;
      else if (filter === 4) {
        const pa = Math.abs(b - c), pb = Math.abs(a - c), pc = Math.abs(a + b - 2 * c);
        v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[x] = v & 255;
    }
    for (let x = 0; x < width; x++) {
      for (let k = 0; k < 3; k++) out[(y * width + x) * 4 + k] = cur[x * channels + k];
      out[(y * width + x) * 4 + 3] = channels === 4 ? cur[x * channels + 3] : 255;
    }
    prev.set(cur);
  }
  return { width, height, rgba: out };
}

/** [r, g, b] of pixel (x, y) of a decoded PNG. */
export function pixel(img, x, y) {
  const k = (Math.round(y) * img.width + Math.round(x)) * 4;
  return [img.rgba[k], img.rgba[k + 1], img.rgba[k + 2]];
}

/** The colour the page's colour map table gives t in [0, 1] (msii render's colours, from data.json). */
export function tableColor(hex, t) {
  const n = hex.length / 6;
  const at = (i, k) => parseInt(hex.substr(i * 6 + k * 2, 2), 16);
  const pos = Math.min(1, Math.max(0, t)) * (n - 1);
  const i = Math.min(n - 2, Math.floor(pos)), f = pos - i;
  return [0, 1, 2].map((k) => at(i, k) + f * (at(i + 1, k) - at(i, k)));
}

/** A failed check throws; every check is counted, so a run reports what it compared. */
export class Checks {
  constructor() { this.count = 0; this.log = []; }
  ok(condition, what) {
    this.count++;
    if (!condition) throw new Error(`FAIL: ${what}`);
  }
  near(actual, expected, tolerance, what) {
    this.ok(Math.abs(actual - expected) <= tolerance, `${what}: ${actual} vs ${expected} (tolerance ${tolerance})`);
  }
  note(text) {
    this.log.push(text);
    console.log(text);
  }
}
