// The pilot pass that decides where the fit's samples go (Kavan et al. 2011, section 4.1,
// classify faces by how well interpolation reproduces them; issue 11).
//
// The fit can only improve on the vertex values where the signal inside a face is not what
// their linear interpolant says: a shadow edge or a contact shadow crossing a face. On a dense
// scan that is a few faces in a hundred, and sampling every face spends most of a bake's rays
// on faces the interpolant already reproduces. So we first trace a few samples per face
// (`per_triangle`, spread by area) and compare each with the prior interpolated at it:
//
//   r = f̂(p) − Σ_c h_c(p) x̂_c,   E‖r‖² = ‖β(p)‖² + v,   v = var f̂(p) + Σ_c h_c² var x̂_c,
//
// β the interpolation error and v the two estimates' noise, both measured (the transfer
// estimator's two ray halves). d = ‖r‖² − v is an unbiased estimate of ‖β‖², with a standard
// deviation of about √2·v. One sample says little, so each face pools the samples of the faces
// within `rings` vertex rings of its face (each sample once): the face needs samples when Σd
// exceeds `significance` standard errors, √(2Σv²). A face that does not is left to
// interpolation (no samples; the fit uses the prior's interpolant as its data). Among the
// sampled faces the density follows area_share·1 + (1 − area_share)·√ē_f / mean, ē_f the mean
// excess over the faces sharing a corner with f (a tighter pool than the test's): Neyman's
// allocation by the estimated error, mixed with a uniform share so a face whose pilot missed a
// shadow still gets its samples.
//
// A screen comes first: up to 65,536 of the hold-out samples (below), spread over the surface,
// traced and compared as above. Their area-weighted mean excess Σw·d, over the interpolated vertex
// noise Σw·Σh²·var x̂ at the same points, says whether the signal varies inside the faces by more
// than the vertices' own noise. Below 1 (the dense scans: 0.18–2.6 on the shared scenes, every
// other mesh 13 or more), faces the test could single out are too few to pay for the pilot, let
// alone the fit's samples (armadillo's AO lost 3% to point sampling at equal rays with them): the
// pilot stops, no face is sampled, the screen's samples are the hold-out, and the sample rays go
// to the vertices. Otherwise the pilot goes on as if the screen had not been: each sample's rays
// are its own, so the plan is the same to the bit.
//
// In two stages (the default), half the pilot samples (every other, by index: spread over the
// faces in order) are traced first and every face is tested on them at a lower bar (one standard
// error); only the faces that pass it, or whose pool holds no first-stage sample, have the rest of
// their samples traced and face the full test. On a dense scan, where interpolation serves almost
// every face, the pilot then costs little more than its first half.
//
// When the fit projects the unshadowed transfer's curvature exactly (exact_unshadowed), what is
// compared is what is left after that known part, w(p)·t_u(n(p)) (w the vertices' open shares,
// interpolated): r = f̂(p) − w(p)·t_u(n(p)) − Σ_c h_c(p)(x̂_c − w_c·t_u(n_c)). A face is then sampled
// for a shadow inside it, not for curvature the projection handles with no rays.
//
// The pilot also measures what the rays per fit sample are chosen from (sample_ray_choices;
// choose_sample_rays decides, given the budget). With B sample rays on a face, Q rays per sample
// give n = B/Q samples, and a face moment's error is about ‖β‖²/n² + σ²(Q)/n: the variation of
// the signal about the interpolant, which the face's lattice of samples averages out, and each
// sample's own noise, independent from sample to sample. Both are measured, not modelled: ‖β‖²
// is the mean excess d on the sampled faces, and σ²(Q) the mean of ½‖a − b‖² over a subset of the
// samples on the faces in question, each traced twice at Q with independent seeds. (The cosine
// lattice's noise is no power law of Q: on the shared scenes it falls 3.6–16x from 4 to 16 rays
// and 1.9–4.2x from 16 to 32.) A shadow across large faces (conference: ‖β‖² 140x σ²(16)) takes
// 4 rays and four times the samples; a smooth scan's noise-dominated faces take 32.
//
// The pilot's own samples are not reused in the fit: its allocation would depend on their
// values, and the fit's moments would no longer be unbiased.
#include "prtsub/prt/sample_plan.h"

#include <algorithm>
#include <cstdint>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>

#include "prtsub/prt/parallel.h"
#include "prtsub/prt/sh.h"
#include "prtsub/prt/trace_log.h"
#include "prtsub/prt/unshadowed_projection.h"
#include "prtsub/subdiv/adjacency.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/random.h"
#include "prtsub/subdiv/stopwatch.h"

namespace prtsub {

SampleAllocation parse_sample_allocation(const std::string& name) {
  if (name == "area") return SampleAllocation::Area;
  if (name == "pilot") return SampleAllocation::Pilot;
  throw InputError("unknown sample allocation '" + name + "' (area, pilot)");
}

const char* sample_allocation_name(SampleAllocation a) { return a == SampleAllocation::Area ? "area" : "pilot"; }

SurfaceSamples make_pilot_samples(const Mesh& mesh, const PilotOptions& o, uint64_t seed) {
  if (!(o.per_triangle > 0) || !std::isfinite(o.per_triangle)) throw InputError("sample plan: pilot samples must be positive");
  SampleOptions so;
  const double F = static_cast<double>(std::max<size_t>(mesh.num_faces(), 1));
  so.per_triangle = std::max(o.per_triangle, static_cast<double>(o.min_samples) / F);
  so.min_per_triangle = so.per_triangle >= 1 ? 1 : 0;  // below one per face: by area, and the pools cover the rest
  so.seed = seed;
  return make_surface_samples(mesh, so);
}

void choose_sample_rays(SampleRaysChoice& c, double face_rays, int given, double keep) {
  if (c.choices.empty() || c.noise.size() != c.choices.size()) throw InputError("sample rays: one measured noise per candidate is needed");
  if (!(face_rays > 0) || !std::isfinite(face_rays)) throw InputError("sample rays: the rays per sampled face must be positive");
  c.cost.assign(c.choices.size(), 0.0);
  double least = INFINITY;
  for (size_t i = 0; i < c.choices.size(); ++i) {
    const double n = face_rays / double(c.choices[i]);
    c.cost[i] = std::max(c.variation, 0.0) / (n * n) + c.noise[i] / n;
    if (c.cost[i] < least) least = c.cost[i], c.rays = c.choices[i];
  }
  for (size_t i = 0; i < c.choices.size(); ++i)
    if (c.choices[i] == given && !(least < keep * c.cost[i])) c.rays = given;
}

SamplePlan plan_samples(const Mesh& mesh, const RayScene& scene, const SurfaceSamples& pilot, const RowMatrixXd& prior,
                        const std::vector<double>& prior_variance, const TransferOptions& rays,
                        const PilotOptions& o, const ProgressFn& progress) {
  const size_t V = mesh.num_vertices(), F = mesh.num_faces();
  if (static_cast<size_t>(prior.rows()) != V || prior_variance.size() != V)
    throw InputError("sample plan: the prior and its variance need one row per vertex");
  TransferOptions to = rays;
  to.rays = o.rays;
  if (to.rays < 2) throw InputError("sample plan: the pilot needs at least 2 rays per sample for a variance");
  if (!(o.significance >= 0) || !(o.area_share >= 0 && o.area_share <= 1))
    throw InputError("sample plan: the significance must be non-negative and the area share in [0, 1]");
  if (pilot.begin.size() != F + 1) throw InputError("sample plan: the pilot samples were drawn on another mesh");
  const Stopwatch clock;
  const size_t S = pilot.size();
  const Eigen::Index K = prior.cols();
  if (rays.order * rays.order != K) throw InputError("sample plan: the prior's columns do not match the SH order");
  // Compared: what is left after the known part w·t_u (the fit's), when the fit projects it exactly.
  const std::vector<double> open = o.exact_unshadowed ? open_share(prior) : std::vector<double>();
  RowMatrixXd residual_prior;
  if (o.exact_unshadowed) {
    residual_prior = unshadowed_at(mesh.normals, rays.order);
    for (Eigen::Index i = 0; i < residual_prior.rows(); ++i) residual_prior.row(i) *= -open[static_cast<size_t>(i)];
    residual_prior += prior;
  }
  const RowMatrixXd& compared = o.exact_unshadowed ? residual_prior : prior;

  // The samples of the first stage: every one, or a systematic share of them (by index, so
  // spread over the faces in order) when the pilot runs in two stages.
  const bool two_stages = o.first_share > 0 && o.first_share < 1;
  std::vector<char> traced(S, 0);
  std::vector<size_t> first;
  first.reserve(two_stages ? size_t(double(S) * o.first_share) + 1 : S);
  for (size_t k = 0; k < S; ++k)
    if (!two_stages || std::floor(double(k + 1) * o.first_share) > std::floor(double(k) * o.first_share)) first.push_back(k);

  // Each traced sample's excess d = ‖r‖² − v and noise v. A stage traces its samples in groups
  // of 64, each with its own stream (its index), so a sample's rays do not depend on the stage.
  std::vector<double> excess(S, 0.0), noise(S, 0.0), vertex_noise(S, 0.0);
  TransferStats stats;
  SamplePlan plan;
  // The hold-out: every stride-th sample of the first stage, which covers the whole surface.
  const size_t stride = o.holdout > 0 ? std::max<size_t>(1, (first.size() + o.holdout - 1) / o.holdout) : 0;
  Holdout& held = plan.holdout;
  const size_t n_held = stride > 0 ? (first.size() + stride - 1) / stride : 0;
  held.face.resize(n_held), held.weight.resize(n_held), held.variance.resize(n_held);
  held.barycentric.resize(static_cast<Eigen::Index>(n_held), 3);
  held.values.resize(static_cast<Eigen::Index>(n_held), K);
  held.rays = to.rays;
  std::vector<size_t> slot(S, SIZE_MAX);  // each held-out sample's row
  for (size_t h = 0; h < n_held; ++h) slot[first[h * stride]] = h;
  // The pilot samples `which`: their points, normals and offsets, row by row.
  auto gather = [&](const std::vector<size_t>& which, RowMatrixX3d& points, RowMatrixX3d& normals, RowMatrixX3d& offsets) {
    const auto n = static_cast<Eigen::Index>(which.size());
    points.resize(n, 3), normals.resize(n, 3), offsets.resize(n, 3);
    for (Eigen::Index j = 0; j < n; ++j) {
      const auto k = static_cast<Eigen::Index>(which[size_t(j)]);
      points.row(j) = pilot.points.row(k), normals.row(j) = pilot.normals.row(k), offsets.row(j) = pilot.offsets.row(k);
    }
  };
  auto trace = [&](const std::vector<size_t>& which) {
    const size_t n = which.size();
    if (n == 0) return;
    const bool all = n == S;  // one stage: the pilot's own arrays and streams, no copies
    RowMatrixX3d points, normals, offsets;
    std::vector<uint64_t> streams;
    if (!all) gather(which, points, normals, offsets), streams.resize(n);
    for (size_t j = 0; j < n; ++j) {
      traced[which[j]] = 1;
      if (!all) streams[j] = to.stream_offset + which[j];
    }
    std::vector<size_t> group_begin;
    for (size_t j = 0; j < n; j += 64) group_begin.push_back(j);
    group_begin.push_back(n);
    TransferOptions stage = to;
    if (!all) stage.streams = &streams;
    TransferStats stage_stats;
    shadowed_transfer_groups(
        scene, all ? pilot.points : points, all ? pilot.normals : normals, group_begin, stage,
        [&](size_t g, const double* values, const double* variance, size_t rows) {
          Eigen::VectorXd r(K), known(K);
          for (size_t i = 0; i < rows; ++i) {
            const size_t j = group_begin[g] + i, k = which[j];
            if (slot[k] != SIZE_MAX) {  // rows of distinct samples: no two threads share one
              const auto h = static_cast<Eigen::Index>(slot[k]);
              held.face[size_t(h)] = pilot.face[k], held.weight[size_t(h)] = pilot.weight[k], held.variance[size_t(h)] = variance[i];
              held.barycentric.row(h) = pilot.barycentric.row(static_cast<Eigen::Index>(k));
              for (Eigen::Index q = 0; q < K; ++q) held.values(h, q) = static_cast<float>(values[i * size_t(K) + size_t(q)]);
            }
            const Triangle& t = mesh.triangles[pilot.face[k]];
            double v = variance[i], vn = 0;
            for (Eigen::Index q = 0; q < K; ++q) r[q] = values[i * size_t(K) + size_t(q)];
            if (o.exact_unshadowed) {
              const auto kk = static_cast<Eigen::Index>(k);
              unshadowed_transfer(rays.order, pilot.normals.row(kk).transpose(), known.data());
              r -= (pilot.barycentric(kk, 0) * open[t[0]] + pilot.barycentric(kk, 1) * open[t[1]] + pilot.barycentric(kk, 2) * open[t[2]]) * known;
            }
            for (int c = 0; c < 3; ++c) {
              const double h = pilot.barycentric(static_cast<Eigen::Index>(k), c);
              r -= h * compared.row(t[c]).transpose();
              vn += h * h * prior_variance[t[c]];
            }
            v += vn;
            noise[k] = v, vertex_noise[k] = vn;
            excess[k] = r.squaredNorm() - v;
          }
        },
        &stage_stats, progress, all ? &pilot.offsets : &offsets);
    stats.rays += stage_stats.rays;
  };
  // The noise of a fit sample at each candidate ray count: a systematic subset of the samples
  // traced on faces still in question once the last stage is traced (`in_question`), each traced
  // twice at Q with seeds of their own, in that stage's phase (a sharded bake gathers them with it).
  const std::vector<int>& choices = o.sample_ray_choices;
  for (int q : choices)
    if (q < 1) throw InputError("sample plan: rays per sample must be positive");
  std::vector<size_t> measured;
  std::vector<RowMatrixXd> twice;  // per candidate, its two traces
  auto measure = [&](const std::vector<char>& in_question) {
    std::vector<size_t> which;
    for (size_t k = 0; k < S; ++k)
      if (traced[k] && in_question[pilot.face[k]]) which.push_back(k);
    // At most an eighth of the pilot's own rays, and not at all on fewer than 64 points (on a
    // small mesh, where it would cost more than the choice can gain: the caller's count stands).
    uint64_t per_point = 0;
    for (int q : choices) per_point += 2 * uint64_t(q);
    const uint64_t pilot_rays = uint64_t(std::count(traced.begin(), traced.end(), 1)) * uint64_t(to.rays);  // (not stats: a shard counts its slice)
    const size_t count = std::min<size_t>({o.noise_points, which.size(), per_point ? size_t(pilot_rays / (8 * per_point)) : 0});
    if (choices.empty() || count < 64) return;
    const size_t step = std::max<size_t>(1, (which.size() + count - 1) / count);
    for (size_t j = 0; j < which.size(); j += step) measured.push_back(which[j]);
    RowMatrixX3d points, normals, offsets;
    gather(measured, points, normals, offsets);
    for (size_t c = 0; c < choices.size(); ++c)
      for (uint64_t t = 0; t < 2; ++t) {
        TransferOptions m = to;
        m.rays = choices[c], m.stream_offset = 0, m.streams = nullptr;
        m.seed = mix64(mix64(to.seed ^ 0x0153C0DEull) + 2 * uint64_t(c) + t);
        TransferStats st;
        twice.push_back(shadowed_transfer(scene, points, normals, m, &st, {}, &offsets));
        plan.sample_rays.rays_traced += st.rays, stats.rays += st.rays;
      }
  };
  // The screen (PilotOptions::screen_ratio): a spread share of the hold-out, traced first.
  if (o.screen_ratio > 0 && n_held > 0) {
    const size_t step = std::max<size_t>(1, (n_held + o.screen_samples - 1) / std::max<size_t>(o.screen_samples, 1));
    std::vector<size_t> screen;
    for (size_t h = 0; h < n_held; h += step) screen.push_back(first[h * stride]);
    trace(screen);
    if (to.log) to.log->barrier(false);  // a sharded bake: the decision reads the screen
    // The ratio of two area-weighted sums over the screen, and its standard error (delta method).
    double sd = 0, sv = 0;
    for (size_t k : screen)
      if (std::isfinite(excess[k]) && std::isfinite(vertex_noise[k])) sd += pilot.weight[k] * excess[k], sv += pilot.weight[k] * vertex_noise[k];
    plan.screen_samples = screen.size();
    plan.screen_ratio = sv > 0 ? sd / sv : INFINITY;
    double e2 = 0;
    if (sv > 0)
      for (size_t k : screen)
        if (std::isfinite(excess[k]) && std::isfinite(vertex_noise[k])) {
          const double e = pilot.weight[k] * (excess[k] - plan.screen_ratio * vertex_noise[k]);
          e2 += e * e;
        }
    plan.screen_standard_error = sv > 0 ? std::sqrt(e2) / sv : 0;
    if (sv > 0 && plan.screen_ratio < o.screen_ratio) {
      plan.screened_out = true;
      Holdout kept;  // the screen's rows of the hold-out, in order
      kept.rays = held.rays;
      kept.face.reserve(screen.size()), kept.weight.reserve(screen.size()), kept.variance.reserve(screen.size());
      kept.barycentric.resize(static_cast<Eigen::Index>(screen.size()), 3);
      kept.values.resize(static_cast<Eigen::Index>(screen.size()), K);
      for (size_t j = 0; j < screen.size(); ++j) {
        const size_t h = j * step;
        kept.face.push_back(held.face[h]), kept.weight.push_back(held.weight[h]), kept.variance.push_back(held.variance[h]);
        kept.barycentric.row(static_cast<Eigen::Index>(j)) = held.barycentric.row(static_cast<Eigen::Index>(h));
        kept.values.row(static_cast<Eigen::Index>(j)) = held.values.row(static_cast<Eigen::Index>(h));
      }
      held = std::move(kept);
      // The phases a sharded bake counts on pass with nothing traced in them.
      if (to.log) to.log->barrier(false);
      if (to.log && two_stages) to.log->barrier(false);
      if (progress) progress(S - screen.size());
      plan.face_weight.assign(F, 0.0);
      plan.pilot_drawn = S;
      plan.pilot_samples = screen.size();
      plan.rays = stats.rays;
      plan.seconds = clock.total();
      return plan;
    }
  }
  {
    std::vector<size_t> rest;  // the first stage, but for the screen's samples
    rest.reserve(first.size());
    for (size_t k : first)
      if (!traced[k]) rest.push_back(k);
    trace(rest);
  }
  if (!two_stages) measure(std::vector<char>(F, 1));
  if (to.log) to.log->barrier(false);  // a sharded bake: what follows reads the first stage

  // Per face: the sums of its traced samples' excess and squared noise.
  std::vector<double> face_sum(F, 0.0), face_v2(F, 0.0);
  std::vector<size_t> face_count(F, 0);
  std::vector<char> unknown(F, 0);  // a noise we could not estimate: sample to be safe
  auto sum_faces = [&]() {
    std::fill(face_sum.begin(), face_sum.end(), 0.0), std::fill(face_v2.begin(), face_v2.end(), 0.0);
    std::fill(face_count.begin(), face_count.end(), size_t(0)), std::fill(unknown.begin(), unknown.end(), 0);
    for (size_t k = 0; k < S; ++k) {
      if (!traced[k]) continue;
      const size_t f = pilot.face[k];
      if (!std::isfinite(noise[k]) || !std::isfinite(excess[k])) {
        unknown[f] = 1;
        continue;
      }
      face_sum[f] += excess[k], face_v2[f] += noise[k] * noise[k], ++face_count[f];
    }
  };
  sum_faces();
  // Rounding: an exact estimate (an open point, whose transfer the control variate makes exact)
  // leaves residuals of ~1e-16 and no noise to weigh them against.
  double typical = 0;
  for (Eigen::Index i = 0; i < prior.rows(); ++i) typical += prior.row(i).squaredNorm();
  const double rounding = 1e-20 * typical / static_cast<double>(std::max<size_t>(V, 1));

  // Each face pools the faces within `rings` vertex rings of it, each sample once, so the pooled
  // sum's noise is √(2Σv²) exactly as for one face.
  const Buckets corners = vertex_corners(mesh.triangles, V);
  struct Pool {
    double sum = 0, v2 = 0, n = 0, sum1 = 0, n1 = 0;  // sum1, n1: the first ring's, for the density
    bool unsure = false;
  };
  // Pools are independent: faces in parallel, each worker with its own marks (tagged by pass and
  // face, so that the second pass starts clean), each pool summed in its own fixed order.
  struct Marks {
    std::vector<size_t> face, vertex, ring, next;
  };
  tbb::enumerable_thread_specific<Marks> marks([&] { return Marks{std::vector<size_t>(F, SIZE_MAX), std::vector<size_t>(V, SIZE_MAX), {}, {}}; });
  size_t pass = 0;
  auto pool = [&](size_t f) {
    Marks& m = marks.local();
    Pool p;
    const size_t tag = pass * F + f;
    m.ring.assign(mesh.triangles[f].begin(), mesh.triangles[f].end());
    for (uint32_t v : mesh.triangles[f]) m.vertex[v] = tag;
    for (int r = 0; r < std::max(1, o.rings); ++r) {
      m.next.clear();
      for (size_t v : m.ring)
        for (size_t j = corners.begin[v]; j < corners.begin[v + 1]; ++j) {
          const size_t g = corners.entry[j] / 3;
          if (m.face[g] == tag) continue;
          m.face[g] = tag;
          p.sum += face_sum[g], p.v2 += face_v2[g], p.n += static_cast<double>(face_count[g]);
          p.unsure |= unknown[g] != 0;
          for (uint32_t u : mesh.triangles[g])
            if (m.vertex[u] != tag) m.vertex[u] = tag, m.next.push_back(u);
        }
      m.ring.swap(m.next);
      if (r == 0) p.sum1 = p.sum, p.n1 = p.n;
    }
    return p;
  };
  auto significant = [&](const Pool& p, double z) { return p.unsure || (p.n > 0 && p.sum > z * std::sqrt(2 * p.v2) + p.n * rounding); };

  // Two stages: a face whose first-stage pool is not even `first_significance` standard errors
  // above zero is left to interpolation; the faces whose pools are (or hold no first-stage
  // sample) get the rest of their own samples traced, and are tested again on everything
  // traced within their pools. (Tracing the rest of every such pool would trace most of the
  // pilot again: a 2-ring pool holds some 25 faces.)
  std::vector<char> candidate(F, 1);
  if (two_stages) {
    parallel_range(F, to.threads, size_t(1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const Pool p = pool(f);
        candidate[f] = p.n == 0 || significant(p, o.first_significance);
      }
    });
    std::vector<size_t> second;
    for (size_t k = 0; k < S; ++k)
      if (!traced[k] && candidate[pilot.face[k]]) second.push_back(k);
    trace(second);
    measure(candidate);
    if (to.log) to.log->barrier(false);
    if (progress) progress(S - first.size() - second.size());  // the untraced rest: the bar completes
    sum_faces();
    ++pass;
  }
  plan.face_weight.assign(F, 0.0);
  std::vector<double> raw(F, 0.0), area(F, 0.0);
  double weighted = 0, total_area = 0;
  parallel_range(F, to.threads, size_t(1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f < r.end(); ++f) {
      if (!candidate[f]) continue;
      const Pool p = pool(f);
      if (!significant(p, o.significance)) continue;
      const Triangle& t = mesh.triangles[f];
      raw[f] = p.n1 > 0 ? std::sqrt(std::max(0.0, p.sum1 / p.n1)) : 0;
      area[f] = triangle_area(mesh.point(t[0]), mesh.point(t[1]), mesh.point(t[2]));
      if (!std::isfinite(area[f])) area[f] = 0;
      plan.face_weight[f] = 1;
    }
  });
  for (size_t f = 0; f < F; ++f)
    if (plan.face_weight[f] > 0) weighted += area[f] * raw[f], total_area += area[f];
  const double mean = total_area > 0 ? weighted / total_area : 0;
  for (size_t f = 0; f < F; ++f) {
    if (plan.face_weight[f] == 0) continue;
    ++plan.sampled_faces;
    plan.sampled_area += area[f];
    // (a floor: a face that is sampled only for an unknown noise keeps its minimum)
    if (mean > 0) plan.face_weight[f] = std::max(1e-3, o.area_share + (1 - o.area_share) * raw[f] / mean);
  }
  if (!measured.empty() && plan.sampled_faces > 0) {
    // Over the sampled faces, each pilot sample weighted as the fit's samples will be (their
    // density follows the face weight, the pilot's follows area).
    double w = 0, variation = 0;
    for (size_t k = 0; k < S; ++k) {
      const double fw = plan.face_weight[pilot.face[k]];
      if (traced[k] && fw > 0 && std::isfinite(excess[k])) w += fw, variation += fw * excess[k];
    }
    SampleRaysChoice& c = plan.sample_rays;
    c.choices = choices, c.points = measured.size();
    double wn = 0;
    std::vector<double> noise_sum(choices.size(), 0.0), d(choices.size());
    for (size_t j = 0; j < measured.size(); ++j) {
      const double fw = plan.face_weight[pilot.face[measured[j]]];
      if (!(fw > 0)) continue;
      bool finite = true;
      for (size_t q = 0; q < choices.size(); ++q) {
        const auto row = static_cast<Eigen::Index>(j);
        d[q] = 0.5 * (twice[2 * q].row(row) - twice[2 * q + 1].row(row)).squaredNorm();
        finite &= std::isfinite(d[q]);
      }
      if (!finite) continue;
      wn += fw;
      for (size_t q = 0; q < choices.size(); ++q) noise_sum[q] += fw * d[q];
    }
    if (w > 0 && wn > 0) {
      c.variation = std::max(0.0, variation / w);
      for (double& v : noise_sum) v /= wn;
      c.noise = noise_sum;
    }
  }
  plan.pilot_drawn = S;
  plan.pilot_samples = size_t(std::count(traced.begin(), traced.end(), 1));
  plan.rays = stats.rays;
  plan.seconds = clock.total();
  return plan;
}

}  // namespace prtsub
