// The relighting viewer: one self-contained page `prtsub view` writes, the asset embedded as a
// GLB. Plain WebGL2 draws the triangles with one radiance per vertex, interpolated across each
// face, which is the Gouraud frame `prtsub render` computes by ray casting: the radiance is
// albedo/π · Σ_i l_i t_i per colour (docs/sh_convention.md), in double precision on the CPU each
// time the light changes (V·N²·3 multiply-adds), and the fragment shader applies the same
// exposure and sRGB curve as the tool's PNG writer. Lights are projected here with the tool's
// own quadratures (sh.js); random lights, whose generator is the library's, come embedded.
//
// URL parameters (query or hash) set up a view, as the tool's options do, so that the browser
// test can compare pixels with `prtsub render`: light=SPEC (repeatable: sky[:X,Y,Z], sun:X,Y,Z[,R],
// sh:c0,c1,..., random:SEED, const:V|R,G,B, env, the bundled studio map), light-rotate=AXIS,DEG
// (repeatable), camera=eye=X,Y,Z:target=X,Y,Z[:up=X,Y,Z][:fov=DEG], size=W,H, exposure=E,
// albedo=A, view=gouraud|ao|error, ui=0. window.prtsubViewer reports {ready, webgl2, error}.
import studioPng from '../assets/studio.png';
import { parseGlb } from './glb.js';
import {
  addLights, axisRotation, coefficientsLight, emptyLight, environmentLight, multiply3, rotateLight, sgLight, sgZonal, skyLight, srgbToLinear, sunLight,
} from './sh.js';

const status = (window.prtsubViewer = { ready: false, webgl2: false, error: null, frames: 0 });
const AO_PER_T0 = 1.1283791670955126;

function fail(message) {
  status.error = message;
  const box = document.getElementById('message');
  if (box) box.textContent = message;
  console.error('prtsub viewer: ' + message);
}

function base64Bytes(text) {
  const raw = atob(text), out = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; ++i) out[i] = raw.charCodeAt(i);
  return out;
}

const numbers = (text, what) => {
  const v = text.split(',').map(Number);
  if (v.some((x) => !Number.isFinite(x))) throw new Error(`${what}: '${text}' is not a list of numbers`);
  return v;
};

function parseParams() {
  const params = new URLSearchParams(location.search.slice(1) + '&' + location.hash.slice(1));
  return {
    lights: params.getAll('light'),
    rotations: params.getAll('light-rotate'),
    camera: params.get('camera'),
    size: params.get('size') ? numbers(params.get('size'), 'size') : null,
    exposure: params.has('exposure') ? Number(params.get('exposure')) : 1,
    albedo: params.has('albedo') ? Number(params.get('albedo')) : 0.8,
    view: params.get('view') || 'gouraud',
    ui: params.get('ui') !== '0',
  };
}

// camera=eye=X,Y,Z:target=X,Y,Z[:up=X,Y,Z][:fov=DEG], as cli/specs.cpp parse_camera.
function parseCamera(spec) {
  const c = { eye: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0], fov: 40 };
  for (const part of spec.split(':')) {
    const [key, value] = part.split('=');
    if (key === 'fov') c.fov = Number(value);
    else if (key in c) c[key] = numbers(value, 'camera ' + key);
    else throw new Error(`camera: unknown part '${key}'`);
  }
  return c;
}

// As prt/render.cpp auto_camera: a three-quarter view that fits the bounding sphere.
function autoCamera(lo, hi, width, height) {
  const ext = [0, 1, 2].map((i) => hi[i] - lo[i]);
  const zUp = ext[2] < 0.35 * Math.min(ext[0], ext[1]);
  const dir = zUp ? [0.6, -0.75, 0.45] : [0.6, 0.45, 0.75], n = Math.hypot(...dir);
  const target = [0, 1, 2].map((i) => 0.5 * (lo[i] + hi[i]));
  const radius = Math.max(0.5 * Math.hypot(...ext), 1e-30), halfV = (0.5 * 40 * Math.PI) / 180;
  const halfH = Math.atan((Math.tan(halfV) * width) / Math.max(height, 1));
  const distance = radius / Math.sin(Math.min(halfV, halfH));
  return { eye: target.map((t, i) => t + (dir[i] / n) * distance), target, up: zUp ? [0, 0, 1] : [0, 1, 0], fov: 40 };
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const unit = (a) => {
  const n = Math.hypot(...a);
  return [a[0] / n, a[1] / n, a[2] / n];
};

// Column-major view-projection for the camera: the pixel rays of render.cpp camera_ray.
function viewProjection(cam, width, height, radius) {
  const f = unit(sub(cam.target, cam.eye)), r = unit(cross(f, cam.up)), u = cross(r, f);
  const t = Math.tan((0.5 * cam.fov * Math.PI) / 180), aspect = width / height;
  const distance = Math.hypot(...sub(cam.target, cam.eye));
  const near = Math.max(distance - 2 * radius, distance * 1e-3, 1e-6), far = distance + 2 * radius;
  const view = [r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0, -dot(r, cam.eye), -dot(u, cam.eye), dot(f, cam.eye), 1];
  const proj = [1 / (t * aspect), 0, 0, 0, 0, 1 / t, 0, 0, 0, 0, -(far + near) / (far - near), -1, 0, 0, (-2 * far * near) / (far - near), 0];
  const out = new Float32Array(16);
  for (let c = 0; c < 4; ++c) for (let rr = 0; rr < 4; ++rr) {
    let s = 0;
    for (let k = 0; k < 4; ++k) s += proj[k * 4 + rr] * view[c * 4 + k];
    out[c * 4 + rr] = s;
  }
  return out;
}

// A lat-long image file (PNG/JPEG through the browser, Radiance .hdr here) as linear RGB,
// box-filtered to at most 256 texels wide: order ≤ 10 light sees nothing finer.
async function decodeImage(blob, name) {
  let width, height, rgb;
  if (/\.hdr$/i.test(name)) ({ width, height, rgb } = decodeHdr(new Uint8Array(await blob.arrayBuffer())));
  else {
    const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const canvas = new OffscreenCanvas(bitmap.width, bitmap.height), g = canvas.getContext('2d');
    g.drawImage(bitmap, 0, 0);
    const px = g.getImageData(0, 0, bitmap.width, bitmap.height).data;
    width = bitmap.width, height = bitmap.height, rgb = new Float32Array(width * height * 3);
    for (let i = 0; i < width * height; ++i) for (let c = 0; c < 3; ++c) rgb[3 * i + c] = srgbToLinear(px[4 * i + c] / 255);
  }
  let step = 1;
  while (width / step > 256 && width % (2 * step) === 0 && height % (2 * step) === 0) step *= 2;
  if (step === 1) return { width, height, rgb };
  const w = width / step, h = height / step, out = new Float32Array(w * h * 3);
  for (let y = 0; y < height; ++y) for (let x = 0; x < width; ++x)
    for (let c = 0; c < 3; ++c) out[3 * (Math.floor(y / step) * w + Math.floor(x / step)) + c] += rgb[3 * (y * width + x) + c] / (step * step);
  return { width: w, height: h, rgb: out };
}

// Radiance RGBE (.hdr): flat or new-style run-length rows, -Y H +X W orientation only.
function decodeHdr(bytes) {
  let at = 0;
  const line = () => {
    let s = '';
    while (at < bytes.length && bytes[at] !== 10) s += String.fromCharCode(bytes[at++]);
    ++at;
    return s;
  };
  if (!line().startsWith('#?')) throw new Error('not a Radiance .hdr file');
  for (let l = line(); l !== ''; l = line()) if (at >= bytes.length) throw new Error('.hdr header never ends');
  const m = /^-Y (\d+) \+X (\d+)$/.exec(line());
  if (!m) throw new Error('.hdr orientation other than -Y H +X W');
  const height = Number(m[1]), width = Number(m[2]), rgb = new Float32Array(width * height * 3), row = new Uint8Array(width * 4);
  for (let y = 0; y < height; ++y) {
    if (width >= 8 && width < 32768 && bytes[at] === 2 && bytes[at + 1] === 2 && ((bytes[at + 2] << 8) | bytes[at + 3]) === width) {
      at += 4;
      for (let c = 0; c < 4; ++c)
        for (let x = 0; x < width;) {
          let n = bytes[at++];
          if (n > 128) for (n -= 128, ++at; n-- > 0 && x < width;) row[4 * x++ + c] = bytes[at - 1];
          else while (n-- > 0 && x < width) row[4 * x++ + c] = bytes[at++];
        }
    } else {
      row.set(bytes.subarray(at, at + 4 * width));
      at += 4 * width;
    }
    for (let x = 0; x < width; ++x) {
      const e = row[4 * x + 3], f = e ? Math.pow(2, e - 136) : 0;
      for (let c = 0; c < 3; ++c) rgb[3 * (y * width + x) + c] = row[4 * x + c] * f;
    }
  }
  return { width, height, rgb };
}

const VERTEX = `#version 300 es
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_value;
uniform mat4 u_view_projection;
out vec3 v_value;
void main() {
  v_value = a_value;
  gl_Position = u_view_projection * vec4(a_position, 1.0);
}`;

// mode 0: linear radiance, exposed and sRGB-encoded as the tool's PNG; 1: a heat value in
// [0, 1+] on black-red-yellow; 2: AO, shown as the tool shows it (sRGB of the value).
const FRAGMENT = `#version 300 es
precision highp float;
in vec3 v_value;
uniform int u_mode;
uniform float u_exposure;
out vec4 colour;
float srgb(float v) {
  v = clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
void main() {
  if (u_mode == 1) {
    float e = clamp(v_value.x, 0.0, 1.0);
    colour = vec4(min(2.0 * e, 1.0), max(2.0 * e - 1.0, 0.0), 0.0, 1.0);
  } else {
    vec3 v = u_mode == 0 ? u_exposure * v_value : v_value;
    colour = vec4(srgb(v.r), srgb(v.g), srgb(v.b), 1.0);
  }
}`;

function compile(gl, type, source) {
  const s = gl.createShader(type);
  gl.shaderSource(s, source);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
  return s;
}

async function main() {
  const data = JSON.parse(document.getElementById('prtsub-data').textContent);
  const asset = parseGlb(base64Bytes(data.glb));
  const params = parseParams();
  const canvas = document.getElementById('view');
  const fixedSize = params.size && params.size.length === 2;
  const resize = () => {
    const dpr = fixedSize ? 1 : window.devicePixelRatio || 1;
    const [w, h] = fixedSize ? params.size : [window.innerWidth, window.innerHeight];
    canvas.style.width = w + 'px', canvas.style.height = h + 'px';
    canvas.width = Math.round(w * dpr), canvas.height = Math.round(h * dpr);
  };
  resize();
  const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true, alpha: !params.ui });
  if (!gl) throw new Error('WebGL2 is not available in this browser');
  status.webgl2 = true;

  const V = asset.positions.length / 3, K = asset.values, KC = K * asset.channels;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let v = 0; v < V; ++v) for (let c = 0; c < 3; ++c) lo[c] = Math.min(lo[c], asset.positions[3 * v + c]), hi[c] = Math.max(hi[c], asset.positions[3 * v + c]);
  const radius = 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  // The error view's own mesh: a grid of points in every triangle (n segments an edge) with the
  // asset's transfer interpolated there, and the reference the page carries for each point,
  // in the order of cli/viewer_page.cpp error_view_points.
  const errorMesh = data.error && errorGrid(asset, data.error.segments, new Float32Array(base64Bytes(data.error.reference).buffer));
  const reference = errorMesh;

  const program = gl.createProgram();
  gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT));
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error('shader link: ' + gl.getProgramInfoLog(program));
  const buffer = (target, array, location, size) => {
    const b = gl.createBuffer();
    gl.bindBuffer(target, b);
    gl.bufferData(target, array, gl.DYNAMIC_DRAW);
    if (location !== undefined) {
      gl.enableVertexAttribArray(location);
      gl.vertexAttribPointer(location, size, gl.FLOAT, false, 0, 0);
    }
    return b;
  };
  // A mesh to draw: positions, one value (RGB) per vertex, triangles.
  const drawable = (positions, indices) => {
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    buffer(gl.ARRAY_BUFFER, Float32Array.from(positions), 0, 3);
    const values = new Float32Array(positions.length);
    const valueBuffer = buffer(gl.ARRAY_BUFFER, values, 1, 3);
    buffer(gl.ELEMENT_ARRAY_BUFFER, indices);
    gl.bindVertexArray(null);
    return { vao, values, valueBuffer, count: indices.length };
  };
  const main = drawable(asset.positions, asset.indices);
  const errorDraw = errorMesh && drawable(errorMesh.positions, errorMesh.indices);

  // The view's state; the panel and the mouse change it, URL parameters set it first.
  const state = {
    camera: params.camera ? parseCamera(params.camera) : autoCamera(lo, hi, canvas.width, canvas.height),
    lights: params.lights.length ? params.lights : ['sky'],
    rotation: [1, 0, 0, 0, 1, 0, 0, 0, 1],
    exposure: params.exposure, albedo: params.albedo,
    view: params.view === 'error' && !reference ? 'gouraud' : params.view,
    env: null,
  };
  for (const spec of params.rotations) {
    const [a, d] = spec.split(',').length === 2 ? spec.split(',') : [spec.split(',').slice(0, 3).join(','), spec.split(',')[3]];
    const axis = { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] }[a] || numbers(a, 'light-rotate');
    state.rotation = multiply3(axisRotation(axis, Number(d)), state.rotation);
  }
  const studio = await decodeImage(new Blob([base64Bytes(studioPng.slice(studioPng.indexOf(',') + 1))], { type: 'image/png' }), 'studio.png');

  const lightOf = (spec) => {
    const [kind, arg] = [spec.split(':')[0], spec.slice(spec.indexOf(':') + 1)];
    const has = spec.includes(':');
    if (kind === 'sky') return skyLight(asset.order, has ? numbers(arg, 'sky') : [0, 1, 0]);
    if (kind === 'sun') {
      const v = numbers(arg, 'sun');
      return sunLight(asset.order, v.slice(0, 3), v[3] || 0);
    }
    if (kind === 'sh') return coefficientsLight(asset.order, numbers(arg, 'sh'));
    if (kind === 'const') {
      const v = numbers(arg, 'const'), rgb = v.length === 1 ? [v[0], v[0], v[0]] : v, l = emptyLight(asset.order);
      for (let c = 0; c < 3; ++c) l.coeffs[c] = 2 * Math.sqrt(Math.PI) * rgb[c];
      return l;
    }
    if (kind === 'random') {
      const c = data.random_lights[arg];
      if (!c) throw new Error(`random:${arg}: the page holds random lights ${Object.keys(data.random_lights).join(', ')} (prtsub view --random-seeds)`);
      return { order: asset.order, coeffs: Float64Array.from(c) };
    }
    if (kind === 'env') return environmentLight(asset.order, has && arg !== 'studio' && state.env ? state.env : studio);
    throw new Error(`unknown light '${spec}'`);
  };

  // t0, the band-0 transfer AO is made of: lobes hold it as Σ_k c_k · g_0 y_0 (Funk–Hecke).
  const lobeDc = asset.sg && sgZonal(asset.sg.sharpness, 1)[0] / (2 * Math.sqrt(Math.PI));
  const dcOf = (v) => {
    if (!asset.sg) return asset.transfer[v * KC];
    let s = 0;
    for (let k = 0; k < K; ++k) s += asset.transfer[v * K + k];
    return s * lobeDc;
  };

  let radiance = null, errorRadiance = null, referenceRadiance = null;
  const relight = () => {
    let light = state.lights.map(lightOf).reduce(addLights);
    light = rotateLight(light, state.rotation);
    // Lobes dot what each lobe sees of the light; SH values dot the light's coefficients.
    const lobeLight = asset.sg && sgLight(light, asset.sg.axes, asset.sg.sharpness);
    // channels 3: colour c dots the light's colour c with its own block; an asset's own albedo
    // (COLOR_0) replaces the page's grey one.
    const shade = (t, channels, albedo, L, K) => {
      const stride = K * channels, n = t.length / stride, out = new Float64Array(n * 3);
      for (let v = 0; v < n; ++v)
        for (let c = 0; c < 3; ++c) {
          const base = v * stride + (channels === 3 ? c * K : 0);
          let s = 0;
          for (let i = 0; i < K; ++i) s += L[3 * i + c] * t[base + i];
          out[3 * v + c] = ((albedo ? albedo[3 * v + c] : state.albedo) / Math.PI) * s;
        }
      return out;
    };
    const assetLight = lobeLight || light.coeffs, SK = asset.order * asset.order;
    radiance = shade(asset.transfer, asset.channels, asset.albedo, assetLight, K);
    // The error view's reference is SH of the asset's order, whatever the asset's basis.
    if (errorMesh) errorRadiance = shade(errorMesh.asset, 1, null, assetLight, K), referenceRadiance = shade(errorMesh.reference, 1, null, light.coeffs, SK);
    fill();
  };

  // What each vertex carries into the shader for the current view.
  const fill = () => {
    const target = state.view === 'error' ? errorDraw : main, values = target.values;
    if (state.view === 'ao') for (let v = 0; v < V; ++v) values.fill(dcOf(v) * AO_PER_T0, 3 * v, 3 * v + 3);
    else if (state.view === 'error') {
      const P = values.length / 3;
      let mean = 0;
      for (let v = 0; v < P; ++v) mean += (referenceRadiance[3 * v] + referenceRadiance[3 * v + 1] + referenceRadiance[3 * v + 2]) / (3 * P);
      const scale = 0.25 * Math.abs(mean) || 1;  // yellow at 25% of the mean, as compare's heat maps
      for (let v = 0; v < P; ++v) {
        let e = 0;
        for (let c = 0; c < 3; ++c) e += Math.abs(errorRadiance[3 * v + c] - referenceRadiance[3 * v + c]) / 3;
        values.fill(e / scale, 3 * v, 3 * v + 3);
      }
    } else values.set(radiance);
    gl.bindBuffer(gl.ARRAY_BUFFER, target.valueBuffer);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, values);
    draw();
  };

  const draw = () => {
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0, 0, 0, params.ui ? 1 : 0);  // test mode: uncovered pixels transparent, as the tool's
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.disable(gl.CULL_FACE);
    gl.useProgram(program);
    gl.uniformMatrix4fv(gl.getUniformLocation(program, 'u_view_projection'), false, viewProjection(state.camera, canvas.width, canvas.height, radius));
    gl.uniform1i(gl.getUniformLocation(program, 'u_mode'), { gouraud: 0, error: 1, ao: 2 }[state.view]);
    gl.uniform1f(gl.getUniformLocation(program, 'u_exposure'), state.exposure);
    const target = state.view === 'error' ? errorDraw : main;
    gl.bindVertexArray(target.vao);
    gl.drawElements(gl.TRIANGLES, target.count, gl.UNSIGNED_INT, 0);
    status.frames += 1;
  };

  if (params.ui) panel(state, data, asset, reference, relight, fill, draw, decodeImage);
  else {
    document.getElementById('panel').remove();
    document.documentElement.style.background = document.body.style.background = 'transparent';
  }
  controls(canvas, state, relight, draw);
  window.addEventListener('resize', () => {
    if (!fixedSize) resize(), draw();
  });
  relight();
  status.ready = true;
}

function errorGrid(asset, n, reference) {
  const F = asset.indices.length / 3, K = asset.values, per = ((n + 1) * (n + 2)) / 2, SK = asset.order * asset.order;
  const positions = new Float32Array(F * per * 3), values = new Float64Array(F * per * K), indices = [];
  for (let f = 0; f < F; ++f) {
    const t = [asset.indices[3 * f], asset.indices[3 * f + 1], asset.indices[3 * f + 2]], base = f * per;
    const index = (i, j) => base + i * (n + 1) - (i * (i - 1)) / 2 + j;
    for (let i = 0; i <= n; ++i)
      for (let j = 0; j <= n - i; ++j) {
        const w = [1 - i / n - j / n, i / n, j / n], r = index(i, j);
        for (let c = 0; c < 3; ++c) positions[3 * r + c] = w[0] * asset.positions[3 * t[0] + c] + w[1] * asset.positions[3 * t[1] + c] + w[2] * asset.positions[3 * t[2] + c];
        for (let k = 0; k < K; ++k) values[r * K + k] = w[0] * asset.transfer[t[0] * K + k] + w[1] * asset.transfer[t[1] * K + k] + w[2] * asset.transfer[t[2] * K + k];
        if (i + j < n) indices.push(index(i, j), index(i + 1, j), index(i, j + 1));
        if (i + j < n - 1) indices.push(index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
      }
  }
  if (reference.length !== F * per * SK) throw new Error(`the error view's reference holds ${reference.length} values for ${F * per * SK}`);
  return { positions, indices: Uint32Array.from(indices), asset: values, reference };
}

// Mouse: drag orbits the camera about its target, shift-drag (or the right button) turns the
// light, the wheel moves the camera in and out.
function controls(canvas, state, relight, draw) {
  let last = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    last = [e.clientX, e.clientY, e.shiftKey || e.button === 2];
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointerup', () => (last = null));
  canvas.addEventListener('pointermove', (e) => {
    if (!last) return;
    const dx = e.clientX - last[0], dy = e.clientY - last[1];
    last[0] = e.clientX, last[1] = e.clientY;
    const c = state.camera;
    if (last[2]) {
      state.rotation = multiply3(axisRotation(c.up, dx * 0.5), multiply3(axisRotation(unit(cross(sub(c.target, c.eye), c.up)), dy * 0.5), state.rotation));
      relight();
      return;
    }
    const offset = sub(c.eye, c.target), right = unit(cross(offset, c.up));
    const R = multiply3(axisRotation(c.up, -dx * 0.4), axisRotation(right, -dy * 0.4));
    const next = [0, 1, 2].map((i) => R[3 * i] * offset[0] + R[3 * i + 1] * offset[1] + R[3 * i + 2] * offset[2]);
    if (Math.abs(dot(unit(next), unit(c.up))) < 0.995) c.eye = [0, 1, 2].map((i) => c.target[i] + next[i]);
    draw();
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const c = state.camera, k = Math.exp(e.deltaY * 0.001);
    c.eye = [0, 1, 2].map((i) => c.target[i] + (c.eye[i] - c.target[i]) * k);
    draw();
  }, { passive: false });
}

// The panel: light, view and exposure; what the asset is. Text from the file is set as text.
function panel(state, data, asset, reference, relight, fill, draw, decode) {
  const root = document.getElementById('panel');
  const el = (tag, props = {}, ...children) => {
    const e = document.createElement(tag);
    Object.assign(e, props);
    children.forEach((c) => e.append(c));
    return e;
  };
  root.append(el('div', { className: 'title', textContent: data.name }));
  root.append(el('div', { className: 'info', textContent: `${asset.indices.length / 3} triangles, ${asset.positions.length / 3} vertices, ` +
    (asset.signal === 'ao' ? 'ambient occlusion' : asset.sg ? `${asset.sg.lobes} spherical-Gaussian lobes` : `SH order ${asset.order}`) }));
  const lights = [['sky', 'sky'], ['sun:0.5,1,0.6,2', 'sun'], ['sky+sun:0.5,1,0.6,2', 'sky and sun'], ['env:studio', 'studio (environment)'],
    ...Object.keys(data.random_lights).map((s) => [`random:${s}`, `random ${s}`]), ['sh:', 'SH coefficients…'], ['env:file', 'environment file…']];
  const select = el('select', {}, ...lights.map(([v, t]) => el('option', { value: v, textContent: t })));
  const shText = el('input', { type: 'text', placeholder: 'c0,c1,c2,…', hidden: true });
  const file = el('input', { type: 'file', accept: '.png,.jpg,.jpeg,.hdr', hidden: true });
  const apply = () => {
    try {
      const v = select.value;
      shText.hidden = v !== 'sh:', file.hidden = v !== 'env:file';
      if (v === 'sh:') state.lights = ['sh:' + (shText.value || '3.5449')];
      else if (v === 'env:file') {
        if (!state.env) return;
        state.lights = ['env:file'];
      } else state.lights = v.split('+');
      relight();
      document.getElementById('message').textContent = '';
    } catch (e) {
      document.getElementById('message').textContent = e.message;
    }
  };
  const first = state.lights.join('+');
  if (lights.some(([v]) => v === first)) select.value = first;
  else if (first.startsWith('sh:')) (select.value = 'sh:'), (shText.hidden = false), (shText.value = first.slice(3));
  else if (first.startsWith('env')) select.value = 'env:studio';
  select.onchange = apply, shText.onchange = apply;
  file.onchange = async () => {
    try {
      state.env = await decode(file.files[0], file.files[0].name);
      apply();
    } catch (e) {
      document.getElementById('message').textContent = `${file.files[0].name}: ${e.message}`;
    }
  };
  root.append(el('label', {}, 'light ', select), shText, file);
  const views = el('div', { className: 'views' });
  for (const [v, t] of [['gouraud', asset.signal === 'ao' ? 'AO (Gouraud)' : 'transfer (Gouraud)'], ['ao', 'AO'], ['error', 'error']]) {
    const r = el('input', { type: 'radio', name: 'view', value: v, checked: state.view === v, disabled: v === 'error' && !reference });
    r.onchange = () => ((state.view = v), fill());
    views.append(el('label', { title: v === 'error' && !reference ? 'prtsub view --source MESH adds a reference' : '' }, r, ' ' + t));
  }
  root.append(views);
  const exposure = el('input', { type: 'range', min: -4, max: 4, step: 0.1, value: Math.log2(state.exposure) });
  exposure.oninput = () => ((state.exposure = Math.pow(2, Number(exposure.value))), draw());
  root.append(el('label', {}, 'exposure ', exposure));
  root.append(el('div', { className: 'help', textContent: 'drag: camera · shift-drag: light · wheel: zoom' }));
  if (reference) root.append(el('div', { className: 'help', textContent: `error: |radiance − reference| on the surface under this light (reference ${data.reference_rays} rays a point), yellow at 25% of its mean` }));
}

main().catch((e) => fail(e.message));
