// Compile-time shape of a map stack and its run-time parameters.
//
// A stack (paper Fig. 2) is an optional piece-wise constant finest layer followed by CCM
// layers, each twice the cell width of the one before and centred on the robot. The sides (in
// cells, powers of two) are part of the type, so the whole map is one statically sized object;
// the cell widths are run-time parameters (finest width * 2^k) so one type serves several
// resolutions. See docs/design.md, "The CADRE preset", for the argument behind the sizes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap {

/// Cell type of the finest layer.
enum class FineKind : std::uint8_t {
  kNone = 0,    ///< no piece-wise constant layer: every layer is CCM
  kKalman = 1,  ///< Kalman height update (paper ref. [13])
  kOmg = 2,     ///< Optimal Mixture of Gaussians update (paper ref. [14])
};

/// CADRE-like stack: 4 cm Kalman layer, then 8/16/32/64 cm CCM layers (default widths), full
/// CCM cells (docs/design.md, "The CADRE preset", says why the full cell).
///   layer 0: 4 cm,  64 x 64  -> +-1.28 m around the robot
///   layer 1: 8 cm,  64 x 64  -> +-2.56 m
///   layer 2: 16 cm, 64 x 64  -> +-5.12 m
///   layer 3: 32 cm, 32 x 32  -> +-5.12 m
///   layer 4: 64 cm, 32 x 32  -> +-10.24 m
struct CadreConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 64;
  static constexpr std::array<std::int32_t, 4> kCcmSides{{64, 64, 32, 32}};
  static constexpr float kDefaultFinestCellWidthM = 0.04F;
};

/// One CCM layer of 256 x 256 cells (8 cm default: +-10.24 m), full CCM cells.
struct SingleCcmConfig {
  static constexpr FineKind kFineKind = FineKind::kNone;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 0;
  static constexpr std::array<std::int32_t, 1> kCcmSides{{256}};
  static constexpr float kDefaultFinestCellWidthM = 0.08F;
};

/// One Kalman layer of 256 x 256 cells (baseline).
struct SingleKalmanConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr std::int32_t kFineSide = 256;
  static constexpr std::array<std::int32_t, 0> kCcmSides{};
  static constexpr float kDefaultFinestCellWidthM = 0.08F;
};

/// One OMG layer of 256 x 256 cells (baseline).
struct SingleOmgConfig {
  static constexpr FineKind kFineKind = FineKind::kOmg;
  static constexpr std::int32_t kFineSide = 256;
  static constexpr std::array<std::int32_t, 0> kCcmSides{};
  static constexpr float kDefaultFinestCellWidthM = 0.08F;
};

/// A configuration with another CCM cell kind: WithCcmCell<CadreConfig, CcmCellKind::kPaper> is
/// the CADRE stack with the paper's 9-float cells (PaperCell<Config> below). Everything else of
/// Base is kept.
template <typename Base, CcmCellKind Kind>
struct WithCcmCell : Base {
  // cppcheck-suppress duplInheritedMember ; hiding Base::kCcmCell is the point of WithCcmCell
  static constexpr CcmCellKind kCcmCell = Kind;
};
template <typename Base>
using PaperCell = WithCcmCell<Base, CcmCellKind::kPaper>;

namespace detail {
template <typename Config, typename = void>
struct ConfigCcmCellKind {
  static constexpr CcmCellKind value = CcmCellKind::kFull;
};
template <typename Config>
struct ConfigCcmCellKind<Config, std::void_t<decltype(Config::kCcmCell)>> {
  static constexpr CcmCellKind value = Config::kCcmCell;
};
}  // namespace detail

/// The CCM cell kind of a Config: its `kCcmCell` member (CcmCellKind), the full cell if it has
/// none (so a Config written before the member existed keeps compiling, with full cells).
template <typename Config>
inline constexpr CcmCellKind kConfigCcmCell = detail::ConfigCcmCellKind<Config>::value;

namespace detail {
template <typename Config, typename = void>
struct ConfigOutlierGate {
  static constexpr bool value = true;
};
template <typename Config>
struct ConfigOutlierGate<Config, std::void_t<decltype(Config::kOutlierGate)>> {
  static constexpr bool value = Config::kOutlierGate;
};
template <typename Config, typename = void>
struct ConfigCcmHeldSlots {
  static constexpr std::size_t value = 0U;  // the update path's default (map/update/held_pool.hpp)
};
template <typename Config>
struct ConfigCcmHeldSlots<Config, std::void_t<decltype(Config::kCcmHeldSlots)>> {
  static constexpr std::size_t value = Config::kCcmHeldSlots;
};
template <typename Config, typename = void>
struct ConfigFineHeldSlots {
  static constexpr std::size_t value = 0U;
};
template <typename Config>
struct ConfigFineHeldSlots<Config, std::void_t<decltype(Config::kFineHeldSlots)>> {
  static constexpr std::size_t value = Config::kFineHeldSlots;
};
}  // namespace detail

/// Whether a Config compiles the outlier gate in: its `kOutlierGate` member (bool), true if it
/// has none. A stack whose Config says false carries none of the gate's memory (the held-point
/// pools, the per-cell tags) or instructions, and refuses StackParams::outlier_gate_sigma > 0
/// at init; with the gate compiled in, outlier_gate_sigma = 0 switches it off at run time.
template <typename Config>
inline constexpr bool kConfigOutlierGate = detail::ConfigOutlierGate<Config>::value;

/// The held-point slots of a Config with the gate, per pool (the CCM layers', the finest
/// layer's): its `kCcmHeldSlots` / `kFineHeldSlots` members, or 0 for the update path's defaults
/// (map/update/held_pool.hpp: kHeldSlots, kFineHeldSlots). A power of two (held_pool.hpp asserts
/// it: slot indices are masked to the pool, map/detail/integrity.hpp).
template <typename Config>
inline constexpr std::size_t kConfigCcmHeldSlots = detail::ConfigCcmHeldSlots<Config>::value;
template <typename Config>
inline constexpr std::size_t kConfigFineHeldSlots = detail::ConfigFineHeldSlots<Config>::value;

/// A configuration without the outlier gate compiled in: WithoutOutlierGate<CadreConfig> is the
/// CADRE stack that runs the paper's update and carries no gate memory. Everything else of Base
/// is kept.
template <typename Base>
struct WithoutOutlierGate : Base {
  static constexpr bool kOutlierGate = false;
};
/// A configuration with or without free space from lines of sight (docs/design.md, "Free space
/// from lines of sight"): WithFreeSpace<CadreConfig, false> is the CADRE stack that carries none
/// of its memory (4 bytes per cell, the ray scratch) and never clears a cell or marks a drop-off.
template <typename Base, bool kOn>
struct WithFreeSpace : Base {
  // cppcheck-suppress duplInheritedMember ; hiding Base::kFreeSpace is the point of WithFreeSpace
  static constexpr bool kFreeSpace = kOn;
};

namespace detail {
template <typename Config, typename = void>
struct ConfigFreeSpace {
  static constexpr bool value = true;
};
template <typename Config>
struct ConfigFreeSpace<Config, std::void_t<decltype(Config::kFreeSpace)>> {
  static constexpr bool value = Config::kFreeSpace;
};
}  // namespace detail

/// Whether a Config carries free space: its `kFreeSpace` member, true if it has none (every
/// preset of the library carries it; StackParams::free_space_rays = 0 switches it off at run time).
template <typename Config>
inline constexpr bool kConfigFreeSpace = detail::ConfigFreeSpace<Config>::value;

/// A Config whose sampled walk takes `kCandidatesPerRay` candidates per walked line of sight
/// (map/visibility/free_space.hpp, FreeSpace::choose; the presets: 4, detail::kRayCandidates). One
/// is the even subsample of the frame's points.
template <typename Base, std::size_t kCandidatesPerRay>
struct WithRayCandidates : Base {
  static constexpr std::size_t kRayCandidates = kCandidatesPerRay;
};

/// Largest number of layers a stack may have (bounds the per-layer parameter arrays).
inline constexpr int kMaxLayers = 8;

/// Run-time parameters of a stack. Start from default_stack_params() and change what you need.
/// Every member starts at zero (init() refuses such params), never uninitialised.
struct StackParams {
  float finest_cell_width_m = 0.0F;   ///< width of layer 0; layer k is 2^k times wider
  float weight_limit = 0.0F;          ///< W_l of CCM and OMG cells (eqs. 6-7)
  float coverage_tau = 0.0F;          ///< tau of eq. (12), paper: 0.8
  float min_weight = 0.0F;            ///< a cell with less accumulated weight is unknown
  float obstacle_fraction = 0.0F;     ///< minimum obstacle height as a share of the cell width (paper: 0.75)
  float max_inclination = 0.0F;       ///< steeper gradients (dz/dxy, not degrees) are kSteep
  float kalman_min_variance = 0.0F;   ///< variance floor of Kalman cells (m^2)
  /// Normal-variance thresholds (m^2) per layer; a value <= 0 means "calibrate at init" from
  /// obstacle_fraction (Section IV-E: step of the minimum height at 50 % coverage).
  std::array<float, kMaxLayers> normal_variance_threshold{};
  /// Finest (piece-wise constant) layer: largest range sigma_m it accepts (m). Section IV-G
  /// constrains CCM layers only; the default is the layer's own IV-G bound
  /// (sensor::constant_layer_max_sigma). Must stay below layer 1's IV-G bound.
  float finest_max_sigma_m = 0.0F;
  /// Outlier gate (docs/design.md, "Outlier gate and change"): a point farther from its cell
  /// than this many standard deviations of what the cell and the sensor model predict is held
  /// back until the end of its frame, which drops it as an outlier or admits it as a change.
  /// 0 switches the gate off: every point is trusted, the paper's update, bitwise.
  float outlier_gate_sigma = 0.0F;
  /// Change rule (cell/outlier_gate.hpp, change_verdict): the points of a cell inside and
  /// outside its gate are each a surface of their own when they number at least
  /// change_min_points (point counts, whatever their weights) and at least change_share of the
  /// cell's points. Held points that are a surface are merged into the cell beside the points
  /// inside (a rock or box covering part of it) or, when those are none, replace them (re-seed:
  /// the ground after a pose jump, a cell first seeded by outliers, a rock covering it); held
  /// points that are no surface are dropped as outliers.
  float change_min_points = 0.0F;
  float change_share = 0.0F;
  /// Frame budget (docs/integration.md, "The frame budget"): a frame update processes at most
  /// frame_point_budget points (0: no limit) and starts no chunk of kFrontChunkPoints (256)
  /// points once frame_time_budget_us microseconds of the platform's monotonic clock have passed
  /// since it began (0: no limit; the overrun is at most one chunk). With either limit set the
  /// points are taken chunk by chunk in an interleaved (bit-reversed) order, so that a frame cut
  /// short covers the whole field of view at a lower density; each chunk is processed whole or
  /// not at all, and the points left are counted (FrameCounters::skipped_budget). With both 0
  /// the chunks are taken in order (the update of earlier versions, bitwise).
  std::uint32_t frame_point_budget = 0U;
  std::uint32_t frame_time_budget_us = 0U;
  /// Free space from lines of sight (docs/design.md, "Free space from lines of sight"): the
  /// lines of sight walked per frame, from the sensor to points of the frame: each of an evenly
  /// spread subsample's points brings 4 candidates (WithRayCandidates), and those whose lines of
  /// sight cross hidden ground or a contradicted cell are walked first (a whole number in [0, 65535]; 0 switches the feature off at run time: no
  /// cell is cleared, no drop-off marked, the frame costs what it did without it). A stack whose
  /// Config has kFreeSpace = false ignores it. On a stack that carries the viewshed table
  /// (WithEveryLineOfSight, map/visibility/sight_table.hpp) 65535 casts every line of sight of
  /// the frame and 65536 - k those of one point in k (k = 2, 4, 8, 16) instead of walking rays.
  float free_space_rays = 0.0F;
  /// Frames (a whole number in [1, 255]) in which rays must pass clearly below a cell's surface,
  /// with no ray ending on it in between, before the cell is cleared.
  float free_space_clear_frames = 0.0F;
  /// The sensor's viewing direction in the sensor frame of update_frame_sensor (any length; all
  /// zero: not given). A sensor-frame point whose dot product with it is <= 0 lies behind the
  /// sensor: its line of sight is refused (counted in FrameCounters::free_rays_refused). Map-frame
  /// input carries no orientation, so update_frame has no "behind".
  std::array<float, 3> sensor_view_axis{};
  sensor::NoiseModel noise;           ///< routes points and gives their weight and variance
};

/// CADRE defaults: W_l = 1000, tau = 0.8, min weight 5, obstacles at 75 % of a cell,
/// 20 deg maximum inclination (tan 20 deg = 0.364), the CADRE stereo model, calibrated
/// thresholds; the outlier gate at 3 sigma with the change rule 3 points / 8 % (docs/design.md,
/// "Outlier gate and change", says how they were chosen); free space from 256 lines of sight per
/// frame (within the stage's share of the flight cycle's budget), a cell cleared after 3 contradicting frames, no sensor view axis (docs/design.md, "Free
/// space from lines of sight"). Set outlier_gate_sigma = 0 for the paper's update,
/// free_space_rays = 0 for no free space.
[[nodiscard]] StackParams default_stack_params(float finest_cell_width_m) noexcept;

}  // namespace ccmap
