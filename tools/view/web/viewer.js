// msii view: the scan (or the DEM as a map) coloured by any invariant at any radius, a
// click that shows a vertex's feature vectors and colours everything by the feature
// distance to it, as `msii metric` computes it. docs/view.md describes the page.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { MapControls } from 'three/addons/controls/MapControls.js';
import { fetchView, decodeSection, NAN_CODE } from './data.js';
import { METRICS, MISSING, isSimilarity, featureTable, computeMetric, rowOf, vertexReference } from './metrics.js';
import { drawFeatureCurves, formatNumber, niceTicks } from './plot.js';

/** What the page measured, in milliseconds (performance.now(): from the start of loading the page). */
const timings = {
  fetched: null,        // data.bin fetched whole (the first frame does not wait for it)
  decoded: null,        // the mesh (or the map) and the first column decoded
  firstFrame: null,     // the first frame drawn and finished
  allColumns: null,     // every feature column decoded
  radiusChanges: [],    // {work, frame} per change of radius
  clicks: [],           // {pick, metric, work, frame} per click on the scan: metric ⊂ work, pick ⊂ work
};
window.msiiViewTimings = timings;

const $ = (id) => document.getElementById(id);
const statusLine = $('status');
function setStatus(text, error = false) {
  statusLine.textContent = text;
  statusLine.classList.toggle('error', error);
}

const LETTERS = {
  V: { symbol: 'V̂', name: 'volume' },
  S: { symbol: 'Ŝ', name: 'sphere area' },
  P: { symbol: 'P̂', name: 'patch area' },
  L: { symbol: 'L̂', name: 'line length' },
};
const FEATURE = /^([VSPL])_(\d+)$/;

// ---------------------------------------------------------------------------------------
// State, and the link that holds it

const state = {
  show: null,        // a column name, or 'distance'
  cmap: 'viridis',
  range: null,       // [lo, hi] chosen by the user; null: automatic
  shade: 0.6,
  sel: null,         // the selected vertex (or cell)
  metric: 'mahalanobis',
  p: 2,
  inv: 'V',
  thr: null,         // threshold of the distance; null: automatic
  camera: null,      // numbers, see cameraState()
};

function stateToHash() {
  const h = new URLSearchParams();
  if (state.camera) h.set('cam', state.camera.map((v) => Number(v.toPrecision(7))).join(','));
  if (state.show) h.set('show', state.show);
  h.set('cmap', state.cmap);
  if (state.range) h.set('range', state.range.map((v) => Number(v.toPrecision(7))).join(','));
  if (state.shade !== view.header.shading.strength) h.set('shade', String(state.shade));
  if (state.sel !== null) {
    h.set('sel', String(state.sel));
    h.set('metric', state.metric);
    if (state.metric === 'lp' || state.metric === 'lpw') h.set('p', String(state.p));
    h.set('inv', state.inv);
    if (state.thr !== null) h.set('thr', String(Number(state.thr.toPrecision(7))));
  }
  return '#' + h.toString().replaceAll('%2C', ',');
}

function hashToState(hash) {
  const h = new URLSearchParams(hash.replace(/^#/, ''));
  const numbers = (key) => (h.get(key) || '').split(',').filter((s) => s !== '').map(Number);
  const s = {};
  const cam = numbers('cam');
  if (cam.length && cam.every(Number.isFinite)) s.camera = cam;
  if (h.has('show')) s.show = h.get('show');
  if (h.has('cmap')) s.cmap = h.get('cmap');
  const range = numbers('range');
  if (range.length === 2 && range[0] < range[1]) s.range = range;
  if (h.has('shade') && Number.isFinite(Number(h.get('shade')))) s.shade = Math.min(1, Math.max(0, Number(h.get('shade'))));
  if (h.has('sel') && /^\d+$/.test(h.get('sel'))) s.sel = Number(h.get('sel'));
  if (h.has('metric')) s.metric = h.get('metric');
  if (h.has('p') && Number(h.get('p')) > 0) s.p = Number(h.get('p'));
  if (h.has('inv') && /^[VSPL]+$/.test(h.get('inv'))) s.inv = h.get('inv');
  if (h.has('thr') && Number.isFinite(Number(h.get('thr')))) s.thr = Number(h.get('thr'));
  return s;
}

let hashTimer = null;
function writeHash(delay = 0) {
  clearTimeout(hashTimer);
  hashTimer = setTimeout(() => history.replaceState(null, '', stateToHash()), delay);
}

// ---------------------------------------------------------------------------------------
// The data

const view = {
  header: null,
  bin: null,
  columns: new Map(),   // name → {q: Uint16Array, lo, step, info}
  pending: new Map(),   // name → Promise of the column
  features: {},         // letter → [{j, name, radius}] radius ascending
  others: [],           // names of the other columns
  n: 0,
  positions: null,
  tables: new Map(),    // letters → {table, cache}
  distance: null,       // Float32Array of the last metric, NaN where undefined
  distanceUpload: null, // the same with NaN as MISSING, for the GPU
  distanceRange: null,
  distanceVersion: 0,   // counts the distances computed, so the GPU's copy is refreshed once each
  generation: 0,        // counts the computations begun: an answer to an older one is dropped
};

function loadColumn(name) {
  if (view.columns.has(name)) return Promise.resolve(view.columns.get(name));
  if (!view.pending.has(name)) {
    const info = view.header.columns.find((c) => c.name === name);
    if (!info) return Promise.reject(new Error(`there is no column '${name}'`));
    view.pending.set(name, decodeSection(view.header, view.bin, info.section, view.arrived).then((q) => {
      const column = { q, lo: info.lo, step: info.step, info };
      view.columns.set(name, column);
      return column;
    }));
  }
  return view.pending.get(name);
}

function radiusOf(j) {
  const radii = view.header.radii || [];
  return j <= radii.length ? radii[j - 1] : null;
}

function indexColumns() {
  for (const c of view.header.columns) {
    const m = FEATURE.exec(c.name);
    if (m) (view.features[m[1]] ||= []).push({ j: Number(m[2]), name: c.name, radius: radiusOf(Number(m[2])) });
    else view.others.push(c.name);
  }
  for (const list of Object.values(view.features)) list.sort((a, b) => a.j - b.j);
}

// ---------------------------------------------------------------------------------------
// Drawing

const canvas = $('canvas');
let renderer = null; // made in main(), where a browser without WebGL 2 is told so
const scene = new THREE.Scene();

function makeRenderer() {
  try {
    renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: false });
  } catch (e) {
    throw new Error(`this browser offers no WebGL 2 (${e.message})`);
  }
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace; // the shaders write sRGB as msii render does
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xffffff, 1);
}
let camera = null;
let controls = null;
let object = null;     // the mesh, or the map's plane
let material = null;
const colormaps = {};

function colormapTexture(hex) {
  const n = hex.length / 6;
  const data = new Uint8Array(n * 4);
  for (let i = 0; i < n; i++) {
    for (let k = 0; k < 3; k++) data[i * 4 + k] = parseInt(hex.substr(i * 6 + k * 2, 2), 16);
    data[i * 4 + 3] = 255;
  }
  const t = new THREE.DataTexture(data, n, 1, THREE.RGBAFormat, THREE.UnsignedByteType);
  t.minFilter = t.magFilter = THREE.LinearFilter;
  t.wrapS = t.wrapT = THREE.ClampToEdgeWrapping;
  t.colorSpace = THREE.NoColorSpace;
  t.needsUpdate = true;
  t.userData.bytes = data;
  return t;
}

/** The colour of t in [0, 1] from a table of n entries at i/(n−1), interpolated as the GPU does. */
function tableColor(name, t) {
  const bytes = colormaps[name].userData.bytes;
  const n = bytes.length / 4;
  const pos = Math.min(1, Math.max(0, t)) * (n - 1);
  const i = Math.min(n - 2, Math.floor(pos)), f = pos - i;
  return [0, 1, 2].map((k) => Math.round(bytes[i * 4 + k] + f * (bytes[(i + 1) * 4 + k] - bytes[i * 4 + k])));
}

/** What mesh and map share: a colour map lookup, the light of msii render, the threshold. */
const SHADE_GLSL = /* glsl */ `
uniform sampler2D uColormap;
uniform float uColormapSize;
uniform vec2 uRange;
uniform float uShade;
uniform float uAmbient;
uniform vec3 uLight;
uniform int uColour;       // 0: relief only
uniform int uThresholdMode; // 0: none; 1: colour where value <= uThreshold; 2: where value >= uThreshold
uniform float uThreshold;

vec3 shadeColour(float value, bool missing, vec3 n) {
  // msii render: brightness = ambient + (1 − ambient) · max(0, n·l); colours are scaled by
  // 1 − s + s · brightness (s: the shading strength), grey 128 where a value is missing.
  float lambert = uAmbient + (1.0 - uAmbient) * max(0.0, dot(normalize(n), uLight));
  bool outside = uThresholdMode == 1 ? !(value <= uThreshold) : uThresholdMode == 2 ? !(value >= uThreshold) : false;
  if (uColour == 0 || (!missing && outside)) return vec3(lambert);
  vec3 c;
  if (missing) {
    c = vec3(128.0 / 255.0);
  } else {
    float t = clamp((value - uRange.x) / (uRange.y - uRange.x), 0.0, 1.0);
    c = texture2D(uColormap, vec2((t * (uColormapSize - 1.0) + 0.5) / uColormapSize, 0.5)).rgb;
  }
  return c * (1.0 - uShade + uShade * lambert);
}
`;

function commonUniforms() {
  const s = view.header.shading;
  const az = (s.azimuth * Math.PI) / 180, el = (s.elevation * Math.PI) / 180;
  return {
    uColormap: { value: colormaps[state.cmap] },
    uColormapSize: { value: colormaps[state.cmap].image.width },
    uRange: { value: new THREE.Vector2(0, 1) },
    uShade: { value: state.shade },
    uAmbient: { value: s.ambient },
    // Towards the light in the picture frame (x right, y up, z to the viewer).
    uLight: { value: new THREE.Vector3(-Math.cos(el) * Math.cos(az), -Math.cos(el) * Math.sin(az), Math.sin(el)) },
    uColour: { value: 1 },
    uThresholdMode: { value: 0 },
    uThreshold: { value: 0 },
    uStep: { value: 1 },
    uLo: { value: 0 },
    uNanCode: { value: NAN_CODE },
    uUseFloats: { value: 0 },
  };
}

function meshMaterial() {
  return new THREE.ShaderMaterial({
    uniforms: commonUniforms(),
    side: THREE.DoubleSide,
    vertexShader: /* glsl */ `
      attribute float value;     // a column's codes
      attribute float distance;  // the metric's values
      uniform int uUseFloats;
      uniform float uLo, uStep, uNanCode;
      varying float vValue;
      varying float vMissing;
      varying vec3 vNormal;
      varying vec3 vPosition;
      void main() {
        vPosition = position;
        float v = uUseFloats == 1 ? distance : value;
        vMissing = v >= uNanCode ? 1.0 : 0.0;
        vValue = vMissing > 0.5 ? 0.0 : uLo + v * uStep;
        vNormal = normalMatrix * normal;
        gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
      }`,
    fragmentShader: SHADE_GLSL + /* glsl */ `
      layout(location = 1) out highp vec4 pc_position;  // the surface point, for a click
      varying float vValue;
      varying float vMissing;
      varying vec3 vNormal;
      varying vec3 vPosition;
      void main() {
        vec3 n = gl_FrontFacing ? vNormal : -vNormal;  // an open scan seen from behind
        gl_FragColor = vec4(shadeColour(vValue, vMissing > 0.0, n), 1.0);
        pc_position = vec4(vPosition, 1.0);
      }`,
  });
}

function mapMaterial(heights) {
  const r = view.header.raster;
  const uniforms = commonUniforms();
  Object.assign(uniforms, {
    uHeights: { value: heights },
    uHasHeights: { value: r.heights ? 1 : 0 },
    uCodes: { value: null },
    uFloats: { value: null },
    uSize: { value: new THREE.Vector2(r.width, r.height) },
    uCell: { value: new THREE.Vector2(r.cell[0], r.cell[1]) },
  });
  return new THREE.ShaderMaterial({
    uniforms,
    vertexShader: /* glsl */ `
      varying vec2 vUv;
      void main() {
        vUv = uv;
        gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
      }`,
    fragmentShader: SHADE_GLSL + /* glsl */ `
      precision highp usampler2D;
      uniform sampler2D uHeights;
      uniform int uHasHeights;
      uniform usampler2D uCodes;
      uniform sampler2D uFloats;
      uniform int uUseFloats;
      uniform vec2 uSize, uCell;
      uniform float uLo, uStep, uNanCode;
      varying vec2 vUv;
      float heightAt(ivec2 c) {
        if (c.x < 0 || c.y < 0 || c.x >= int(uSize.x) || c.y >= int(uSize.y)) return -1e30;
        return texelFetch(uHeights, c, 0).r;
      }
      // The slope between the cells before and after (central difference), one-sided at the
      // edges and next to nodata, as msii render shades a DEM.
      float slope(ivec2 c, ivec2 d, float z, float h) {
        float a = heightAt(c - d), b = heightAt(c + d);
        bool ha = a > -1e29, hb = b > -1e29;
        if (ha && hb) return (b - a) / (2.0 * h);
        if (hb) return (b - z) / h;
        if (ha) return (z - a) / h;
        return 0.0;
      }
      void main() {
        ivec2 c = ivec2(int(floor(vUv.x * uSize.x)), int(uSize.y) - 1 - int(floor(vUv.y * uSize.y)));
        c = clamp(c, ivec2(0), ivec2(uSize) - 1);
        float value;
        bool missing;
        if (uUseFloats == 1) {
          value = texelFetch(uFloats, c, 0).r;
          missing = value >= uNanCode;
        } else {
          uint q = texelFetch(uCodes, c, 0).r;
          missing = float(q) >= uNanCode;
          value = uLo + float(q) * uStep;
        }
        vec3 n = vec3(0.0, 0.0, 1.0);
        if (uHasHeights == 1) {
          float z = heightAt(c);
          if (z <= -1e29 && missing) discard;  // no cell there: the background
          if (z > -1e29) {
            float gx = slope(c, ivec2(1, 0), z, uCell.x), gy = -slope(c, ivec2(0, 1), z, uCell.y);
            n = vec3(-gx, -gy, 1.0);
          }
        } else if (missing) {
          discard;
        }
        gl_FragColor = vec4(shadeColour(value, missing, n), 1.0);
      }`,
  });
}

/** The selected vertex (or cell) marked by a ring of fixed size on the screen, always in front. */
const marker = new THREE.Points(
  new THREE.BufferGeometry().setAttribute('position', new THREE.BufferAttribute(new Float32Array(3), 3)),
  new THREE.ShaderMaterial({
    uniforms: { uSize: { value: 14 * (window.devicePixelRatio || 1) } },
    vertexShader: 'uniform float uSize; varying vec3 vPosition; void main() { vPosition = position; gl_PointSize = uSize; gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
    fragmentShader: `layout(location = 1) out highp vec4 pc_position;
      varying vec3 vPosition;
      void main() {
        float r = length(gl_PointCoord - 0.5) * 2.0;
        if (r > 1.0 || r < 0.45) discard;
        gl_FragColor = vec4(r > 0.72 ? vec3(1.0) : vec3(0.85, 0.1, 0.1), 1.0);
        pc_position = vec4(vPosition, 1.0);  // a click on the ring picks its vertex again
      }`,
    depthTest: false,
    depthWrite: false,
  }));
marker.renderOrder = 1;
marker.frustumCulled = false;
marker.visible = false;

/** Puts the marker on item i (null: hides it). */
function placeMarker(i) {
  marker.visible = i !== null;
  if (i === null) return;
  const p = marker.geometry.getAttribute('position');
  if (view.header.kind === 'mesh') p.array.set(view.positions.subarray(3 * i, 3 * i + 3));
  else {
    const r = view.header.raster;
    p.array.set([(i % r.width + 0.5 - r.width / 2) * r.cell[0], (r.height / 2 - Math.floor(i / r.width) - 0.5) * r.cell[1], 0.001]);
  }
  p.needsUpdate = true;
}

let frameRequested = false;
let afterFrame = [];
/** Draws at the next animation frame; resolves with the time the frame took to draw (ms). */
function requestRender() {
  return new Promise((resolve) => {
    afterFrame.push(resolve);
    if (frameRequested) return;
    frameRequested = true;
    requestAnimationFrame(() => {
      frameRequested = false;
      const ms = drawNow();
      const waiting = afterFrame;
      afterFrame = [];
      for (const r of waiting) r(ms);
    });
  });
}

// A mesh is drawn into two pictures at once: the colours, copied to the canvas, and the
// surface point under each pixel, which a click reads (one pixel) instead of drawing the
// mesh again to find what it hit: in software WebGL, drawing a million vertices takes
// longer than a click may.
let frameTarget = null;
const blitCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
const blitMaterial = new THREE.ShaderMaterial({
  uniforms: { uColour: { value: null } },
  vertexShader: 'varying vec2 vUv; void main() { vUv = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }',
  // Where nothing was drawn (alpha 0: three.js clears to premultiplied black) the page is white.
  fragmentShader: 'uniform sampler2D uColour; varying vec2 vUv; void main() { vec4 c = texture2D(uColour, vUv); gl_FragColor = vec4(mix(vec3(1.0), c.rgb, c.a), 1.0); }',
  depthTest: false,
  depthWrite: false,
});
const blitScene = new THREE.Scene().add(new THREE.Mesh(new THREE.PlaneGeometry(2, 2), blitMaterial));

function frameTargetOfSize() {
  const size = renderer.getDrawingBufferSize(new THREE.Vector2());
  if (!frameTarget || frameTarget.width !== size.x || frameTarget.height !== size.y) {
    frameTarget?.dispose();
    frameTarget = new THREE.WebGLRenderTarget(size.x, size.y, {
      count: 2, type: THREE.UnsignedByteType, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: true,
    });
    frameTarget.textures[1].type = THREE.FloatType; // the points: exact to the float
    blitMaterial.uniforms.uColour.value = frameTarget.textures[0];
  }
  return frameTarget;
}

const finishPixel = new Uint8Array(4);
/** Draws, and waits for the GPU to finish (reading a pixel), so that the time is the frame's. */
function drawNow() {
  const t0 = performance.now();
  if (view.header.kind === 'mesh') {
    renderer.setRenderTarget(frameTargetOfSize());
    renderer.setClearColor(0xffffff, 0); // alpha 0 in the points: nothing hit there
    renderer.clear();
    renderer.render(scene, camera);
    renderer.setRenderTarget(null);
    renderer.render(blitScene, blitCamera);
  } else {
    renderer.render(scene, camera);
  }
  const gl = renderer.getContext();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, finishPixel);
  return performance.now() - t0;
}

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (!w || !h) return;
  renderer.setSize(w, h, false);
  if (camera) {
    const aspect = w / h;
    const half = camera.userData.halfHeight;
    camera.left = -half * aspect;
    camera.right = half * aspect;
    camera.top = half;
    camera.bottom = -half;
    camera.updateProjectionMatrix();
  }
  requestRender();
}

// ---------------------------------------------------------------------------------------
// The mesh, or the map

async function buildMesh() {
  const h = view.header;
  const [positions, normals, indices] = await Promise.all([
    decodeSection(h, view.bin, 'positions', view.arrived),
    decodeSection(h, view.bin, 'normals', view.arrived),
    decodeSection(h, view.bin, 'indices', view.arrived),
  ]);
  view.positions = positions;
  view.inFace = new Uint8Array(view.n);
  for (let k = 0; k < indices.length; k++) view.inFace[indices[k]] = 1;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('normal', new THREE.BufferAttribute(normals, 3, true));
  geometry.setIndex(new THREE.BufferAttribute(indices, 1));
  // One attribute for a column's codes and one for the distances, refilled (not replaced:
  // three.js keeps the buffer of a replaced attribute until the geometry goes).
  geometry.setAttribute('value', new THREE.BufferAttribute(new Uint16Array(view.n), 1));
  const min = h.mesh.bbox_min, max = h.mesh.bbox_max;
  geometry.boundingBox = new THREE.Box3(
    new THREE.Vector3(...min.map((v, k) => v - h.mesh.center[k])),
    new THREE.Vector3(...max.map((v, k) => v - h.mesh.center[k])));
  geometry.boundingSphere = geometry.boundingBox.getBoundingSphere(new THREE.Sphere());
  material = meshMaterial();
  object = new THREE.Mesh(geometry, material);
  object.frustumCulled = false;
  scene.add(object);

  const v = h.mesh.view;
  camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0.01, 1);
  camera.up.set(...v.up);
  controls = new OrbitControls(camera, canvas);
  controls.zoomToCursor = true;
  controls.enableDamping = false;
}

async function buildMap() {
  const r = view.header.raster;
  let heights = null;
  if (r.heights) {
    const z = await decodeSection(view.header, view.bin, 'heights', view.arrived);
    for (let i = 0; i < z.length; i++) if (Number.isNaN(z[i])) z[i] = -1e30;
    heights = new THREE.DataTexture(z, r.width, r.height, THREE.RedFormat, THREE.FloatType);
    heights.minFilter = heights.magFilter = THREE.NearestFilter;
    heights.needsUpdate = true;
  }
  const geometry = new THREE.PlaneGeometry(r.width * r.cell[0], r.height * r.cell[1]);
  material = mapMaterial(heights);
  object = new THREE.Mesh(geometry, material);
  scene.add(object);
  camera = new THREE.OrthographicCamera(-1, 1, 1, -1, -10, 10);
  camera.position.set(0, 0, 1);
  controls = new MapControls(camera, canvas);
  controls.enableRotate = false;
  controls.screenSpacePanning = true;
  controls.zoomToCursor = true;
}

/** The whole object in view: msii render's default view for a mesh (its best-fit plane), north up for a map. */
function homeCamera() {
  const h = view.header;
  const aspect = (canvas.clientWidth || 1) / (canvas.clientHeight || 1);
  let halfW, halfH;
  if (h.kind === 'mesh') {
    const v = h.mesh.view;
    const right = new THREE.Vector3(...v.right), up = new THREE.Vector3(...v.up), normal = new THREE.Vector3(...v.normal);
    const min = h.mesh.bbox_min.map((x, k) => x - h.mesh.center[k]), max = h.mesh.bbox_max.map((x, k) => x - h.mesh.center[k]);
    halfW = 0, halfH = 0;
    for (let c = 0; c < 8; c++) {
      const p = new THREE.Vector3(c & 1 ? max[0] : min[0], c & 2 ? max[1] : min[1], c & 4 ? max[2] : min[2]);
      halfW = Math.max(halfW, Math.abs(p.dot(right)));
      halfH = Math.max(halfH, Math.abs(p.dot(up)));
    }
    const diag = new THREE.Vector3(...max).sub(new THREE.Vector3(...min)).length() || 1;
    camera.near = 0.01 * diag;
    camera.far = 10 * diag;
    controls.target.set(0, 0, 0);
    camera.position.copy(normal.multiplyScalar(3 * diag));
  } else {
    const r = h.raster;
    halfW = (r.width * r.cell[0]) / 2;
    halfH = (r.height * r.cell[1]) / 2;
    controls.target.set(0, 0, 0);
    camera.position.set(0, 0, 1);
  }
  const half = Math.max(halfH, halfW / aspect) * 1.04;
  camera.userData.halfHeight = half;
  camera.zoom = 1;
  resize();
  camera.updateProjectionMatrix();
  controls.update();
}

/** position (3), target (3), zoom: the camera as the link holds it. */
function cameraState() {
  return [...camera.position.toArray(), ...controls.target.toArray(), camera.zoom];
}

function applyCamera(numbers) {
  if (!numbers || numbers.length !== 7) return;
  camera.position.fromArray(numbers, 0);
  controls.target.fromArray(numbers, 3);
  camera.zoom = numbers[6] > 0 ? numbers[6] : 1;
  camera.updateProjectionMatrix();
  controls.update();
  state.camera = cameraState();
}

// ---------------------------------------------------------------------------------------
// Colouring

// A raster's shown values: one texture for a column's codes, one for the distances, refilled.
let codeTexture = null;
let floatTexture = null;
let uploadedDistances = 0; // the distanceVersion on the GPU

/** The range of the colours: the user's, else the column's 1st to 99th percentile (as msii render), centred for coolwarm. */
function currentRange() {
  if (state.range) return state.range;
  let lo, hi, centre = null;
  if (state.show === 'distance') {
    [lo, hi] = view.distanceRange || [0, 1];
  } else {
    const info = view.columns.get(state.show)?.info || view.header.columns.find((c) => c.name === state.show);
    [lo, hi] = info.percentiles;
    const m = FEATURE.exec(state.show);
    if (m) centre = m[1] === 'V' || m[1] === 'S' ? 0.5 : 1;
  }
  if (state.cmap === 'coolwarm' && centre !== null) {
    const d = Math.max(Math.abs(lo - centre), Math.abs(hi - centre));
    lo = centre - d;
    hi = centre + d;
  }
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  return [lo, hi];
}

/** Puts the shown values (a column or the distances) onto the GPU, with their range and colours. */
function applyColouring() {
  const u = material.uniforms;
  u.uColormap.value = colormaps[state.cmap];
  u.uColormapSize.value = colormaps[state.cmap].image.width;
  u.uShade.value = state.shade;
  const [lo, hi] = currentRange();
  u.uRange.value.set(lo, hi);
  u.uThresholdMode.value = 0;
  if (state.show === 'distance' && view.distance) {
    u.uLo.value = 0;
    u.uStep.value = 1;
    u.uNanCode.value = MISSING;
    if (state.thr !== null) {
      u.uThresholdMode.value = isSimilarity(state.metric) ? 2 : 1;
      u.uThreshold.value = state.thr;
    }
    u.uUseFloats.value = 1;
    if (view.header.kind === 'mesh') {
      // Added at the first click: the first frame has 4 bytes per vertex less to send.
      if (!object.geometry.getAttribute('distance')) object.geometry.setAttribute('distance', new THREE.BufferAttribute(view.distanceUpload, 1));
      const attribute = object.geometry.getAttribute('distance');
      if (uploadedDistances !== view.distanceVersion) {
        attribute.array = view.distanceUpload;
        attribute.needsUpdate = true;
        uploadedDistances = view.distanceVersion;
      }
    } else {
      if (!floatTexture) {
        const r = view.header.raster;
        floatTexture = new THREE.DataTexture(view.distanceUpload, r.width, r.height, THREE.RedFormat, THREE.FloatType);
        floatTexture.minFilter = floatTexture.magFilter = THREE.NearestFilter;
      }
      if (uploadedDistances !== view.distanceVersion) {
        floatTexture.image.data = view.distanceUpload;
        floatTexture.needsUpdate = true;
        uploadedDistances = view.distanceVersion;
      }
      u.uFloats.value = floatTexture;
    }
  } else {
    const column = view.columns.get(state.show);
    u.uLo.value = column.lo;
    u.uStep.value = column.step;
    u.uNanCode.value = NAN_CODE;
    u.uUseFloats.value = 0;
    if (view.header.kind === 'mesh') {
      const attribute = object.geometry.getAttribute('value');
      if (attribute.array !== column.q) {
        attribute.array = column.q;
        attribute.needsUpdate = true;
      }
    } else {
      if (!codeTexture) {
        const r = view.header.raster;
        codeTexture = new THREE.DataTexture(column.q, r.width, r.height, THREE.RedIntegerFormat, THREE.UnsignedShortType);
        codeTexture.internalFormat = 'R16UI';
        codeTexture.minFilter = codeTexture.magFilter = THREE.NearestFilter;
        codeTexture.unpackAlignment = 2;
        codeTexture.needsUpdate = true;
      } else if (codeTexture.image.data !== column.q) {
        codeTexture.image.data = column.q;
        codeTexture.needsUpdate = true;
      }
      u.uCodes.value = codeTexture;
    }
  }
  drawColorBar();
}

function labelOfShown() {
  if (state.show === 'distance') {
    const name = METRICS.find(([k]) => k === state.metric)?.[1] || state.metric;
    return `${name} of ${state.inv} to ${itemWord()} ${state.sel}`;
  }
  const m = FEATURE.exec(state.show);
  if (!m) return state.show;
  const r = radiusOf(Number(m[2]));
  return `${LETTERS[m[1]].symbol} at r = ${r === null ? `${m[2]}·R/N` : `${formatNumber(r)} ${view.header.units}`} (${state.show})`;
}

function drawColorBar(target = $('colorbar'), scale = 1) {
  const ctx = target.getContext('2d');
  const W = target.width, H = target.height;
  ctx.clearRect(0, 0, W, H);
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, W, H);
  const [lo, hi] = currentRange();
  const x0 = 8 * scale, x1 = W - 8 * scale, y0 = 16 * scale, y1 = 32 * scale;
  for (let x = Math.floor(x0); x < x1; x++) {
    const c = tableColor(state.cmap, (x + 0.5 - x0) / (x1 - x0));
    ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
    ctx.fillRect(x, y0, 1, y1 - y0);
  }
  ctx.strokeStyle = '#444';
  ctx.strokeRect(x0, y0, x1 - x0, y1 - y0);
  ctx.fillStyle = '#222';
  ctx.font = `${10 * scale}px system-ui, "DejaVu Sans", sans-serif`;
  ctx.textAlign = 'left';
  ctx.fillText(labelOfShown(), x0, 11 * scale, x1 - x0);
  ctx.textAlign = 'center';
  const px = (v) => x0 + ((v - lo) / (hi - lo)) * (x1 - x0);
  for (const t of niceTicks(lo, hi, 4)) {
    ctx.fillRect(px(t), y1, 1, 3 * scale);
    ctx.fillText(formatNumber(t, 3), px(t), y1 + 13 * scale);
  }
  if (state.show === 'distance' && state.thr !== null && state.thr >= lo && state.thr <= hi) {
    ctx.fillStyle = '#c0392b';
    ctx.fillRect(px(state.thr) - scale, y0 - 3 * scale, 2 * scale, y1 - y0 + 6 * scale);
  }
}

// ---------------------------------------------------------------------------------------
// The panel

function itemWord() {
  return view.header.kind === 'mesh' ? 'vertex' : 'cell';
}

function fillMenus() {
  const show = $('show');
  show.textContent = '';
  for (const letter of Object.keys(view.features)) show.append(new Option(`${LETTERS[letter].symbol} (${LETTERS[letter].name})`, letter));
  for (const name of view.others) show.append(new Option(name, name));
  show.append(new Option('distance to the selected ' + itemWord(), 'distance'));
  const metric = $('metric');
  for (const [k, label] of METRICS) metric.append(new Option(label, k));
  const inv = $('inv');
  for (const letter of 'VSPL') {
    if (!view.features[letter]) continue;
    const label = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.value = letter;
    label.append(box, ` ${letter}`);
    inv.append(label);
  }
}

function syncPanel() {
  const m = FEATURE.exec(state.show || '');
  const show = $('show');
  show.value = m ? m[1] : state.show;
  show.querySelector('option[value="distance"]').disabled = !view.distance;
  const radiusRow = $('radius-row');
  radiusRow.hidden = !m;
  if (m) {
    const list = view.features[m[1]];
    const k = list.findIndex((f) => f.name === state.show);
    const slider = $('radius');
    slider.max = String(list.length);
    slider.value = String(k + 1);
    const r = list[k].radius;
    $('radius-text').value = `${r === null ? `j = ${list[k].j}` : `${formatNumber(r)} ${view.header.units}`} (${state.show})`;
  }
  $('cmap').value = state.cmap;
  const [lo, hi] = currentRange();
  $('range-lo').value = String(Number(lo.toPrecision(5)));
  $('range-hi').value = String(Number(hi.toPrecision(5)));
  $('shade').value = String(state.shade);
  $('shade-text').value = state.shade.toFixed(2);
  $('metric').value = state.metric;
  $('p-row').hidden = !(state.metric === 'lp' || state.metric === 'lpw');
  $('p').value = String(state.p);
  for (const box of $('inv').querySelectorAll('input')) box.checked = state.inv.includes(box.value);
  syncThreshold();
}

function syncThreshold() {
  const out = $('threshold-text');
  if (!view.distance || state.thr === null) {
    out.value = 'all';
    return;
  }
  const [lo, hi] = currentRange();
  $('threshold').value = String(Math.round(((state.thr - lo) / (hi - lo)) * 1000));
  out.value = `${isSimilarity(state.metric) ? '≥' : '≤'} ${formatNumber(state.thr)}`;
}

/** Reads the invariants given by the view: the menus' entries and the radius slider. */
function shownFromMenus() {
  const value = $('show').value;
  if (view.features[value]) {
    const list = view.features[value];
    const k = Math.min(list.length, Math.max(1, Number($('radius').value))) - 1;
    const current = FEATURE.exec(state.show || '');
    // Another invariant keeps the radius index where it can.
    if (current && current[1] !== value) {
      const same = list.findIndex((f) => f.j === Number(current[2]));
      return list[same >= 0 ? same : list.length - 1].name;
    }
    return list[k].name;
  }
  return value;
}

async function show(name, { timed = false } = {}) {
  const t0 = performance.now();
  if (name !== 'distance') await loadColumn(name);
  state.show = name;
  applyColouring();
  syncPanel();
  const work = performance.now() - t0;
  writeHash();
  const frame = await requestRender();
  if (timed) {
    timings.radiusChanges.push({ work, frame });
    showTimings();
  }
}

function showTimings() {
  const med = (list, key) => {
    if (!list.length) return null;
    const v = list.map((x) => x[key]).sort((a, b) => a - b);
    return v[Math.floor(v.length / 2)];
  };
  const parts = [];
  if (timings.firstFrame !== null) parts.push(`first frame ${(timings.firstFrame / 1000).toFixed(2)} s`);
  const r = med(timings.radiusChanges, 'work');
  if (r !== null) parts.push(`radius ${r.toFixed(0)} ms (+${med(timings.radiusChanges, 'frame').toFixed(0)} ms frame)`);
  const c = med(timings.clicks, 'work');
  if (c !== null) parts.push(`click ${c.toFixed(0)} ms (+${med(timings.clicks, 'frame').toFixed(0)} ms frame)`);
  $('timings').textContent = parts.join(' · ');
}

// ---------------------------------------------------------------------------------------
// A click: the vertex, its feature vectors, the distance of every vertex to it

const pickPixel = new Float32Array(4);

/** The point of the surface under the pixel (x, y) (device pixels, from the top left) in the last frame, or null. */
function surfacePointAt(x, y) {
  if (!frameTarget) return null;
  renderer.readRenderTargetPixels(frameTarget, x, frameTarget.height - 1 - y, 1, 1, pickPixel, undefined, 1);
  return pickPixel[3] > 0.5 ? [pickPixel[0], pickPixel[1], pickPixel[2]] : null;
}

/** The vertex nearest to p (a scan of all of them: a few ms for a million, and no index to build). */
function nearestVertex(p) {
  const pos = view.positions, inFace = view.inFace;
  let best = -1, bestD = Infinity;
  for (let i = 0, k = 0; i < view.n; i++, k += 3) {
    if (!inFace[i]) continue; // not drawn (and without values): not what was clicked
    const dx = pos[k] - p[0], dy = pos[k + 1] - p[1], dz = pos[k + 2] - p[2];
    const d = dx * dx + dy * dy + dz * dz;
    if (d < bestD) {
      bestD = d;
      best = i;
    }
  }
  return best;
}

/** The cell under the CSS pixel (x, y) of the canvas, or null. */
function cellAt(x, y) {
  const r = view.header.raster;
  const ndc = new THREE.Vector3((x / canvas.clientWidth) * 2 - 1, -(y / canvas.clientHeight) * 2 + 1, 0).unproject(camera);
  const col = Math.floor(ndc.x / r.cell[0] + r.width / 2);
  const row = Math.floor(r.height / 2 - ndc.y / r.cell[1]);
  if (col < 0 || row < 0 || col >= r.width || row >= r.height) return null;
  return row * r.width + col;
}

/** The CSS pixel of the canvas where item i (a vertex, a cell's centre) is drawn. */
function screenOf(i) {
  let p;
  if (view.header.kind === 'mesh') {
    p = new THREE.Vector3(view.positions[3 * i], view.positions[3 * i + 1], view.positions[3 * i + 2]);
  } else {
    const r = view.header.raster;
    const col = i % r.width, row = Math.floor(i / r.width);
    p = new THREE.Vector3((col + 0.5 - r.width / 2) * r.cell[0], (r.height / 2 - row - 0.5) * r.cell[1], 0);
  }
  p.project(camera);
  const rect = canvas.getBoundingClientRect();
  return { x: rect.left + ((p.x + 1) / 2) * canvas.clientWidth, y: rect.top + ((1 - p.y) / 2) * canvas.clientHeight };
}

/** The feature table of `letters` (one is kept: the table of all 64 elements of a million vertices takes 140 MB). */
async function tableOf(letters) {
  if (!view.tables.has(letters)) {
    const needed = [...letters].flatMap((l) => (view.features[l] || []).map((f) => f.name));
    await Promise.all(needed.map(loadColumn));
    const table = featureTable(letters, view.columns, view.n);
    view.tables.clear();
    view.tables.set(letters, { table, cache: {} });
  }
  return view.tables.get(letters);
}

function featureVectorOf(i) {
  const out = {};
  for (const [letter, list] of Object.entries(view.features)) {
    out[letter] = list.map((f) => {
      const c = view.columns.get(f.name);
      return c ? (c.q[i] === NAN_CODE ? NaN : c.lo + c.q[i] * c.step) : undefined;
    });
  }
  return out;
}

function describeSelection(i) {
  const h = view.header;
  $('selection').hidden = false;
  $('sel-title').textContent = `${itemWord()[0].toUpperCase()}${itemWord().slice(1)} ${i}`;
  if (h.kind === 'mesh') {
    const p = [0, 1, 2].map((k) => view.positions[3 * i + k] + h.mesh.center[k]);
    $('sel-where').textContent = `at (${p.map((v) => formatNumber(v, 6)).join(', ')}) ${h.units}`;
  } else {
    const r = h.raster, t = r.transform;
    const col = i % r.width, row = Math.floor(i / r.width);
    const x = t[0] + (col + 0.5) * t[1] + (row + 0.5) * t[2], y = t[3] + (col + 0.5) * t[4] + (row + 0.5) * t[5];
    $('sel-where').textContent = `column ${col}, row ${row}: (${formatNumber(x, 9)}, ${formatNumber(y, 9)})${r.crs ? ' ' + r.crs : ''}`;
  }
  const vectors = featureVectorOf(i);
  const curves = Object.entries(vectors).map(([letter, values]) => ({
    letter,
    radii: view.features[letter].map((f) => (f.radius === null ? f.j : f.radius)),
    values,
  }));
  drawFeatureCurves($('curves'), curves, view.header.radii?.length ? h.units : 'j');
  // The numbers, with full precision in data-value for whoever reads them (the tests do);
  // made as one piece of HTML, which is several times faster than a cell at a time.
  const letters = Object.keys(vectors);
  const rows = Math.max(...Object.values(view.features).map((l) => l.length));
  // Property names come from the file: escaped.
  const escape = (text) => String(text).replace(/[&<>"']/g, (ch) => `&#${ch.charCodeAt(0)};`);
  const cell = (name, v) => `<td data-name="${escape(name)}" data-value="${v}">${v === undefined ? '…' : formatNumber(v, 5)}</td>`;
  let html = `<tr><th>r</th>${letters.map((l) => `<th>${LETTERS[l].symbol}</th>`).join('')}</tr>`;
  for (let k = 0; k < rows; k++) {
    const first = Object.values(view.features).find((l) => l[k])[k];
    html += `<tr><td>${first.radius === null ? `j=${first.j}` : formatNumber(first.radius)}</td>`;
    for (const l of letters) html += view.features[l][k] ? cell(view.features[l][k].name, vectors[l][k]) : '<td></td>';
    html += '</tr>';
  }
  for (const name of view.others) {
    const c = view.columns.get(name);
    if (c) html += `<tr><td>${escape(name)}</td>${cell(name, c.q[i] === NAN_CODE ? NaN : c.lo + c.q[i] * c.step).replace('<td', `<td colspan="${letters.length}"`)}</tr>`;
  }
  $('vector').innerHTML = html;
}

/** Percentiles of the finite values of `f`, from an even sample of at most 16,384 of them (a colour range needs no more). */
function samplePercentiles(f, ps) {
  const stride = Math.max(1, Math.floor(f.length / 16384));
  const sample = new Float32Array(Math.ceil(f.length / stride));
  let m = 0;
  for (let i = 0; i < f.length; i += stride) if (Number.isFinite(f[i])) sample[m++] = f[i];
  if (!m) return ps.map(() => 0);
  const sorted = sample.subarray(0, m).sort();
  return ps.map((p) => sorted[Math.min(m - 1, Math.round((p / 100) * (m - 1)))]);
}

/** The metric of every vertex to the selected one; false (with the reason shown) where it is undefined. */
async function computeDistances() {
  const note = $('metric-note');
  note.classList.remove('error');
  const generation = ++view.generation;
  try {
    const entry = await tableOf(state.inv);
    const { table } = entry;
    const reference = vertexReference(table, state.sel);
    if (!view.distance) {
      view.distance = new Float32Array(view.n);
      view.distanceUpload = new Float32Array(view.n);
    }
    if (generation !== view.generation) return 'superseded'; // another click came while the table was made
    const tk = performance.now();
    const undefinedCount = computeMetric(table, reference, state.metric, state.p, view.distance, view.distanceUpload, entry.cache);
    view.kernelMs = performance.now() - tk;
    const f = view.distance;
    view.distanceVersion = (view.distanceVersion || 0) + 1;
    const sim = isSimilarity(state.metric);
    const [p1, p50, p99] = samplePercentiles(f, [1, 50, 99]);
    let min = Infinity, max = -Infinity;
    for (let i = 0; i < f.length; i += Math.max(1, Math.floor(f.length / 16384))) {
      if (f[i] < min) min = f[i];
      if (f[i] > max) max = f[i];
    }
    view.distanceRange = sim ? [p1, Math.max(max, p99)] : [Math.min(min, 0), p99];
    // Halfway between the clicked vertex and the typical one (most of a scan is plain
    // surface): what is nearer than that is like the clicked mark.
    if (state.thr === null) {
      const thr = sim ? p50 + (view.distanceRange[1] - p50) / 2 : view.distanceRange[0] + (p50 - view.distanceRange[0]) / 2;
      state.thr = Number(thr.toPrecision(4)); // as the link writes it
    }
    note.textContent = `${table.blocks.map((b) => `${b.letter}×${b.count}`).join(', ')}; ` +
      `${sim ? 'similar' : 'near'} ${view.header.kind === 'mesh' ? 'vertices' : 'cells'} ${sim ? 'above' : 'below'} the threshold in colour` +
      (undefinedCount ? `; ${undefinedCount} undefined (NaN), grey` : '');
    return true;
  } catch (e) {
    if (generation !== view.generation) return 'superseded';
    view.distance = null;
    note.textContent = e.message;
    note.classList.add('error');
    return false;
  }
}

async function select(i, { timed = false, t0 = performance.now(), pickMs = 0 } = {}) {
  state.sel = i;
  placeMarker(i);
  describeSelection(i);
  const tm = performance.now();
  const ok = await computeDistances();
  if (ok === 'superseded') return;
  const metricMs = performance.now() - tm;
  if (ok) state.show = 'distance';
  else if (state.show === 'distance') state.show = defaultColumn();
  applyColouring();
  syncPanel();
  const work = performance.now() - t0;
  writeHash();
  const frame = await requestRender();
  if (timed) {
    timings.clicks.push({ pick: pickMs, metric: metricMs, kernel: view.kernelMs, work, frame });
    showTimings();
  }
}

function clearSelection() {
  view.generation++; // a computation under way is for nothing now
  state.sel = null;
  placeMarker(null);
  state.thr = null;
  view.distance = null;
  $('selection').hidden = true;
  if (state.show === 'distance') state.show = defaultColumn();
  applyColouring();
  syncPanel();
  writeHash();
  requestRender();
}

/** The vertex (or cell) under the page's point (clientX, clientY), or null. */
function itemAt(clientX, clientY) {
  const rect = canvas.getBoundingClientRect();
  const x = clientX - rect.left, y = clientY - rect.top;
  if (view.header.kind !== 'mesh') return cellAt(x, y);
  const ratio = renderer.domElement.width / canvas.clientWidth;
  const p = surfacePointAt(Math.floor(x * ratio), Math.floor(y * ratio));
  return p ? nearestVertex(p) : null;
}

async function onClick(event) {
  const t0 = performance.now();
  const i = itemAt(event.clientX, event.clientY);
  const pickMs = performance.now() - t0;
  if (i === null) return;
  await select(i, { timed: true, t0, pickMs });
}

// ---------------------------------------------------------------------------------------
// PNG and link

function savePng() {
  drawNow();
  const gl = renderer.domElement;
  const bar = document.createElement('canvas');
  const scale = Math.max(1, Math.round(gl.height / 600));
  bar.width = 300 * scale;
  bar.height = 58 * scale;
  drawColorBar(bar, scale);
  const out = document.createElement('canvas');
  out.width = gl.width;
  out.height = gl.height + bar.height;
  const ctx = out.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, out.width, out.height);
  ctx.drawImage(gl, 0, 0);
  ctx.drawImage(bar, Math.max(0, out.width - bar.width), gl.height);
  out.toBlob((blob) => {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = view.header.source.replace(/\.(ply|tif|tiff)$/i, '') + '.view.png';
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  }, 'image/png');
}

// ---------------------------------------------------------------------------------------
// Start

function defaultColumn() {
  const names = view.header.columns.map((c) => c.name);
  return names.includes('quality') ? 'quality' : names[0];
}

function wireEvents() {
  new ResizeObserver(resize).observe(canvas);
  controls.addEventListener('change', () => {
    state.camera = cameraState();
    writeHash(300);
    requestRender();
  });
  let down = null;
  canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY, t: performance.now(), b: e.button }; });
  canvas.addEventListener('pointerup', (e) => {
    if (down && down.b === 0 && Math.hypot(e.clientX - down.x, e.clientY - down.y) < 4 && performance.now() - down.t < 600) onClick(e);
    down = null;
  });
  $('show').addEventListener('change', () => show(shownFromMenus()));
  $('radius').addEventListener('input', () => show(shownFromMenus(), { timed: true }));
  $('cmap').addEventListener('change', () => {
    state.cmap = $('cmap').value;
    applyColouring();
    syncPanel();
    writeHash();
    requestRender();
  });
  const setRange = () => {
    const lo = Number($('range-lo').value), hi = Number($('range-hi').value);
    if (Number.isFinite(lo) && Number.isFinite(hi) && lo < hi) state.range = [lo, hi];
    applyColouring();
    syncPanel();
    writeHash();
    requestRender();
  };
  $('range-lo').addEventListener('change', setRange);
  $('range-hi').addEventListener('change', setRange);
  $('range-auto').addEventListener('click', () => {
    state.range = null;
    applyColouring();
    syncPanel();
    writeHash();
    requestRender();
  });
  $('shade').addEventListener('input', () => {
    state.shade = Number($('shade').value);
    applyColouring();
    syncPanel();
    writeHash();
    requestRender();
  });
  const remeasure = async () => {
    state.thr = null;
    if (state.sel !== null) await select(state.sel);
  };
  $('metric').addEventListener('change', () => {
    state.metric = $('metric').value;
    remeasure();
  });
  $('p').addEventListener('change', () => {
    const p = Number($('p').value);
    if (p > 0) state.p = p;
    remeasure();
  });
  $('inv').addEventListener('change', () => {
    const letters = [...$('inv').querySelectorAll('input:checked')].map((b) => b.value).join('');
    state.inv = letters || 'V';
    remeasure();
  });
  $('threshold').addEventListener('input', () => {
    const [lo, hi] = currentRange();
    state.thr = lo + (Number($('threshold').value) / 1000) * (hi - lo);
    applyColouring();
    syncThreshold();
    writeHash(200);
    requestRender();
  });
  $('clear').addEventListener('click', clearSelection);
  $('reset').addEventListener('click', () => {
    homeCamera();
    state.camera = cameraState();
    writeHash();
    requestRender();
  });
  $('png').addEventListener('click', savePng);
  $('link').addEventListener('click', async () => {
    history.replaceState(null, '', stateToHash());
    try {
      await navigator.clipboard.writeText(location.href);
      setStatus('The link is copied.');
    } catch {
      setStatus('The link is in the address bar.');
    }
    setTimeout(() => setStatus(''), 2500);
  });
  window.addEventListener('hashchange', () => applyState(hashToState(location.hash)));
}

/** Applies a state read from a link (at the start, or when the address changes). */
async function applyState(s) {
  if (s.camera) applyCamera(s.camera);
  if (s.cmap && colormaps[s.cmap]) state.cmap = s.cmap;
  if ('range' in s) state.range = s.range;
  if ('shade' in s) state.shade = s.shade;
  if (s.metric && METRICS.some(([k]) => k === s.metric)) state.metric = s.metric;
  if (s.p) state.p = s.p;
  if (s.inv) state.inv = s.inv;
  state.thr = 'thr' in s ? s.thr : null;
  if (s.show && s.show !== 'distance' && view.header.columns.some((c) => c.name === s.show)) state.show = s.show;
  if (s.sel !== undefined && s.sel < view.n) {
    if (s.show === 'distance' || s.show === undefined) state.show = 'distance';
    await select(s.sel);
  } else {
    if (state.sel !== null) clearSelection();
    if (state.show === 'distance') state.show = defaultColumn();
    await show(state.show);
  }
}

async function main() {
  if (location.protocol === 'file:') {
    throw new Error('open this page through a web server: msii view FOLDER serves it, as does python3 -m http.server in the folder');
  }
  if (typeof DecompressionStream === 'undefined') {
    throw new Error('this browser cannot inflate the data (DecompressionStream: Chrome 80, Firefox 113, Safari 16.4 and later)');
  }
  makeRenderer();
  const { header, bin, arrived, complete } = await fetchView(new URL('.', location.href));
  complete.then(() => { timings.fetched = performance.now(); }, () => {});
  view.header = header;
  view.bin = bin;
  view.arrived = arrived;
  view.n = header.items;
  for (const [name, hex] of Object.entries(header.colormaps)) colormaps[name] = colormapTexture(hex);
  indexColumns();
  document.title = `${header.source} · msii view`;
  $('title').textContent = header.source;
  const units = header.units;
  $('about').textContent = header.kind === 'mesh'
    ? `${header.mesh.vertices.toLocaleString('en')} vertices, ${header.mesh.triangles.toLocaleString('en')} triangles` +
      (header.radius ? `; R = ${formatNumber(header.radius)} ${units}, N = ${header.scales}` : '')
    : `${header.raster.width} × ${header.raster.height} cells of ${formatNumber(header.raster.cell[0])} ${units}` +
      (header.radius ? `; R = ${formatNumber(header.radius)} ${units}, N = ${header.scales}` : '');
  $('hint').textContent = header.kind === 'mesh'
    ? 'Drag: turn · right-drag or shift-drag: move · wheel: zoom · click: a vertex'
    : 'Drag: move · wheel: zoom · click: a cell';
  fillMenus();

  const initial = hashToState(location.hash);
  state.show = initial.show && initial.show !== 'distance' && header.columns.some((c) => c.name === initial.show)
    ? initial.show : defaultColumn();
  if (initial.cmap && colormaps[initial.cmap]) state.cmap = initial.cmap;
  if ('shade' in initial) state.shade = initial.shade;
  else state.shade = header.shading.strength;
  if (initial.range) state.range = initial.range;

  setStatus('Drawing…');
  await Promise.all([header.kind === 'mesh' ? buildMesh() : buildMap(), loadColumn(state.show)]);
  timings.decoded = performance.now();
  scene.add(marker);
  homeCamera();
  if (initial.camera) applyCamera(initial.camera);
  state.camera = cameraState();
  applyColouring();
  syncPanel();
  drawNow();
  timings.firstFrame = performance.now();
  showTimings();
  wireEvents();

  // The other columns, those of the metric's invariants first, while the user looks.
  setStatus('Reading the features…');
  const order = [...new Set([...(view.features[state.inv[0]] || []).map((f) => f.name), ...header.columns.map((c) => c.name)])];
  let done = 0;
  for (const name of order) {
    await loadColumn(name);
    done++;
    if (done % 8 === 0) setStatus(`Reading the features: ${done} of ${order.length}`);
  }
  timings.allColumns = performance.now();
  view.bin = null; // every section is decoded
  // The feature table of the first click, made while nobody waits; where it cannot be made
  // (a DEM's default bands hold V at some radii only) a click says why.
  await tableOf(state.inv).catch(() => {});
  setStatus('');
  await applyState(initial);
}

const ready = main().catch((e) => {
  console.error(e);
  setStatus(`msii view: ${e.message}`, true);
  throw e;
});

/** For tests and scripts: what the page shows and knows. */
window.msiiView = {
  ready,
  timings,
  get header() { return view.header; },
  state: () => JSON.parse(JSON.stringify(state)),
  screenOf,
  itemAt,
  featureVector: featureVectorOf,
  distance: () => (view.distance ? Array.from(view.distance) : null),
  distanceAt: (i) => (view.distance ? view.distance[i] : null),
  valueOf: (name, i) => {
    const c = view.columns.get(name);
    return c.q[i] === NAN_CODE ? NaN : c.lo + c.q[i] * c.step;
  },
  colorOf: (value) => {
    const [lo, hi] = currentRange();
    return tableColor(state.cmap, (value - lo) / (hi - lo));
  },
  range: currentRange,
  select: (i) => select(i, { timed: true }),
  show: (name) => show(name, { timed: true }),
  render: requestRender,
  rowOf: (letters, i) => rowOf(view.tables.get(letters).table, i),
  get distanceVersion() { return view.distanceVersion; },
};
