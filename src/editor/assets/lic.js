// Line integral convolution of the key light's highlight tangent ℓ on the page (B. Cabral,
// L. Leedom, "Imaging Vector Fields Using Line Integral Convolution", SIGGRAPH 1993; the paper's
// Fig. 5), image space, remade for every frame drawn, so it follows an orbit, a new grain and a
// turned light at once. As the preview's src/render/lic.rs, with the direction from the page's
// own shading instead of the per-vertex ℓ:
//
// 1. the part is drawn into a render target holding, per pixel, the screen direction of ℓ.
//    ℓ = n × ∇g is tangent to the level sets of g = hᵀu (h the key light's half vector for the
//    camera's eye, per pixel as brdf.js computes it; u the per-corner grain), so its projection
//    is the level set's screen tangent, perpendicular to the screen gradient of g:
//    (−∂g/∂y, ∂g/∂x) from dFdx / dFdy. Nothing (alpha 0) on the background, on faces turned
//    away from the eye, and where the grain or the gradient vanishes;
// 2. a full-screen pass averages white noise on the pixel grid (a PCG hash of the pixel and a
//    fixed seed: the same texture in every frame) along the streamline through each pixel,
//    ±LENGTH unit steps (midpoint rule; the direction re-oriented at every step, since ℓ is a
//    line field), stopping at the image's edge and where the direction is undefined; the mean
//    of n uniforms is stretched to a standard deviation of 0.2 (as the preview);
// 3. the part's shader (brdf.js) multiplies its colour by (1 − s) + 2 s · LIC, s = 0.6 (the
//    preview's `lic.strength` default), and adds 0.2 s · LIC so that the flow shows on the
//    dark body too (the preview only modulates); the overlays are drawn over it as before.

/** Half length of the streamlines, pixels (the preview's `lic.length_px` default). */
export const LENGTH = 12;
/** How much the texture modulates the shading (the preview's `lic.strength` default). */
export const STRENGTH = 0.6;

const dirFragment = /* glsl */ `
precision highp float;
uniform int uKeyType;   // 0 directional (uKeyVec: towards it), 1 point (its position)
uniform vec3 uKeyVec;
varying vec3 vPos;
varying vec3 vNormal;
varying vec3 vGrain;
void main() {
  vec3 n = normalize(vNormal);
  vec3 wo = normalize(cameraPosition - vPos);
  vec3 wi = uKeyType == 1 ? normalize(uKeyVec - vPos) : normalize(uKeyVec);
  vec3 h = normalize(wi + wo);
  vec3 u = vGrain - dot(vGrain, n) * n;
  float ul = length(u);
  float g = dot(h, u) / max(ul, 1e-6);
  vec2 grad = vec2(dFdx(g), dFdy(g));
  float gl = length(grad);
  bool ok = ul > 1e-3 && dot(n, wo) > 0.0 && gl > 1e-9;
  vec2 d = ok ? vec2(-grad.y, grad.x) / gl : vec2(0.0);
  gl_FragColor = vec4(0.5 + 0.5 * d, 0.0, ok ? 1.0 : 0.0);
}
`;

const quadVertex = /* glsl */ `
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }
`;

const licFragment = /* glsl */ `
precision highp float;
precision highp int;
uniform sampler2D uDir;
uniform vec2 uRes;
uniform uint uSeed;
#define LENGTH ${LENGTH}

// PCG hash (M. Jarzynski, M. Olano, "Hash Functions for GPU Rendering", JCGT 2020).
uvec3 pcg3d(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z; v.y += v.z * v.x; v.z += v.x * v.y;
  return v;
}
// White noise in [0, 1) at the pixel holding p: 24 bits of the hash.
float noise(vec2 p) {
  return float(pcg3d(uvec3(uvec2(p), uSeed)).x >> 8u) / 16777216.0;
}
// The direction at p, or vec2(0) outside the part.
vec2 dirAt(vec2 p) {
  if (p.x < 0.0 || p.y < 0.0 || p.x >= uRes.x || p.y >= uRes.y) return vec2(0.0);
  vec4 c = texture2D(uDir, p / uRes);
  return c.a < 0.5 ? vec2(0.0) : c.xy * 2.0 - 1.0;
}
// d, or −d when it points against \`along\` (ℓ is a line field).
vec2 orient(vec2 d, vec2 along) { return dot(d, along) < 0.0 ? -d : d; }
void main() {
  vec2 p0 = gl_FragCoord.xy;
  vec2 d0 = dirAt(p0);
  if (d0 == vec2(0.0)) { gl_FragColor = vec4(0.5, 0.0, 0.0, 0.0); return; }
  float sum = noise(p0), n = 1.0;
  for (int side = 0; side < 2; side++) {
    vec2 p = p0;
    vec2 d = side == 0 ? d0 : -d0;
    for (int k = 0; k < LENGTH; k++) {
      vec2 m = dirAt(p + 0.5 * d);
      if (m == vec2(0.0)) break;
      p += orient(m, d);
      vec2 e = dirAt(p);
      if (e == vec2(0.0)) break;
      d = orient(e, d);
      sum += noise(p);
      n += 1.0;
    }
  }
  // The mean of n uniforms has standard deviation 0.2887/√n: stretched to 0.2.
  float v = 0.5 + (sum / n - 0.5) * (0.2 / 0.2887) * sqrt(n);
  gl_FragColor = vec4(clamp(v, 0.0, 1.0), 0.0, 0.0, 1.0);
}
`;

/**
 * The LIC passes. `uniforms` is the part material's: it gains uLicTex / uLicRes /
 * uLicStrength (read by brdf.js) and shares uKeyType / uKeyVec with the direction pass.
 */
export function createLic(THREE, renderer, uniforms, vertexShader) {
  const floatable = renderer.extensions.has('EXT_color_buffer_float');
  const target = (type) => new THREE.WebGLRenderTarget(1, 1, {
    type, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: true, generateMipmaps: false,
  });
  const dirTarget = target(floatable ? THREE.HalfFloatType : THREE.UnsignedByteType);
  const licTarget = target(THREE.UnsignedByteType);
  licTarget.depthBuffer = false;
  Object.assign(uniforms, {
    uLicTex: { value: licTarget.texture }, uLicRes: { value: new THREE.Vector2(1, 1) },
    uLicStrength: { value: 0 },
  });
  const dirMaterial = new THREE.ShaderMaterial({
    uniforms: { uKeyType: uniforms.uKeyType, uKeyVec: uniforms.uKeyVec },
    vertexShader, fragmentShader: dirFragment, side: THREE.DoubleSide,
  });
  const dirMesh = new THREE.Mesh(new THREE.BufferGeometry(), dirMaterial);
  dirMesh.frustumCulled = false;
  const dirScene = new THREE.Scene();
  dirScene.add(dirMesh);
  const licUniforms = {
    uDir: { value: dirTarget.texture }, uRes: { value: new THREE.Vector2(1, 1) }, uSeed: { value: 1 },
  };
  const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.ShaderMaterial({
    uniforms: licUniforms, vertexShader: quadVertex, fragmentShader: licFragment,
    depthTest: false, depthWrite: false,
  }));
  quad.frustumCulled = false;
  const quadScene = new THREE.Scene();
  quadScene.add(quad);
  const quadCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
  const size = new THREE.Vector2(), clear = new THREE.Color();
  const lic = {
    enabled: false,
    frames: 0,
    setGeometry(g) { dirMesh.geometry = g; },
    /** Passes 1 and 2 for `camera` (before the frame is drawn), or the modulation off. */
    update(camera) {
      uniforms.uLicStrength.value = lic.enabled ? STRENGTH : 0;
      if (!lic.enabled) return;
      renderer.getDrawingBufferSize(size);
      if (dirTarget.width !== size.x || dirTarget.height !== size.y) {
        dirTarget.setSize(size.x, size.y);
        licTarget.setSize(size.x, size.y);
      }
      licUniforms.uRes.value.copy(size);
      uniforms.uLicRes.value.copy(size);
      renderer.getClearColor(clear);
      const alpha = renderer.getClearAlpha();
      renderer.setClearColor(0x000000, 0);
      renderer.setRenderTarget(dirTarget);
      renderer.clear();
      renderer.render(dirScene, camera);
      renderer.setRenderTarget(licTarget);
      renderer.clear();
      renderer.render(quadScene, quadCamera);
      renderer.setRenderTarget(null);
      renderer.setClearColor(clear, alpha);
      lic.frames++;
    },
  };
  return lic;
}
