// Spherical harmonics and lights, in prtsub's convention (docs/sh_convention.md): real
// orthonormal, index l(l+1)+m, no Condon-Shortley phase, y_1,-1 = c·y, y_1,0 = c·z, y_1,1 = c·x.
// Each function follows its C++ counterpart in prt/sh.cpp and prt/lights.cpp step for step
// (the same recurrences and quadratures), so the viewer lights an asset exactly as
// `prtsub render` does; the browser test holds it to that.

const MAX_ORDER = 10;

// K_l^m normalisation (√2 for m > 0), the recurrence factors and (2m-1)!!, as in sh.cpp.
const norm = [], ra = [], rb = [], diag = [1];
for (let l = 0; l < MAX_ORDER; ++l) {
  norm.push([]), ra.push([]), rb.push([]);
  for (let m = 0; m <= l; ++m) {
    let ratio = 1;
    for (let k = l - m + 1; k <= l + m; ++k) ratio /= k;
    const k = Math.sqrt(((2 * l + 1) / (4 * Math.PI)) * ratio);
    norm[l][m] = m === 0 ? k : Math.SQRT2 * k;
    ra[l][m] = l > m + 1 ? (2 * l - 1) / (l - m) : 0;
    rb[l][m] = l > m + 1 ? (l + m - 1) / (l - m) : 0;
  }
}
for (let m = 1; m < MAX_ORDER; ++m) diag[m] = diag[m - 1] * (2 * m - 1);

export const shIndex = (l, m) => l * (l + 1) + m;

// All order² basis functions at the unit direction (x, y, z), into `out`.
export function shEval(order, x, y, z, out = new Float64Array(order * order)) {
  let c = 1, s = 0;
  for (let m = 0; m < order; ++m) {
    let qPrev = 0, q = diag[m];
    for (let l = m; l < order; ++l) {
      if (l === m + 1) {
        qPrev = q;
        q = (2 * m + 1) * z * q;
      } else if (l > m + 1) {
        const qNext = ra[l][m] * z * q - rb[l][m] * qPrev;
        qPrev = q;
        q = qNext;
      }
      const v = norm[l][m] * q;
      if (m === 0) out[shIndex(l, 0)] = v;
      else {
        out[shIndex(l, m)] = v * c;
        out[shIndex(l, -m)] = v * s;
      }
    }
    const cNext = x * c - y * s;
    s = x * s + y * c;
    c = cNext;
  }
  return out;
}

function legendre(n, t) {
  const p = new Float64Array(Math.max(n, 2));
  p[0] = 1;
  if (n > 1) p[1] = t;
  for (let l = 2; l < n; ++l) p[l] = ((2 * l - 1) * t * p[l - 1] - (l - 1) * p[l - 2]) / l;
  return p;
}

const normalize = (v) => {
  const n = Math.hypot(v[0], v[1], v[2]);
  return [v[0] / n, v[1] / n, v[2] / n];
};

// A light is { order, coeffs: Float64Array(K * 3) } (row i = coefficient i, RGB).
export const emptyLight = (order) => ({ order, coeffs: new Float64Array(order * order * 3) });

export function addLights(a, b) {
  const out = emptyLight(a.order);
  for (let i = 0; i < out.coeffs.length; ++i) out.coeffs[i] = a.coeffs[i] + b.coeffs[i];
  return out;
}

// The zonal function about `axis` with Legendre moments m_l = 2π ∫ g P_l dt (RGB each).
function addZonal(light, axis, moments) {
  const a = normalize(axis);
  const y = shEval(light.order, a[0], a[1], a[2]);
  for (let l = 0; l < light.order; ++l)
    for (let m = -l; m <= l; ++m)
      for (let c = 0; c < 3; ++c) light.coeffs[3 * shIndex(l, m) + c] += y[shIndex(l, m)] * moments[l][c];
}

const GX8 = [-0.9602898564975363, -0.796666477413626, -0.525532409916329, -0.1834346424956498, 0.1834346424956498, 0.525532409916329,
  0.796666477413626, 0.9602898564975363];
const GW8 = [0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.362683783378362, 0.362683783378362, 0.3137066458778873,
  0.2223810344533745, 0.1012285362903763];

// prtsub's sky (lights.cpp sky_light): linear from horizon to zenith above, ground below.
export function skyLight(order, up = [0, 1, 0], zenith = [0.35, 0.55, 1.0], horizon = [0.9, 0.9, 0.85], ground = [0.15, 0.13, 0.12]) {
  const light = emptyLight(order);
  const moments = Array.from({ length: order }, () => [0, 0, 0]);
  for (let k = 0; k < 8; ++k) {
    const tl = 0.5 * (GX8[k] - 1), tu = 0.5 * (GX8[k] + 1);
    const pl = legendre(order, tl), pu = legendre(order, tu);
    for (let l = 0; l < order; ++l)
      for (let c = 0; c < 3; ++c) {
        moments[l][c] += 2 * Math.PI * 0.5 * GW8[k] * pl[l] * ground[c];
        moments[l][c] += 2 * Math.PI * 0.5 * GW8[k] * pu[l] * (horizon[c] + (zenith[c] - horizon[c]) * tu);
      }
  }
  addZonal(light, up, moments);
  return light;
}

// A sun: a cap of angular radius `radiusDeg` about `direction`, irradiance π·rgb at normal
// incidence (lights.cpp sun_light).
export function sunLight(order, direction, radiusDeg = 0, rgb = [1, 1, 1]) {
  const light = emptyLight(order);
  const c = Math.cos((radiusDeg * Math.PI) / 180);
  const p = legendre(order + 1, c);
  const moments = [];
  for (let l = 0; l < order; ++l) {
    const ratio = 1 - c < 1e-12 ? 1 : (l === 0 ? 1 - c : (p[l - 1] - p[l + 1]) / (2 * l + 1)) / (1 - c);
    moments.push(rgb.map((v) => Math.PI * ratio * v));
  }
  addZonal(light, direction, moments);
  return light;
}

// Coefficients given, the same in each channel (`--light sh:...`).
export function coefficientsLight(order, values) {
  const light = emptyLight(order);
  values.slice(0, order * order).forEach((v, i) => {
    for (let c = 0; c < 3; ++c) light.coeffs[3 * i + c] = v;
  });
  return light;
}

export const srgbToLinear = (v) => (v <= 0.04045 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4));

const GX4 = [-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526];
const GW4 = [0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538];

// A lat-long map {width, height, rgb: Float32Array(W*H*3), linear} projected with the exact
// per-texel quadrature of lights.cpp environment_light (4 Gauss points in cos θ × 4 in φ).
export function environmentLight(order, map) {
  const K = order * order, light = emptyLight(order);
  const y = new Float64Array(K), integral = new Float64Array(K);
  const { width: W, height: H, rgb } = map;
  // The basis is separable per texel row and column: tabulate each sub-sample's y once per row.
  for (let r = 0; r < H; ++r) {
    const z0 = Math.cos((Math.PI * r) / H), z1 = Math.cos((Math.PI * (r + 1)) / H);
    const zmid = 0.5 * (z0 + z1), zhalf = 0.5 * (z0 - z1);
    for (let col = 0; col < W; ++col) {
      integral.fill(0);
      for (let a = 0; a < 4; ++a)
        for (let b = 0; b < 4; ++b) {
          const phi = (2 * Math.PI * (col + (a + 0.5) / 4)) / W;
          const ct = zmid + zhalf * GX4[b], st = Math.sqrt(Math.max(0, 1 - ct * ct));
          const w = ((2 * Math.PI) / W / 4) * zhalf * GW4[b];
          shEval(order, st * Math.cos(phi), ct, -st * Math.sin(phi), y);
          for (let i = 0; i < K; ++i) integral[i] += w * y[i];
        }
      const t = 3 * (r * W + col);
      for (let i = 0; i < K; ++i)
        for (let c = 0; c < 3; ++c) light.coeffs[3 * i + c] += integral[i] * rgb[t + c];
    }
  }
  return light;
}

// Fibonacci directions, as lights.cpp spread_directions.
function spreadDirections(n) {
  const d = [];
  for (let i = 0; i < n; ++i) {
    const z = 1 - (2 * i + 1) / n, r = Math.sqrt(Math.max(0, 1 - z * z)), phi = 2 * Math.PI * i * 0.6180339887498949;
    d.push([r * Math.cos(phi), r * Math.sin(phi), z]);
  }
  return d;
}

// Solves the least-squares system A X = B (rows × n, n × n unknowns) by the normal equations
// with partial pivoting; n ≤ 19, well conditioned by construction (4n spread directions).
function leastSquares(A, B, rows, n) {
  const N = new Float64Array(n * n), R = new Float64Array(n * n);
  for (let i = 0; i < n; ++i)
    for (let j = 0; j < n; ++j) {
      let s = 0, t = 0;
      for (let k = 0; k < rows; ++k) s += A[k * n + i] * A[k * n + j], t += A[k * n + i] * B[k * n + j];
      N[i * n + j] = s, R[i * n + j] = t;
    }
  for (let col = 0; col < n; ++col) {
    let p = col;
    for (let r = col + 1; r < n; ++r) if (Math.abs(N[r * n + col]) > Math.abs(N[p * n + col])) p = r;
    for (let j = 0; j < n; ++j) {
      [N[col * n + j], N[p * n + j]] = [N[p * n + j], N[col * n + j]];
      [R[col * n + j], R[p * n + j]] = [R[p * n + j], R[col * n + j]];
    }
    for (let r = 0; r < n; ++r) {
      if (r === col) continue;
      const f = N[r * n + col] / N[col * n + col];
      for (let j = 0; j < n; ++j) N[r * n + j] -= f * N[col * n + j], R[r * n + j] -= f * R[col * n + j];
    }
  }
  for (let r = 0; r < n; ++r) for (let j = 0; j < n; ++j) R[r * n + j] /= N[r * n + r];
  return R;
}

// The band-diagonal SH rotation (lights.cpp sh_rotation): coefficients of f(R⁻¹ω) are M·c.
// R is a row-major 3×3 array.
export function shRotation(order, R) {
  const bands = [];
  for (let l = 1; l < order; ++l) {
    const n = 2 * l + 1, rows = 4 * n, dirs = spreadDirections(rows);
    const A = new Float64Array(rows * n), B = new Float64Array(rows * n), y = new Float64Array(order * order);
    dirs.forEach((d, k) => {
      shEval(order, d[0], d[1], d[2], y);
      for (let j = 0; j < n; ++j) A[k * n + j] = y[l * l + j];
      // R⁻¹ d = Rᵀ d
      const e = [R[0] * d[0] + R[3] * d[1] + R[6] * d[2], R[1] * d[0] + R[4] * d[1] + R[7] * d[2], R[2] * d[0] + R[5] * d[1] + R[8] * d[2]];
      shEval(order, e[0], e[1], e[2], y);
      for (let j = 0; j < n; ++j) B[k * n + j] = y[l * l + j];
    });
    bands.push(leastSquares(A, B, rows, n));
  }
  return bands;
}

export function rotateLight(light, R) {
  const out = emptyLight(light.order);
  for (let c = 0; c < 3; ++c) out.coeffs[c] = light.coeffs[c];
  shRotation(light.order, R).forEach((M, b) => {
    const l = b + 1, n = 2 * l + 1;
    for (let i = 0; i < n; ++i)
      for (let c = 0; c < 3; ++c) {
        let s = 0;
        for (let j = 0; j < n; ++j) s += M[i * n + j] * light.coeffs[3 * (l * l + j) + c];
        out.coeffs[3 * (l * l + i) + c] = s;
      }
  });
  return out;
}

// Row-major rotation about a unit axis by `degrees` (right-handed).
export function axisRotation(axis, degrees) {
  const [x, y, z] = normalize(axis), t = (degrees * Math.PI) / 180, c = Math.cos(t), s = Math.sin(t), k = 1 - c;
  return [c + x * x * k, x * y * k - z * s, x * z * k + y * s, y * x * k + z * s, c + y * y * k, y * z * k - x * s, z * x * k - y * s,
    z * y * k + x * s, c + z * z * k];
}

export function multiply3(A, B) {
  const C = new Array(9).fill(0);
  for (let i = 0; i < 3; ++i) for (let j = 0; j < 3; ++j) for (let k = 0; k < 3; ++k) C[3 * i + j] += A[3 * i + k] * B[3 * k + j];
  return C;
}

// Spherical-Gaussian lobes G_k(ω) = exp(λ(μ_k·ω − 1)) (docs/sh_convention.md, "Spherical
// Gaussians"). A lobe is zonal about its axis, so an SH light reaches it band by band (Funk–Hecke):
// L_k = Σ_lm g_l y_lm(μ_k) l_lm, g_l = 4π e^{−λ} i_l(λ), i_l from its power series
// i_l(x) = Σ_j x^{l+2j} / (2^j j! (2l+2j+1)!!), every term positive; e^{−λ} is folded in first so
// sharp lobes stay finite (prt/sg_basis.cpp does the same).
export function sgZonal(sharpness, order) {
  const x = sharpness, g = new Float64Array(order);
  let lead = 1;
  for (let l = 0; l < order; ++l) {
    if (l > 0) lead *= x / (2 * l + 1);
    let term = Math.exp(-x) * lead, sum = 0;
    for (let j = 0; j < 100000 && term > 1e-18 * sum; ++j) {
      sum += term;
      term *= (x * x) / (2 * (j + 1) * (2 * l + 2 * j + 3));
    }
    g[l] = 4 * Math.PI * sum;
  }
  return g;
}

// What each lobe sees of an SH light: N × 3 (RGB), row k = ∫ L G_k.
export function sgLight(light, axes, sharpness) {
  const order = light.order, K = order * order, g = sgZonal(sharpness, order), y = new Float64Array(K);
  const out = new Float64Array(axes.length * 3);
  axes.forEach((mu, k) => {
    shEval(order, mu[0], mu[1], mu[2], y);
    for (let l = 0; l < order; ++l)
      for (let i = l * l; i < (l + 1) * (l + 1); ++i)
        for (let c = 0; c < 3; ++c) out[3 * k + c] += g[l] * y[i] * light.coeffs[3 * i + c];
  });
  return out;
}
