// Reading a view folder: data.json (the header) and data.bin (the sections it lists).
// The format is described in docs/view.md, "The folder".

/** The code of a value that is not there (NaN in the feature file, nodata in a raster). */
export const NAN_CODE = 65535;

const TYPES = {
  float32: Float32Array,
  uint32: Uint32Array,
  uint16: Uint16Array,
  int8: Int8Array,
};

/**
 * Fetches the header and starts on the binary file of the folder at `base`. data.bin is
 * read as it arrives: `arrived(end)` resolves once its first `end` bytes are in, so that
 * the page decodes (and draws) the geometry while the columns still stream in; `complete`
 * resolves when all of it is.
 */
export async function fetchView(base) {
  const get = async (name) => {
    const response = await fetch(new URL(name, base));
    if (!response.ok) throw new Error(`${name}: HTTP ${response.status}`);
    return response;
  };
  const [header, response] = await Promise.all([get('data.json').then((r) => r.json()), get('data.bin')]);
  if (!String(header.format).startsWith('msii-view 1')) {
    throw new Error(`data.json is not a view of msii 1 (format ${header.format})`);
  }
  const total = Object.values(header.sections).reduce((m, sec) => Math.max(m, sec.offset + sec.bytes), 0);
  const bin = new ArrayBuffer(total);
  const bytes = new Uint8Array(bin);
  let received = 0;
  let failed = null;
  const waiting = [];
  const wake = () => {
    for (let k = waiting.length - 1; k >= 0; k--) {
      const w = waiting[k];
      if (failed) w.reject(failed);
      else if (w.end <= received) w.resolve();
      else continue;
      waiting.splice(k, 1);
    }
  };
  const complete = (async () => {
    const reader = response.body.getReader();
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      if (received + value.length > total) throw new Error(`data.bin is longer than data.json says (${total} bytes)`);
      bytes.set(value, received);
      received += value.length;
      wake();
    }
    if (received !== total) throw new Error(`data.bin has ${received} bytes, data.json says ${total}`);
  })().catch((e) => {
    failed = e;
    wake();
    throw e;
  });
  complete.catch(() => {}); // reported by whoever waits for the bytes
  const arrived = (end) => (end <= received ? Promise.resolve()
    : failed ? Promise.reject(failed) : new Promise((resolve, reject) => waiting.push({ end, resolve, reject })));
  return { header, bin, arrived, complete };
}

/** The zlib stream `bytes` inflated, by the browser's own zlib. */
async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

/**
 * The typed array of section `name` of `header.sections`, decoded: inflated, its byte
 * planes put back together, and its differences summed where the writer took them.
 * `arrived` (fetchView's) waits for the section's bytes; without it `bin` must be whole.
 */
export async function decodeSection(header, bin, name, arrived = null) {
  const s = header.sections[name];
  if (!s) throw new Error(`data.json lists no section '${name}'`);
  if (arrived) await arrived(s.offset + s.bytes);
  const Type = TYPES[s.type];
  const size = Type.BYTES_PER_ELEMENT;
  const raw = await inflate(new Uint8Array(bin, s.offset, s.bytes));
  if (raw.length !== s.count * size) {
    throw new Error(`section ${name}: ${raw.length} bytes, expected ${s.count * size}`);
  }
  let values;
  if (s.planes && size > 1) {
    // Plane b holds byte b of every element: deflate finds the slowly varying high bytes
    // of neighbouring values far more alike than interleaved ones. Each element is put
    // together from its bytes at once (little-endian, as typed arrays are here).
    const n = s.count;
    const words = size === 2 ? new Uint16Array(n) : new Uint32Array(n);
    if (size === 2) {
      for (let i = 0; i < n; i++) words[i] = raw[i] | (raw[n + i] << 8);
    } else {
      for (let i = 0; i < n; i++) words[i] = raw[i] | (raw[n + i] << 8) | (raw[2 * n + i] << 16) | (raw[3 * n + i] << 24);
    }
    values = new Type(words.buffer);
  } else {
    values = new Type(raw.buffer, raw.byteOffset, s.count);
  }
  if (s.delta) {
    // Each element was stored as its difference to the previous one, modulo the type's
    // range; the typed array wraps the sums the same way.
    for (let i = 1; i < values.length; i++) values[i] += values[i - 1];
  }
  return values;
}

/**
 * A quantized column: value = lo + q · step for q < NAN_CODE; NAN_CODE marks a missing value.
 * `column` is its entry in header.columns.
 */
export function dequantize(column, q) {
  return q === NAN_CODE ? NaN : column.lo + q * column.step;
}
