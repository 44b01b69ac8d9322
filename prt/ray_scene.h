// The Embree scene every ray query goes through. Built once per mesh and shared by many
// calls (transfer, refinement, the fit's samples, rendering, evaluation and benchmarks).
#pragma once

#include <embree3/rtcore.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "prtsub/subdiv/mesh.h"

namespace prtsub {

struct RaySceneOptions {
  //! Ray origins move off the surface by this fraction of the scene's bounding-box diagonal
  //! (plus the float rounding of the point's local coordinates).
  double relative_offset = 4e-6;
};

//! Owners of Embree's reference-counted handles: each releases its reference when it goes, so a
//! constructor that throws half-way leaks nothing.
struct EmbreeRelease {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
  void operator()(RTCGeometry g) const { rtcReleaseGeometry(g); }
};
using EmbreeDevice = std::unique_ptr<RTCDeviceTy, EmbreeRelease>;
using EmbreeScene = std::unique_ptr<RTCSceneTy, EmbreeRelease>;
using EmbreeGeometry = std::unique_ptr<RTCGeometryTy, EmbreeRelease>;

//! A committed Embree triangle scene in local coordinates: the bounding box's centre is
//! subtracted in double before converting to float, so a scene far from the origin keeps its
//! full float precision. Every scene of the process is built on one Embree device (made with the
//! first scene, released with the last), so a batch of bakes pays for the device once; Embree's
//! errors are recorded per device, so check() reports the first error since this scene was made.
class RayScene {
 public:
  //! \param positions #P by 3
  //! \param triangles #F triangles indexing positions
  //! \throw EmbreeError if Embree fails (the message carries Embree's own)
  RayScene(const RowMatrixX3d& positions, const std::vector<Triangle>& triangles,
           const RaySceneOptions& options = {});
  ~RayScene();  // the scene before the device: members go in reverse order
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  RTCScene handle() const { return scene_.get(); }
  //! World point to the scene's local (float) frame.
  Eigen::Vector3f to_local(const Eigen::Vector3d& p) const { return (p - centre_).cast<float>(); }
  //! Distance a ray origin is pushed along the normal, in local units.
  float ray_offset(const Eigen::Vector3f& local_point) const;
  double diagonal() const { return diagonal_; }
  //! Throws EmbreeError if Embree recorded an error since the last check.
  void check(const char* what) const;

  struct ErrorState;  //!< what Embree's error callback recorded
  struct Device;      //!< the process's one Embree device and its error state

 private:
  std::shared_ptr<Device> device_;  // shared by every scene: a batch of bakes makes one device
  EmbreeScene scene_;
  Eigen::Vector3d centre_;
  double diagonal_ = 0;
  double offset_ = 0;
};

//! Triangles of a mesh with corners mapped from render vertices to positions.
std::vector<Triangle> position_triangles(const Mesh& mesh);

//! A ray of an occlusion query: origin, direction, and maximum length; occluded after the
//! query when tfar is -inf. Fields are set so Embree never ignores the ray (mask all ones).
void init_occlusion_ray(RTCRay& ray, const Eigen::Vector3f& origin, const Eigen::Vector3f& direction);

}  // namespace prtsub
