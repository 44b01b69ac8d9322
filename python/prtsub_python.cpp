// Python bindings (pybind11): `import prtsub` binds the library's API, not the command line.
//
// Meshes and assets hold their C++ data, and their arrays (vertices, normals, uv, faces,
// source_face, transfer, ao, a frame's pixels) are NumPy views of it: no copy, and the view
// keeps its owner alive. Only the transfer of an asset is writeable; the rest are read-only so
// that a mesh's indices cannot be broken behind its back. Input arrays are read through
// NumPy's buffer protocol; they are copied once, into the mesh build_mesh welds.
//
// Errors keep the library's one-line messages: InputError is a ValueError, IoError an OSError,
// EmbreeError and SolverError RuntimeErrors, all below prtsub.Error.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Geometry>
#include <functional>

#include "prtsub/prt/asset.h"
#include "prtsub/prt/bake.h"
#include "prtsub/prt/gltf.h"
#include "prtsub/prt/sg_basis.h"
#include "prtsub/prt/transfer.h"
#include "prtsub/prt/image_io.h"
#include "prtsub/prt/lights.h"
#include "prtsub/prt/ray_scene.h"
#include "prtsub/prt/render.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/mesh_io.h"
#include "prtsub/version.h"

namespace py = pybind11;

namespace prtsub {
namespace {

// A read-only (or writeable) view of `rows` × `cols` values at `data`, owned by `owner`.
template <class T>
py::array view(const T* data, py::ssize_t rows, py::ssize_t cols, py::handle owner, bool writeable = false) {
  py::array a = cols > 0 ? py::array(py::dtype::of<T>(), {rows, cols}, {static_cast<py::ssize_t>(sizeof(T)) * cols, static_cast<py::ssize_t>(sizeof(T))}, data, owner)
                         : py::array(py::dtype::of<T>(), {rows}, {static_cast<py::ssize_t>(sizeof(T))}, data, owner);
  if (!writeable) a.attr("setflags")(py::arg("write") = false);
  return a;
}

py::array faces_view(const std::vector<Triangle>& t, py::handle owner) {
  static_assert(sizeof(Triangle) == 3 * sizeof(uint32_t), "triangles are packed");
  return view(t.empty() ? nullptr : t[0].data(), static_cast<py::ssize_t>(t.size()), 3, owner);
}

// An asset in memory: what write_asset takes, plus what bake measured.
struct PyAsset {
  Mesh mesh;
  RowMatrixXd transfer;  // #V by N² (3·N² for RGB transfer), order-1 transfer for AO; #V by lobes for SG
  RowMatrixX3d albedo;    // #V by 3 when the albedo is coloured, else no rows
  RowMatrixX3d vertices;  // render vertices' positions
  Eigen::VectorXd ao;     // AO assets: ao = t0 · kAoPerT0
  Metadata metadata;
  AssetSignal signal = AssetSignal::Transfer;
  int order = 0;  // SG: the SH order it is relit through (sg_shading_order)
  int lobes = 0;  // SG assets: the lobe count (0: SH)
  py::dict stats;
  std::vector<std::string> warnings;

  void finish() {
    vertices = vertex_positions(mesh);
    lobes = metadata_lobes(metadata, "the asset");
    if (lobes > 0) order = sg_shading_order(sg_basis(lobes));
    if (signal == AssetSignal::Ao) ao = transfer.col(0) * kAoPerT0;
  }
};

// A light whose SH is made at the order of the asset it lights.
struct PyLight {
  std::vector<std::function<ShLight(int)>> terms;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();

  ShLight at(int order) const {
    ShLight sum = terms.at(0)(order);
    for (size_t i = 1; i < terms.size(); ++i) sum += terms[i](order);
    return rotation.isIdentity() ? sum : rotate_light(sum, rotation);
  }
};

PyLight single(std::function<ShLight(int)> f) { return PyLight{{std::move(f)}, Eigen::Matrix3d::Identity()}; }

Eigen::Vector3d vec3(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw InputError(std::string(what) + " takes three numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

RawMesh raw_mesh(py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                 py::array_t<int64_t, py::array::c_style | py::array::forcecast> faces) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw InputError("vertices must be an array of shape (V, 3), got " + std::to_string(vertices.ndim()) + " dimensions");
  if (faces.ndim() != 2 || faces.shape(1) < 3)
    throw InputError("faces must be an array of shape (F, k) with k >= 3 corners per face");
  RawMesh raw;
  const auto V = static_cast<Eigen::Index>(vertices.shape(0));
  raw.positions = Eigen::Map<const RowMatrixX3d>(vertices.data(), V, 3);
  const auto F = static_cast<size_t>(faces.shape(0)), k = static_cast<size_t>(faces.shape(1));
  raw.face_indices.assign(faces.data(), faces.data() + F * k);
  raw.face_offsets.resize(F + 1);
  for (size_t f = 0; f <= F; ++f) raw.face_offsets[f] = f * k;
  return raw;
}

// bake()'s keyword options, each checked by the library as it would check the CLI's.
BakeOptions bake_options(const py::kwargs& kw, std::string& source) {
  BakeOptions o;
  for (const auto& [key_handle, value] : kw) {
    const std::string key = py::cast<std::string>(key_handle);
    if (key == "order") {
      if (py::isinstance<py::str>(value) && value.cast<std::string>() == "auto") o.order_auto = true;
      else o.transfer.order = value.cast<int>();
    } else if (key == "max_order") o.order_choice.max_order = value.cast<int>();
    else if (key == "order_tolerance") o.order_choice.tolerance_percent = value.cast<double>();
    else if (key == "rays") o.transfer.rays = value.cast<int>();
    else if (key == "first_rays") o.round_rays = value.cast<int>();
    else if (key == "ray_noise") o.stop_noise_percent = value.cast<double>();
    else if (key == "seed") o.transfer.seed = value.cast<uint64_t>();
    else if (key == "estimator") o.transfer.estimator = estimator_from_name(value.cast<std::string>());
    else if (key == "pls_acceleration") o.transfer.progressive.acceleration = value.cast<double>();
    else if (key == "threads") o.transfer.threads = value.cast<int>();
    else if (key == "signal") o.signal = parse_asset_signal(value.cast<std::string>());
    else if (key == "basis") {
      const std::string b = value.cast<std::string>();
      if (b.rfind("sg:", 0) == 0) o.sg_lobes = std::atoi(b.c_str() + 3), o.fit.method = FitMethod::Point;
      else if (b != "sh") throw InputError("basis: 'sh' or 'sg:N', got '" + b + "'");
    } else if (key == "sg_signed") o.sg_signed = value.cast<bool>();
    else if (key == "fit") o.fit.method = parse_fit_method(value.cast<std::string>());
    else if (key == "alpha") {
      if (py::isinstance<py::str>(value) && value.cast<std::string>() == "auto") o.alpha_auto = true;
      else o.fit.alpha = value.cast<double>(), o.alpha_auto = false;
    }
    else if (key == "refine") o.refine = parse_refinement(value.cast<std::string>());
    else if (key == "budget") o.adaptive.budget = value.cast<size_t>();
    else if (key == "levels") o.uniform.levels = value.cast<int>();
    else if (key == "auto_share") o.auto_share = value.cast<double>();
    else if (key == "auto_cycles") o.auto_cycles = value.cast<int>();
    else if (key == "auto_cycle_share") o.auto_cycle_share = value.cast<double>();
    else if (key == "simplify_metric") o.simplify.metric = parse_simplify_metric(value.cast<std::string>());
    else if (key == "min_angle") o.simplify.min_angle_deg = value.cast<double>();
    else if (key == "lock_corners") o.simplify.collapse_corners = !value.cast<bool>();
    else if (key == "simplify_alpha") o.simplified_alpha = value.cast<double>();
    else if (key == "error") o.target_error = value.cast<double>();
    else if (key == "sample_rays") {
      if (py::isinstance<py::str>(value) && value.cast<std::string>() == "auto") o.sample_rays_auto = true;
      else o.sample_rays = value.cast<int>(), o.sample_rays_auto = false;
    }
    else if (key == "bounces") {
      if (py::isinstance<py::str>(value) && value.cast<std::string>() == "auto") o.bounce.until_converged = true, o.bounce.bounces = 16;
      else o.bounce.bounces = value.cast<int>();
    } else if (key == "albedo") {
      // A number (grey), "vertex", "R,G,B", or three numbers.
      const std::string text = py::isinstance<py::str>(value) ? value.cast<std::string>()
                               : py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value)
                                   ? std::to_string(value.cast<double>())
                                   : [&] {
                                       const std::vector<double> c = value.cast<std::vector<double>>();
                                       if (c.size() != 3) throw InputError("albedo: give a number, 'vertex', or three numbers R, G, B");
                                       return std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]);
                                     }();
      const AlbedoSpec a = parse_albedo(text);
      if (a.coloured()) o.albedo_colour = a;
      else o.bounce.albedo = a.constant.x();
    } else if (key == "albedo_map") o.albedo_colour = read_albedo_map(value.cast<std::string>());
    else if (key == "bounce_rekey") o.rekey_share = value.cast<double>();
    else if (key == "source") source = value.cast<std::string>();
    else
      throw py::type_error("bake() got an unexpected keyword argument '" + key +
                           "' (order, max_order, order_tolerance, rays, first_rays, ray_noise, seed, threads, signal, basis, sg_signed, fit, alpha, refine, budget, levels, auto_share, auto_cycles, auto_cycle_share, simplify_metric, min_angle, lock_corners, simplify_alpha, error, sample_rays, bounces, albedo, albedo_map, bounce_rekey, source)");
  }
  if ((o.refine == Refinement::Adaptive || o.refine == Refinement::Auto) && o.adaptive.budget == 0)
    throw InputError(std::string("refine='") + refinement_name(o.refine) + "' needs budget=T triangles");
  return o;
}

PyAsset bake_mesh(const Mesh& mesh, const BakeOptions& options) {
  BakeResult r;
  {
    py::gil_scoped_release release;  // the bake runs on its own threads; other Python threads may go on
    r = bake(mesh, options);
  }
  PyAsset a;
  a.mesh = std::move(r.mesh);
  a.transfer = std::move(r.transfer);
  a.albedo = std::move(r.albedo);
  a.metadata = std::move(r.metadata);
  a.signal = options.signal;
  a.order = options.signal == AssetSignal::Ao ? 1 : r.order.order > 0 ? r.order.order : options.transfer.order;
  a.warnings = r.warnings;
  a.finish();
  py::dict s;
  s["triangles_in"] = mesh.num_faces();
  s["vertices_in"] = mesh.num_vertices();
  s["triangles_out"] = a.mesh.num_faces();
  s["vertices_out"] = a.mesh.num_vertices();
  s["rays"] = r.rays;
  s["seconds_total"] = r.seconds_total;
  s["seconds_transfer"] = r.seconds_transfer;
  s["seconds_refine"] = r.seconds_refine;
  s["seconds_samples"] = r.seconds_samples;
  s["seconds_fit"] = r.seconds_fit;
  s["predicted_error_percent"] = r.predicted.percent;
  s["predicted_error_standard_error"] = r.predicted.standard_error;
  s["fit_samples"] = r.fit_data.samples.face.size();
  s["bounces"] = r.bounce.passes;
  s["order"] = a.order;
  a.stats = s;
  return a;
}

Camera camera_of(const py::object& camera, const Bounds& b, int width, int height) {
  if (camera.is_none()) return auto_camera(b, width, height);
  Camera c;
  const py::dict d = camera.cast<py::dict>();
  for (const auto& [k, v] : d) {
    const std::string key = py::cast<std::string>(k);
    if (key == "eye") c.eye = vec3(v.cast<std::vector<double>>(), "camera eye");
    else if (key == "target") c.target = vec3(v.cast<std::vector<double>>(), "camera target");
    else if (key == "up") c.up = vec3(v.cast<std::vector<double>>(), "camera up");
    else if (key == "fov") c.fov_deg = v.cast<double>();
    else throw InputError("camera has no key '" + key + "' (eye, target, up, fov)");
  }
  check_camera(c);
  return c;
}

}  // namespace
}  // namespace prtsub

PYBIND11_MODULE(prtsub, m) {
  using namespace prtsub;
  m.doc() = "prtsub: meshes in, per-vertex PRT transfer out (the C++ library's API). docs/python.md";
  m.attr("__version__") = kVersion;

  // Translators are tried newest first, so the specific errors are registered after Error.
  const py::exception<Error>& error = py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  py::register_exception<InputError>(m, "InputError", py::make_tuple(error, py::handle(PyExc_ValueError)));
  py::register_exception<IoError>(m, "IoError", py::make_tuple(error, py::handle(PyExc_OSError)));

  py::class_<Mesh>(m, "Mesh", "A triangle mesh as the library holds it: welded positions, render vertices per crease side.")
      .def_property_readonly("positions", [](py::object self) {
        const Mesh& x = self.cast<const Mesh&>();
        return view(x.positions.data(), x.positions.rows(), 3, self);
      }, "welded positions, (P, 3) float64")
      .def_property_readonly("normals", [](py::object self) {
        const Mesh& x = self.cast<const Mesh&>();
        return view(x.normals.data(), x.normals.rows(), 3, self);
      }, "render vertices' unit normals, (V, 3) float64")
      .def_property_readonly("vertex_position", [](py::object self) {
        const Mesh& x = self.cast<const Mesh&>();
        return view(x.vertex_position.data(), static_cast<py::ssize_t>(x.vertex_position.size()), 0, self);
      }, "each render vertex's row of positions, (V,) uint32")
      .def_property_readonly("faces", [](py::object self) { return faces_view(self.cast<const Mesh&>().triangles, self); },
                             "triangles over render vertices, (F, 3) uint32")
      .def_property_readonly("uv", [](py::object self) {
        const Mesh& x = self.cast<const Mesh&>();
        return view(x.uv.data(), x.uv.rows(), 2, self);
      }, "texture coordinates, (V, 2), or (0, 2) without UVs")
      .def_property_readonly("num_vertices", &Mesh::num_vertices)
      .def_property_readonly("num_faces", &Mesh::num_faces);

  m.def("load_mesh", [](const std::string& path, double crease_angle) { return load_mesh(path, LoadOptions{crease_angle}); },
        py::arg("path"), py::arg("crease_angle") = kDefaultCreaseAngleDeg,
        "Reads an OBJ, PLY, OFF or STL mesh as `prtsub bake` does (welded, normals from the file or computed with the crease angle).");
  m.def("mesh", [](py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                   py::array_t<int64_t, py::array::c_style | py::array::forcecast> faces, double crease_angle, const std::string& name) {
        return build_mesh(raw_mesh(vertices, faces), name, LoadOptions{crease_angle});
      }, py::arg("vertices"), py::arg("faces"), py::arg("crease_angle") = kDefaultCreaseAngleDeg, py::arg("name") = "(in memory)",
      "Builds a mesh from a (V, 3) array of positions and an (F, k) array of 0-based polygon corners.");

  py::class_<PyAsset>(m, "Asset", "A PRT asset: render vertices with their transfer (or AO), faces, metadata and statistics.")
      .def_property_readonly("vertices", [](py::object self) {
        const PyAsset& a = self.cast<const PyAsset&>();
        return view(a.vertices.data(), a.vertices.rows(), 3, self);
      }, "positions, (V, 3) float64")
      .def_property_readonly("normals", [](py::object self) {
        const PyAsset& a = self.cast<const PyAsset&>();
        return view(a.mesh.normals.data(), a.mesh.normals.rows(), 3, self);
      })
      .def_property_readonly("uv", [](py::object self) {
        const PyAsset& a = self.cast<const PyAsset&>();
        return view(a.mesh.uv.data(), a.mesh.uv.rows(), 2, self);
      })
      .def_property_readonly("faces", [](py::object self) { return faces_view(self.cast<const PyAsset&>().mesh.triangles, self); })
      .def_property_readonly("source_face", [](py::object self) {
        const PyAsset& a = self.cast<const PyAsset&>();
        return view(a.mesh.source_face.data(), static_cast<py::ssize_t>(a.mesh.source_face.size()), 0, self);
      }, "each face's input triangle, (F,) uint32")
      .def_property_readonly("transfer", [](py::object self) -> py::object {
        PyAsset& a = self.cast<PyAsset&>();
        if (a.signal == AssetSignal::Ao) return py::none();
        return view(a.transfer.data(), a.transfer.rows(), a.transfer.cols(), self, true);
      }, "SH transfer, (V, N²) float64, index l(l+1)+m (docs/sh_convention.md); (V, 3·N²) for RGB transfer, the red, green and\n"
         "blue blocks side by side; (V, lobes) lobe coefficients for an SG asset; writeable; None for AO assets")
      .def_readonly("lobes", &PyAsset::lobes, "spherical-Gaussian lobes per vertex (basis='sg:N'), or 0 for SH")
      .def_property_readonly("albedo", [](py::object self) -> py::object {
        PyAsset& a = self.cast<PyAsset&>();
        if (a.albedo.rows() == 0) return py::none();
        return view(a.albedo.data(), a.albedo.rows(), 3, self);
      }, "the linear albedo at each vertex, (V, 3) float64, when it is coloured; None for a grey asset")
      .def_property_readonly("channels", [](const PyAsset& a) { return a.signal == AssetSignal::Ao || a.lobes > 0 ? 1 : std::max(transfer_channels(a.transfer.cols()), 1); },
                             "1, or 3 for RGB transfer (a coloured albedo that bounced)")
      .def_property_readonly("ao", [](py::object self) -> py::object {
        const PyAsset& a = self.cast<const PyAsset&>();
        if (a.signal != AssetSignal::Ao) return py::none();
        return view(a.ao.data(), a.ao.rows(), 0, self);
      }, "ambient occlusion in [0, 1], (V,) float64; None for transfer assets")
      .def_readonly("order", &PyAsset::order)
      .def_property_readonly("signal", [](const PyAsset& a) { return std::string(asset_signal_name(a.signal)); })
      .def_readonly("metadata", &PyAsset::metadata, "the asset's (key, value) lines, in order")
      .def_readonly("stats", &PyAsset::stats, "what bake measured (counts, rays, seconds, the predicted error)")
      .def_readonly("warnings", &PyAsset::warnings)
      .def("__repr__", [](const PyAsset& a) {
        return "<prtsub.Asset " + std::string(asset_signal_name(a.signal)) + ", order " + std::to_string(a.order) + ", " +
               std::to_string(a.mesh.num_vertices()) + " vertices, " + std::to_string(a.mesh.num_faces()) + " faces>";
      });

  m.def("bake", [](py::object first, py::object faces, const py::kwargs& kw) {
        std::string source = "(in memory)";
        BakeOptions o = bake_options(kw, source);
        Mesh mesh;
        if (py::isinstance<Mesh>(first)) {
          if (!faces.is_none()) throw py::type_error("bake(mesh) takes no faces; bake(vertices, faces) builds a mesh");
          mesh = first.cast<Mesh>();
        } else {
          if (faces.is_none()) throw py::type_error("bake(vertices, faces, **options) needs faces");
          mesh = build_mesh(raw_mesh(first.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>(),
                                     faces.cast<py::array_t<int64_t, py::array::c_style | py::array::forcecast>>()),
                            source);
        }
        o.source = source;
        return bake_mesh(mesh, o);
      }, py::arg("mesh_or_vertices"), py::arg("faces") = py::none(),
      "bake(vertices, faces, **options) or bake(mesh, **options): the whole pipeline, as `prtsub bake`.\n"
      "Options: order (N or 'auto'), max_order, order_tolerance, rays, seed, threads, signal ('transfer'|'ao'), basis ('sh'|'sg:N': N\n"
      "spherical-Gaussian lobes, point values), sg_signed, fit ('point'|'average'|'lsq'), alpha,\n"
      "refine ('none'|'adaptive'|'uniform'), budget (below the input's count: simplify), levels, simplify_metric\n"
      "('transfer'|'geometry'), min_angle, lock_corners, simplify_alpha, error (target %), sample_rays, bounces (N or 'auto'), albedo (A, 'vertex', 'R,G,B' or\n"
      "(R, G, B)), albedo_map (a diffuse texture through the UVs), source.");

  m.def("load", [](const std::string& path) {
        const Asset in = read_asset(path);
        PyAsset a;
        a.mesh = asset_mesh(in);
        a.transfer = stored_values(in);  // an SG asset's lobes, as the file has them
        a.albedo = in.albedo;
        a.metadata = in.metadata;
        a.signal = in.signal;
        a.order = in.order;
        a.finish();
        return a;
      }, py::arg("path"), "Reads an asset (.ply, .glb or .gltf), checked as `prtsub inspect` checks it.");

  m.def("save", [](const PyAsset& a, const std::string& path, bool quantize, bool compress, const std::string& up) {
        GltfOptions g;
        g.quantize = quantize, g.compress = compress, g.up = parse_up_axis(up);
        if (is_gltf_path(path)) write_gltf_asset(path, a.mesh, a.transfer, a.metadata, a.signal, g, a.albedo);
        else if (quantize || compress || g.up != UpAxis::Y) throw InputError(path + ": quantize, compress and up are for .glb and .gltf assets");
        else write_asset(path, a.mesh, a.transfer, a.metadata, a.signal, a.albedo);
      }, py::arg("asset"), py::arg("path"), py::kw_only(), py::arg("quantize") = false, py::arg("compress") = false, py::arg("up") = "y",
      "Writes the asset: a PLY, or glTF 2.0 for a path ending in .glb or .gltf (docs/asset_format.md). Atomic: a failure leaves no file.");

  py::class_<PyLight>(m, "Light", "A distant light, projected into SH at the order of the asset it lights.")
      .def("__add__", [](const PyLight& a, const PyLight& b) {
        // Each side keeps its own rotation.
        PyLight sum;
        sum.terms = {[a](int order) { return a.at(order); }, [b](int order) { return b.at(order); }};
        return sum;
      })
      .def("rotated", [](const PyLight& l, const std::vector<double>& axis, double degrees) {
        PyLight r = l;
        r.rotation = Eigen::AngleAxisd(degrees * M_PI / 180, vec3(axis, "axis").normalized()).toRotationMatrix() * l.rotation;
        return r;
      }, py::arg("axis"), py::arg("degrees"), "The light after turning the world by `degrees` about `axis`.")
      .def("coefficients", [](const PyLight& l, int order) {
        const ShLight s = l.at(order);
        return py::array_t<double>({static_cast<py::ssize_t>(s.coeffs.rows()), py::ssize_t(3)}, s.coeffs.data());
      }, py::arg("order"), "The light's SH coefficients at `order`: (order², 3), RGB.");

  m.def("sg_transfer", [](const Mesh& mesh, int lobes, int rays, uint64_t seed, bool non_negative, int threads) {
        const SgBasis basis = sg_basis(lobes);
        const RayScene scene(mesh.positions, position_triangles(mesh));
        TransferOptions o;
        o.rays = rays, o.seed = seed, o.threads = threads, o.progressive.non_negative = non_negative;
        const RowMatrixX3d offsets = vertex_offset_directions(mesh);
        const RowMatrixXd c = sg_transfer(scene, vertex_positions(mesh), mesh.normals, basis, o, &offsets);
        return py::array_t<double>({static_cast<py::ssize_t>(c.rows()), static_cast<py::ssize_t>(c.cols())}, c.data());
      }, py::arg("mesh"), py::arg("lobes"), py::kw_only(), py::arg("rays") = 256, py::arg("seed") = 0, py::arg("non_negative") = true,
      py::arg("threads") = 0,
      "Transfer at the mesh's render vertices in `lobes` spherical Gaussians (docs/transfer.md): (#V, lobes), fitted to `rays` rays "
      "per vertex by the progressive least-squares encoder, non-negative unless told otherwise.");
  m.def("sg_to_sh", [](py::array_t<double, py::array::c_style | py::array::forcecast> c, int order) {
        if (c.ndim() != 2) throw InputError("sg_to_sh: coefficients must be an array of shape (P, lobes)");
        const RowMatrixXd in = Eigen::Map<const RowMatrixXd>(c.data(), c.shape(0), c.shape(1));
        const RowMatrixXd t = sg_to_sh(sg_basis(static_cast<int>(c.shape(1))), in, order);
        return py::array_t<double>({static_cast<py::ssize_t>(t.rows()), static_cast<py::ssize_t>(t.cols())}, t.data());
      }, py::arg("coefficients"), py::arg("order"),
      "Lobe coefficients (P, lobes) as SH transfer (P, order²), exact for every light of that order (Funk-Hecke).");
  m.def("sg_light", [](const PyLight& l, int lobes, int order) {
        const auto L = sg_light(sg_basis(lobes), l.at(order));
        return py::array_t<double>({static_cast<py::ssize_t>(L.rows()), py::ssize_t(3)}, L.data());
      }, py::arg("light"), py::arg("lobes"), py::arg("order") = 10,
      "What each of the `lobes` spherical Gaussians sees of the light (projected into SH at `order` first): (lobes, 3), RGB. "
      "A vertex with coefficients c shades as albedo/pi * c @ sg_light(...).");

  m.def("sky", [](const std::vector<double>& up) {
        const Eigen::Vector3d u = vec3(up, "up");
        return single([u](int order) { return default_sky(order, u.normalized()); });
      }, py::arg("up") = std::vector<double>{0, 1, 0}, "The sky of `prtsub render --light sky`.");
  m.def("sun", [](const std::vector<double>& direction, double radius_deg, const std::vector<double>& color) {
        const Eigen::Vector3d d = vec3(direction, "direction"), c = vec3(color, "color");
        if (!(d.norm() > 0)) throw InputError("sun direction must not be zero");
        return single([d, radius_deg, c](int order) { return sun_light(order, d.normalized(), radius_deg, c); });
      }, py::arg("direction"), py::arg("radius_deg") = 0.0, py::arg("color") = std::vector<double>{1, 1, 1},
      "A sun towards `direction`, irradiance π·color at normal incidence.");
  m.def("constant", [](const std::vector<double>& color) {
        const Eigen::Vector3d c = vec3(color, "color");
        return single([c](int order) { return constant_light(order, c); });
      }, py::arg("color") = std::vector<double>{1, 1, 1});
  m.def("random_light", [](uint64_t seed) { return single([seed](int order) { return random_light(order, seed); }); }, py::arg("seed"),
        "A seeded random light of unit power.");
  m.def("sh_light", [](const std::vector<double>& coefficients) {
        return single([coefficients](int order) { return coefficients_light(order, coefficients); });
      }, py::arg("coefficients"), "A light from its SH coefficients (the same in each channel).");
  m.def("environment", [](const std::string& path) {
        const Image map = read_image(path);
        return single([map](int order) { return environment_light(order, map); });
      }, py::arg("path"), "A lat-long environment map (EXR, HDR, PNG, ...), as `--light env:PATH`.");

  m.def("render", [](const PyAsset& a, const PyLight& light, std::pair<int, int> size, py::object camera, py::object albedo_arg, int threads) {
        // None: the asset's own per-vertex albedo when it has one, else 0.8.
        if (!albedo_arg.is_none() && a.albedo.rows() > 0) throw InputError("render: this asset stores its own albedo per vertex; albedo= is for grey assets");
        const double albedo = albedo_arg.is_none() ? 0.8 : albedo_arg.cast<double>();
        const auto [width, height] = size;
        if (width < 1 || height < 1 || width > 16384 || height > 16384) throw InputError("size must be 1 to 16384 pixels a side");
        const Camera cam = camera_of(camera, bounds(a.vertices), width, height);
        const ShLight sh = light.at(a.order);
        const RowMatrixXd shaded = a.lobes > 0 ? sg_to_sh(sg_basis(a.lobes), a.transfer, a.order) : a.transfer;
        auto* frame = new Image;
        {
          py::gil_scoped_release release;
          const RayScene scene(a.vertices, a.mesh.triangles);
          const SurfaceHits hits = trace_primary(scene, cam, width, height, threads);
          *frame = shade_gouraud(hits, a.mesh.triangles, a.albedo.rows() > 0 ? vertex_radiance(shaded, sh, a.albedo)
                                                                             : vertex_radiance(shaded, sh, albedo));
        }
        py::capsule owner(frame, [](void* p) { delete static_cast<Image*>(p); });
        return py::array(py::dtype::of<float>(), {frame->height, frame->width, frame->channels},
                         {static_cast<py::ssize_t>(sizeof(float)) * frame->width * frame->channels,
                          static_cast<py::ssize_t>(sizeof(float)) * frame->channels, static_cast<py::ssize_t>(sizeof(float))},
                         frame->pixels.data(), owner);
      }, py::arg("asset"), py::arg("light"), py::arg("size") = std::pair<int, int>{800, 600}, py::arg("camera") = py::none(),
      py::arg("albedo") = py::none(), py::arg("threads") = 0,
      "The Gouraud frame `prtsub render` writes: (height, width, 4) float32 linear RGBA, row 0 at the top.\n"
      "camera: None (framed automatically) or dict(eye=..., target=..., up=..., fov=degrees).");
}
