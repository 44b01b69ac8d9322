#include "cli/images.h"
#include "cli/specs.h"

#include <cmath>
#include <sstream>


namespace prtsub {
namespace {

std::vector<double> split_numbers(const std::string& s, const std::string& what) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(v))
      throw UsageError(what + ": expected numbers separated by commas, got '" + s + "'");
    out.push_back(v);
  }
  if (out.empty()) throw UsageError(what + ": expected numbers separated by commas, got nothing");
  return out;
}

Eigen::Vector3d vec3(const std::string& s, const std::string& what) {
  const std::vector<double> v = split_numbers(s, what);
  if (v.size() != 3) throw UsageError(what + ": expected three numbers, got '" + s + "'");
  return {v[0], v[1], v[2]};
}

}  // namespace

ShLight parse_light(const std::string& spec, int order, const std::string& option) {
  const size_t colon = spec.find(':');
  const std::string kind = spec.substr(0, colon), arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  const std::string what = option + " " + spec;
  if (kind == "env") {
    if (arg.empty()) throw UsageError(what + ": expected env:PATH");
    return environment_light(order, cli_read_image(arg));
  }
  if (kind == "sh") {
    const std::vector<double> c = split_numbers(arg, what);
    if (c.size() > static_cast<size_t>(order) * static_cast<size_t>(order))
      throw UsageError(what + ": " + std::to_string(c.size()) + " coefficients for order " + std::to_string(order));
    return coefficients_light(order, c);
  }
  if (kind == "sun") {
    std::vector<double> v = split_numbers(arg, what);
    if (v.size() != 3 && v.size() != 4) throw UsageError(what + ": expected sun:X,Y,Z[,RADIUS_DEG]");
    if (!(Eigen::Vector3d(v[0], v[1], v[2]).norm() > 0)) throw UsageError(what + ": the direction must be non-zero");
    if (v.size() == 4 && !(v[3] >= 0 && v[3] < 90)) throw UsageError(what + ": the radius must be in [0, 90) degrees");
    return sun_light(order, Eigen::Vector3d(v[0], v[1], v[2]), v.size() == 4 ? v[3] : 0.5);
  }
  if (kind == "sky") {
    if (arg.empty()) return default_sky(order);
    const Eigen::Vector3d up = vec3(arg, what);
    if (!(up.norm() > 0)) throw UsageError(what + ": expected sky or sky:X,Y,Z (a non-zero up)");
    return default_sky(order, up.normalized());
  }
  if (kind == "random") {
    std::vector<double> v = split_numbers(arg, what);
    if (v.size() != 1 || v[0] < 0 || v[0] != std::floor(v[0]) || v[0] > 9.007199254740992e15)
      throw UsageError(what + ": expected random:SEED (a non-negative integer)");
    return random_light(order, static_cast<uint64_t>(v[0]));
  }
  if (kind == "const") {
    std::vector<double> v = split_numbers(arg, what);
    if (v.size() == 1) v = {v[0], v[0], v[0]};
    if (v.size() != 3) throw UsageError(what + ": expected const:V or const:R,G,B");
    return constant_light(order, Eigen::Vector3d(v[0], v[1], v[2]));
  }
  throw UsageError(what + ": unknown light kind '" + kind + "' (env, sh, sun, sky, random, const)");
}

ShLight parse_lights(const std::vector<std::string>& specs, int order, const std::string& option) {
  ShLight light = parse_light(specs.at(0), order, option);
  for (size_t i = 1; i < specs.size(); ++i) light += parse_light(specs[i], order, option);
  return light;
}

Eigen::Matrix3d parse_rotation(const std::string& spec, const std::string& option) {
  const size_t last = spec.rfind(',');
  if (last == std::string::npos) throw UsageError(option + ": expected AXIS,DEG, got '" + spec + "'");
  const std::string axis_s = spec.substr(0, last);
  const std::vector<double> deg = split_numbers(spec.substr(last + 1), option);
  if (deg.size() != 1) throw UsageError(option + ": expected AXIS,DEG, got '" + spec + "'");
  Eigen::Vector3d axis;
  if (axis_s == "x" || axis_s == "X") axis = Eigen::Vector3d::UnitX();
  else if (axis_s == "y" || axis_s == "Y") axis = Eigen::Vector3d::UnitY();
  else if (axis_s == "z" || axis_s == "Z") axis = Eigen::Vector3d::UnitZ();
  else {
    std::vector<double> v = split_numbers(axis_s, option);
    if (v.size() != 3) throw UsageError(option + ": AXIS is x, y, z or X,Y,Z; got '" + axis_s + "'");
    axis = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (!(axis.norm() > 0)) throw UsageError(option + ": the axis must be non-zero");
  return Eigen::AngleAxisd(deg[0] * M_PI / 180, axis.normalized()).toRotationMatrix();
}

Camera parse_camera(const std::string& spec, const std::string& option) {
  Camera cam;
  bool has_eye = false, has_target = false;
  std::stringstream ss(spec);
  std::string part;
  while (std::getline(ss, part, ':')) {
    const size_t eq = part.find('=');
    if (eq == std::string::npos) throw UsageError(option + ": expected key=value, got '" + part + "'");
    const std::string key = part.substr(0, eq), value = part.substr(eq + 1), what = option + " " + key;
    if (key == "eye") cam.eye = vec3(value, what), has_eye = true;
    else if (key == "target") cam.target = vec3(value, what), has_target = true;
    else if (key == "up") cam.up = vec3(value, what);
    else if (key == "fov") {
      const std::vector<double> v = split_numbers(value, what);
      if (v.size() != 1 || !(v[0] > 0 && v[0] < 180)) throw UsageError(what + ": must be between 0 and 180 degrees, got '" + value + "'");
      cam.fov_deg = v[0];
    } else {
      throw UsageError(option + ": unknown key '" + key + "' (eye, target, up, fov)");
    }
  }
  if (!has_eye || !has_target) throw UsageError(option + ": needs eye=X,Y,Z and target=X,Y,Z (or 'auto')");
  try {
    check_camera(cam);
  } catch (const InputError& e) {
    throw UsageError(option + ": " + e.what());
  }
  return cam;
}

}  // namespace prtsub
