// Embree reports errors through a callback; we record the first one and throw from C++ after
// the rtc* call returns, never through Embree's C frames. Every handle is owned (EmbreeDevice,
// EmbreeScene, EmbreeGeometry), so a throw at any step releases what was made before it.
#include "prtsub/prt/ray_scene.h"

#include <cfloat>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {

struct RayScene::ErrorState {
  std::mutex mutex;
  RTCError code = RTC_ERROR_NONE;
  std::string message;
};

struct RayScene::Device {
  ErrorState errors;
  EmbreeDevice device;
};

namespace {

void on_embree_error(void* user, RTCError code, const char* message) {
  auto* state = static_cast<RayScene::ErrorState*>(user);
  std::lock_guard<std::mutex> lock(state->mutex);
  if (state->code == RTC_ERROR_NONE) {
    state->code = code;
    state->message = message ? message : "unknown";
  }
}

}  // namespace

namespace {

// The process's device: kept while any scene holds it, made again after the last one goes.
std::shared_ptr<RayScene::Device> shared_device() {
  static std::mutex mutex;
  static std::weak_ptr<RayScene::Device> current;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto d = current.lock()) return d;
  auto d = std::make_shared<RayScene::Device>();
  d->device.reset(rtcNewDevice(nullptr));
  if (!d->device) throw EmbreeError("Embree: cannot create device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(d->device.get(), on_embree_error, &d->errors);
  current = d;
  return d;
}

}  // namespace

RayScene::RayScene(const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
                   const RaySceneOptions& options) {
  if (positions.rows() == 0 || triangles.empty()) throw EmbreeError("ray scene: no triangles");
  Bounds b = bounds(positions);
  centre_ = b.centre();
  diagonal_ = b.diagonal();
  offset_ = options.relative_offset * diagonal_;

  device_ = shared_device();
  {
    std::lock_guard<std::mutex> lock(device_->errors.mutex);  // an earlier scene's error is not this one's
    device_->errors.code = RTC_ERROR_NONE;
    device_->errors.message.clear();
  }
  scene_.reset(rtcNewScene(device_->device.get()));
  check("creating the scene");
  rtcSetSceneBuildQuality(scene_.get(), RTC_BUILD_QUALITY_MEDIUM);

  const EmbreeGeometry geom(rtcNewGeometry(device_->device.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
  check("creating the geometry");
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), static_cast<size_t>(positions.rows())));
  auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), triangles.size()));
  check("allocating geometry buffers");
  if (!vb || !ib) throw EmbreeError("Embree: cannot allocate geometry buffers");
  for (Eigen::Index i = 0; i < positions.rows(); ++i) {
    Eigen::Vector3f p = to_local(positions.row(i).transpose());
    vb[3 * i] = p.x(), vb[3 * i + 1] = p.y(), vb[3 * i + 2] = p.z();
  }
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) ib[3 * f + k] = triangles[f][k];
  rtcCommitGeometry(geom.get());
  rtcAttachGeometry(scene_.get(), geom.get());
  rtcCommitScene(scene_.get());
  check("building the scene");
}

RayScene::~RayScene() = default;  // the scene first, then (if it was the last) the device

void RayScene::check(const char* what) const {
  std::lock_guard<std::mutex> lock(device_->errors.mutex);
  if (device_->errors.code != RTC_ERROR_NONE)
    throw EmbreeError(std::string("Embree error while ") + what + ": " + device_->errors.message);
}

float RayScene::ray_offset(const Eigen::Vector3f& local_point) const {
  // Float rounding of the point itself, with margin, plus a fixed fraction of the scene.
  return static_cast<float>(offset_) + 32.0f * FLT_EPSILON * local_point.cwiseAbs().maxCoeff();
}

std::vector<Triangle> position_triangles(const Mesh& mesh) {
  std::vector<Triangle> out(mesh.triangles.size());
  for (size_t f = 0; f < out.size(); ++f)
    for (int k = 0; k < 3; ++k) out[f][k] = mesh.vertex_position[mesh.triangles[f][k]];
  return out;
}

void init_occlusion_ray(RTCRay& ray, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  ray.org_x = o.x(), ray.org_y = o.y(), ray.org_z = o.z();
  ray.dir_x = d.x(), ray.dir_y = d.y(), ray.dir_z = d.z();
  ray.tnear = 0.0f;
  ray.tfar = std::numeric_limits<float>::infinity();
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
}

}  // namespace prtsub
