// Validates glTF files with the Khronos validator (npm gltf-validator, pinned in
// package-lock.json) and exits 1 if any file has an error; warnings and infos are printed but
// do not fail. The validator cannot look inside EXT_meshopt_compression, so a compressed file
// is also decoded with meshoptimizer's reference JavaScript decoder (an implementation
// independent of the C++ codec that wrote it) into a plain GLB, which is validated too and,
// with --decoded DIR, written there as NAME.decoded.glb for the tests to compare.
//   node validate.mjs [--decoded DIR] FILE.glb|FILE.gltf ...
import { readFileSync, writeFileSync } from 'node:fs';
import { basename, join } from 'node:path';
import { createRequire } from 'node:module';
import { MeshoptDecoder } from 'meshoptimizer/meshopt_decoder_reference.js';

const validator = createRequire(import.meta.url)('gltf-validator');
const MESHOPT = 'EXT_meshopt_compression';

function parse(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.length >= 12 && view.getUint32(0, true) === 0x46546c67) {
    let at = 12, json = null, bin = null;
    while (at + 8 <= bytes.length) {
      const length = view.getUint32(at, true), type = view.getUint32(at + 4, true);
      const chunk = bytes.subarray(at + 8, at + 8 + length);
      if (type === 0x4e4f534a) json = JSON.parse(new TextDecoder().decode(chunk));
      else if (type === 0x004e4942) bin = chunk;
      at += 8 + length;
    }
    return { json, buffers: json.buffers.map((b, i) => (i === 0 && !b.uri ? bin : null)) };
  }
  const json = JSON.parse(new TextDecoder().decode(bytes));
  return { json, buffers: json.buffers.map((b) => (b.uri ? new Uint8Array(Buffer.from(b.uri.split(',')[1], 'base64')) : null)) };
}

function glb(json, bin) {
  const pad = (n) => (4 - (n % 4)) % 4;
  let text = JSON.stringify(json);
  text += ' '.repeat(pad(text.length));
  const j = new TextEncoder().encode(text), binLength = bin.length + pad(bin.length);
  const out = new Uint8Array(28 + j.length + binLength);
  const v = new DataView(out.buffer);
  v.setUint32(0, 0x46546c67, true), v.setUint32(4, 2, true), v.setUint32(8, out.length, true);
  v.setUint32(12, j.length, true), v.setUint32(16, 0x4e4f534a, true), out.set(j, 20);
  v.setUint32(20 + j.length, binLength, true), v.setUint32(24 + j.length, 0x004e4942, true);
  out.set(bin, 28 + j.length);
  return out;
}

// The same asset with every compressed view decoded into one plain buffer.
function decode({ json, buffers }) {
  const parts = [];
  let size = 0;
  for (const view of json.bufferViews) {
    const e = view.extensions && view.extensions[MESHOPT];
    let data;
    if (e) {
      data = new Uint8Array(e.count * e.byteStride);
      const source = buffers[e.buffer].subarray(e.byteOffset ?? 0, (e.byteOffset ?? 0) + e.byteLength);
      MeshoptDecoder.decodeGltfBuffer(data, e.count, e.byteStride, source, e.mode, e.filter ?? 'NONE');
      delete view.extensions[MESHOPT];
      if (Object.keys(view.extensions).length === 0) delete view.extensions;
    } else {
      data = buffers[view.buffer].subarray(view.byteOffset ?? 0, (view.byteOffset ?? 0) + view.byteLength);
    }
    size += (4 - (size % 4)) % 4;
    parts.push([size, data]);
    view.buffer = 0, view.byteOffset = size, view.byteLength = data.length;
    size += data.length;
  }
  const bin = new Uint8Array(size);
  for (const [at, data] of parts) bin.set(data, at);
  json.buffers = [{ byteLength: size }];
  for (const key of ['extensionsUsed', 'extensionsRequired']) {
    if (json[key]) json[key] = json[key].filter((x) => x !== MESHOPT);
    if (json[key] && json[key].length === 0) delete json[key];
  }
  return glb(json, bin);
}

async function validate(name, bytes) {
  const report = await validator.validateBytes(bytes, {
    uri: name,
    maxIssues: 100,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}: assets are self-contained`)),
  });
  const i = report.issues;
  console.log(`${name}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
  for (const m of i.messages) console.log(`  ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  return i.numErrors;
}

const args = process.argv.slice(2);
let decodedDir = null;
if (args[0] === '--decoded') decodedDir = args[1], args.splice(0, 2);
if (args.length === 0) {
  console.error('usage: node validate.mjs [--decoded DIR] FILE.glb|FILE.gltf ...');
  process.exit(2);
}
let failed = 0;
for (const file of args) {
  const bytes = new Uint8Array(readFileSync(file));
  if ((await validate(file, bytes)) > 0) failed += 1;
  const asset = parse(bytes);
  if ((asset.json.extensionsUsed ?? []).includes(MESHOPT)) {
    let decoded;
    try {
      decoded = decode(asset);
    } catch (e) {
      console.log(`${file}: the reference decoder fails: ${e.message}`);
      failed += 1;
      continue;
    }
    const name = basename(file).replace(/\.(glb|gltf)$/i, '') + '.decoded.glb';
    if ((await validate(`${file} (decoded)`, decoded)) > 0) failed += 1;
    if (decodedDir) writeFileSync(join(decodedDir, name), decoded);
  }
}
process.exit(failed ? 1 : 0);
