#include "experiments/lateral.hpp"

#include <cmath>
#include <functional>

#include "ccmap/cell/ccm_cell.hpp"
#include "experiments/common.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kTau = 0.8F;

struct Sample {
  double x, y, z;
};
using Keep = std::function<bool(double, double)>;

/// n points uniform over the part of the cell [-w/2, w/2]^2 where keep(x, y), on the plane.
std::vector<Sample> seen_points(sim::Rng& rng, int n, double w, double a, double b, const Keep& keep) {
  std::vector<Sample> pts;
  while (static_cast<int>(pts.size()) < n) {
    const double x = rng.uniform(-0.5 * w, 0.5 * w), y = rng.uniform(-0.5 * w, 0.5 * w);
    if (keep(x, y)) pts.push_back(Sample{x, y, 0.1 + a * x + b * y});
  }
  return pts;
}

template <typename Cell>
Cell fold(const std::vector<Sample>& pts) {
  Cell cell{};
  for (const Sample& p : pts) {
    // Points inside a 16 cm cell: never refused.
    (void)ccm_update(cell, static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), 1.0F,
                     kNoWeightLimit);
  }
  return cell;
}

struct ErrorStats {
  double sum_sq = 0.0, max = 0.0;
  int n = 0, covered = 0;
  void add(const CcmSurface& s, double a, double b, bool is_covered) {
    const double e = std::hypot(s.slope_x - a, s.slope_y - b);
    sum_sq += e * e;
    max = std::fmax(max, e);
    ++n;
    covered += is_covered ? 1 : 0;
  }
  double rms() const { return n > 0 ? std::sqrt(sum_sq / n) : 0.0; }
};

/// One case over `trials` cells; keep_of(trial rng) gives the seen part of each.
LateralSlopeRow slope_case(const std::string& name, sim::Rng& rng, int trials, int points, double w, double a,
                           double b, const std::function<Keep(sim::Rng&)>& keep_of) {
  LateralSlopeRow row;
  row.name = name;
  row.truth_slope_x = a;
  row.truth_slope_y = b;
  ErrorStats paper, full;
  for (int t = 0; t < trials; ++t) {
    const Keep keep = keep_of(rng);
    const std::vector<Sample> pts = seen_points(rng, points, w, a, b, keep);
    const CcmPaperCell pc = fold<CcmPaperCell>(pts);
    const CcmCell fc = fold<CcmCell>(pts);
    const CcmSurface ps = ccm_surface(pc), fs = ccm_surface(fc);
    if (t == 0) {
      row.paper_slope_x = ps.slope_x;
      row.full_slope_x = fs.slope_x;
    }
    paper.add(ps, a, b, ccm_is_covered(pc, static_cast<float>(w), kTau, 1.0F));
    full.add(fs, a, b, ccm_is_covered(fc, static_cast<float>(w), kTau, 1.0F));
  }
  row.paper_rms = paper.rms();
  row.paper_max = paper.max;
  row.full_rms = full.rms();
  row.full_max = full.max;
  row.paper_covered = paper.covered;
  row.full_covered = full.covered;
  row.trials = trials;
  return row;
}

/// Child i (ix + 2 iy) of width `child`: a regular 12 x 12 grid of the plane (x, y uncorrelated).
template <typename Cell>
Cell grid_child(int i, double child, double a, double b) {
  const double cx = ((i & 1) != 0 ? 0.5 : -0.5) * child, cy = ((i & 2) != 0 ? 0.5 : -0.5) * child;
  std::vector<Sample> pts;
  for (int p = 0; p < 12; ++p) {
    for (int q = 0; q < 12; ++q) {
      const double x = -0.5 * child + child * (p + 0.5) / 12, y = -0.5 * child + child * (q + 0.5) / 12;
      pts.push_back(Sample{x, y, 0.1 + a * (cx + x) + b * (cy + y)});
    }
  }
  return fold<Cell>(pts);
}

LateralSlopeRow pooled_case(const std::string& name, int mask, double child, double a, double b) {
  LateralSlopeRow row;
  row.name = name;
  row.truth_slope_x = a;
  row.truth_slope_y = b;
  CcmPaperCell pc[4] = {};
  CcmCell fc[4] = {};
  for (int i = 0; i < 4; ++i) {
    if (((mask >> i) & 1) == 0) continue;
    pc[i] = grid_child<CcmPaperCell>(i, child, a, b);
    fc[i] = grid_child<CcmCell>(i, child, a, b);
  }
  const CcmPaperCell pp = ccm_pool4(pc, static_cast<float>(child), kNoWeightLimit);
  const CcmCell fp = ccm_pool4(fc, static_cast<float>(child), kNoWeightLimit);
  ErrorStats paper, full;
  paper.add(ccm_surface(pp), a, b, ccm_is_covered(pp, static_cast<float>(2.0 * child), kTau, 1.0F));
  full.add(ccm_surface(fp), a, b, ccm_is_covered(fp, static_cast<float>(2.0 * child), kTau, 1.0F));
  row.paper_slope_x = ccm_surface(pp).slope_x;
  row.full_slope_x = ccm_surface(fp).slope_x;
  row.paper_rms = row.paper_max = paper.max;
  row.full_rms = row.full_max = full.max;
  row.paper_covered = paper.covered;
  row.full_covered = full.covered;
  row.trials = 1;
  return row;
}

/// The smallest seen share passing coverage for a straight edge with normal at `deg` to x:
/// bisection on the edge offset t (seen: n . p < t) over an n x n grid of the cell.
template <typename Cell>
double needed_share(double w, double deg) {
  const int n = 400;
  const double nx = std::cos(deg * kPi / 180.0), ny = std::sin(deg * kPi / 180.0);
  const double reach = 0.5 * w * (std::fabs(nx) + std::fabs(ny));
  double lo = -reach, hi = reach;  // covered at hi (whole cell), not at lo (nothing)
  double share_hi = 1.0;
  for (int it = 0; it < 40; ++it) {
    const double t = 0.5 * (lo + hi);
    Cell cell{};
    int seen = 0;
    for (int i = 0; i < n; ++i) {
      const double x = -0.5 * w + w * (i + 0.5) / n;
      for (int j = 0; j < n; ++j) {
        const double y = -0.5 * w + w * (j + 0.5) / n;
        if (nx * x + ny * y < t) {
          (void)ccm_update(cell, static_cast<float>(x), static_cast<float>(y), 0.0F, 1.0F, kNoWeightLimit);
          ++seen;
        }
      }
    }
    if (ccm_is_covered(cell, static_cast<float>(w), kTau, 1.0F)) {
      hi = t;
      share_hi = static_cast<double>(seen) / (static_cast<double>(n) * n);
    } else {
      lo = t;
    }
  }
  return share_hi;
}

}  // namespace

LateralResult run_lateral(const LateralConfig& cfg) {
  LateralResult r;
  const double w = cfg.cell_width_m;
  const double b12 = std::tan(12.0 * kPi / 180.0), b20 = std::tan(20.0 * kPi / 180.0);
  sim::Rng rng(sim::hash_combine(cfg.seed, 0x11A7));
  const auto all = [](sim::Rng&) { return Keep([](double, double) { return true; }); };
  r.slopes.push_back(slope_case("diagonal half (x + y < 0), 12 deg along y", rng, 1, 20000, w, 0.0, b12,
                                [](sim::Rng&) { return Keep([](double x, double y) { return x + y < 0.0; }); }));
  r.slopes.push_back(slope_case("half at a random angle, 12 deg along y", rng, cfg.trials, cfg.points, w, 0.0, b12,
                                [](sim::Rng& g) {
                                  const double phi = g.uniform(0.0, 2.0 * kPi);
                                  const double nx = std::cos(phi), ny = std::sin(phi);
                                  return Keep([=](double x, double y) { return nx * x + ny * y < 0.0; });
                                }));
  r.slopes.push_back(slope_case("full cell, 500 points, 12 deg along y", rng, cfg.trials, 500, w, 0.0, b12, all));
  r.slopes.push_back(slope_case("L (3 quadrants), 12 deg along y", rng, 1, 20000, w, 0.0, b12, [](sim::Rng&) {
    return Keep([](double x, double y) { return !(x > 0.0 && y > 0.0); });
  }));
  const double child = 0.08;
  r.slopes.push_back(pooled_case("pooled, 3 of 4 children (L), 20 deg along y", 0b0111, child, 0.0, b20));
  r.slopes.push_back(pooled_case("pooled, 2 diagonal children, 20 deg along y", 0b1001, child, 0.0, b20));
  r.slopes.push_back(pooled_case("pooled, 2 adjacent children, 20 deg along y", 0b0011, child, 0.0, b20));
  r.slopes.push_back(pooled_case("pooled, all 4 children, 20 deg along y", 0b1111, child, 0.0, b20));
  for (const double deg : {0.0, 15.0, 30.0, 45.0}) {
    r.coverage.push_back(
        LateralCoverageRow{deg, needed_share<CcmPaperCell>(w, deg), needed_share<CcmCell>(w, deg)});
  }
  return r;
}

std::string lateral_table(const LateralConfig& cfg, const LateralResult& r) {
  Table t({"case", "trials", "paper slope_x", "full slope_x", "paper |error| rms / max", "full |error| rms / max",
           "covered paper / full"});
  for (const LateralSlopeRow& s : r.slopes) {
    t.add_row({s.name, format("%d", s.trials), format("%+.4f", s.paper_slope_x), format("%+.6f", s.full_slope_x),
               format("%.4f / %.4f", s.paper_rms, s.paper_max), format("%.6f / %.6f", s.full_rms, s.full_max),
               format("%d / %d", s.paper_covered, s.full_covered)});
  }
  Table c({"shadow edge normal to x", "seen share needed: paper cell (per axis)", "full cell (smaller eigenvalue)"});
  for (const LateralCoverageRow& row : r.coverage) {
    c.add_row({format("%.0f deg", row.edge_deg), format("%.1f %%", 100.0 * row.paper_share),
               format("%.1f %%", 100.0 * row.full_share)});
  }
  return format("%.0f cm cells (pooled: 8 cm children), noiseless planes; slope_x truth 0; |error| = |(a, b) - truth|; "
                "coverage with tau = 0.8\n\n",
                100.0 * cfg.cell_width_m) +
         t.str() + "\nseen share of a cell (one side of a straight shadow edge) from which coverage passes\n\n" + c.str();
}

}  // namespace ccmap::experiments
