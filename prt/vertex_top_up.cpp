// A second round of vertex rays, spent by noise (issue 11: rays per vertex are chosen, not fixed).
//
// The error to lower is the surface's, so vertex i's variance counts with the area w_i it
// interpolates over (a third of its faces'): minimise Σ w_i c_i/(R + e_i), giving R + e_i = λ√(w_i c_i).
//
// After the first round every vertex has an estimate x_i from R rays and its variance v_i (from
// the estimator's two independent halves), so its per-ray variance is c_i = R·v_i. With e_i more
// rays the merged estimate (R·x_i + e_i·x'_i)/(R + e_i) has variance c_i/(R + e_i); the e_i ≥ 0
// that minimise Σ c_i/(R + e_i) for a budget Σ e_i = B are R + e_i = λ√c_i wherever that exceeds
// R (water-filling; Neyman's allocation with the first round already paid). The cosine-lattice control variate makes an unoccluded vertex
// exact (c_i = 0), so open surfaces get nothing and penumbrae get the most: on a scan a third to
// a half of the vertices see the whole sky.
//
// Counts are rounded to 16·2^(k/4) and traced one bucket per count, each with its own seed, so
// the result is a function of the plan, which is a function of the first round: not of threads.
#include "prtsub/prt/vertex_top_up.h"

#include <algorithm>
#include <cmath>

#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

namespace {
constexpr int kLevels = 48;  // 16·2^(k/4) rays: 16 to about 64k
int level_rays(int k) { return static_cast<int>(std::lround(16 * std::exp2(k / 4.0))); }
}  // namespace

TopUpPlan plan_top_up(const std::vector<double>& variance, const std::vector<double>& rays, uint64_t budget,
                      const std::vector<double>& weight, double max_rays) {
  const size_t V = variance.size();
  if (!weight.empty() && weight.size() != V) throw InputError("top-up: one weight per vertex expected");
  if (rays.size() != V) throw InputError("top-up: one ray count per vertex expected");
  TopUpPlan plan;
  plan.level.assign(V, -1);
  std::vector<double> spread(V, 0.0);  // √c_i, the per-ray standard deviation
  double total = 0;
  for (size_t i = 0; i < V; ++i) {
    const double w = weight.empty() ? 1.0 : weight[i];
    if (rays[i] >= 2 && std::isfinite(variance[i]) && variance[i] > 0 && w > 0 && std::isfinite(w))
      spread[i] = std::sqrt(w * variance[i] * rays[i]);
    total += spread[i];
  }
  if (!(total > 0) || budget == 0) return plan;
  // Water-filling: R_i + e_i = λ√c_i where that exceeds R_i (up to max_rays in all), with λ set by
  // bisection so that Σ e_i meets the budget. Counts are then rounded to the nearest of
  // 16·2^(k/4) in log space, so a few buckets carry everything and the total stays close to the
  // budget.
  auto extra = [&](double lambda, size_t i) {
    return spread[i] > 0 ? std::clamp(lambda * spread[i] - rays[i], 0.0, std::max(0.0, max_rays - rays[i])) : 0.0;
  };
  auto spent = [&](double lambda) {
    double sum = 0;
    for (size_t i = 0; i < V; ++i) sum += extra(lambda, i);
    return sum;
  };
  double lo = 0, hi = 1;
  while (spent(hi) < static_cast<double>(budget) && hi < 1e30) hi *= 2;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (spent(mid) < static_cast<double>(budget) ? lo : hi) = mid;
  }
  for (size_t i = 0; i < V; ++i) {
    const double e = extra(lo, i);
    if (e < 16 / std::sqrt(std::sqrt(2.0))) continue;
    plan.level[i] = std::clamp(static_cast<int>(std::lround(4 * std::log2(e / 16))), 0, kLevels - 1);
    ++plan.vertices;
    plan.rays += static_cast<uint64_t>(level_rays(plan.level[i]));
  }
  return plan;
}

double planned_variance(const TopUpPlan& plan, const std::vector<double>& variance, const std::vector<double>& rays,
                        const std::vector<double>& weight) {
  double sum = 0;
  for (size_t i = 0; i < variance.size(); ++i) {
    if (!std::isfinite(variance[i])) continue;
    const double w = weight.empty() ? 1.0 : weight[i], e = plan.level[i] < 0 ? 0.0 : level_rays(plan.level[i]);
    sum += w * variance[i] * rays[i] / (rays[i] + e);
  }
  return sum;
}

TopUpStats apply_top_up(const Mesh& mesh, const RayScene& scene, const TransferOptions& options, const TopUpPlan& plan,
                        RowMatrixXd& values, std::vector<double>& variance, std::vector<double>& rays, const ProgressFn& progress) {
  const size_t V = mesh.num_vertices();
  if (static_cast<size_t>(values.rows()) != V || variance.size() != V || plan.level.size() != V || rays.size() != V)
    throw InputError("top-up: values, variances and the plan need one row per vertex");
  const Stopwatch clock;
  TopUpStats stats;
  stats.histogram.assign(kLevels + 1, 0);
  for (size_t i = 0; i < V; ++i) {
    stats.variance_before += std::isfinite(variance[i]) ? variance[i] : 0;
    ++stats.histogram[size_t(plan.level[i] + 1)];
  }
  const Eigen::Index K = values.cols();
  const RowMatrixX3d offsets = vertex_offset_directions(mesh), positions = vertex_positions(mesh);
  for (int k = 0; k < kLevels; ++k) {
    std::vector<size_t> members;
    for (size_t i = 0; i < V; ++i)
      if (plan.level[i] == k) members.push_back(i);
    if (members.empty()) continue;
    const auto n = static_cast<Eigen::Index>(members.size());
    RowMatrixX3d p(n, 3), nrm(n, 3), off(n, 3);
    for (Eigen::Index j = 0; j < n; ++j) {
      const auto i = static_cast<Eigen::Index>(members[size_t(j)]);
      p.row(j) = positions.row(i), nrm.row(j) = mesh.normals.row(i), off.row(j) = offsets.row(i);
    }
    TransferOptions o = options;
    o.rays = level_rays(k);
    o.seed = mix64(options.seed ^ (0x7095ull + uint64_t(k)));
    o.stream_offset = 0;
    TransferStats ts;
    std::vector<double> v2;
    const RowMatrixXd x2 = shadowed_transfer(scene, p, nrm, o, &ts, progress, &off, &v2);
    if (x2.cols() != K) throw InputError("top-up: the order does not match the values");
    stats.rays += ts.rays;
    stats.vertices += members.size();
    for (Eigen::Index j = 0; j < n; ++j) {
      const size_t i = members[size_t(j)];
      const auto r = static_cast<Eigen::Index>(i);
      const double r1 = rays[i], r2 = o.rays, sum = r1 + r2;
      rays[i] = sum;
      values.row(r) = (r1 * values.row(r) + r2 * x2.row(j)) / sum;
      variance[i] = (r1 * r1 * variance[i] + r2 * r2 * v2[size_t(j)]) / (sum * sum);
    }
  }
  for (size_t i = 0; i < V; ++i) stats.variance_after += std::isfinite(variance[i]) ? variance[i] : 0;
  stats.seconds = clock.total();
  return stats;
}

std::vector<double> vertex_areas(const Mesh& mesh) {
  std::vector<double> a(mesh.num_vertices(), 0.0);
  for (const Triangle& t : mesh.triangles) {
    const double area = triangle_area(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]));
    if (std::isfinite(area))
      for (int c = 0; c < 3; ++c) a[t[c]] += area / 3;
  }
  return a;
}

TopUpStats top_up_vertices(const Mesh& mesh, const RayScene& scene, const TransferOptions& options, int rays_done,
                           uint64_t budget, RowMatrixXd& values, std::vector<double>& variance, const ProgressFn& progress) {
  if (variance.size() != mesh.num_vertices()) throw InputError("top-up: values and variances need one row per vertex");
  std::vector<double> rays(variance.size(), rays_done);
  return apply_top_up(mesh, scene, options, plan_top_up(variance, rays, budget, vertex_areas(mesh), 17.0 * rays_done), values,
                      variance, rays, progress);
}

}  // namespace prtsub
