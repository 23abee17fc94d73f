// node render.mjs JOB.json
// Renders a .glb with three.js (GLTFLoader, MeshPhysicalMaterial with KHR_materials_anisotropy)
// in headless Chromium (puppeteer-core, /usr/bin/chromium, WebGL 2 on SwiftShader), with one
// directional light and a pinhole camera given in the *scene's* coordinates (the part node's
// transform -- glTF scale and up rotation -- is applied to them here, as to the mesh).
//
// JOB.json: { "glb": path, "width": 512, "height": 512,
//             "camera": { "eye": [x,y,z], "target": [x,y,z], "up": [x,y,z], "fov_deg": f },
//             "light": { "direction": [x,y,z] (towards the light), "irradiance": E },
//             (when the file has its own camera and KHR_lights_punctual light, those are used
//             and reported beside these, as "file_camera" / "file_light" and "expected"),
//             "renders": [ { "rotate_anisotropy_deg": 0 (added to anisotropyRotation: a
//                              deliberate error, for the test that must fail),
//                            "raw": out path (linear RGBA f32, little-endian, rows top to bottom),
//                            "png": out path (optional; sRGB, clamped, the preview's background) } ] }
// Exit 0 on success, 1 on a rendering failure, 2 on a set-up problem.
import { readFileSync, writeFileSync, existsSync } from 'node:fs';
import { createServer } from 'node:http';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

const here = dirname(fileURLToPath(import.meta.url));
const job = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const chromium = process.env.GRAINLINE_CHROMIUM || '/usr/bin/chromium';
if (!existsSync(chromium)) {
  console.error(`render.mjs: ${chromium} not found (run setup.sh)`);
  process.exit(2);
}

const page_html = `<!doctype html><html><body style="margin:0">
<canvas id="c" width="${job.width}" height="${job.height}"></canvas>
<script type="importmap">{"imports": {"three": "/three/build/three.module.js",
  "three/addons/": "/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
window.render = async (job) => {
  const W = job.width, H = job.height;
  const canvas = document.getElementById('c');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: true,
    preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(W, H, false);
  renderer.setClearColor(0x000000, 0);
  const gltf = await new GLTFLoader().loadAsync('/model.glb');
  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  scene.updateMatrixWorld(true);
  let part = null, info = {};
  gltf.scene.traverse((o) => {
    if (o.isMesh && !part) part = o;
  });
  if (!part) throw new Error('no mesh in the glTF');
  const m = part.material;
  info.material = { type: m.type, anisotropy: m.anisotropy, anisotropyRotation: m.anisotropyRotation,
    roughness: m.roughness, metalness: m.metalness, hasTangents: !!part.geometry.attributes.tangent };
  const base = m.anisotropyRotation;
  const M = part.matrixWorld;
  const v = (a) => new THREE.Vector3(a[0], a[1], a[2]);
  const eye = v(job.camera.eye).applyMatrix4(M), target = v(job.camera.target).applyMatrix4(M);
  const up = v(job.camera.up).transformDirection(M);
  const dist = eye.distanceTo(target);
  const toLight = v(job.light.direction).transformDirection(M);
  info.expected = { eye: eye.toArray(), forward: target.clone().sub(eye).normalize().toArray(),
    up: up.toArray(), fov_deg: job.camera.fov_deg, light: toLight.toArray() };
  // The file's own camera and key light (KHR_lights_punctual), when it has them, are used for
  // the render: the test then checks them too.
  let camera;
  if (gltf.cameras.length > 0) {
    camera = gltf.cameras[0];
    camera.aspect = W / H;
    camera.near = 1e-3 * dist;
    camera.far = 100 * dist;
    camera.updateProjectionMatrix();
    camera.updateMatrixWorld(true);
    const f = new THREE.Vector3();
    camera.getWorldDirection(f);
    const u = new THREE.Vector3(0, 1, 0).transformDirection(camera.matrixWorld);
    info.file_camera = { eye: new THREE.Vector3().setFromMatrixPosition(camera.matrixWorld).toArray(),
      forward: f.toArray(), up: u.toArray(), fov_deg: camera.fov };
  } else {
    camera = new THREE.PerspectiveCamera(job.camera.fov_deg, W / H, 1e-3 * dist, 100 * dist);
    camera.position.copy(eye);
    camera.up.copy(up);
    camera.lookAt(target);
  }
  const fileLights = [];
  gltf.scene.traverse((o) => { if (o.isDirectionalLight) fileLights.push(o); });
  if (fileLights.length > 0) {
    const l = fileLights[0];
    l.updateMatrixWorld(true);
    l.target.updateMatrixWorld(true);
    const p = new THREE.Vector3().setFromMatrixPosition(l.matrixWorld);
    const t = new THREE.Vector3().setFromMatrixPosition(l.target.matrixWorld);
    info.file_light = { towards: p.sub(t).normalize().toArray(), intensity: l.intensity, count: fileLights.length };
  } else {
    const light = new THREE.DirectionalLight(0xffffff, job.light.irradiance);
    light.position.copy(toLight);
    light.target.position.set(0, 0, 0);
    scene.add(light);
    scene.add(light.target);
  }
  const rt = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType, format: THREE.RGBAFormat });
  const results = [];
  for (const r of job.renders) {
    m.anisotropyRotation = base + r.rotate_anisotropy_deg * Math.PI / 180;
    renderer.setRenderTarget(rt);
    renderer.toneMapping = THREE.NoToneMapping;
    renderer.setClearColor(0x000000, 0);
    renderer.render(scene, camera);
    const px = new Float32Array(W * H * 4);
    renderer.readRenderTargetPixels(rt, 0, 0, W, H, px);
    renderer.setRenderTarget(null);
    // The PNG: clamped like the preview's "tone_map": "none", on the preview's background.
    renderer.outputColorSpace = THREE.SRGBColorSpace;
    renderer.setClearColor(new THREE.Color().setRGB(0.12, 0.12, 0.13, THREE.SRGBColorSpace), 1);
    renderer.render(scene, camera);
    const png = canvas.toDataURL('image/png');
    // GL rows run bottom to top: flip to top to bottom.
    const out = new Float32Array(W * H * 4);
    for (let y = 0; y < H; y++) out.set(px.subarray((H - 1 - y) * W * 4, (H - y) * W * 4), y * W * 4);
    const bytes = new Uint8Array(out.buffer);
    let s = '';
    for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    results.push({ raw: btoa(s), png });
  }
  info.gl = renderer.getContext().getParameter(renderer.getContext().VERSION);
  return { results, info };
};
window.ready = true;
</script></body></html>`;

const types = { '.js': 'text/javascript', '.html': 'text/html', '.glb': 'model/gltf-binary' };
const server = createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  let file = null;
  if (url === '/favicon.ico') {
    res.writeHead(204);
    return res.end();
  } else if (url === '/' || url === '/index.html') {
    res.writeHead(200, { 'content-type': 'text/html' });
    return res.end(page_html);
  } else if (url === '/model.glb') {
    file = resolve(job.glb);
  } else if (url.startsWith('/three/')) {
    const root = join(here, 'node_modules', 'three');
    file = resolve(root, '.' + url.slice('/three'.length));
    if (!file.startsWith(root)) file = null;
  }
  if (!file || !existsSync(file)) {
    res.writeHead(404);
    return res.end();
  }
  const ext = file.slice(file.lastIndexOf('.'));
  res.writeHead(200, { 'content-type': types[ext] || 'application/octet-stream' });
  res.end(readFileSync(file));
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const port = server.address().port;
let browser;
let code = 0;
try {
  browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--ignore-gpu-blocklist', '--disable-dev-shm-usage'],
  });
  const page = await browser.newPage();
  const logs = [];
  page.on('console', (m) => logs.push(m.text()));
  page.on('pageerror', (e) => logs.push(String(e)));
  await page.goto(`http://127.0.0.1:${port}/`);
  await page.waitForFunction('window.ready === true', { timeout: 60000 });
  const r = await page.evaluate((j) => window.render(j), job);
  job.renders.forEach((out, i) => {
    writeFileSync(out.raw, Buffer.from(r.results[i].raw, 'base64'));
    if (out.png) writeFileSync(out.png, Buffer.from(r.results[i].png.split(',')[1], 'base64'));
  });
  console.log(JSON.stringify({ ok: true, info: r.info, logs }));
} catch (e) {
  console.error(`render.mjs: ${e && e.stack || e}`);
  code = 1;
} finally {
  if (browser) await browser.close();
  server.close();
}
process.exit(code);
