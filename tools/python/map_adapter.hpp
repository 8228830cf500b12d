// Host adapter between the Python module (ccmap_module.cpp) and the library's Stack<Config>
// templates: one run-time interface over the four presets of the `ccmap` CLI (cadre, ccm, kf,
// omg; tools/cli/map_runner.cpp has the same names and types). It speaks the library's own
// types and Status codes and knows nothing of Python: every refusal is the library's Status.
// The stack lives on the heap (MBs), owned by the adapter; the adapter holds no Python object.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/map/config.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap::python {

class MapAdapter {
 public:
  virtual ~MapAdapter() = default;

  [[nodiscard]] virtual Status init(const StackParams& params) = 0;
  [[nodiscard]] virtual Status move_to(float x, float y) = 0;
  /// Map-frame points; `weights` is nullptr (the noise model weighs) or one weight per point.
  [[nodiscard]] virtual Status update_frame(const PointXYZ* points, const float* weights, std::size_t n,
                                            const PointXYZ& sensor_origin, FrameCounters* counters) = 0;
  /// Sensor-frame points, p_map = R p + t.
  [[nodiscard]] virtual Status update_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& pose,
                                                   FrameCounters* counters) = 0;
  /// Registration (registration/registration.hpp): map-frame points with the sensor origin.
  [[nodiscard]] virtual RegistrationResult register_frame(const PointXYZ* points, std::size_t n,
                                                          const PointXYZ& sensor_origin,
                                                          const RegistrationParams& params) const = 0;
  /// The same for sensor-frame points with the pose.
  [[nodiscard]] virtual RegistrationResult register_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& pose,
                                                                 const RegistrationParams& params) const = 0;
  /// Team alignment (registration/alignment.hpp) of a snapshot placed by `offset` (m); the
  /// rotation centre and the snapshot's usable cells in *centre_x, *centre_y, *cells.
  [[nodiscard]] virtual RegistrationResult align_snapshot(const std::uint8_t* data, std::size_t size, const float (&offset)[3],
                                                          const RegistrationParams& params, float* centre_x,
                                                          float* centre_y, std::uint32_t* cells) const = 0;
  [[nodiscard]] virtual QueryResult query(float x, float y) const = 0;
  [[nodiscard]] virtual QueryResult query_layer(int layer, float x, float y) const = 0;
  /// Every observed cell of `layer` (Stack::export_layer order: rows of increasing y).
  [[nodiscard]] virtual Status export_layer(int layer, std::vector<CellRecord>* cells) const = 0;
  /// The library's snapshot (persistence/snapshot.hpp) of the whole stack.
  [[nodiscard]] virtual Status save(std::vector<std::uint8_t>* bytes) const = 0;
  /// All-or-nothing: on failure the stack is unchanged (kVersionMismatch: another preset's snapshot).
  [[nodiscard]] virtual Status load(const std::uint8_t* data, std::size_t size) = 0;

  [[nodiscard]] virtual bool initialised() const = 0;
  [[nodiscard]] virtual int layer_count() const = 0;
  [[nodiscard]] virtual std::int32_t layer_side(int layer) const = 0;
  [[nodiscard]] virtual bool layer_is_ccm(int layer) const = 0;
  [[nodiscard]] virtual float layer_cell_width(int layer) const = 0;
  [[nodiscard]] virtual CellIndex layer_centre(int layer) const = 0;
  [[nodiscard]] virtual float normal_variance_threshold(int layer) const = 0;
  [[nodiscard]] virtual const StackParams& params() const = 0;
  [[nodiscard]] virtual const FrameCounters& total_counters() const = 0;
  [[nodiscard]] virtual std::uint32_t rejected_moves() const = 0;
  [[nodiscard]] virtual std::uint32_t rejected_frames() const = 0;
  [[nodiscard]] virtual std::uint64_t last_update_ns() const = 0;

  // ---- the flight interface (ccmap.h, "parameters as commands", "health", "the map product") ----
  /// Stack<Config>::validate_params: init()'s checks, nothing touched.
  [[nodiscard]] virtual Status validate_params(const StackParams& params) const = 0;
  /// Stack::set_params (cells kept); *needs_reinit: the param_field mask of a refusal.
  [[nodiscard]] virtual Status set_params(const StackParams& params, std::uint32_t* needs_reinit) = 0;
  [[nodiscard]] virtual Status reset_counters() = 0;
  [[nodiscard]] virtual Status state_status() const = 0;
  [[nodiscard]] virtual std::uint32_t frames_since_reset() const = 0;
  [[nodiscard]] virtual std::uint32_t accepted_frames() const = 0;
  [[nodiscard]] virtual std::uint32_t params_changes() const = 0;
  [[nodiscard]] virtual const FrameCounters& last_frame() const = 0;
  [[nodiscard]] virtual std::uint32_t observed_cells(int layer) const = 0;
  /// The product of one layer's window (product/publish.hpp), its bytes in *bytes.
  [[nodiscard]] virtual Status product(int layer, bool layer_answer, const float (&pose)[4], std::uint32_t tag,
                                       std::uint32_t params_crc, std::vector<std::uint8_t>* bytes) const = 0;
};

/// One preset: its CLI name, the library's configuration behind it, factories for its full-cell
/// configuration and, for the presets with CCM layers, the paper-cell one (PaperCell<Config>:
/// the CLI's --paper-cell).
struct Preset {
  const char* name;                   ///< cadre, ccm, kf, omg
  float default_cell_width_m;         ///< Config::kDefaultFinestCellWidthM
  int layer_count;                    ///< Stack<Config>::kLayerCount
  std::size_t snapshot_bytes;         ///< snapshot_size<Config>()
  std::unique_ptr<MapAdapter> (*make)();  ///< an uninitialised stack (full CCM cells)
  std::size_t paper_snapshot_bytes;   ///< snapshot_size<PaperCell<Config>>(); 0 without CCM layers
  std::unique_ptr<MapAdapter> (*make_paper)();  ///< the paper's 9-float cells; nullptr without CCM layers
};

/// The four presets, in the CLI's order.
const std::vector<Preset>& presets();
/// nullptr for an unknown name.
const Preset* find_preset(const std::string& name);

/// The one place that knows how ccmap::Pose stores its rotation (row-major, sensor -> map) and
/// translation (metres, map frame).
Pose make_pose(const float (&rotation)[3][3], const float (&translation)[3]);

}  // namespace ccmap::python
