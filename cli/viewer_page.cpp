#include "cli/viewer_page.h"

#include <cstdio>
#include <cstring>

#include "cli/escape.h"
#include "prtsub/prt/base64.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

extern const char kViewerScript[];    // viewer/dist/viewer.js (cmake/embed_text.cmake)
extern const char kViewerTemplate[];  // viewer/src/page.html

namespace {

// Little-endian float32 (or uint32) bytes of a row-major array, base64-encoded for the page.
template <class T, class Source>
std::string packed(const Source* data, size_t n) {
  std::string bytes(n * sizeof(T), '\0');
  for (size_t i = 0; i < n; ++i) {
    const T v = static_cast<T>(data[i]);
    std::memcpy(&bytes[i * sizeof v], &v, sizeof v);
  }
  return "\"" + base64_encode(bytes) + "\"";
}

}  // namespace

ErrorView trace_error_view(const Asset& a, const RayScene& source, TransferOptions options, size_t target) {
  const size_t F = a.triangles.size();
  ErrorView p;
  while (p.segments < 8 && F * static_cast<size_t>((p.segments + 1) * (p.segments + 1)) <= target) ++p.segments;  // F·n² triangles
  const int n = p.segments, per = (n + 1) * (n + 2) / 2;
  p.positions.resize(static_cast<Eigen::Index>(F) * per, 3);
  p.normals.resize(p.positions.rows(), 3);
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = a.triangles[f];
    const auto base = static_cast<uint32_t>(f * static_cast<size_t>(per));
    auto index = [&](int i, int j) { return base + static_cast<uint32_t>(i * (n + 1) - i * (i - 1) / 2 + j); };  // row i, j ≤ n − i
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n - i; ++j) {
        const double w1 = double(i) / n, w2 = double(j) / n, w0 = 1 - w1 - w2;
        const auto r = static_cast<Eigen::Index>(index(i, j));
        p.positions.row(r) = w0 * a.positions.row(t[0]) + w1 * a.positions.row(t[1]) + w2 * a.positions.row(t[2]);
        const Eigen::RowVector3d nrm = w0 * a.normals.row(t[0]) + w1 * a.normals.row(t[1]) + w2 * a.normals.row(t[2]);
        p.normals.row(r) = nrm.norm() > 0 ? Eigen::RowVector3d(nrm.normalized()) : Eigen::RowVector3d(a.normals.row(t[0]));
      }
  }
  options.order = a.order;
  p.reference = shadowed_transfer(source, p.positions, p.normals, options);
  p.rays = options.rays;
  return p;
}

std::string viewer_data_json(const Asset& asset, const ViewerPageOptions& o) {
  const Eigen::Index K = asset.transfer.cols();
  if (o.error && (o.error->reference.rows() != o.error->positions.rows() || o.error->reference.cols() != K))
    throw InputError("viewer: the reference does not hold one row of " + std::to_string(K) + " values per error-view point");
  const std::string glb = gltf_asset_bytes("viewer.glb", asset_mesh(asset), stored_values(asset), asset.metadata, asset.signal, {}, asset.albedo);
  std::string out = "{\"glb\":\"" + base64_encode(glb) + "\",\"name\":" + json_quote(o.name) + ",\"random_lights\":{";
  char number[32];
  for (size_t s = 0; s < o.random_seeds.size(); ++s) {
    const ShLight l = random_light(asset.order, o.random_seeds[s]);
    out += (s ? ",\"" : "\"") + std::to_string(o.random_seeds[s]) + "\":[";
    for (Eigen::Index i = 0; i < l.coeffs.size(); ++i) {
      std::snprintf(number, sizeof number, "%.17g", l.coeffs.data()[i]);
      out += (i ? "," : "") + std::string(number);
    }
    out += "]";
  }
  out += "},\"error\":";
  if (o.error) {
    if (!o.error->reference.allFinite()) throw InputError("viewer: the reference holds NaN or Inf");
    // The page rebuilds the points and their triangles from the segment count (viewer/src/main.js
    // errorGrid, the same order as trace_error_view).
    const auto P = static_cast<size_t>(o.error->positions.rows());
    out += "{\"segments\":" + std::to_string(o.error->segments) + ",\"reference\":" +
           packed<float>(o.error->reference.data(), P * static_cast<size_t>(K)) + "}";
  } else {
    out += "null";
  }
  out += ",\"reference_rays\":" + std::to_string(o.error ? o.error->rays : 0) + "}";
  return out;
}

std::string viewer_page(const Asset& asset, const ViewerPageOptions& o) {
  const std::string page = kViewerTemplate, script = kViewerScript;
  // The bundle is inlined in a <script> element; the build checks it cannot close it early.
  if (script.find("</script") != std::string::npos) throw Error("viewer: the bundled script contains </script");
  std::string out;
  size_t at = 0;
  for (const auto& [marker, text] : {std::pair<const char*, std::string>{"@TITLE@", html_escape(o.name)},
                                     {"@DATA@", viewer_data_json(asset, o)},
                                     {"@SCRIPT@", script}}) {
    const size_t next = page.find(marker, at);
    if (next == std::string::npos) throw Error(std::string("viewer: the page template lacks ") + marker);
    out += page.substr(at, next - at) + text;
    at = next + std::strlen(marker);
  }
  return out + page.substr(at);
}

}  // namespace prtsub
