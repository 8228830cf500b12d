// Alignment beyond the capture range: a coarse-to-fine search over (dx, dy, dyaw) on the coarse
// layers' covariances, then the registration (registration/alignment.hpp) to refine.
//
// Registration of one map against another converges within about a cell of its finest layers
// (docs/design.md, "Team alignment"). A rover that returns after a long drive, or a patch
// written under an uncertain pose, can be off by metres and tens of degrees. CoarseAligner:
//  1. Level 0, the coarsest layer's pooled cells pooled once more, 2 x 2 (CADRE: 128 cm; exact
//     moments, ccm_pool4): our cells as Gaussians (mean, 3 x 3 covariance of their points); the
//     height each predicts at a horizontal position is the conditional Gaussian z | (x, y):
//     mean mu_z + g . (p - mu), variance sigma_z|xy^2 + model_sigma^2 (g = Sigma_xy^-1
//     Sigma_xyz, the cell's plane). Their cells of the same level (means) are moved by every
//     candidate (dx, dy, dyaw) of a grid over the search box (steps: half a cell; the yaw step
//     moves the farthest sample by half a cell); the candidate's dz is the mean height residual
//     of its matches, and its score the sum of the Gaussian likelihoods exp(-r^2 / 2 var) of the
//     matched samples (NDT's score on the cells' own covariances). Ties (flat ground: every
//     candidate scores alike) go to the candidate nearest the nominal offset.
//  2. Level 1, the coarsest layer (CADRE: 64 cm), then level 2, the next finer one (32 cm): the
//     same around the level before's best, over +-1 of its steps, at half its steps.
//  3. The registration (align_maps' solver) from the last level's best, with every layer: of
//     their cells (align), or of the frame's own points their map was built from (align_frame:
//     point to plane against our cells, as Stack::register_frame; where their cells hold a few
//     points each, a sparse scan, the points fix the motion 2-4 times better than the cells'
//     means: docs/design.md, "Against ICP, GICP and NDT").
// A level with fewer usable cells than RegistrationParams::min_matches (a small view) is
// skipped: the next, finer one searches the whole box (its steps capped at kMaxSteps a side).
// The answer is registration's: its statuses and its observability claims. A direction the
// registration does not claim keeps no coarse component either (flat ground: dz only, no x, y
// or yaw; a ditch along x: no x), so the search invents nothing the terrain does not fix.
//
// Bounds: candidates per level <= (2 kMaxSteps + 1)^3, samples per level <= kMaxCoarseSamples;
// time O(candidates x samples) plus one registration (at most max_iterations + 2 passes over
// at most max_points samples). Memory: the tables of one layer
// (kTableCells cells x 6 floats, kTableCells x 3 floats, kMaxCoarseSamples x 2 floats) in the
// aligner, no heap.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/registration/registration.hpp"

namespace ccmap {

struct CoarseSearchParams {
  float range_xy_m;     ///< half-width of the horizontal search box about the nominal offset (m, > 0)
  float range_yaw_rad;  ///< half-width of the yaw search (rad, in (0, pi/2])
  float model_sigma_m;  ///< added to every predicted height's sigma (m, > 0): cell curvature, changed ground
};
/// +-2 m, +-20 deg, 5 cm.
[[nodiscard]] inline CoarseSearchParams default_coarse_search_params() noexcept {
  return CoarseSearchParams{2.0F, 0.35F, 0.05F};
}

/// What the search found before the registration refined it (diagnostics).
struct CoarseReport {
  float dx_m;    ///< the last level's best, about the same centre as the result
  float dy_m;
  float dyaw_rad;
  float dz_m;
  float score;   ///< its score (matched samples' likelihood sum)
  std::uint32_t matched;     ///< samples on known cells at the best candidate
  std::uint32_t candidates;  ///< candidates scored, all levels
  std::uint32_t samples;     ///< their samples at level 0
};

namespace detail {

/// Registration samples (CellSamples, FrameSamples) shifted by `shift` (a nominal offset not yet
/// in them), then turned by dyaw about (cx, cy) and moved by (dx, dy).
template <typename Inner>
class TurnedSamples {
 public:
  TurnedSamples(const Inner& inner, const MapOffset& shift, float cx, float cy, float dx, float dy, float dyaw) noexcept
      : inner_(inner), shift_(shift), cx_(cx), cy_(cy), dx_(dx), dy_(dy), c_(std::cos(dyaw)), s_(std::sin(dyaw)) {}
  template <typename Fn>
  SampleRefusals for_each(Fn&& fn) const noexcept {
    return inner_.for_each([&](RegistrationSample sample) {
      const float x = sample.x + shift_.x_m - cx_;
      const float y = sample.y + shift_.y_m - cy_;
      sample.x = c_ * x - s_ * y + cx_ + dx_;
      sample.y = s_ * x + c_ * y + cy_ + dy_;
      sample.z += shift_.z_m;
      fn(sample);
    });
  }

 private:
  const Inner& inner_;
  MapOffset shift_;
  float cx_, cy_, dx_, dy_, c_, s_;
};

}  // namespace detail

/// The coarse-to-fine aligner of Stack<Config> maps; place it in static storage (its tables).
template <typename Config>
class CoarseAligner {
 public:
  using StackType = Stack<Config>;
  static_assert(StackType::kCcmLayerCount >= 1, "the coarse search needs a CCM layer");
  static constexpr int kTop = StackType::kLayerCount - 1;
  static constexpr int kLevels = StackType::layer_is_ccm(kTop - 1) ? 3 : 2;
  static constexpr std::size_t kTableCells =
      StackType::layer_capacity(kTop) > StackType::layer_capacity(kTop - kLevels + 2)
          ? StackType::layer_capacity(kTop)
          : StackType::layer_capacity(kTop - kLevels + 2);
  static constexpr std::uint32_t kMaxCoarseSamples = 512U;
  static constexpr std::int32_t kMaxSteps = 16;

  /// Aligns their map with ours from `offset` (their map-frame points are at p + offset in ours,
  /// give or take the search box). The result is align_maps' (registration/alignment.hpp): the
  /// correction (coarse and fine together) about (centre_x_m, centre_y_m), its statuses, plus
  /// kInvalidArgument for bad search parameters. report may be nullptr.
  [[nodiscard]] AlignmentResult align(const StackType& ours, const StackType& theirs, const MapOffset& offset,
                                      const RegistrationParams& params, const CoarseSearchParams& search,
                                      CoarseReport* report) noexcept {
    if (report != nullptr) {
      *report = CoarseReport{};
    }
    return searched(ours, theirs, offset, params, search, report, [&](const TheirCells& all, const Best& best) {
      return refine(ours, all, MapOffset{0.0F, 0.0F, 0.0F}, 0.0F, all.count(), best, params);
    });
  }

  /// As align, but the registration after the search matches the frame's own points (their map
  /// frame: the points `theirs` was built from, `origin` the sensor's position there) against
  /// our cells, point to plane as Stack::register_frame, instead of their cells. Where their
  /// cells hold a few points each (a sparse scan: about one point per finest cell), the cells'
  /// means carry less than the points (docs/design.md, "Against ICP, GICP and NDT"). The search
  /// is align's, on their map's coarse layers. Points are sampled and refused as by
  /// register_frame (RegistrationParams::max_points, non-finite ones counted); the result's
  /// cells is the point count. Statuses: align's, plus kInvalidArgument for points == nullptr
  /// with n > 0 and kNonFiniteInput / kOutOfRange for the origin.
  [[nodiscard]] AlignmentResult align_frame(const StackType& ours, const StackType& theirs, const PointXYZ* points,
                                            std::size_t n, const PointXYZ& origin, const MapOffset& offset,
                                            const RegistrationParams& params, const CoarseSearchParams& search,
                                            CoarseReport* report) noexcept {
    if (report != nullptr) {
      *report = CoarseReport{};
    }
    if (points == nullptr && n > 0U) {
      return detail::refused_alignment(Status::kInvalidArgument);
    }
    if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z)) {
      return detail::refused_alignment(Status::kNonFiniteInput);
    }
    if (!(std::fabs(origin.x) <= kMaxAbsCoordinateM && std::fabs(origin.y) <= kMaxAbsCoordinateM &&
          std::fabs(origin.z) <= kMaxAbsCoordinateM)) {
      return detail::refused_alignment(Status::kOutOfRange);
    }
    return searched(ours, theirs, offset, params, search, report, [&](const TheirCells&, const Best& best) {
      const detail::FrameSamples<Config> frame(ours, points, n, origin, nullptr, params.max_points);
      const auto count = static_cast<std::uint32_t>(n < 0xFFFFFFFFU ? n : 0xFFFFFFFFU);
      return refine(ours, frame, offset, origin.z + offset.z_m, count, best, params);
    });
  }

 private:
  struct Best {
    float dx, dy, dyaw, dz, score;
    std::uint32_t matched;
  };

  using TheirCells = detail::CellSamples<Config, detail::StackCells<Config>>;

  /// The checks, their usable cells and the search; then fine(cells, best) answers, or the refusal.
  template <typename Fine>
  [[nodiscard]] AlignmentResult searched(const StackType& ours, const StackType& theirs, const MapOffset& offset,
                                         const RegistrationParams& params, const CoarseSearchParams& search,
                                         CoarseReport* report, Fine&& fine) noexcept {
    Status status = check(ours, theirs, offset, params, search);
    if (status != Status::kOk) {
      return detail::refused_alignment(status);
    }
    const detail::StackCells<Config> source{theirs};
    const TheirCells all(ours, source, offset, params.max_points);
    Best best{};
    status = coarse(ours, theirs, all, offset, params, search, report, &best);
    if (status != Status::kOk) {
      return detail::refused_alignment(status);
    }
    return fine(all, best);
  }

  /// The checks every alignment makes first: kOk, or why not.
  [[nodiscard]] static Status check(const StackType& ours, const StackType& theirs, const MapOffset& offset,
                                    const RegistrationParams& params, const CoarseSearchParams& search) noexcept {
    Status status = detail::check_alignment(ours, offset, params);
    if (status == Status::kOk) {
      status = theirs.state_status();
    }
    if (status == Status::kOk && !detail::same_float_bits(theirs.layer_cell_width(0), ours.layer_cell_width(0))) {
      status = Status::kMisaligned;
    }
    if (status == Status::kOk && !(search.range_xy_m > 0.0F && search.range_xy_m <= kMaxAbsCoordinateM &&
                                   search.range_yaw_rad > 0.0F && search.range_yaw_rad <= 1.5708F &&
                                   search.model_sigma_m > 0.0F && std::isfinite(search.model_sigma_m))) {
      status = Status::kInvalidArgument;
    }
    return status;
  }

  /// The search (levels 0 .. kLevels - 1) after check(): kOk and *out (about (cx_, cy_), the
  /// centre of their usable cells `all`, which it sets), or kInsufficientOverlap.
  [[nodiscard]] Status coarse(const StackType& ours, const StackType& theirs, const TheirCells& all,
                              const MapOffset& offset, const RegistrationParams& params,
                              const CoarseSearchParams& search, CoarseReport* report, Best* out) noexcept {
    CoarseReport r{};
    if (all.count() < params.min_matches) {
      return Status::kInsufficientOverlap;
    }
    cx_ = all.centre_x();
    cy_ = all.centre_y();
    Best best{0.0F, 0.0F, 0.0F, 0.0F, -1.0F, 0U};
    float step_xy = 0.0F;
    float step_yaw = 0.0F;
    float half_xy = search.range_xy_m;
    float half_yaw = search.range_yaw_rad;
    for (int level = 0; level < kLevels; ++level) {
      // Level 0: the coarsest layer pooled once more; then the coarsest layer; then the next.
      const int layer = level == 0 ? kTop : kTop - level + 1;
      const bool pool2 = level == 0;
      build_ours(ours, layer, pool2, search.model_sigma_m);
      build_theirs(theirs, layer, pool2, offset);
      const float width = width_;
      if (level == 0) {
        r.samples = samples_;
      }
      if (samples_ < params.min_matches || samples_ == 0U) {
        continue;  // too few cells at this level (a small view): the next, finer level searches the box
      }
      step_xy = 0.5F * width;
      step_yaw = lever_ > 0.0F ? 0.5F * width / lever_ : half_yaw;
      if (best.score >= 0.0F) {
        // +-1 step of the level before, at this level's (half as large) steps.
        half_xy = 2.0F * step_xy;
        half_yaw = 2.0F * step_yaw;
      }
      const Best found = search_level(best.score < 0.0F ? 0.0F : best.dx, best.score < 0.0F ? 0.0F : best.dy,
                                      best.score < 0.0F ? 0.0F : best.dyaw, half_xy, half_yaw, step_xy, step_yaw,
                                      &r.candidates);
      if (found.score > 0.0F) {
        best = found;
      }
    }
    if (best.score < 0.0F) {
      best = Best{0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0U};
    }
    r.dx_m = best.dx;
    r.dy_m = best.dy;
    r.dyaw_rad = best.dyaw;
    r.dz_m = best.dz;
    r.score = best.score;
    r.matched = best.matched;
    if (report != nullptr) {
      *report = r;
    }
    *out = best;
    return Status::kOk;
  }

  /// The registration of `samples` (shifted by `shift`) from the search's best, about (cx_, cy_),
  /// composed with it.
  template <typename Samples>
  [[nodiscard]] AlignmentResult refine(const StackType& ours, const Samples& samples, const MapOffset& shift, float oz,
                                       std::uint32_t count, const Best& best, const RegistrationParams& params) noexcept {
    const detail::TurnedSamples<Samples> turned(samples, shift, cx_, cy_, best.dx, best.dy, best.dyaw);
    const detail::StackSurface<Config> surface(ours);
    const RegistrationResult fine =
        detail::solve_registration(turned, surface, cx_, cy_, oz, params, ours.layer_cell_width(0),
                                   ours.layer_cell_width(StackType::kLayerCount - 1));
    AlignmentResult out{};
    out.cells = count;
    out.centre_x_m = cx_;
    out.centre_y_m = cy_;
    out.correction = fine;
    if (fine.status != Status::kOk) {
      return out;
    }
    // Compose: p' = R1 (R0 (p - o) + o + d0 - o) + o + d1 = R1 R0 (p - o) + o + R1 d0 + d1. A
    // coarse component along a direction the registration does not claim is dropped.
    const float x0 = fine.observable[kAxisX] ? best.dx : 0.0F;
    const float y0 = fine.observable[kAxisY] ? best.dy : 0.0F;
    const float yaw0 = fine.observable[kAxisYaw] ? best.dyaw : 0.0F;
    const float c1 = std::cos(fine.dyaw);
    const float s1 = std::sin(fine.dyaw);
    out.correction.dx = c1 * x0 - s1 * y0 + fine.dx;
    out.correction.dy = s1 * x0 + c1 * y0 + fine.dy;
    out.correction.dyaw = yaw0 + fine.dyaw;
    if (!fine.observable[kAxisX]) {
      out.correction.dx = 0.0F;
    }
    if (!fine.observable[kAxisY]) {
      out.correction.dy = 0.0F;
    }
    return out;
  }

  /// One of our cells as a height predictor; known == 0: no prediction.
  struct Predictor {
    float mx, my, mz, gx, gy, inv_var;  ///< inv_var 0: unknown
  };

  /// Calls fn(index, cell) for every cell of a level: layer `layer`'s pooled cells (pool2 false) or
  /// those pooled once more, 2 x 2 into cells twice as wide (pool2 true: exact moments, ccm_pool4).
  /// Sets the level's cell width, window minimum and side.
  template <typename Fn>
  static void for_each_level_cell(const StackType& stack, int layer, bool pool2, float* width, CellIndex* min,
                                  std::int32_t* side, Fn&& fn) noexcept {
    const float w = stack.layer_cell_width(layer);
    const std::int32_t s = StackType::layer_side(layer);
    const CellIndex centre = stack.layer_centre(layer);
    const CellIndex lo{centre.x - s / 2, centre.y - s / 2};
    if (!pool2) {
      *width = w;
      *min = lo;
      *side = s;
      for (std::int32_t j = 0; j < s; ++j) {
        for (std::int32_t i = 0; i < s; ++i) {
          const CellIndex index{lo.x + i, lo.y + j};
          fn(index, stack.pooled_cell(layer, index));
        }
      }
      return;
    }
    *width = 2.0F * w;
    // Parent of child index c: c >> 1, floor(c / 2) (arithmetic shift, as map exchange's offsets).
    *min = CellIndex{lo.x >> 1, lo.y >> 1};
    *side = ((lo.x + s - 1) >> 1) - min->x + 1;
    for (std::int32_t j = 0; j < *side; ++j) {
      for (std::int32_t i = 0; i < *side; ++i) {
        const CellIndex index{min->x + i, min->y + j};
        typename StackType::CcmCellType children[4];
        for (int k = 0; k < 4; ++k) {
          children[k] = stack.pooled_cell(layer, CellIndex{2 * index.x + (k & 1), 2 * index.y + (k >> 1)});
        }
        fn(index, ccm_pool4(children, w, stack.params().weight_limit));
      }
    }
  }

  template <typename Cell>
  [[nodiscard]] static bool usable(const Cell& cell, const StackParams& p, float width) noexcept {
    return cell.weight >= p.min_weight && cell.weight > 0.0F &&
           ccm_is_covered(cell, width, p.coverage_tau, p.min_weight);
  }

  void build_ours(const StackType& ours, int layer, bool pool2, float model_sigma) noexcept {
    const StackParams& p = ours.params();
    for_each_level_cell(ours, layer, pool2, &width_, &min_, &side_, [&](CellIndex index, const auto& cell) {
      Predictor& out = table_[static_cast<std::size_t>(index.y - min_.y) * static_cast<std::size_t>(side_) +
                              static_cast<std::size_t>(index.x - min_.x)];
      out = Predictor{0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
      if (!usable(cell, p, width_)) {
        return;
      }
      // z | xy of the cell's Gaussian (covariance s / W).
      const float w = cell.weight;
      const float sxx = cell.s_xx / w;
      const float syy = cell.s_yy / w;
      float sxy = 0.0F;
      if constexpr (StackType::kCcmCellKind == CcmCellKind::kFull) {
        sxy = cell.s_xy / w;
      }
      const float sxz = cell.s_xz / w;
      const float syz = cell.s_yz / w;
      const float szz = cell.s_zz / w;
      const float det = sxx * syy - sxy * sxy;
      if (!(det > 1e-12F)) {
        return;
      }
      const float gx = (syy * sxz - sxy * syz) / det;
      const float gy = (sxx * syz - sxy * sxz) / det;
      float conditional = szz - (gx * sxz + gy * syz);
      conditional = conditional > 0.0F ? conditional : 0.0F;
      const float var = conditional + model_sigma * model_sigma;
      out = Predictor{grid::cell_centre(index.x, width_) + cell.mean_x, grid::cell_centre(index.y, width_) + cell.mean_y,
                      cell.mean_z, gx, gy, 1.0F / var};
    });
  }

  /// Their usable cells of the level, every k-th (at most kMaxCoarseSamples), relative to the
  /// rotation centre, moved by the offset.
  void build_theirs(const StackType& theirs, int layer, bool pool2, const MapOffset& offset) noexcept {
    const StackParams& p = theirs.params();
    std::uint32_t usable_cells = 0U;
    float width = 0.0F;
    CellIndex min{};
    std::int32_t side = 0;
    for_each_level_cell(theirs, layer, pool2, &width, &min, &side, [&](CellIndex index, const auto& cell) {
      if (usable(cell, p, width)) {
        sx_[usable_cells] = grid::cell_centre(index.x, width) + cell.mean_x + offset.x_m - cx_;
        sy_[usable_cells] = grid::cell_centre(index.y, width) + cell.mean_y + offset.y_m - cy_;
        sz_[usable_cells] = cell.mean_z + offset.z_m;
        ++usable_cells;
      }
    });
    const std::uint32_t stride = usable_cells > kMaxCoarseSamples ? (usable_cells + kMaxCoarseSamples - 1U) / kMaxCoarseSamples : 1U;
    samples_ = 0U;
    float lever_sq = 0.0F;
    for (std::uint32_t k = 0; k < usable_cells; k += stride) {
      sx_[samples_] = sx_[k];
      sy_[samples_] = sy_[k];
      sz_[samples_] = sz_[k];
      const float r2 = sx_[k] * sx_[k] + sy_[k] * sy_[k];
      lever_sq = r2 > lever_sq ? r2 : lever_sq;
      ++samples_;
    }
    lever_ = std::sqrt(lever_sq);
  }

  /// Score of one candidate (dx, dy about the nominal offset; c, s: cos, sin of dyaw).
  [[nodiscard]] Best score(float dx, float dy, float dyaw, float c, float s) noexcept {
    // Pass 1: the candidate's dz, the mean residual of its matches (kept with their inverse
    // variances: samples_ <= kMaxCoarseSamples); pass 2: the likelihoods of the kept ones.
    float sum_r = 0.0F;
    std::uint32_t matched = 0U;
    auto residual = [&](std::uint32_t n, float* r, float* inv_var) {
      const float x = c * sx_[n] - s * sy_[n] + cx_ + dx;
      const float y = s * sx_[n] + c * sy_[n] + cy_ + dy;
      const auto ix = static_cast<std::int32_t>(std::floor(x / width_)) - min_.x;
      const auto iy = static_cast<std::int32_t>(std::floor(y / width_)) - min_.y;
      if (ix < 0 || iy < 0 || ix >= side_ || iy >= side_) {
        return false;
      }
      const Predictor& p =
          table_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(side_) + static_cast<std::size_t>(ix)];
      if (p.inv_var == 0.0F) {
        return false;
      }
      *r = p.mz + p.gx * (x - p.mx) + p.gy * (y - p.my) - sz_[n];
      *inv_var = p.inv_var;
      return true;
    };
    for (std::uint32_t n = 0; n < samples_; ++n) {
      float r = 0.0F;
      float inv_var = 0.0F;
      if (residual(n, &r, &inv_var)) {
        sum_r += r;
        matched_r_[matched] = r;
        matched_inv_var_[matched] = inv_var;
        ++matched;
      }
    }
    const float dz = matched > 0U ? sum_r / static_cast<float>(matched) : 0.0F;
    float total = 0.0F;
    for (std::uint32_t k = 0; k < matched; ++k) {
      const float e = matched_r_[k] - dz;
      total += std::exp(-0.5F * e * e * matched_inv_var_[k]);
    }
    return Best{dx, dy, dyaw, dz, total, matched};
  }

  [[nodiscard]] Best search_level(float x0, float y0, float yaw0, float half_xy, float half_yaw, float step_xy,
                                  float step_yaw, std::uint32_t* candidates) noexcept {
    const std::int32_t nxy = clamp_steps(half_xy / step_xy);
    const std::int32_t nyaw = clamp_steps(half_yaw / step_yaw);
    const float sxy = nxy > 0 ? half_xy / static_cast<float>(nxy) : 0.0F;
    const float syaw = nyaw > 0 ? half_yaw / static_cast<float>(nyaw) : 0.0F;
    Best best{x0, y0, yaw0, 0.0F, -1.0F, 0U};
    float best_distance = 0.0F;
    for (std::int32_t a = -nyaw; a <= nyaw; ++a) {
      const float yaw = yaw0 + syaw * static_cast<float>(a);
      const float c = std::cos(yaw);
      const float s = std::sin(yaw);
      for (std::int32_t j = -nxy; j <= nxy; ++j) {
        for (std::int32_t i = -nxy; i <= nxy; ++i) {
          const float dx = x0 + sxy * static_cast<float>(i);
          const float dy = y0 + sxy * static_cast<float>(j);
          const Best b = score(dx, dy, yaw, c, s);
          ++*candidates;
          // Nearer the nominal offset wins a tie (within 1e-4 of the score): flat ground stays put.
          const float lever = lever_ > 0.0F ? lever_ : 1.0F;
          const float distance = dx * dx + dy * dy + yaw * yaw * lever * lever;
          const float tolerance = 1e-4F * (best.score > 0.0F ? best.score : 0.0F);
          if (b.score > best.score + tolerance ||
              (b.score >= best.score - tolerance && best.score >= 0.0F && distance < best_distance)) {
            best = b;
            best_distance = distance;
          }
        }
      }
    }
    return best;
  }

  [[nodiscard]] static std::int32_t clamp_steps(float n) noexcept {
    const float up = std::ceil(n);
    return !(up > 0.0F) ? 0 : (up > static_cast<float>(kMaxSteps) ? kMaxSteps : static_cast<std::int32_t>(up));
  }

  Predictor table_[kTableCells]{};
  float sx_[kTableCells]{};  ///< their usable cells, then the samples taken from them
  float sy_[kTableCells]{};
  float sz_[kTableCells]{};
  float matched_r_[kMaxCoarseSamples]{};  ///< one candidate's matched residuals (score)
  float matched_inv_var_[kMaxCoarseSamples]{};
  std::uint32_t samples_ = 0U;
  float lever_ = 0.0F;
  float width_ = 1.0F;
  std::int32_t side_ = 0;
  CellIndex min_{};
  float cx_ = 0.0F;
  float cy_ = 0.0F;
};

}  // namespace ccmap
