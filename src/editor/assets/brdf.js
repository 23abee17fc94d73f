// The preview's BRDFs (src/render/brdf) as GLSL, in the local frame of the grain:
// x = u (the grain), y = v = n × u, z = n; wi, wo unit, pointing away from the surface.
// Ashikhmin–Shirley follows AshikhminShirley::eval_f32 (the (h·n)^e of the lobe by
// exp(e·ln(1 − δ)), δ = 1 − h·n computed without cancellation); Ward and GGX follow their
// f64 eval; Fresnel: none, Schlick, exact conductor (fresnel.rs). Tone maps and the sRGB
// curve follow src/render/image.rs. The LIC texture of lic.js modulates the colour when on.

export const vertexShader = /* glsl */ `
attribute vec3 grain;
attribute float brushed;
varying vec3 vPos;
varying vec3 vNormal;
varying vec3 vGrain;
varying float vBrushed;
void main() {
  vec4 p = modelMatrix * vec4(position, 1.0);
  vPos = p.xyz;
  vNormal = normal;
  vGrain = grain;
  vBrushed = brushed;
  gl_Position = projectionMatrix * viewMatrix * p;
}
`;

export const fragmentShader = /* glsl */ `
precision highp float;
#define PI 3.141592653589793
#define MAX_LIGHTS 8
uniform int uBrdf;          // 0 Ashikhmin–Shirley, 1 Ward, 2 GGX
uniform vec3 uParam;        // AS: (nu, nv, -); Ward: (alpha_x, alpha_y, rho_s); GGX: (alpha_u, alpha_v, -)
uniform vec3 uBareParam;    // the same metal where no brush passed: isotropic, the narrower lobe
uniform vec3 uRs;           // AS: R_s
uniform vec3 uDiffuse;      // AS: R_d; Ward, GGX: the Lambert albedo
uniform int uFresnel;       // 0 none, 1 Schlick, 2 conductor
uniform vec3 uF0;
uniform vec3 uEta;
uniform vec3 uK;
uniform int uLightCount;
uniform int uLightType[MAX_LIGHTS];   // 0 directional (uLightVec: towards it), 1 point (position)
uniform vec3 uLightVec[MAX_LIGHTS];
uniform vec3 uLightE[MAX_LIGHTS];     // irradiance (or intensity) × colour
uniform int uToneMap;       // 0 none, 1 exposure, 2 reinhard
uniform float uExposure;
uniform vec3 uBrush;        // brush centre (world)
uniform float uBrushRadius; // 0: no brush ring
uniform sampler2D uLicTex;  // the LIC of ℓ per pixel (lic.js), alpha 0 off the part
uniform vec2 uLicRes;       // its size, pixels
uniform float uLicStrength; // 0: no LIC
varying vec3 vPos;
varying vec3 vNormal;
varying vec3 vGrain;
varying float vBrushed;     // interpolated share of brushed corners (as brushed; 1 designed)

float conductor(float c, float eta, float k) {
  float c2 = c * c;
  float s2 = 1.0 - c2;
  float t0 = eta * eta - k * k - s2;
  float a2b2 = sqrt(t0 * t0 + 4.0 * eta * eta * k * k);
  float a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
  float t1 = a2b2 + c2;
  float t2 = 2.0 * c * a;
  float rs = (t1 - t2) / max(t1 + t2, 1e-30);
  float t3 = c2 * a2b2 + s2 * s2;
  float t4 = t2 * s2;
  float rp = rs * (t3 - t4) / max(t3 + t4, 1e-30);
  return clamp(0.5 * (rs + rp), 0.0, 1.0);
}

vec3 fresnel(float cosv) {
  float c = clamp(cosv, 0.0, 1.0);
  if (uFresnel == 1) {
    float w = pow(1.0 - c, 5.0);
    return uF0 + (1.0 - uF0) * w;
  }
  if (uFresnel == 2) {
    return vec3(conductor(c, uEta.x, uK.x), conductor(c, uEta.y, uK.y), conductor(c, uEta.z, uK.z));
  }
  return vec3(1.0);
}

vec3 ashikhminShirley(vec3 wi, vec3 wo, vec3 prm) {
  float nu = prm.x, nv = prm.y;
  float dwi = 1.0 - pow(1.0 - 0.5 * wi.z, 5.0);
  float dwo = 1.0 - pow(1.0 - 0.5 * wo.z, 5.0);
  float diffuseGeo = 28.0 / (23.0 * PI) * dwi * dwo;
  vec3 s = wi + wo;
  float t2 = s.x * s.x + s.y * s.y;
  float l = sqrt(t2 + s.z * s.z);
  float specGeo = 0.0, c5 = 1.0;
  if (l > 1e-12) {
    float hk = dot(s, wi) / l;
    float p = 1.0;
    if (t2 > 0.0) {
      float e = (nu * s.x * s.x + nv * s.y * s.y) / t2;
      float delta = t2 / (l * (l + s.z));
      float lnhn = delta < 1.0 / 128.0
        ? -delta * (1.0 + delta * (0.5 + delta * (1.0 / 3.0 + delta * 0.25)))
        : log(max(1.0 - delta, 1e-30));
      p = exp(e * lnhn);
    }
    specGeo = sqrt((nu + 1.0) * (nv + 1.0)) / (8.0 * PI) * p / (max(hk, 1e-12) * max(wi.z, wo.z));
    c5 = pow(1.0 - clamp(hk, 0.0, 1.0), 5.0);
  }
  vec3 f = uRs + (1.0 - uRs) * c5;
  return specGeo * f + diffuseGeo * uDiffuse * (1.0 - uRs);
}

vec3 ward(vec3 wi, vec3 wo, vec3 prm) {
  vec3 d = uDiffuse / PI;
  vec3 s = wi + wo;
  float l = length(s);
  if (l <= 1e-12) return d;
  vec3 h = s / l;
  if (h.z <= 0.0) return d;
  float a = h.x / prm.x, b = h.y / prm.y;
  float e = exp(-(a * a + b * b) / (h.z * h.z));
  float sp = prm.z * e / (4.0 * PI * prm.x * prm.y * sqrt(wi.z * wo.z));
  return d + sp * fresnel(dot(h, wi));
}

float ggxLambda(vec3 w, vec3 prm) {
  float t = pow(prm.x * w.x, 2.0) + pow(prm.y * w.y, 2.0);
  return 0.5 * (sqrt(1.0 + t / (w.z * w.z)) - 1.0);
}

vec3 ggx(vec3 wi, vec3 wo, vec3 prm) {
  vec3 d = uDiffuse / PI;
  vec3 s = wi + wo;
  float l = length(s);
  if (l <= 1e-12) return d;
  vec3 h = s / l;
  float q = pow(h.x / prm.x, 2.0) + pow(h.y / prm.y, 2.0) + h.z * h.z;
  float dist = 1.0 / (PI * prm.x * prm.y * q * q);
  float g2 = 1.0 / (1.0 + ggxLambda(wi, prm) + ggxLambda(wo, prm));
  float sp = dist * g2 / (4.0 * wi.z * wo.z);
  return d + sp * fresnel(dot(h, wi));
}

vec3 brdf(vec3 wi, vec3 wo, vec3 prm) {
  if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
  if (uBrdf == 1) return ward(wi, wo, prm);
  if (uBrdf == 2) return ggx(wi, wo, prm);
  return ashikhminShirley(wi, wo, prm);
}

float toneMap(float x) {
  x = max(x, 0.0);
  if (uToneMap == 0) return min(x, 1.0);
  float y = x * exp2(uExposure);
  if (uToneMap == 1) return min(y, 1.0);
  return y / (1.0 + y);
}

float srgb(float x) {
  x = clamp(x, 0.0, 1.0);
  return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

void main() {
  vec3 n = normalize(vNormal);
  vec3 wo = normalize(cameraPosition - vPos);
  vec3 u = vGrain - dot(vGrain, n) * n;
  float ul = length(u);
  if (ul < 1e-6) {
    vec3 a = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    u = normalize(cross(n, a));
  } else {
    u /= ul;
  }
  vec3 v = cross(n, u);
  vec3 lwo = vec3(dot(wo, u), dot(wo, v), dot(wo, n));
  vec3 L = vec3(0.0), bare = vec3(0.0);
  // Where a corner has no grain (as brushed: no stroke's brush reached it) the bare metal is
  // blended in by the interpolated share of brushed corners, as the glb's anisotropy strength.
  bool someBare = vBrushed < 0.999;
  for (int i = 0; i < MAX_LIGHTS; i++) {
    if (i >= uLightCount) break;
    vec3 wi = uLightVec[i];
    vec3 e = uLightE[i];
    if (uLightType[i] == 1) {
      vec3 d = uLightVec[i] - vPos;
      float r2 = max(dot(d, d), 1e-24);
      wi = d / sqrt(r2);
      e = e / r2;
    }
    float c = dot(wi, n);
    if (c <= 0.0) continue;
    vec3 lwi = vec3(dot(wi, u), dot(wi, v), c);
    L += brdf(lwi, lwo, uParam) * e * c;
    if (someBare) bare += brdf(lwi, lwo, uBareParam) * e * c;
  }
  if (someBare) L = mix(bare, L, clamp(vBrushed, 0.0, 1.0));
  vec3 col = vec3(srgb(toneMap(L.r)), srgb(toneMap(L.g)), srgb(toneMap(L.b)));
  if (uLicStrength > 0.0) {
    // As the preview (render::resolve_pixel), the encoded colour times (1 − s) + 2 s · LIC,
    // plus 0.2 s · LIC, so that the flow shows on the dark body too (the preview only modulates).
    vec4 lic = texture2D(uLicTex, gl_FragCoord.xy / uLicRes);
    if (lic.a > 0.5) col = clamp(col * ((1.0 - uLicStrength) + 2.0 * uLicStrength * lic.r) + 0.2 * uLicStrength * lic.r, 0.0, 1.0);
  }
  if (uBrushRadius > 0.0) {
    float d = length(vPos - uBrush);
    float w = 0.025 * uBrushRadius;
    if (abs(d - uBrushRadius) < w) col = mix(col, vec3(0.2, 0.8, 1.0), 0.8);
  }
  gl_FragColor = vec4(col, 1.0);
}
`;
