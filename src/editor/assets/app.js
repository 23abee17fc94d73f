// grainline edit: the page. The part in WebGL shaded with the scene's BRDF and the current
// grain (brdf.js), the key light's highlight curves and critical points over it, orbit / pan /
// zoom (OrbitControls), and the scene's tools driven by the mouse. Every change is sent to the
// server, which solves it off the request thread; the page long-polls /api/state and loads the
// newest solved grain. window.editor exposes the state for tests.
import * as THREE from './three.module.js';
import { OrbitControls } from './OrbitControls.js';
import { vertexShader, fragmentShader } from './brdf.js';
import { createLic } from './lic.js';

const $ = (id) => document.getElementById(id);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const editor = {
  ready: false, version: 0, solvedVersion: null, displayedVersion: null, state: null,
  error: null, saved: 0, lastEdit: null, info: null,
};
window.editor = editor;

async function api(path, body) {
  const r = await fetch(path, {
    method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(body ?? {}),
  });
  const j = await r.json().catch(() => ({ error: `HTTP ${r.status}` }));
  if (!r.ok) throw new Error(j.error || `HTTP ${r.status}`);
  return j;
}

function status(text, isError) {
  const el = $('status');
  el.textContent = text;
  el.classList.toggle('error', !!isError);
}

const info = await (await fetch('/api/info')).json();
editor.info = info;
// The scene's file name (its whole path in the tooltip).
const sceneName = info.scene.split(/[\\/]/).pop();
$('scene-name').title = info.scene;
$('scene-name').textContent = `${sceneName} · ${info.vertices} vertices`;

// ---- the mesh: non-indexed, so that a line field's corners can be aligned per triangle ----
// The server solves a drag on the part as prepared for the committed edits and refines the
// part inside a brush when the drag ends: a solved grain names its part (`partId`), and the
// page loads that part's mesh (more vertices) when it is not the one shown.
let partId = 0, nv = 0, nf = 0, vpos = null, faces = null, cgrain = null, grainAttr = null;
let cbrushed = null, brushedAttr = null;
let geometry = new THREE.BufferGeometry();
function setMesh(buf, id) {
  const head = new Uint32Array(buf, 0, 2);
  nv = head[0]; nf = head[1];
  vpos = new Float32Array(buf, 8, 3 * nv);
  const vnor = new Float32Array(buf, 8 + 12 * nv, 3 * nv);
  faces = new Uint32Array(buf, 8 + 24 * nv, 3 * nf);
  const cpos = new Float32Array(9 * nf), cnor = new Float32Array(9 * nf);
  cgrain = new Float32Array(9 * nf);
  for (let k = 0; k < 3 * nf; k++) {
    const v = faces[k];
    for (let c = 0; c < 3; c++) {
      cpos[3 * k + c] = vpos[3 * v + c];
      cnor[3 * k + c] = vnor[3 * v + c];
    }
  }
  geometry.setAttribute('position', new THREE.BufferAttribute(cpos, 3));
  geometry.setAttribute('normal', new THREE.BufferAttribute(cnor, 3));
  grainAttr = new THREE.BufferAttribute(cgrain, 3);
  grainAttr.setUsage(THREE.DynamicDrawUsage);
  geometry.setAttribute('grain', grainAttr);
  // 1 where the corner's grain is brushed (or designed), 0 where no stroke's brush reached it.
  cbrushed = new Float32Array(3 * nf).fill(1);
  brushedAttr = new THREE.BufferAttribute(cbrushed, 1);
  brushedAttr.setUsage(THREE.DynamicDrawUsage);
  geometry.setAttribute('brushed', brushedAttr);
  geometry.computeBoundingSphere();
  geometry.computeBoundingBox();
  partId = id;
  editor.partId = id;
  editor.vertices = nv;
  $('scene-name').textContent = `${sceneName} · ${nv} vertices`;
}
async function loadMesh(id) {
  const r = await fetch(`/api/mesh?part=${id}`);
  if (!r.ok) return false;
  const buf = await r.arrayBuffer();
  if (nv === 0) { setMesh(buf, id); return true; }
  // Another mesh: a new geometry on the part, the old one's GPU buffers freed.
  const old = geometry;
  geometry = new THREE.BufferGeometry();
  setMesh(buf, id);
  part.geometry = geometry;
  lic.setGeometry(geometry);
  old.dispose();
  return true;
}
await loadMesh(0);

// ---- the material: the scene's BRDF, lights and tone map ----
// Both sides are drawn, as in the preview: a back face keeps its outward normal, so it is black
// (ω_out below the surface), e.g. the inside of an open part.
const MAX_LIGHTS = 8;
const m = info.material;
const brdfKind = { ashikhmin_shirley: 0, ward: 1, ggx: 2 }[m.brdf.kind] ?? 0;
const param = brdfKind === 0 ? [m.brdf.nu, m.brdf.nv, 0]
  : brdfKind === 1 ? [m.brdf.alpha_x, m.brdf.alpha_y, m.brdf.rho_s] : [m.brdf.alpha_u, m.brdf.alpha_v, 0];
// The bare metal where no brush passed (Material::unbrushed): isotropic, the narrower lobe.
const bareParam = brdfKind === 0 ? [Math.max(param[0], param[1]), Math.max(param[0], param[1]), 0]
  : [Math.min(param[0], param[1]), Math.min(param[0], param[1]), param[2]];
const fr = info.fresnel;
const v3 = (a) => new THREE.Vector3(a[0], a[1], a[2]);
const uniforms = {
  uBrdf: { value: brdfKind }, uParam: { value: v3(param) }, uBareParam: { value: v3(bareParam) },
  uRs: { value: v3(m.brdf.rs ?? [0, 0, 0]) }, uDiffuse: { value: v3(m.diffuse) },
  uFresnel: { value: { none: 0, schlick: 1, conductor: 2 }[fr.kind] },
  uF0: { value: v3(fr.f0 ?? [0, 0, 0]) }, uEta: { value: v3(fr.eta ?? [1, 1, 1]) },
  uK: { value: v3(fr.k ?? [0, 0, 0]) },
  uLightCount: { value: 0 }, uLightType: { value: new Array(MAX_LIGHTS).fill(0) },
  uLightVec: { value: Array.from({ length: MAX_LIGHTS }, () => new THREE.Vector3()) },
  uLightE: { value: Array.from({ length: MAX_LIGHTS }, () => new THREE.Vector3()) },
  uToneMap: { value: { none: 0, exposure: 1, reinhard: 2 }[info.tone_map] ?? 2 },
  uExposure: { value: info.exposure },
  uBrush: { value: new THREE.Vector3() }, uBrushRadius: { value: 0 },
  uKeyType: { value: 0 }, uKeyVec: { value: new THREE.Vector3(0, 0, 1) },
};
function setLights(keyDirection) {
  let k = 0;
  info.lights.forEach((l, i) => {
    if (k >= MAX_LIGHTS || (l.type !== 'directional' && l.type !== 'point')) return;
    const c = l.colour ?? [1, 1, 1];
    if (l.type === 'directional') {
      const d = i === info.key_light && keyDirection ? keyDirection : l.direction;
      uniforms.uLightType.value[k] = 0;
      uniforms.uLightVec.value[k].copy(v3(d).normalize());
      uniforms.uLightE.value[k].set(c[0] * l.irradiance, c[1] * l.irradiance, c[2] * l.irradiance);
    } else {
      uniforms.uLightType.value[k] = 1;
      uniforms.uLightVec.value[k].copy(v3(l.position));
      uniforms.uLightE.value[k].set(c[0] * l.intensity, c[1] * l.intensity, c[2] * l.intensity);
    }
    // The key light's highlight is the one the LIC follows (lic.js).
    if (i === info.key_light) {
      uniforms.uKeyType.value = uniforms.uLightType.value[k];
      uniforms.uKeyVec.value.copy(uniforms.uLightVec.value[k]);
    }
    k++;
  });
  uniforms.uLightCount.value = k;
}
setLights(null);
const material = new THREE.ShaderMaterial({
  uniforms, vertexShader, fragmentShader, side: THREE.DoubleSide,
  polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
});
const part = new THREE.Mesh(geometry, material);

// ---- overlays: highlight curves (the zero set of hᵀu), critical points, the drawn curve ----
const curveGeom = new THREE.BufferGeometry();
const curves = new THREE.LineSegments(curveGeom, new THREE.LineBasicMaterial({ color: 0xffc400 }));
const critGeom = new THREE.BufferGeometry();
const critical = new THREE.Points(critGeom, new THREE.PointsMaterial({ color: 0xff40ff, size: 5, sizeAttenuation: false }));
const strokeGeom = new THREE.BufferGeometry();
const stroke = new THREE.Line(strokeGeom, new THREE.LineBasicMaterial({ color: 0x40e0ff }));
stroke.frustumCulled = false;
// The light tool's tangent: a segment through the pressed point along the drag, both ways.
const tangentGeom = new THREE.BufferGeometry();
const tangentLine = new THREE.Line(tangentGeom, new THREE.LineBasicMaterial({ color: 0xff7030, depthTest: false }));
tangentLine.frustumCulled = false;
tangentLine.renderOrder = 1;
const grainGeom = new THREE.BufferGeometry();
const grainLinesObj = new THREE.LineSegments(grainGeom, new THREE.LineBasicMaterial({ color: 0xb0b0b0, transparent: true, opacity: 0.5 }));
grainLinesObj.visible = false;
grainLinesObj.frustumCulled = false;
const strokeLineGeom = new THREE.BufferGeometry();
const strokeLines = new THREE.LineSegments(strokeLineGeom, new THREE.LineBasicMaterial({ color: 0x30e070 }));
strokeLines.visible = false;
strokeLines.frustumCulled = false;
curves.frustumCulled = false;
critical.frustumCulled = false;

// ---- renderer, camera, controls ----
THREE.ColorManagement.enabled = false;
const canvas = $('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
renderer.setPixelRatio(window.devicePixelRatio || 1);
const bg = info.background;
renderer.setClearColor(new THREE.Color(bg[0], bg[1], bg[2]), 1);
const scene = new THREE.Scene();
scene.add(part, curves, critical, stroke, tangentLine, grainLinesObj, strokeLines);
const lic = createLic(THREE, renderer, uniforms, vertexShader);
lic.setGeometry(geometry);
editor.lic = lic;
const view = info.view;
const diag = info.diagonal;
const camera = new THREE.PerspectiveCamera(view.fov_deg, 1, diag * 1e-3, diag * 100 + v3(view.eye).distanceTo(v3(view.target)) * 4);

let gesture = null;
// The tools' listener is added before OrbitControls', so it can take a press on the part.
canvas.addEventListener('pointerdown', onDown);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = false;
function resetView() {
  camera.up.copy(v3(view.up).normalize());
  camera.position.copy(v3(view.eye));
  controls.target.copy(v3(view.target));
  camera.lookAt(controls.target);
  controls.update();
  requestRender();
}

let renderQueued = false;
function requestRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(() => {
    renderQueued = false;
    resize();
    lic.update(camera);
    renderer.render(scene, camera);
    editor.frames = (editor.frames ?? 0) + 1;
  });
}
function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  const pr = renderer.getPixelRatio();
  if (canvas.width !== Math.floor(w * pr) || canvas.height !== Math.floor(h * pr)) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
}
controls.addEventListener('change', requestRender);
window.addEventListener('resize', requestRender);

// ---- controls: tool, radius, strength, toggles ----
let tool = 'orbit';
let ringShown = true; // the brush ring under the pointer
function setTool(t) {
  tool = t;
  for (const r of document.querySelectorAll('input[name=tool]')) r.checked = r.value === t;
  if (t === 'orbit') uniforms.uBrushRadius.value = 0;
  requestRender();
}
for (const r of document.querySelectorAll('input[name=tool]')) r.addEventListener('change', () => setTool(r.value));
const rmin = diag / 400, rmax = diag / 2;
let radius = Math.min(Math.max(info.radius, rmin), rmax);
function setRadius(r) {
  radius = Math.min(Math.max(r, rmin), rmax);
  $('radius').value = Math.round(1000 * Math.log(radius / rmin) / Math.log(rmax / rmin));
  $('radius-value').textContent = `${radius.toPrecision(3)} ${info.units}`;
  if (uniforms.uBrushRadius.value > 0) uniforms.uBrushRadius.value = radius;
  requestRender();
}
$('radius').addEventListener('input', () => setRadius(rmin * Math.pow(rmax / rmin, $('radius').value / 1000)));
setRadius(radius);
const strength = () => Number($('strength').value);
const showStrength = () => { $('strength-value').textContent = strength().toFixed(2); };
$('strength').addEventListener('input', showStrength);
showStrength();
$('show-curves').addEventListener('change', () => { curves.visible = $('show-curves').checked; requestRender(); });
$('show-critical').addEventListener('change', () => { critical.visible = $('show-critical').checked; requestRender(); });
$('show-grain').addEventListener('change', () => {
  grainLinesObj.visible = $('show-grain').checked;
  if (grainLinesObj.visible) grainLines();
  requestRender();
});
$('show-lic').addEventListener('change', () => { lic.enabled = $('show-lic').checked; requestRender(); });
$('show-strokes').addEventListener('change', () => wantStrokes());
$('show-brushed').addEventListener('change', () => wantStrokes());
$('reset-view').addEventListener('click', resetView);
$('undo').addEventListener('click', () => change('/api/undo'));
$('redo').addEventListener('click', () => change('/api/redo'));
$('save').addEventListener('click', save);
for (const what of ['svg', 'gcode', 'glb']) $(`export-${what}`).addEventListener('click', () => exportFile(what));

// ---- the grain from the server ----
const symmetryLine = info.symmetry === 'line';
async function loadGrain(version) {
  const r = await fetch(`/api/grain?version=${version}`);
  if (!r.ok) return false; // superseded meanwhile: the next poll brings the newer one
  const buf = await r.arrayBuffer();
  const h = new Uint32Array(buf, 0, 4);
  const n = h[0], s = h[1], c = h[2];
  if (h[3] !== partId && !(await loadMesh(h[3]))) return false;
  if (n !== nv) return false;
  const u = new Float32Array(buf, 16, 3 * n);
  const seg = new Float32Array(buf, 16 + 12 * n, 6 * s);
  const crit = new Uint32Array(buf, 16 + 12 * n + 24 * s, c);
  designedU = u;
  brushedU = null;
  strokeLines.visible = false; // the strokes shown were another version's
  shadeGrain();
  curveGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(seg), 3));
  const cp = new Float32Array(3 * c);
  for (let i = 0; i < c; i++) for (let k = 0; k < 3; k++) cp[3 * i + k] = vpos[3 * crit[i] + k];
  critGeom.setAttribute('position', new THREE.BufferAttribute(cp, 3));
  editor.displayedVersion = version;
  editor.segments = seg;
  requestRender();
  return true;
}

// ---- the grain shown: designed, or rebuilt from the strokes (as brushed) ----
let designedU = null, brushedU = null;
/** Fills the per-corner grain from `u` (per vertex); where `fallback` is given, a zero vector
 * of `u` (no stroke's brush reached the vertex) is bare metal: the corner is marked unbrushed
 * (shaded without grain) and takes the fallback's direction only as the shading frame. */
function fillGrain(u, fallback) {
  const bare = (v) => {
    const x = u[3 * v], y = u[3 * v + 1], z = u[3 * v + 2];
    return fallback != null && x * x + y * y + z * z < 0.25;
  };
  const at = (v) => {
    if (bare(v)) return [fallback[3 * v], fallback[3 * v + 1], fallback[3 * v + 2]];
    return [u[3 * v], u[3 * v + 1], u[3 * v + 2]];
  };
  let unbrushed = 0;
  for (let k = 0; k < 3 * nf; k++) {
    const b = bare(faces[k]);
    cbrushed[k] = b ? 0 : 1;
    if (b) unbrushed++;
  }
  brushedAttr.needsUpdate = true;
  editor.unbrushedCorners = unbrushed;
  for (let f = 0; f < nf; f++) {
    const ua = at(faces[3 * f]);
    for (let k = 0; k < 3; k++) {
      let [x, y, z] = at(faces[3 * f + k]);
      // A line field's directions are defined up to sign: align the corners to the first.
      if (symmetryLine && x * ua[0] + y * ua[1] + z * ua[2] < 0) { x = -x; y = -y; z = -z; }
      cgrain[9 * f + 3 * k] = x; cgrain[9 * f + 3 * k + 1] = y; cgrain[9 * f + 3 * k + 2] = z;
    }
  }
  grainAttr.needsUpdate = true;
}
function shadeGrain() {
  if (!designedU) return;
  const brushed = $('show-brushed').checked && brushedU;
  fillGrain(brushed ? brushedU : designedU, brushed ? designedU : null);
  editor.shading = brushed ? 'as-brushed' : 'designed';
  if ($('show-grain').checked) grainLines();
  requestRender();
}

// ---- grain lines: a short streamline of the shown grain through each triangle's centroid ----
// Euler steps of the grain interpolated across the face (barycentric), both ways from the
// centroid, each step projected onto the face's plane; a line stops at the face's edge.
function grainLines() {
  const STEPS = 3, out = [];
  const P = (v, c) => vpos[3 * v + c];
  for (let f = 0; f < nf; f++) {
    const [a, b, c] = [faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]];
    const e1 = [0, 1, 2].map((i) => P(b, i) - P(a, i)), e2 = [0, 1, 2].map((i) => P(c, i) - P(a, i));
    const dot = (x, y) => x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    const g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2), det = g11 * g22 - g12 * g12;
    if (!(det > 0)) continue;
    // Step length: a third of the face's in-radius scale, √(2·area)/STEPS/2 per side.
    const h = Math.sqrt(Math.sqrt(det)) / (2 * STEPS);
    const corner = (k) => [cgrain[9 * f + 3 * k], cgrain[9 * f + 3 * k + 1], cgrain[9 * f + 3 * k + 2]];
    const u0 = corner(0), u1 = corner(1), u2 = corner(2);
    const point = (bb) => [0, 1, 2].map((i) => P(a, i) + bb[1] * e1[i] + bb[2] * e2[i]);
    for (const sign of [1, -1]) {
      let bb = [1 / 3, 1 / 3, 1 / 3];
      for (let k = 0; k < STEPS; k++) {
        const d = [0, 1, 2].map((i) => bb[0] * u0[i] + bb[1] * u1[i] + bb[2] * u2[i]);
        // The step in the face's coordinates: the least-squares (β1, β2) with β1 e1 + β2 e2 ≈ d.
        const r1 = dot(d, e1), r2 = dot(d, e2);
        let b1 = (g22 * r1 - g12 * r2) / det, b2 = (g11 * r2 - g12 * r1) / det;
        const len = Math.hypot(...[0, 1, 2].map((i) => b1 * e1[i] + b2 * e2[i]));
        if (!(len > 0)) break;
        b1 *= sign * h / len; b2 *= sign * h / len;
        const next = [bb[0] - b1 - b2, bb[1] + b1, bb[2] + b2];
        if (next.some((x) => x < 0)) break;
        out.push(...point(bb), ...point(next));
        bb = next;
      }
    }
  }
  grainGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(out), 3));
  editor.grainSegments = out.length / 6;
}

// ---- the strokes of the committed field, and the as-brushed grain (GET /api/strokes) ----
let strokesVersion = null, strokesLoading = null;
/** Loads the strokes of `version` (one load at a time: a second call waits for the first). */
async function loadStrokes(version) {
  while (strokesLoading) await strokesLoading;
  if (strokesVersion === version) return;
  strokesLoading = fetchStrokes(version);
  try { await strokesLoading; } finally { strokesLoading = null; }
}
async function fetchStrokes(version) {
  {
    const r = await fetch(`/api/strokes?version=${version}`);
    if (!r.ok) {
      const j = await r.json().catch(() => ({ error: `HTTP ${r.status}` }));
      if (r.status !== 409) { editor.strokesError = j.error; status(j.error, true); strokesVersion = version; }
      return;
    }
    const buf = await r.arrayBuffer();
    const h = new Uint32Array(buf, 0, 4);
    const [ns, np, n, id] = h;
    if (id !== partId || n !== nv || version !== editor.displayedVersion) return;
    const lens = new Uint32Array(buf, 16, ns);
    const pts = new Float32Array(buf, 16 + 4 * ns, 3 * np);
    const seg = [];
    let o = 0;
    for (let i = 0; i < ns; i++) {
      for (let k = o; k + 1 < o + lens[i]; k++) seg.push(...pts.subarray(3 * k, 3 * k + 6));
      o += lens[i];
    }
    strokeLineGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(seg), 3));
    brushedU = new Float32Array(buf, 16 + 4 * ns + 12 * np, 3 * n);
    let bare = 0;
    for (let v = 0; v < n; v++) if (brushedU[3 * v] === 0 && brushedU[3 * v + 1] === 0 && brushedU[3 * v + 2] === 0) bare++;
    editor.bareVertices = bare;
    strokesVersion = version;
    strokeLines.visible = $('show-strokes').checked;
    editor.strokes = ns;
    editor.strokesError = null;
  }
}
/** Loads the strokes of the shown version when a toggle needs them and no drag is going on. */
async function wantStrokes() {
  const on = $('show-strokes').checked || $('show-brushed').checked;
  strokeLines.visible = $('show-strokes').checked && strokesVersion === editor.displayedVersion;
  if (on && editor.displayedVersion != null && !gesture && !(editor.state && editor.state.previewing)) {
    await loadStrokes(editor.displayedVersion);
  }
  shadeGrain();
}
editor.wantStrokes = wantStrokes;

function applyState(st) {
  editor.state = st;
  editor.version = st.version;
  editor.solvedVersion = st.solved_version;
  if (st.key_light && !gizmoDir) { setLights(st.key_light); requestRender(); }
  $('undo').disabled = st.undo === 0;
  $('redo').disabled = st.redo === 0;
  $('save').textContent = st.dirty ? 'Save *' : 'Save';
  const err = st.error && st.error[0] > (st.solved_version ?? 0) ? st.error[1] : null;
  editor.error = err;
  const landed = st.fidelity.map((f) => `#${f.index} ${f.tool}: ${f.landed ? 'landed' : 'missed'} (${(100 * f.within).toFixed(0)} %)`);
  const line = [
    `version ${st.version}${st.solving ? ' · solving…' : ''}`,
    st.solved_version != null ? `shown ${st.solved_version} · solver: ${st.stop} · ${(1000 * st.seconds).toFixed(0)} ms` : 'solving…',
    ...landed,
  ];
  // A light edit sets the key light after the scene's (the gizmo's) light: it wins.
  const lit = st.edits.map((e, i) => [e, i]).filter(([e]) => e.tool === 'light').map(([, i]) => i);
  if (lit.length) line.push(`key light: set by light edit #${lit[lit.length - 1]} (the gizmo turns the light under the edits)`);
  const text = line.join('\n');
  status(err ? `${text}\n${err}` : text, !!err);
  drawGizmo();
  $('edits').textContent = st.edits.map((e, i) => `${i}: ${e.tool} r=${(e.radius ?? 0).toPrecision(3)}`).join('\n');
}

async function poll() {
  let after = 0;
  for (;;) {
    try {
      const st = await (await fetch(`/api/state?after=${after}`)).json();
      applyState(st);
      if (st.solved_version != null && st.solved_version !== editor.displayedVersion) {
        await loadGrain(st.solved_version);
      }
      if (editor.displayedVersion === st.solved_version && !st.previewing) wantStrokes();
      after = Math.max(st.solved_version ?? 0, st.error ? st.error[0] : 0);
      editor.ready = editor.displayedVersion != null;
    } catch (e) {
      status(`lost the server: ${e.message}`, true);
      await sleep(1000);
    }
  }
}

/** Resolves once the newest version is solved and shown (or failed). */
editor.whenIdle = async () => {
  for (;;) {
    const st = editor.state;
    if (st && !inflight && !pending && !gesture && !changing) {
      const failed = st.error && st.error[0] === st.version;
      if (failed || (st.solved_version === st.version && editor.displayedVersion === st.version)) {
        await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
        return { version: st.version, error: failed ? st.error[1] : null };
      }
    }
    await sleep(20);
  }
};

// ---- changes: previews coalesce (one request in flight, the newest waiting) ----
let inflight = false, pending = null;
function preview(edit) {
  pending = edit;
  if (!inflight) flush();
}
async function flush() {
  while (pending) {
    const e = pending;
    pending = null;
    inflight = true;
    try { applyState(await api('/api/edit', { action: 'preview', edit: e })); } catch (err) { status(err.message, true); }
    inflight = false;
  }
}
async function settle() {
  pending = null;
  while (inflight) await sleep(5);
}
// Changes on their way to the server (a commit waits for the preview in flight first):
// `whenIdle` must not take the last preview's solve for the settled state meanwhile.
let changing = 0;
async function change(path, body) {
  changing++;
  try {
    await settle();
    try { applyState(await api(path, body)); } catch (err) { status(err.message, true); }
  } finally {
    changing--;
  }
}
async function commit(edit) {
  editor.lastEdit = edit;
  await change('/api/edit', { action: 'commit', edit });
}
async function save() {
  await settle();
  try {
    const r = await api('/api/save', {});
    applyState(r.state);
    editor.saved++;
    status(`saved ${r.saved}`);
  } catch (err) { status(err.message, true); }
}

/** Writes the SVG, G-code or glTF of the committed edits (the server runs `grainline run`'s
 * stages for them); the path written is shown. */
async function exportFile(what) {
  await settle();
  status(`exporting ${what}…`);
  try {
    const r = await api('/api/export', { what });
    editor.exported = r.written;
    status(`wrote ${r.written}`);
  } catch (err) { editor.exported = null; status(err.message, true); }
}
editor.exportFile = exportFile;

// ---- picking and the tools ----
const raycaster = new THREE.Raycaster();
function ndc(ev) {
  const r = canvas.getBoundingClientRect();
  return new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
}
function pick(ev) {
  raycaster.setFromCamera(ndc(ev), camera);
  const hit = raycaster.intersectObject(part, false)[0];
  if (!hit) return null;
  return { point: hit.point.clone(), normal: hit.face.normal.clone() };
}
function onPlane(ev, p0, n0) {
  raycaster.setFromCamera(ndc(ev), camera);
  const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(n0, p0);
  const out = new THREE.Vector3();
  return raycaster.ray.intersectPlane(plane, out) ? out : null;
}
const arr = (v) => [v.x, v.y, v.z];

function onDown(ev) {
  if (ev.button !== 0 || tool === 'orbit') return;
  const hit = pick(ev);
  if (!hit) return;
  controls.enabled = false;
  canvas.setPointerCapture(ev.pointerId);
  gesture = { tool, p0: hit.point, n0: hit.normal, points: [hit.point], edit: null, x0: ev.clientX, y0: ev.clientY };
  if (tool === 'curve') strokeGeom.setFromPoints(gesture.points);
}
function warpEdit(g, p1) {
  const d = p1.clone().sub(g.p0);
  const len = d.length();
  if (len < 1e-3 * radius) return null;
  // At the brush centre a warp moves the highlight by s·r/2 (bend: d(0, 0) = 1/2): the drag's
  // length sets s so the highlight follows the pointer, up to the strength control.
  const range = info.strength[g.tool];
  const s = Math.min(2 * len / radius, strength(), range[1] * 0.999);
  return { tool: g.tool, centre: { point: arr(g.p0) }, radius, strength: Number(s.toFixed(6)), direction: arr(d.normalize()) };
}
/** The light tool: the pressed point is the centre, the drag (on the tangent plane there) the
 * highlight's wanted tangent ℓ; the server finds the key light. Drawn as a segment through the
 * centre, both ways (ℓ is a line). */
function lightEdit(g, p1, ev) {
  if (Math.hypot(ev.clientX - g.x0, ev.clientY - g.y0) < 4) return null;
  const d = p1.clone().sub(g.p0);
  if (!(d.length() > 0)) return null;
  const ends = [g.p0.clone().sub(d), g.p0.clone().add(d)];
  tangentGeom.setFromPoints(ends);
  editor.tangent = ends.map(arr);
  requestRender();
  return { tool: 'light', centre: { point: arr(g.p0) }, ell: arr(d.normalize()) };
}
canvas.addEventListener('pointermove', (ev) => {
  if (tool !== 'orbit' && !gesture && ringShown) {
    const hit = pick(ev);
    uniforms.uBrushRadius.value = hit ? radius : 0;
    if (hit) uniforms.uBrush.value.copy(hit.point);
    requestRender();
  }
  if (!gesture) return;
  if (gesture.tool === 'bend' || gesture.tool === 'expand') {
    const p1 = onPlane(ev, gesture.p0, gesture.n0);
    const e = p1 && warpEdit(gesture, p1);
    if (e) { gesture.edit = e; preview(e); }
  } else if (gesture.tool === 'light') {
    const p1 = onPlane(ev, gesture.p0, gesture.n0);
    const e = p1 && lightEdit(gesture, p1, ev);
    if (e) { gesture.edit = e; preview(e); }
  } else if (gesture.tool === 'curve') {
    const hit = pick(ev);
    const last = gesture.points[gesture.points.length - 1];
    if (hit && hit.point.distanceTo(last) > radius / 8) {
      gesture.points.push(hit.point);
      strokeGeom.setFromPoints(gesture.points);
      requestRender();
    }
  }
});
async function onUp(ev) {
  if (!gesture) return;
  const g = gesture;
  gesture = null;
  controls.enabled = true;
  try { canvas.releasePointerCapture(ev.pointerId); } catch (_) { /* already released */ }
  if (g.tool === 'bend' || g.tool === 'expand' || g.tool === 'light') {
    if (g.edit) await commit(g.edit); else await change('/api/edit', { action: 'cancel' });
    tangentGeom.setFromPoints([]);
    editor.tangent = null;
  } else if (g.tool === 'stencil') {
    await commit({ tool: 'stencil', centre: { point: arr(g.p0) }, radius });
  } else if (g.tool === 'curve') {
    strokeGeom.setFromPoints([]);
    if (g.points.length >= 2) await commit({ tool: 'curve', points: [g.points.map(arr)], radius });
  }
  requestRender();
}
canvas.addEventListener('pointerup', onUp);
canvas.addEventListener('pointercancel', onUp);

window.addEventListener('keydown', (ev) => {
  if (ev.target instanceof HTMLInputElement && ev.target.type === 'text') return;
  const k = ev.key.toLowerCase();
  const mod = ev.ctrlKey || ev.metaKey;
  if (mod && k === 'z') { ev.preventDefault(); change(ev.shiftKey ? '/api/redo' : '/api/undo'); return; }
  if (mod && k === 'y') { ev.preventDefault(); change('/api/redo'); return; }
  if (mod && k === 's') { ev.preventDefault(); save(); return; }
  if (mod || ev.altKey) return;
  const tools = { o: 'orbit', b: 'bend', e: 'expand', s: 'stencil', c: 'curve', l: 'light' };
  if (tools[k]) setTool(tools[k]);
  else if (k === 'h') { $('show-curves').click(); }
  else if (k === 'p') { $('show-critical').click(); }
  else if (k === 'g') { $('show-grain').click(); }
  else if (k === 'i') { $('show-lic').click(); }
  else if (k === 't') { $('show-strokes').click(); }
  else if (k === 'a') { $('show-brushed').click(); }
  else if (k === 'r') resetView();
  else if (k === '[') setRadius(radius / 1.15);
  else if (k === ']') setRadius(radius * 1.15);
  else if (k === 'escape' && gesture) {
    gesture = null;
    controls.enabled = true;
    strokeGeom.setFromPoints([]);
    tangentGeom.setFromPoints([]);
    change('/api/edit', { action: 'cancel' });
  }
});

// ---- the key light gizmo: a sphere seen from the camera; the point dragged on it is the
// direction towards the light (x right, y up, z towards the viewer) ----
const keyInfo = info.lights[info.key_light];
const gizmo = $('light-gizmo');
let gizmoDir = null; // the direction shown while dragging
/** The key light shown: the solved field's (after the edits: a light edit wins over the
 * scene's light), or, while a change is being solved, the light set on the page. */
function keyDirection() {
  const st = editor.state;
  if (st && st.key_light && st.solved_version === st.version) return st.key_light;
  return st?.light ?? (keyInfo && keyInfo.direction);
}
function cameraBasis() {
  const right = new THREE.Vector3(), up = new THREE.Vector3(), back = new THREE.Vector3();
  camera.matrixWorld.extractBasis(right, up, back);
  return { right, up, back };
}
function drawGizmo() {
  const d = gizmoDir ?? keyDirection();
  const g = gizmo.getContext('2d');
  const w = gizmo.width, c = w / 2, r = w / 2 - 4;
  g.clearRect(0, 0, w, w);
  g.fillStyle = '#333'; g.strokeStyle = '#777';
  g.beginPath(); g.arc(c, c, r, 0, 2 * Math.PI); g.fill(); g.stroke();
  if (!d) return;
  const { right, up, back } = cameraBasis();
  const v = v3(d).normalize();
  const x = v.dot(right), y = v.dot(up), z = v.dot(back);
  g.beginPath();
  g.arc(c + r * x, c - r * y, 5, 0, 2 * Math.PI);
  // In front of the part (towards the viewer): filled; behind it: a ring.
  if (z >= 0) { g.fillStyle = '#ffd84a'; g.fill(); } else { g.strokeStyle = '#ffd84a'; g.lineWidth = 2; g.stroke(); g.lineWidth = 1; }
  $('light-value').textContent = `${v.x.toFixed(2)}, ${v.y.toFixed(2)}, ${v.z.toFixed(2)}`;
}
/** The world direction under a pointer event on the gizmo (the rim beyond the disc). */
function gizmoDirection(ev) {
  const rect = gizmo.getBoundingClientRect();
  const r = rect.width / 2 - 4;
  let x = (ev.clientX - rect.left - rect.width / 2) / r, y = -(ev.clientY - rect.top - rect.height / 2) / r;
  const rr = x * x + y * y;
  if (rr > 1) { x /= Math.sqrt(rr); y /= Math.sqrt(rr); }
  const z = Math.sqrt(Math.max(0, 1 - x * x - y * y));
  const { right, up, back } = cameraBasis();
  const d = right.multiplyScalar(x).add(up.multiplyScalar(y)).add(back.multiplyScalar(z)).normalize();
  return [d.x, d.y, d.z];
}
if (!keyInfo || keyInfo.type !== 'directional') {
  $('light-box').style.display = 'none';
} else {
  gizmo.addEventListener('pointerdown', (ev) => {
    gizmo.setPointerCapture(ev.pointerId);
    gizmoDir = gizmoDirection(ev);
    setLights(gizmoDir); drawGizmo(); requestRender();
  });
  gizmo.addEventListener('pointermove', (ev) => {
    if (!gizmoDir) return;
    gizmoDir = gizmoDirection(ev);
    setLights(gizmoDir); drawGizmo(); requestRender();
  });
  const release = async () => {
    if (!gizmoDir) return;
    const direction = gizmoDir;
    gizmoDir = null;
    await change('/api/light', { direction });
    drawGizmo();
  };
  gizmo.addEventListener('pointerup', release);
  gizmo.addEventListener('pointercancel', release);
  controls.addEventListener('change', drawGizmo);
}
editor.setKeyLight = (direction) => change('/api/light', { direction });
editor.cameraBasis = () => {
  const { right, up, back } = cameraBasis();
  return { right: right.toArray(), up: up.toArray(), back: back.toArray() };
};

// ---- hooks for tests and scripts ----
editor.setTool = setTool;
/** The part's point (world) under the page point (CSS px), or null. */
editor.pickAt = (x, y) => { const h = pick({ clientX: x, clientY: y }); return h && arr(h.point); };
editor.setRadius = setRadius;
editor.resetView = resetView;
editor.radius = () => radius;
editor.setOverlays = (on) => {
  curves.visible = critical.visible = on;
  ringShown = on;
  if (!on) uniforms.uBrushRadius.value = 0;
  $('show-curves').checked = $('show-critical').checked = on;
  requestRender();
};
/** Page coordinates (CSS px) of a world point, and whether it is the visible surface there. */
editor.project = (p) => {
  const v = v3(p).project(camera);
  const r = canvas.getBoundingClientRect();
  const x = r.left + (v.x + 1) / 2 * r.width, y = r.top + (1 - v.y) / 2 * r.height;
  raycaster.setFromCamera(new THREE.Vector2(v.x, v.y), camera);
  const hit = raycaster.intersectObject(part, false)[0];
  const visible = !!hit && hit.point.distanceTo(v3(p)) < 1e-3 * diag + 0.01 * radius;
  return { x, y, visible };
};
/** The shown highlight segments' midpoints (world) with their page coordinates. */
editor.highlightPoints = () => {
  const s = editor.segments ?? new Float32Array(0);
  const out = [];
  for (let i = 0; i + 5 < s.length; i += 6) {
    const w = [(s[i] + s[i + 3]) / 2, (s[i + 1] + s[i + 4]) / 2, (s[i + 2] + s[i + 5]) / 2];
    out.push({ world: w, ...editor.project(w) });
  }
  return out;
};

resetView();
poll();
