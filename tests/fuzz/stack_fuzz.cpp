// libFuzzer target: sequences of frame updates, moves, queries and exports on a
// Stack<CadreConfig>, decoded from the fuzz bytes. Invariants (a violation aborts):
//  - every status is a defined Status; a refused frame reports zero counts;
//  - per frame: used + every rejection reason == received; the stack's totals equal the sum of
//    the frames' counters; refused moves and frames are counted;
//  - no NaN/Inf in any query answer, exported record, pooled cell, or stored cell;
//  - a refused query answers zeros and kUnknown.
// Built and run by tools/fuzz (clang, -fsanitize=fuzzer,address,undefined).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "ccmap/map/stack.hpp"

namespace {

using S = ccmap::Stack<ccmap::CadreConfig>;

[[noreturn]] void fail(const char* what, int op) {
  std::fprintf(stderr, "ccmap stack fuzz: invariant violated at op %d: %s\n", op, what);
  std::abort();
}

/// Reads the fuzz bytes; zeros once exhausted.
struct Bytes {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t u8() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16); }
  float raw_float() {
    const std::uint32_t bits = u32();
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  /// A coordinate: mostly inside the map (+-32 m in 1/1024 m steps), sometimes a special value
  /// (edges, NaN, Inf, denormals, huge) or any bit pattern.
  float coord() {
    static const float kSpecial[] = {0.0F, -0.0F, std::numeric_limits<float>::quiet_NaN(),
                                     std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                                     std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                                     std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                                     ccmap::kMaxAbsCoordinateM, -ccmap::kMaxAbsCoordinateM, 1.0000001e5F, 1.28F, -1.28F,
                                     2.56F, 5.12F, 10.24F, -10.24F, 0.04F, 0.08F, 0.16F, 0.32F, 0.64F, 1e-30F, 1e30F};
    const std::uint8_t mode = u8();
    if (mode < 16) return raw_float();
    if (mode < 40) return kSpecial[u8() % (sizeof kSpecial / sizeof kSpecial[0])];
    return static_cast<float>(static_cast<std::int16_t>(u16())) * (1.0F / 1024.0F);
  }
  /// A value near `centre` (small int8 steps of 1/64), or a coordinate.
  float near(float centre) {
    const std::uint8_t mode = u8();
    if (mode < 24) return coord();
    return centre + static_cast<float>(static_cast<std::int8_t>(u8())) * (1.0F / 64.0F);
  }
};

bool finite_result(const ccmap::QueryResult& q) {
  return std::isfinite(q.cell_width_m) && std::isfinite(q.height_m) && std::isfinite(q.slope_x) &&
         std::isfinite(q.slope_y) && std::isfinite(q.inclination) && std::isfinite(q.normal_variance) &&
         std::isfinite(q.elevation_variance) && std::isfinite(q.weight) &&
         static_cast<int>(q.cell_class) <= static_cast<int>(ccmap::CellClass::kDropOff);
}

void check_query(const ccmap::QueryResult& q, int op) {
  if (!finite_result(q)) fail("non-finite query answer", op);
  if (q.status != ccmap::Status::kOk) {
    if (q.height_m != 0.0F || q.weight != 0.0F || q.normal_variance != 0.0F ||
        q.cell_class != ccmap::CellClass::kUnknown) {
      fail("a refused query answered non-zero numbers", op);
    }
  }
}

bool finite_cell(const ccmap::CcmCell& c) {
  return std::isfinite(c.weight) && std::isfinite(c.mean_x) && std::isfinite(c.mean_y) && std::isfinite(c.mean_z) &&
         std::isfinite(c.s_xx) && std::isfinite(c.s_yy) && std::isfinite(c.s_zz) && std::isfinite(c.s_xz) &&
         std::isfinite(c.s_yz);
}

/// The documented partition of a frame's received points (FrameCounters, map/types.hpp): the
/// refusals, the used points and the four gate outcomes of the frame itself.
std::uint32_t sum_of_reasons(const ccmap::FrameCounters& c) {
  return c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map + c.too_noisy +
         c.gated_finer + c.gated_occluded + c.gated_held + c.gated_pool_full;
}

void add(ccmap::FrameCounters& t, const ccmap::FrameCounters& f) {
  t.received += f.received;
  t.used += f.used;
  t.rejected_non_finite += f.rejected_non_finite;
  t.rejected_out_of_range += f.rejected_out_of_range;
  t.rejected_weight += f.rejected_weight;
  t.outside_map += f.outside_map;
  t.too_noisy += f.too_noisy;
  t.gated_finer += f.gated_finer;
  t.gated_occluded += f.gated_occluded;
  t.gated_held += f.gated_held;
  t.gated_pool_full += f.gated_pool_full;
  t.gated_admitted += f.gated_admitted;
  t.gated_dropped += f.gated_dropped;
  t.reseeded_cells += f.reseeded_cells;
  t.merged_cells += f.merged_cells;
  t.skipped_budget += f.skipped_budget;
  t.corrupted_cells += f.corrupted_cells;
  t.corrupted_slots += f.corrupted_slots;
  t.free_rays += f.free_rays;
  t.free_rays_refused += f.free_rays_refused;
  t.cleared_cells += f.cleared_cells;
  t.drop_cells += f.drop_cells;
}
static_assert(sizeof(ccmap::FrameCounters) == 22U * sizeof(std::uint32_t), "add() sums every FrameCounters member");

S g_stack;                                      // ~0.5 MB: static storage, as in flight
ccmap::CellRecord g_records[64 * 64];           // largest layer
ccmap::PointXYZ g_points[256];

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  // Parameters: the CADRE defaults with fixed thresholds (calibration is tested elsewhere and
  // would dominate the time per input), in a few variants.
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  for (int k = 0; k < S::kLayerCount; ++k) {
    params.normal_variance_threshold[static_cast<std::size_t>(k)] = 2.0e-4F * static_cast<float>(1 << k);
  }
  const std::uint8_t variant = in.u8();
  switch (variant % 5) {
    case 1: params.noise.set_weight_mode(ccmap::sensor::WeightMode::kInverseVariance, 1.0F); break;
    case 2: params.noise = ccmap::sensor::NoiseModel::lidar(ccmap::sensor::LidarParams{0.0005F, 0.0F}); break;
    case 3: params.weight_limit = 4.0F; break;  // the limiter engages at once
    case 4:
      params.finest_cell_width_m = in.coord();  // init may refuse it; then everything is refused
      params.weight_limit = in.coord();
      break;
    default: break;
  }
  const ccmap::Status init_status = g_stack.init(params);
  const bool initialised = init_status == ccmap::Status::kOk;
  ccmap::FrameCounters expected_totals{};
  std::uint32_t expected_rejected_frames = 0;
  float robot_x = 0.0F, robot_y = 0.0F;

  for (int op = 0; op < 64 && in.n > 0; ++op) {
    switch (in.u8() % 8) {
      case 0: {  // move
        const float x = in.near(robot_x), y = in.near(robot_y);
        const std::uint32_t rejected_before = g_stack.rejected_moves();
        const ccmap::Status s = g_stack.move_to(x, y);
        if (s == ccmap::Status::kOk) {
          robot_x = x, robot_y = y;
        } else if (initialised && g_stack.rejected_moves() != rejected_before + 1U) {
          fail("a refused move was not counted", op);
        }
        break;
      }
      case 1:    // frame in the map frame
      case 7: {  // many copies of one point (one cell, the limiter)
        const bool copies = (op & 1) != 0 && in.u8() > 128;
        const std::size_t n = copies ? in.u8() : in.u8() % 48U;
        const ccmap::PointXYZ origin{in.near(robot_x), in.near(robot_y), in.near(0.5F)};
        for (std::size_t i = 0; i < n; ++i) {
          g_points[i] = (copies && i > 0) ? g_points[0]
                                          : ccmap::PointXYZ{in.near(robot_x), in.near(robot_y), in.near(0.0F)};
        }
        ccmap::FrameCounters c{};
        c.received = 12345U;
        const bool null_points = in.u8() == 0xFF;
        const ccmap::Status s = g_stack.update_frame(null_points ? nullptr : g_points, n, origin, &c);
        if (s == ccmap::Status::kOk) {
          if (c.received != n) fail("received != n", op);
          if (sum_of_reasons(c) != c.received) fail("frame counters do not add up", op);
          add(expected_totals, c);
        } else {
          if (sum_of_reasons(c) != 0U || c.received != 0U) fail("a refused frame reported counts", op);
          if (initialised) ++expected_rejected_frames;
        }
        break;
      }
      case 2: {  // frame in the sensor frame
        ccmap::Pose pose{};
        const bool wild = in.u8() < 32;
        // Mostly rotations (a yaw from a normalised byte pair); sometimes any 9 floats, which
        // the stack must refuse unless they happen to form a rotation.
        const float yc = static_cast<float>(static_cast<std::int8_t>(in.u8())) + 0.5F;
        const float ys = static_cast<float>(static_cast<std::int8_t>(in.u8()));
        const float norm = std::sqrt(yc * yc + ys * ys);
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            const float yaw_entry = (r == 2 || c == 2) ? (r == c ? 1.0F : 0.0F)
                                    : (r == c) ? yc / norm : (r == 0 ? -ys / norm : ys / norm);
            pose.rotation[r][c] = wild ? in.coord() : yaw_entry;
          }
        }
        pose.translation = ccmap::PointXYZ{in.near(robot_x), in.near(robot_y), in.near(0.5F)};
        const std::size_t n = in.u8() % 48U;
        for (std::size_t i = 0; i < n; ++i) g_points[i] = ccmap::PointXYZ{in.near(1.0F), in.near(0.0F), in.near(-0.5F)};
        ccmap::FrameCounters c{};
        const ccmap::Status s = g_stack.update_frame_sensor(g_points, n, pose, &c);
        if (s == ccmap::Status::kOk) {
          if (c.received != n || sum_of_reasons(c) != c.received) fail("sensor frame counters do not add up", op);
          add(expected_totals, c);
        } else {
          if (sum_of_reasons(c) != 0U || c.received != 0U) fail("a refused sensor frame reported counts", op);
          if (initialised) ++expected_rejected_frames;
        }
        break;
      }
      case 3: {
        const float x = in.near(robot_x), y = in.near(robot_y);
        check_query(g_stack.query(x, y), op);
        break;
      }
      case 4: {
        const int layer = static_cast<int>(in.u8() % 8U) - 1;
        const float x = in.near(robot_x), y = in.near(robot_y);
        check_query(g_stack.query_layer(layer, x, y), op);
        break;
      }
      case 5: {
        const int layer = static_cast<int>(in.u8() % 7U) - 1;
        std::size_t written = 0;
        const ccmap::Status s = g_stack.export_layer(layer, g_records, sizeof g_records / sizeof g_records[0], &written);
        if (s != ccmap::Status::kOk && written != 0U) fail("a refused export wrote records", op);
        for (std::size_t i = 0; i < written; ++i) {
          const ccmap::CellRecord& r = g_records[i];
          // An observed cell (weight > 0), or an unobserved drop-off (weight 0, its bound as height).
          const bool drop = r.cell_class == ccmap::CellClass::kDropOff && !(r.weight > 0.0F) && !(r.weight < 0.0F);
          if (!(r.weight > 0.0F || drop) || !std::isfinite(r.weight) || !std::isfinite(r.height_m) || !std::isfinite(r.slope_x) ||
              !std::isfinite(r.slope_y) || !std::isfinite(r.normal_variance) || !std::isfinite(r.elevation_variance) ||
              !std::isfinite(r.centre_x) || !std::isfinite(r.centre_y)) {
            fail("non-finite or empty exported record", op);
          }
        }
        break;
      }
      case 6: {
        const int layer = static_cast<int>(in.u8() % 7U) - 1;
        const bool raw = in.u8() < 64;
        const ccmap::CellIndex centre = g_stack.layer_centre(layer < 0 ? 0 : layer);
        const ccmap::CellIndex index =
            raw ? ccmap::CellIndex{static_cast<std::int32_t>(in.u32()), static_cast<std::int32_t>(in.u32())}
                : ccmap::CellIndex{centre.x + static_cast<std::int8_t>(in.u8()), centre.y + static_cast<std::int8_t>(in.u8())};
        if (!finite_cell(g_stack.pooled_cell(layer, index))) fail("non-finite pooled cell", op);
        break;
      }
      default: break;
    }
  }
  if (initialised) {
    if (std::memcmp(&expected_totals, &g_stack.total_counters(), sizeof expected_totals) != 0) {
      fail("total counters differ from the sum of the frames", -1);
    }
    if (g_stack.rejected_frames() != expected_rejected_frames) fail("rejected frames miscounted", -1);
    // Every stored float finite.
    const S::FineCell* fine = g_stack.fine_layer().storage();
    for (std::size_t i = 0; i < g_stack.fine_layer().cell_count(); ++i) {
      if (!std::isfinite(fine[i].height) || !std::isfinite(fine[i].variance) || !std::isfinite(fine[i].weight)) {
        fail("non-finite fine cell", -1);
      }
    }
    for (int c = 0; c < S::kCcmLayerCount; ++c) {
      const ccmap::CcmCell* cells = g_stack.ccm_layer(c).storage();
      for (std::size_t i = 0; i < g_stack.ccm_layer(c).cell_count(); ++i) {
        if (!finite_cell(cells[i])) fail("non-finite CCM cell", -1);
      }
    }
  } else if (g_stack.query(0.0F, 0.0F).status != ccmap::Status::kNotInitialised) {
    fail("a stack whose init failed answered a query", -1);
  }
  return 0;
}
