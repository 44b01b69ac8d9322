// Reads the GLB that `prtsub view` embeds (docs/asset_format.md, "glTF"): positions, normals,
// indices, and the transfer (_PRT_0.._PRT_k, FLOAT or normalized SHORT with its scales; RGB
// transfer as _PRT_R_j, _PRT_G_j, _PRT_B_j, with the vertices' albedo in COLOR_0; spherical-
// Gaussian lobes as _PRT_j with the basis in extras.sg_*) or AO (_AO). The file is the tool's own, uncompressed; anything else is an error with a message.

// componentType: [bytes, DataView getter]
const COMPONENT = { 5121: [1, 'getUint8'], 5122: [2, 'getInt16'], 5123: [2, 'getUint16'], 5125: [4, 'getUint32'], 5126: [4, 'getFloat32'] };
const WIDTH = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };

export function parseGlb(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.length < 20 || view.getUint32(0, true) !== 0x46546c67) throw new Error('the embedded asset is not a GLB');
  const jsonLength = view.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLength)));
  const binStart = 20 + jsonLength + 8, binLength = view.getUint32(20 + jsonLength, true);
  const bin = bytes.subarray(binStart, binStart + binLength);

  // Accessor i as a Float64Array of count × width numbers (normalized integers mapped to [-1, 1]).
  const accessor = (i) => {
    const a = json.accessors[i], v = json.bufferViews[a.bufferView];
    const [size, get] = COMPONENT[a.componentType], width = WIDTH[a.type];
    const stride = v.byteStride || size * width, base = (v.byteOffset || 0) + (a.byteOffset || 0);
    const data = new DataView(bin.buffer, bin.byteOffset, bin.byteLength);
    const out = new Float64Array(a.count * width);
    const scale = !a.normalized ? 1 : a.componentType === 5122 ? 1 / 32767 : a.componentType === 5123 ? 1 / 65535 : 1 / 255;
    for (let k = 0; k < a.count; ++k)
      for (let c = 0; c < width; ++c) {
        const x = data[get](base + k * stride + c * size, true) * scale;
        out[k * width + c] = a.normalized && a.componentType === 5122 ? Math.max(x, -1) : x;
      }
    return out;
  };

  const mesh = json.meshes[0], prim = mesh.primitives[0], extras = mesh.extras || {};
  const positions = accessor(prim.attributes.POSITION), normals = accessor(prim.attributes.NORMAL);
  const V = positions.length / 3;
  const indices = Uint32Array.from(accessor(prim.indices));
  const ao = extras.signal === 'ao';
  // Lobes (extras.sg_lobes): N values per vertex; lights are built at sg_shading_order and then
  // projected onto the lobes (sh.js sgLight).
  const lobes = ao ? 0 : extras.sg_lobes || 0;
  const order = ao ? 1 : lobes ? extras.sg_shading_order : extras.sh_order, K = lobes || order * order;
  const channels = ao ? 1 : extras.channels || 1, KC = K * channels;  // per vertex: the channels' blocks side by side
  const transfer = new Float64Array(V * KC);
  let albedo = null;
  if (ao) {
    const values = accessor(prim.attributes._AO);
    for (let v = 0; v < V; ++v) transfer[v] = values[v] / 1.1283791670955126;  // t0 = ao · √π / 2
  } else {
    const scale = extras.quantization ? extras.quantization.scale : new Array(KC).fill(1);
    for (let ch = 0; ch < channels; ++ch)
      for (let j = 0; 4 * j < K; ++j) {
        const name = channels === 1 ? '_PRT_' + j : '_PRT_' + 'RGB'[ch] + '_' + j;
        const values = accessor(prim.attributes[name]);
        for (let v = 0; v < V; ++v)
          for (let c = 4 * j; c < Math.min(K, 4 * j + 4); ++c) transfer[v * KC + ch * K + c] = scale[ch * K + c] * values[v * 4 + c - 4 * j];
      }
    if (prim.attributes.COLOR_0 !== undefined) albedo = accessor(prim.attributes.COLOR_0);  // linear, VEC3
  }
  const sg = lobes ? { lobes, axes: extras.sg_axes, sharpness: extras.sg_sharpness } : null;
  return { positions, normals, indices, transfer, order, values: K, sg, channels, albedo, signal: ao ? 'ao' : 'transfer', extras };
}
