#include "map_adapter.hpp"

#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/product/publish.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/registration/registration.hpp"

namespace ccmap::python {
namespace {

template <typename Config>
class StackAdapter final : public MapAdapter {
 public:
  using StackType = Stack<Config>;

  Status init(const StackParams& params) override { return stack_->init(params); }
  Status move_to(float x, float y) override { return stack_->move_to(x, y); }
  Status update_frame(const PointXYZ* points, const float* weights, std::size_t n, const PointXYZ& sensor_origin,
                      FrameCounters* counters) override {
    return stack_->update_frame(points, weights, n, sensor_origin, counters);
  }
  Status update_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& pose,
                             FrameCounters* counters) override {
    return stack_->update_frame_sensor(points, n, pose, counters);
  }
  RegistrationResult register_frame(const PointXYZ* points, std::size_t n, const PointXYZ& sensor_origin,
                                    const RegistrationParams& params) const override {
    return ccmap::register_frame(*stack_, points, n, sensor_origin, params);
  }
  RegistrationResult register_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& pose,
                                           const RegistrationParams& params) const override {
    return ccmap::register_frame_sensor(*stack_, points, n, pose, params);
  }
  RegistrationResult align_snapshot(const std::uint8_t* data, std::size_t size, const float (&offset)[3],
                                    const RegistrationParams& params, float* centre_x, float* centre_y,
                                    std::uint32_t* cells) const override {
    const AlignmentResult a = ccmap::align_snapshot(*stack_, data, size, MapOffset{offset[0], offset[1], offset[2]}, params);
    *centre_x = a.centre_x_m;
    *centre_y = a.centre_y_m;
    *cells = a.cells;
    return a.correction;
  }
  QueryResult query(float x, float y) const override { return stack_->query(x, y); }
  QueryResult query_layer(int layer, float x, float y) const override { return stack_->query_layer(layer, x, y); }
  Status export_layer(int layer, std::vector<CellRecord>* cells) const override {
    cells->resize(StackType::layer_capacity(layer));
    std::size_t written = 0U;
    const Status status = stack_->export_layer(layer, cells->data(), cells->size(), &written);
    cells->resize(written);
    return status;
  }
  Status save(std::vector<std::uint8_t>* bytes) const override {
    bytes->resize(snapshot_size<Config>());
    std::size_t written = 0U;
    const Status status = save_snapshot(*stack_, bytes->data(), bytes->size(), &written);
    bytes->resize(written);
    return status;
  }
  Status load(const std::uint8_t* data, std::size_t size) override { return load_snapshot(*stack_, data, size); }

  bool initialised() const override { return stack_->initialised(); }
  int layer_count() const override { return StackType::kLayerCount; }
  std::int32_t layer_side(int layer) const override { return StackType::layer_side(layer); }
  bool layer_is_ccm(int layer) const override { return StackType::layer_is_ccm(layer); }
  float layer_cell_width(int layer) const override { return stack_->layer_cell_width(layer); }
  CellIndex layer_centre(int layer) const override { return stack_->layer_centre(layer); }
  float normal_variance_threshold(int layer) const override { return stack_->normal_variance_threshold(layer); }
  const StackParams& params() const override { return stack_->params(); }
  const FrameCounters& total_counters() const override { return stack_->total_counters(); }
  std::uint32_t rejected_moves() const override { return stack_->rejected_moves(); }
  std::uint32_t rejected_frames() const override { return stack_->rejected_frames(); }
  std::uint64_t last_update_ns() const override { return stack_->last_update_ns(); }

  Status validate_params(const StackParams& params) const override { return StackType::validate_params(params); }
  Status set_params(const StackParams& params, std::uint32_t* needs_reinit) override {
    return stack_->set_params(params, needs_reinit);
  }
  Status reset_counters() override { return stack_->reset_counters(); }
  Status state_status() const override { return stack_->state_status(); }
  std::uint32_t frames_since_reset() const override { return stack_->frames_since_reset(); }
  std::uint32_t accepted_frames() const override { return stack_->accepted_frames(); }
  std::uint32_t params_changes() const override { return stack_->params_changes(); }
  const FrameCounters& last_frame() const override { return stack_->last_frame(); }
  std::uint32_t observed_cells(int layer) const override { return stack_->observed_cells(layer); }
  Status product(int layer, bool layer_answer, const float (&pose)[4], std::uint32_t tag, std::uint32_t params_crc,
                 std::vector<std::uint8_t>* bytes) const override {
    const auto side = static_cast<std::uint32_t>(StackType::layer_side(layer < 0 ? 0 : layer));
    std::vector<std::uint32_t> storage(3U * product_size(side, side) / 4U + 3U);
    ProductBuffers buffers{};
    Status status = product_buffers_init(&buffers, storage.data(), storage.size() * sizeof(std::uint32_t));
    if (status != Status::kOk) {
      return status;
    }
    ProductSpec spec{};
    spec.layer = layer;
    spec.answer = layer_answer ? ProductAnswer::kLayer : ProductAnswer::kStack;
    spec.pose_x = pose[0];
    spec.pose_y = pose[1];
    spec.pose_z = pose[2];
    spec.pose_yaw = pose[3];
    spec.tag = tag;
    spec.params_crc = params_crc;
    status = publish_product(*stack_, spec, buffers);
    if (status != Status::kOk) {
      return status;
    }
    bytes->resize(product_size(side, side));
    std::size_t written = 0U;
    status = product_read(buffers, bytes->data(), bytes->size(), &written);
    bytes->resize(written);
    return status;
  }

 private:
  std::unique_ptr<StackType> stack_ = std::make_unique<StackType>();  // MBs: never on the C++ stack
};

template <typename Config>
std::unique_ptr<MapAdapter> make_adapter() {
  return std::make_unique<StackAdapter<Config>>();
}

template <typename Config>
Preset preset(const char* name) {
  if constexpr (Stack<Config>::kCcmLayerCount > 0) {
    return Preset{name, Config::kDefaultFinestCellWidthM, Stack<Config>::kLayerCount, snapshot_size<Config>(),
                  &make_adapter<Config>, snapshot_size<PaperCell<Config>>(), &make_adapter<PaperCell<Config>>};
  } else {
    return Preset{name, Config::kDefaultFinestCellWidthM, Stack<Config>::kLayerCount, snapshot_size<Config>(),
                  &make_adapter<Config>, 0U, nullptr};
  }
}

}  // namespace

const std::vector<Preset>& presets() {
  static const std::vector<Preset> all = {preset<CadreConfig>("cadre"), preset<SingleCcmConfig>("ccm"),
                                          preset<SingleKalmanConfig>("kf"), preset<SingleOmgConfig>("omg")};
  return all;
}

const Preset* find_preset(const std::string& name) {
  for (const Preset& p : presets()) {
    if (name == p.name) return &p;
  }
  return nullptr;
}

Pose make_pose(const float (&rotation)[3][3], const float (&translation)[3]) {
  Pose pose{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) pose.rotation[r][c] = rotation[r][c];
  }
  pose.translation = PointXYZ{translation[0], translation[1], translation[2]};
  return pose;
}

}  // namespace ccmap::python
