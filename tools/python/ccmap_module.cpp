// The Python module `ccmap`: the library's Stack<Config> presets behind one class, Map.
// Host only (pybind11 + NumPy); never part of the flight core. docs/python.md is the user's
// page; this comment states the contracts the code below keeps.
//
//  - Frames: every position is in the map frame of the stack, metres, relative to the origin
//    the caller chose (subtract absolute coordinates in float64 first, as in C++).
//  - Arrays: points are (N, 3), query positions (N, 2), weights (N,), float32 or float64 only;
//    anything else is refused before the library sees it (StatusError "invalid_argument"), so
//    the map is unchanged. float64 values are rounded to the nearest float32 (as numpy's
//    astype(np.float32)). A C-contiguous, aligned, native float32 (N, 3) array is handed to the
//    library without a copy; other layouts are copied. Values inside a well-formed array are the
//    library's business: NaN/Inf/out-of-range points and bad weights are counted per point and
//    the good points are used, as in C++. Sensor origins, rotations and translations take any
//    real numeric array-like of the right shape.
//  - Refusals raise ccmap.StatusError (a ValueError) whose .status is the library's status name
//    ("non_finite_input", "invalid_argument", ...) and whose message starts with it; unknown
//    keyword arguments and non-numeric parameters raise TypeError.
//  - The map owns its Stack (heap, via MapAdapter); it holds no Python object. Results are
//    copies (dicts, new NumPy arrays). Every call into the library runs with the GIL held and
//    no Python code in between (arguments are converted before, results built after), so calls
//    on one Map from several Python threads are serialised: safe, not parallel.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ccmap/capi_params.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/param_fields.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/product/product_format.hpp"
#include "ccmap/sensor/noise_model.hpp"
#include "global_map.hpp"
#include "map_adapter.hpp"

namespace py = pybind11;

namespace ccmap::python {
namespace {

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

/// A refusal: the library's Status (or the one the library gives for the same fault, e.g.
/// kInvalidArgument for inconsistent sizes) and what was refused.
class StatusError : public std::runtime_error {
 public:
  StatusError(Status status, const std::string& what)
      : std::runtime_error(std::string(to_string(status)) + ": " + what), status_(status) {}
  [[nodiscard]] Status status() const { return status_; }

 private:
  Status status_;
};

void check(Status status, const std::string& what) {
  if (status != Status::kOk) throw StatusError(status, what);
}

// The Python type ccmap.StatusError; created once at import, lives as long as the interpreter.
py::handle g_status_error_type;

void translate_status_error(std::exception_ptr error) {
  try {
    if (error) std::rethrow_exception(error);
  } catch (const StatusError& e) {
    py::object instance = py::reinterpret_borrow<py::object>(g_status_error_type)(e.what());
    instance.attr("status") = to_string(e.status());
    PyErr_SetObject(g_status_error_type.ptr(), instance.ptr());
  }
}

// ---------------------------------------------------------------------------------------------
// Counters and parameters: one table each
// ---------------------------------------------------------------------------------------------

struct CounterField {
  const char* name;
  std::uint32_t FrameCounters::*member;
};
// Every FrameCounters member, in declaration order. A new member goes here (one line).
constexpr CounterField kCounterFields[] = {
    {"received", &FrameCounters::received},
    {"used", &FrameCounters::used},
    {"rejected_non_finite", &FrameCounters::rejected_non_finite},
    {"rejected_out_of_range", &FrameCounters::rejected_out_of_range},
    {"rejected_weight", &FrameCounters::rejected_weight},
    {"outside_map", &FrameCounters::outside_map},
    {"too_noisy", &FrameCounters::too_noisy},
    {"gated_finer", &FrameCounters::gated_finer},
    {"gated_occluded", &FrameCounters::gated_occluded},
    {"gated_held", &FrameCounters::gated_held},
    {"gated_pool_full", &FrameCounters::gated_pool_full},
    {"gated_admitted", &FrameCounters::gated_admitted},
    {"gated_dropped", &FrameCounters::gated_dropped},
    {"reseeded_cells", &FrameCounters::reseeded_cells},
    {"merged_cells", &FrameCounters::merged_cells},
    {"skipped_budget", &FrameCounters::skipped_budget},
    {"corrupted_cells", &FrameCounters::corrupted_cells},
    {"corrupted_slots", &FrameCounters::corrupted_slots},
    {"free_rays", &FrameCounters::free_rays},
    {"free_rays_refused", &FrameCounters::free_rays_refused},
    {"cleared_cells", &FrameCounters::cleared_cells},
    {"drop_cells", &FrameCounters::drop_cells},
};
static_assert(sizeof(FrameCounters) == std::size(kCounterFields) * sizeof(std::uint32_t),
              "FrameCounters gained a member: add it to kCounterFields");

py::dict counters_dict(const FrameCounters& counters) {
  py::dict d;
  for (const CounterField& f : kCounterFields) d[f.name] = counters.*f.member;
  return d;
}

/// The float members of StackParams settable by name (keyword = member name).
struct ParamField {
  const char* name;
  float StackParams::*member;
};
constexpr ParamField kParamFields[] = {
    {"weight_limit", &StackParams::weight_limit},
    {"coverage_tau", &StackParams::coverage_tau},
    {"min_weight", &StackParams::min_weight},
    {"obstacle_fraction", &StackParams::obstacle_fraction},
    {"max_inclination", &StackParams::max_inclination},
    {"kalman_min_variance", &StackParams::kalman_min_variance},
    {"finest_max_sigma_m", &StackParams::finest_max_sigma_m},
    {"outlier_gate_sigma", &StackParams::outlier_gate_sigma},
    {"change_min_points", &StackParams::change_min_points},
    {"change_share", &StackParams::change_share},
    {"free_space_rays", &StackParams::free_space_rays},
    {"free_space_clear_frames", &StackParams::free_space_clear_frames},
};

// ---------------------------------------------------------------------------------------------
// Numbers and arrays in
// ---------------------------------------------------------------------------------------------

/// double -> float, rounded to nearest-even as IEEE-754 (and numpy's astype) does, including
/// the overflow to +-inf (a plain static_cast is undefined beyond FLT_MAX).
float narrow(double v) {
  const double magnitude = std::fabs(v);
  if (std::isfinite(v) && magnitude > static_cast<double>(std::numeric_limits<float>::max())) {
    // At or beyond FLT_MAX + half an ulp the tie goes to even, i.e. to infinity.
    const float rounded = magnitude >= 0x1.ffffffp+127 ? std::numeric_limits<float>::infinity()
                                                       : std::numeric_limits<float>::max();
    return std::signbit(v) ? -rounded : rounded;
  }
  return static_cast<float>(v);
}

/// A Python real number (int, float, numpy scalar) as float; TypeError otherwise.
float number_arg(py::handle value, const std::string& name) {
  if (PyBool_Check(value.ptr()) || PyUnicode_Check(value.ptr()) || PyBytes_Check(value.ptr()) ||
      PyComplex_Check(value.ptr())) {
    throw py::type_error(name + " must be a real number, not " + std::string(py::str(value.get_type().attr("__name__"))));
  }
  PyObject* as_float = PyNumber_Float(value.ptr());
  if (as_float == nullptr) {
    PyErr_Clear();
    throw py::type_error(name + " must be a real number, not " + std::string(py::str(value.get_type().attr("__name__"))));
  }
  const double v = PyFloat_AsDouble(as_float);
  Py_DECREF(as_float);
  return narrow(v);
}

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i > 0 ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string describe(const py::array& a) {
  return "got shape " + shape_text(a) + " and dtype " + std::string(py::str(a.dtype()));
}

py::array as_array(py::handle obj, const std::string& what, const std::string& wanted) {
  py::array a = py::array::ensure(obj);
  if (!a) throw StatusError(Status::kInvalidArgument, what + " must be " + wanted + ", got a " +
                                                           std::string(py::str(obj.get_type().attr("__name__"))));
  return a;
}

/// A float32 or float64 array of `ndim` dimensions whose last dimension is `columns` (0: 1-D,
/// any length); StatusError(invalid_argument) otherwise.
py::array float_array(py::handle obj, const std::string& what, int ndim, py::ssize_t columns) {
  const std::string wanted = ndim == 1 ? "an (N,) array of float32 or float64"
                                       : "an (N, " + std::to_string(columns) + ") array of float32 or float64";
  py::array a = as_array(obj, what, wanted);
  const bool float_type = py::isinstance<py::array_t<float>>(a) || py::isinstance<py::array_t<double>>(a);
  if (!float_type || a.ndim() != ndim || (ndim == 2 && a.shape(1) != columns)) {
    throw StatusError(Status::kInvalidArgument, what + " must be " + wanted + ", " + describe(a));
  }
  return a;
}

/// Element (i, j) of a float32/float64 array checked by float_array, as float.
template <int Dims>
class FloatReader {
 public:
  explicit FloatReader(const py::array& a) : a_(a), f32_(py::isinstance<py::array_t<float>>(a)) {}
  [[nodiscard]] float at(py::ssize_t i, py::ssize_t j = 0) const {
    const auto* base = static_cast<const char*>(a_.data());
    const py::ssize_t offset = i * a_.strides(0) + (Dims == 2 ? j * a_.strides(1) : 0);
    if (f32_) {
      float v;
      std::memcpy(&v, base + offset, sizeof v);
      return v;
    }
    double v;
    std::memcpy(&v, base + offset, sizeof v);
    return narrow(v);
  }

 private:
  const py::array& a_;
  bool f32_;
};

/// (N, 3) points: a view of the caller's memory when it is C-contiguous, aligned, native
/// float32, else a float32 copy. Keeps the array alive while the library reads it.
class Points {
 public:
  Points(py::handle obj, const std::string& what) : array_(float_array(obj, what, 2, 3)) {
    n_ = static_cast<std::size_t>(array_.shape(0));
    const bool packed = py::isinstance<py::array_t<float>>(array_) &&
                        array_.strides(1) == static_cast<py::ssize_t>(sizeof(float)) &&
                        (n_ <= 1U || array_.strides(0) == static_cast<py::ssize_t>(sizeof(PointXYZ))) &&
                        reinterpret_cast<std::uintptr_t>(array_.data()) % alignof(PointXYZ) == 0U;
    if (packed) {
      data_ = static_cast<const PointXYZ*>(array_.data());  // PointXYZ: three packed floats (types.hpp)
      return;
    }
    const FloatReader<2> r(array_);
    copy_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      const auto row = static_cast<py::ssize_t>(i);
      copy_[i] = PointXYZ{r.at(row, 0), r.at(row, 1), r.at(row, 2)};
    }
    data_ = copy_.data();
  }
  [[nodiscard]] const PointXYZ* data() const { return data_; }
  [[nodiscard]] std::size_t size() const { return n_; }
  [[nodiscard]] bool copied() const { return !copy_.empty(); }

 private:
  py::array array_;
  std::size_t n_ = 0U;
  const PointXYZ* data_ = nullptr;
  std::vector<PointXYZ> copy_;
};

/// weights=None -> nullptr (the noise model weighs); else an (N,) float array copied to float32.
const float* weights_arg(py::handle obj, std::size_t n, std::vector<float>* storage) {
  if (obj.is_none()) return nullptr;
  const py::array a = float_array(obj, "weights", 1, 0);
  if (static_cast<std::size_t>(a.shape(0)) != n) {
    throw StatusError(Status::kInvalidArgument, "weights must hold one weight per point (" + std::to_string(n) +
                                                    "), " + describe(a));
  }
  const FloatReader<1> r(a);
  storage->resize(n);
  for (std::size_t i = 0; i < n; ++i) (*storage)[i] = r.at(static_cast<py::ssize_t>(i));
  return storage->data();
}

/// A small real-valued array-like of exactly `rows` x `cols` (cols 0: a vector of `rows`),
/// ints allowed, as floats in row-major order.
std::vector<float> small_array(py::handle obj, const std::string& what, py::ssize_t rows, py::ssize_t cols) {
  const std::string wanted = cols == 0 ? "a sequence of " + std::to_string(rows) + " numbers"
                                       : "a " + std::to_string(rows) + "x" + std::to_string(cols) + " array of numbers";
  const py::array a = as_array(obj, what, wanted);
  const char kind = a.dtype().kind();
  const bool shape_ok = cols == 0 ? (a.ndim() == 1 && a.shape(0) == rows)
                                  : (a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == cols);
  if ((kind != 'f' && kind != 'i' && kind != 'u') || !shape_ok) {
    throw StatusError(Status::kInvalidArgument, what + " must be " + wanted + ", " + describe(a));
  }
  const py::array_t<double, py::array::c_style | py::array::forcecast> d(a);
  std::vector<float> out(static_cast<std::size_t>(d.size()));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = narrow(d.data()[i]);
  return out;
}

PointXYZ point_arg(py::handle obj, const std::string& what) {
  const std::vector<float> v = small_array(obj, what, 3, 0);
  return PointXYZ{v[0], v[1], v[2]};
}

// ---------------------------------------------------------------------------------------------
// Records out: one field table per record type serves the dict and the structured array
// ---------------------------------------------------------------------------------------------

enum class Kind : std::uint8_t { kFloat32, kFloat64, kInt32, kClassName, kStatusName };

template <typename Record>
struct Field {
  const char* name;
  Kind kind;
  double (*get)(const Record&);  ///< the value (exact for float and int32), or the enum code
};

/// A query's answer with the position asked and the width of the layer named in it.
struct QueryRecord {
  float x;
  float y;
  QueryResult q;
  float layer_width;  ///< width of layer q.layer (0 if q.layer < 0)
};

// The keys of `ccmap query` (tools/cli/cli.cpp). As there: height_m is NaN unless the status is
// ok, cell_width_m is the width of `layer` (the answering layer, or for unknown the finest
// layer holding the point), inclination_deg = atan(inclination) in degrees. The map frame has
// no origin to add (the CLI adds its UTM origin to height_m).
const Field<QueryRecord> kQueryFields[] = {
    {"x", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.x); }},
    {"y", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.y); }},
    {"status", Kind::kStatusName, [](const QueryRecord& r) { return static_cast<double>(r.q.status); }},
    {"layer", Kind::kInt32, [](const QueryRecord& r) { return static_cast<double>(r.q.layer); }},
    {"cell_width_m", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.layer_width); }},
    {"height_m", Kind::kFloat32,
     [](const QueryRecord& r) {
       return r.q.status == Status::kOk ? static_cast<double>(r.q.height_m) : std::numeric_limits<double>::quiet_NaN();
     }},
    {"slope_x", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.q.slope_x); }},
    {"slope_y", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.q.slope_y); }},
    {"inclination", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.q.inclination); }},
    {"inclination_deg", Kind::kFloat64,
     [](const QueryRecord& r) { return std::atan(static_cast<double>(r.q.inclination)) * 180.0 / 3.14159265358979323846; }},
    {"normal_variance_m2", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.q.normal_variance); }},
    {"elevation_variance_m2", Kind::kFloat32,
     [](const QueryRecord& r) { return static_cast<double>(r.q.elevation_variance); }},
    {"weight", Kind::kFloat32, [](const QueryRecord& r) { return static_cast<double>(r.q.weight); }},
    {"class", Kind::kClassName, [](const QueryRecord& r) { return static_cast<double>(r.q.cell_class); }},
    // 1 with status "unknown" when the answering cell failed its check or was reset by the scrub
    // (a single-event upset: QueryResult::upset), else 0. Not a CLI key: the CLI maps in-process.
    {"upset", Kind::kInt32, [](const QueryRecord& r) { return r.q.upset ? 1.0 : 0.0; }},
};

/// One exported cell and its layer.
struct LayerRecord {
  std::int32_t layer;
  float res;  ///< the layer's cell width (m)
  CellRecord cell;
};

// The columns of the CSV of `ccmap map` (tools/io/csv_writer.hpp), map frame.
const Field<LayerRecord> kLayerFields[] = {
    {"layer", Kind::kInt32, [](const LayerRecord& r) { return static_cast<double>(r.layer); }},
    {"ix", Kind::kInt32, [](const LayerRecord& r) { return static_cast<double>(r.cell.index.x); }},
    {"iy", Kind::kInt32, [](const LayerRecord& r) { return static_cast<double>(r.cell.index.y); }},
    {"cx", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.centre_x); }},
    {"cy", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.centre_y); }},
    {"res", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.res); }},
    {"weight", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.weight); }},
    {"height", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.height_m); }},
    {"slope_x", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.slope_x); }},
    {"slope_y", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.slope_y); }},
    {"normal_var", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.normal_variance); }},
    {"elev_var", Kind::kFloat32, [](const LayerRecord& r) { return static_cast<double>(r.cell.elevation_variance); }},
    {"class", Kind::kClassName, [](const LayerRecord& r) { return static_cast<double>(r.cell.cell_class); }},
};

std::string enum_name(Kind kind, int code) {
  return kind == Kind::kClassName ? to_string(static_cast<CellClass>(code)) : to_string(static_cast<Status>(code));
}

/// numpy text dtype wide enough for every name of the kind ("U<n>").
std::string name_dtype(Kind kind) {
  std::size_t longest = 0U;
  for (int code = 0; code <= 0xFF; ++code) longest = std::max(longest, enum_name(kind, code).size());
  return "U" + std::to_string(longest);
}

template <typename Record, std::size_t N>
py::dict to_dict(const Record& record, const Field<Record> (&fields)[N]) {
  py::dict d;
  for (const Field<Record>& f : fields) {
    const double v = f.get(record);
    switch (f.kind) {
      case Kind::kFloat32:
      case Kind::kFloat64: d[f.name] = v; break;
      case Kind::kInt32: d[f.name] = static_cast<std::int32_t>(v); break;
      case Kind::kClassName:
      case Kind::kStatusName: d[f.name] = enum_name(f.kind, static_cast<int>(v)); break;
    }
  }
  return d;
}

template <typename T, typename Record>
py::array numeric_column(const std::vector<Record>& rows, const Field<Record>& f) {
  py::array_t<T> column(static_cast<py::ssize_t>(rows.size()));
  T* out = column.mutable_data();
  for (std::size_t i = 0; i < rows.size(); ++i) out[i] = static_cast<T>(f.get(rows[i]));
  return std::move(column);
}

/// Enum codes as a fixed-width text column (numpy 'U'), through a table of the names present.
template <typename Record>
py::array name_column(const std::vector<Record>& rows, const Field<Record>& f) {
  py::array_t<std::int32_t> codes(static_cast<py::ssize_t>(rows.size()));
  std::int32_t* c = codes.mutable_data();
  std::int32_t max_code = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    c[i] = static_cast<std::int32_t>(f.get(rows[i]));
    max_code = c[i] > max_code ? c[i] : max_code;
  }
  py::list names;
  for (std::int32_t code = 0; code <= max_code; ++code) names.append(enum_name(f.kind, code));
  py::module_ np = py::module_::import("numpy");
  const py::object column = np.attr("array")(names, name_dtype(f.kind))[codes];
  return py::array(column);
}

template <typename Record, std::size_t N>
py::array to_structured(const std::vector<Record>& rows, const Field<Record> (&fields)[N]) {
  py::list spec, columns;
  for (const Field<Record>& f : fields) {
    py::array column;
    switch (f.kind) {
      case Kind::kFloat32: column = numeric_column<float>(rows, f); break;
      case Kind::kFloat64: column = numeric_column<double>(rows, f); break;
      case Kind::kInt32: column = numeric_column<std::int32_t>(rows, f); break;
      case Kind::kClassName:
      case Kind::kStatusName: column = name_column(rows, f); break;
    }
    spec.append(py::make_tuple(f.name, column.dtype()));
    columns.append(column);
  }
  py::module_ np = py::module_::import("numpy");
  py::array out = np.attr("empty")(rows.size(), np.attr("dtype")(spec));
  for (std::size_t i = 0; i < N; ++i) out.attr("__setitem__")(fields[i].name, columns[i]);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Map
// ---------------------------------------------------------------------------------------------

std::string preset_list() {
  std::string s;
  for (const Preset& p : presets()) s += (s.empty() ? "" : ", ") + std::string(p.name);
  return s;
}

const Preset& preset_arg(const std::string& name) {
  const Preset* p = find_preset(name);
  if (p == nullptr) {
    throw StatusError(Status::kInvalidArgument, "unknown preset '" + name + "' (expected one of: " + preset_list() + ")");
  }
  return *p;
}

/// The sensor keywords, gathered before the noise model is built.
struct SensorArgs {
  std::string kind = "stereo";
  bool kind_given = false;
  sensor::StereoParams stereo = sensor::kCadreStereoParams;
  bool stereo_given = false;
  sensor::LidarParams lidar{0.005F, 0.0F};  // the `ccmap` CLI's lidar default (5 mm)
  std::vector<std::string> stereo_keys, lidar_keys;
  bool weight_mode_given = false;
  sensor::WeightMode weight_mode = sensor::WeightMode::kConstant;
  float reference_range_m = 1.0F;
};

std::string string_arg(py::handle value, const std::string& name) {
  if (!PyUnicode_Check(value.ptr())) throw py::type_error(name + " must be a str");
  return value.cast<std::string>();
}

/// True if `key` is a sensor keyword (and records it).
bool sensor_keyword(const std::string& key, py::handle value, SensorArgs* s) {
  struct StereoKey {
    const char* name;
    float sensor::StereoParams::*member;
  };
  static const StereoKey kStereoKeys[] = {{"focal_px", &sensor::StereoParams::focal_px},
                                          {"baseline_m", &sensor::StereoParams::baseline_m},
                                          {"disparity_sigma_px", &sensor::StereoParams::disparity_sigma_px}};
  for (const StereoKey& k : kStereoKeys) {
    if (key == k.name) {
      s->stereo.*k.member = number_arg(value, key);
      s->stereo_given = true;
      s->stereo_keys.push_back(key);
      return true;
    }
  }
  if (key == "sensor") {
    s->kind = string_arg(value, key);
    s->kind_given = true;
    if (s->kind != "stereo" && s->kind != "lidar") {
      throw StatusError(Status::kInvalidArgument, "sensor must be 'stereo' or 'lidar', not '" + s->kind + "'");
    }
  } else if (key == "lidar_sigma_m" || key == "lidar_sigma_per_m") {
    (key == "lidar_sigma_m" ? s->lidar.sigma0_m : s->lidar.sigma_per_m) = number_arg(value, key);
    s->lidar_keys.push_back(key);
  } else if (key == "weight_mode") {
    const std::string mode = string_arg(value, key);
    if (mode != "constant" && mode != "inverse_variance") {
      throw StatusError(Status::kInvalidArgument, "weight_mode must be 'constant' or 'inverse_variance', not '" + mode + "'");
    }
    s->weight_mode = mode == "constant" ? sensor::WeightMode::kConstant : sensor::WeightMode::kInverseVariance;
    s->weight_mode_given = true;
  } else if (key == "reference_range_m") {
    s->reference_range_m = number_arg(value, key);
    s->weight_mode_given = true;
  } else {
    return false;
  }
  return true;
}

/// The unsigned 32-bit members of StackParams settable by name (the frame budget).
struct CountField {
  const char* name;
  std::uint32_t StackParams::*member;
};
constexpr CountField kCountFields[] = {
    {"frame_point_budget", &StackParams::frame_point_budget},
    {"frame_time_budget_us", &StackParams::frame_time_budget_us},
};

/// A Python int in [0, 2^32) (not a bool, not a float): TypeError or ValueError otherwise.
std::uint32_t count_arg(py::handle value, const std::string& name) {
  if (PyBool_Check(value.ptr()) || !PyLong_Check(value.ptr())) {
    throw py::type_error(name + " must be an int");
  }
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow != 0 || v < 0 || v > 0xFFFFFFFFLL) {
    throw py::value_error(name + " must lie in [0, 2^32)");
  }
  return static_cast<std::uint32_t>(v);
}

/// default_stack_params(width) with the keywords applied; with `base` (Map.set_params), *base
/// with the keywords applied (its noise model kept unless a sensor keyword is given).
StackParams build_params(const Preset& preset, py::handle cell_width, const py::kwargs& kwargs,
                         const StackParams* base = nullptr) {
  StackParams params{};
  if (base != nullptr) {
    params = *base;
    if (!cell_width.is_none()) params.finest_cell_width_m = number_arg(cell_width, "cell_width");
  } else {
    const float width = cell_width.is_none() ? preset.default_cell_width_m : number_arg(cell_width, "cell_width");
    params = default_stack_params(width);
  }
  SensorArgs sensor_args;
  if (base != nullptr && base->noise.kind() == sensor::SensorKind::kLidar) {
    sensor_args.kind = "lidar";
    sensor_args.lidar = sensor::LidarParams{base->noise.lidar_sigma0_m(), base->noise.lidar_sigma_per_m()};
  }
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first);
    bool known = false;
    for (const ParamField& f : kParamFields) {
      if (key == f.name) {
        params.*f.member = number_arg(item.second, key);
        known = true;
      }
    }
    for (const CountField& f : kCountFields) {
      if (key == f.name) {
        params.*f.member = count_arg(item.second, key);
        known = true;
      }
    }
    if (known) continue;
    if (key == "normal_variance_threshold") {
      if (PyUnicode_Check(item.second.ptr()) || !PySequence_Check(item.second.ptr())) {
        throw py::type_error(key + " must be a sequence of numbers");
      }
      const auto values = py::reinterpret_borrow<py::sequence>(item.second);
      if (values.size() > params.normal_variance_threshold.size()) {
        throw StatusError(Status::kInvalidArgument, key + " holds at most " +
                                                        std::to_string(params.normal_variance_threshold.size()) +
                                                        " values (one per layer; <= 0 calibrates)");
      }
      for (std::size_t i = 0; i < values.size(); ++i) params.normal_variance_threshold[i] = number_arg(values[i], key);
    } else if (key == "sensor_view_axis") {
      if (PyUnicode_Check(item.second.ptr()) || !PySequence_Check(item.second.ptr()) ||
          py::reinterpret_borrow<py::sequence>(item.second).size() != 3U) {
        throw py::type_error(key + " must be a sequence of 3 numbers (the sensor frame's viewing direction)");
      }
      const auto values = py::reinterpret_borrow<py::sequence>(item.second);
      for (std::size_t i = 0; i < 3U; ++i) params.sensor_view_axis[i] = number_arg(values[i], key);
    } else if (!sensor_keyword(key, item.second, &sensor_args)) {
      throw py::type_error("Map() got an unexpected keyword argument '" + key + "'");
    }
  }
  if (sensor_args.kind == "lidar" && !sensor_args.stereo_keys.empty()) {
    throw py::type_error(sensor_args.stereo_keys.front() + " applies to sensor='stereo', not 'lidar'");
  }
  if (sensor_args.kind == "stereo" && !sensor_args.lidar_keys.empty()) {
    throw py::type_error(sensor_args.lidar_keys.front() + " applies to sensor='lidar' (the default is 'stereo')");
  }
  if (sensor_args.kind == "lidar" && (base == nullptr || sensor_args.kind_given || !sensor_args.lidar_keys.empty())) {
    params.noise = sensor::NoiseModel::lidar(sensor_args.lidar);
  } else if (sensor_args.stereo_given || (base != nullptr && sensor_args.kind_given)) {
    params.noise = sensor::NoiseModel::stereo(sensor_args.stereo);
  }  // else: default_stack_params' CADRE stereo model
  if (sensor_args.weight_mode_given) params.noise.set_weight_mode(sensor_args.weight_mode, sensor_args.reference_range_m);
  return params;
}

/// RegistrationParams from the library's defaults and keyword overrides (field names);
/// TypeError for an unknown keyword, StatusError(invalid_argument) for values the library refuses.
RegistrationParams registration_params(const py::kwargs& kwargs) {
  RegistrationParams p = default_registration_params();
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first);
    auto count = [&](std::uint32_t* field) {
      const float v = number_arg(item.second, key);
      if (!(v >= 0.0F && v <= 4294967295.0F) || std::floor(v) != v) {
        throw StatusError(Status::kInvalidArgument, key + " must be a whole number >= 0");
      }
      *field = static_cast<std::uint32_t>(v);
    };
    if (key == "max_points") count(&p.max_points);
    else if (key == "max_iterations") count(&p.max_iterations);
    else if (key == "min_matches") count(&p.min_matches);
    else if (key == "max_translation_m") p.max_translation_m = number_arg(item.second, key);
    else if (key == "max_yaw_rad") p.max_yaw_rad = number_arg(item.second, key);
    else if (key == "max_sigma_m") p.max_sigma_m = number_arg(item.second, key);
    else if (key == "robust_sigmas") p.robust_sigmas = number_arg(item.second, key);
    else if (key == "model_variance_m2") p.model_variance_m2 = number_arg(item.second, key);
    else if (key == "convergence_m") p.convergence_m = number_arg(item.second, key);
    else throw py::type_error("unknown registration parameter '" + key + "'");
  }
  check(validate_registration_params(p), "the registration parameters are refused");
  return p;
}

/// The answer of a registration as a dict: dx, dy, dz (m), dyaw (rad), their sigmas (inf where
/// not observable), observable (four booleans: dx, dy, dz, dyaw), iterations, status (the
/// library's name: nothing is claimed unless "ok"), and the counts, lever, centre.
py::dict registration_dict(const RegistrationResult& r, float centre_x, float centre_y, std::uint32_t cells) {
  py::dict d;
  d["dx"] = r.dx;
  d["dy"] = r.dy;
  d["dz"] = r.dz;
  d["dyaw"] = r.dyaw;
  d["sigma_dx"] = r.sigma_dx;
  d["sigma_dy"] = r.sigma_dy;
  d["sigma_dz"] = r.sigma_dz;
  d["sigma_dyaw"] = r.sigma_dyaw;
  d["observable"] = py::make_tuple(r.observable[0], r.observable[1], r.observable[2], r.observable[3]);
  d["iterations"] = r.iterations;
  d["status"] = std::string(to_string(r.status));
  d["rank"] = static_cast<unsigned>(r.rank);
  d["points_sampled"] = r.points_sampled;
  d["points_rejected"] = r.points_rejected;
  d["points_matched"] = r.points_matched;
  d["lever_m"] = r.lever_m;
  d["residual_sigma"] = r.residual_sigma;
  d["centre"] = py::make_tuple(centre_x, centre_y);
  d["cells"] = cells;
  return d;
}

/// The names of the param_field bits (ccmap.h CCMAP_PARAM_*, in bit order): the C member names.
const char* const kParamFieldNames[] = {
    "finest_cell_width_m", "weight_limit",      "coverage_tau",       "min_weight",
    "obstacle_fraction",   "max_inclination",   "kalman_min_variance", "normal_variance_threshold",
    "finest_max_sigma_m",  "outlier_gate_sigma", "change_min_points",  "change_share",
    "frame_point_budget",  "frame_time_budget_us", "free_space_rays",  "free_space_clear_frames",
    "sensor_view_axis",    "noise"};
static_assert(sizeof kParamFieldNames / sizeof kParamFieldNames[0] == 18U && param_field::kAll == (1U << 18U) - 1U,
              "one name per param_field bit");

std::vector<std::string> param_field_names(std::uint32_t mask) {
  std::vector<std::string> names;
  for (std::uint32_t bit = 0; bit < 18U; ++bit) {
    if ((mask & (1U << bit)) != 0U) names.emplace_back(kParamFieldNames[bit]);
  }
  return names;
}

/// ccmap.decode_product: the standalone decoder's answer as a dict (the header fields by their
/// ccmap_product_header names) with the cells as a (side_y, side_x) structured array.
py::dict decode_product(py::handle data) {
  PyObject* as_bytes = PyBytes_FromObject(data.ptr());
  if (as_bytes == nullptr) throw py::error_already_set();
  const std::string bytes = py::reinterpret_steal<py::bytes>(as_bytes);
  const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
  ProductHeader h{};
  check(decode_product_header(p, bytes.size(), &h), "not a whole map product");
  py::dict d;
  d["version"] = h.version;
  d["total_bytes"] = h.total_bytes;
  d["product_sequence"] = h.product_sequence;
  d["map_sequence"] = h.map_sequence;
  d["params_crc"] = h.params_crc;
  d["preset"] = h.preset;
  d["layer"] = h.layer;
  d["answer"] = h.answer == 0U ? "stack" : "layer";
  d["side_x"] = h.side_x;
  d["side_y"] = h.side_y;
  d["cell_width_m"] = h.cell_width_m;
  d["min_index_x"] = h.min_index_x;
  d["min_index_y"] = h.min_index_y;
  d["min_corner_x_m"] = h.min_corner_x_m;
  d["min_corner_y_m"] = h.min_corner_y_m;
  d["centre_x_m"] = h.centre_x_m;
  d["centre_y_m"] = h.centre_y_m;
  d["pose_x"] = h.pose_x;
  d["pose_y"] = h.pose_y;
  d["pose_z"] = h.pose_z;
  d["pose_yaw"] = h.pose_yaw;
  d["tag"] = h.tag;
  py::list names, formats;
  for (const char* name : {"cell_class", "cost", "status", "layer"}) {
    names.append(name);
    formats.append(name == std::string("layer") ? "i2" : "u1");
  }
  names.append("height_m");
  formats.append("f4");
  names.append("inclination");
  formats.append("f4");
  py::dict spec;
  spec["names"] = names;
  spec["formats"] = formats;
  const py::dtype dtype = py::dtype::from_args(spec);
  py::array cells(dtype, std::vector<py::ssize_t>{h.side_y, h.side_x});
  auto* out = static_cast<std::uint8_t*>(cells.mutable_data());
  const auto stride = static_cast<std::size_t>(dtype.itemsize());
  for (std::size_t i = 0; i < std::size_t{h.side_x} * h.side_y; ++i) {
    const ProductCell c = decode_product_cell(p, i);
    const std::int16_t layer = c.layer == kProductNoLayer ? std::int16_t{-1} : static_cast<std::int16_t>(c.layer);
    std::uint8_t* rec = out + i * stride;
    rec[0] = c.cell_class;
    rec[1] = c.cost;
    rec[2] = c.status;
    std::memcpy(rec + 3, &layer, sizeof layer);
    std::memcpy(rec + 5, &c.height_m, sizeof c.height_m);
    std::memcpy(rec + 9, &c.inclination, sizeof c.inclination);
  }
  d["cells"] = cells;
  return d;
}

class Map {
 public:
  Map(const Preset& preset, bool paper_cell, std::unique_ptr<MapAdapter> map)
      : preset_(&preset), paper_cell_(paper_cell), map_(std::move(map)) {}

  /// paper_cell (a keyword): the paper's 9-float CCM cells (the CLI's --paper-cell); the other
  /// keywords set StackParams.
  static Map create(const std::string& preset_name, py::handle cell_width, const py::kwargs& kwargs) {
    const Preset& preset = preset_arg(preset_name);
    bool paper_cell = false;
    py::kwargs params_kwargs;
    for (const auto& item : kwargs) {
      if (std::string(py::str(item.first)) != "paper_cell") {
        params_kwargs[item.first] = item.second;
      } else if (!PyBool_Check(item.second.ptr())) {
        throw py::type_error("paper_cell must be True or False");
      } else {
        paper_cell = item.second.ptr() == Py_True;
      }
    }
    if (paper_cell && preset.make_paper == nullptr) {
      throw StatusError(Status::kInvalidArgument,
                        "paper_cell: preset '" + preset_name + "' has no CCM layer (cadre and ccm have)");
    }
    const StackParams params = build_params(preset, cell_width, params_kwargs);
    std::unique_ptr<MapAdapter> map = paper_cell ? preset.make_paper() : preset.make();
    check(map->init(params), "the map refused its parameters");
    return Map(preset, paper_cell, std::move(map));
  }

  /// Loads a snapshot into a new map of `preset`, or of the first of the four presets that
  /// accepts it (another preset's snapshot answers kVersionMismatch: try the next), each with
  /// the full and then the paper CCM cell (the cell kind is part of the snapshot's shape).
  static Map from_snapshot(py::handle data, py::handle preset) {
    PyObject* as_bytes = PyBytes_FromObject(data.ptr());  // bytes, bytearray, memoryview, ...
    if (as_bytes == nullptr) throw py::error_already_set();
    const std::string bytes = py::reinterpret_steal<py::bytes>(as_bytes);
    const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
    std::vector<const Preset*> candidates;
    if (preset.is_none()) {
      for (const Preset& each : presets()) candidates.push_back(&each);
    } else {
      candidates.push_back(&preset_arg(string_arg(preset, "preset")));
    }
    Status refusal = Status::kVersionMismatch;
    for (const Preset* candidate : candidates) {
      for (const bool paper_cell : {false, true}) {
        if (paper_cell && candidate->make_paper == nullptr) continue;
        std::unique_ptr<MapAdapter> map = paper_cell ? candidate->make_paper() : candidate->make();
        const Status status = map->load(p, bytes.size());
        if (status == Status::kOk) return Map(*candidate, paper_cell, std::move(map));
        if (status != Status::kVersionMismatch) refusal = status;  // corrupt for one is corrupt for all
      }
    }
    throw StatusError(refusal, preset.is_none() ? "no preset (" + preset_list() + ") accepts the snapshot"
                                                : "preset '" + std::string(py::str(preset)) + "' refuses the snapshot");
  }

  void move_to(py::handle x, py::handle y) {
    check(map_->move_to(number_arg(x, "x"), number_arg(y, "y")), "the map refused the move");
  }

  py::dict update(py::handle points_obj, py::handle sensor_origin, py::handle weights_obj) {
    const Points points(points_obj, "points");
    const PointXYZ origin = point_arg(sensor_origin, "sensor_origin");
    std::vector<float> weight_storage;
    const float* weights = weights_arg(weights_obj, points.size(), &weight_storage);
    FrameCounters counters{};
    check(map_->update_frame(points.data(), weights, points.size(), origin, &counters), "the map refused the frame");
    return counters_dict(counters);
  }

  py::dict update_sensor(py::handle points_obj, py::handle rotation_obj, py::handle translation_obj) {
    const Points points(points_obj, "points");
    const std::vector<float> r = small_array(rotation_obj, "rotation", 3, 3);
    const PointXYZ t = point_arg(translation_obj, "translation");
    const float rotation[3][3] = {{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, {r[6], r[7], r[8]}};
    const float translation[3] = {t.x, t.y, t.z};
    FrameCounters counters{};
    check(map_->update_frame_sensor(points.data(), points.size(), make_pose(rotation, translation), &counters),
          "the map refused the frame");
    return counters_dict(counters);
  }

  /// Registration of a frame before it is folded in (nothing in the map changes): the dict of
  /// registration_dict. Keywords set RegistrationParams fields (max_points, max_iterations, ...).
  py::dict register_frame(py::handle points_obj, py::handle sensor_origin, const py::kwargs& kwargs) const {
    const Points points(points_obj, "points");
    const PointXYZ origin = point_arg(sensor_origin, "sensor_origin");
    const RegistrationParams params = registration_params(kwargs);
    return registration_dict(map_->register_frame(points.data(), points.size(), origin, params), origin.x, origin.y, 0U);
  }

  py::dict register_sensor(py::handle points_obj, py::handle rotation_obj, py::handle translation_obj,
                           const py::kwargs& kwargs) const {
    const Points points(points_obj, "points");
    const std::vector<float> r = small_array(rotation_obj, "rotation", 3, 3);
    const PointXYZ t = point_arg(translation_obj, "translation");
    const float rotation[3][3] = {{r[0], r[1], r[2]}, {r[3], r[4], r[5]}, {r[6], r[7], r[8]}};
    const float translation[3] = {t.x, t.y, t.z};
    const RegistrationParams params = registration_params(kwargs);
    return registration_dict(map_->register_frame_sensor(points.data(), points.size(), make_pose(rotation, translation), params),
                             t.x, t.y, 0U);
  }

  /// Team alignment of another map's snapshot (bytes) placed by `offset` (x, y, z in m).
  py::dict align_snapshot(py::handle data, py::handle offset_obj, const py::kwargs& kwargs) const {
    PyObject* as_bytes = PyBytes_FromObject(data.ptr());
    if (as_bytes == nullptr) throw py::error_already_set();
    const std::string bytes = py::reinterpret_steal<py::bytes>(as_bytes);
    const PointXYZ o = point_arg(offset_obj, "offset");
    const float offset[3] = {o.x, o.y, o.z};
    const RegistrationParams params = registration_params(kwargs);
    float cx = 0.0F, cy = 0.0F;
    std::uint32_t cells = 0U;
    const RegistrationResult r = map_->align_snapshot(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(),
                                                      offset, params, &cx, &cy, &cells);
    return registration_dict(r, cx, cy, cells);
  }

  /// layer < 0: the stack's answer (query), else that layer's (query_layer).
  QueryRecord answer(float x, float y, int layer) const {
    const QueryResult q = layer < 0 ? map_->query(x, y) : map_->query_layer(layer, x, y);
    return QueryRecord{x, y, q, q.layer >= 0 ? map_->layer_cell_width(q.layer) : 0.0F};
  }

  py::dict query(py::handle x, py::handle y, py::handle layer) const {
    const int k = layer.is_none() ? -1 : layer_arg(layer);
    return to_dict(answer(number_arg(x, "x"), number_arg(y, "y"), k), kQueryFields);
  }

  py::array query_many(py::handle xy_obj, py::handle layer) const {
    const py::array xy = float_array(xy_obj, "xy", 2, 2);
    const int k = layer.is_none() ? -1 : layer_arg(layer);
    const FloatReader<2> r(xy);
    std::vector<QueryRecord> rows(static_cast<std::size_t>(xy.shape(0)));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto row = static_cast<py::ssize_t>(i);
      rows[i] = answer(r.at(row, 0), r.at(row, 1), k);
    }
    return to_structured(rows, kQueryFields);
  }

  std::vector<LayerRecord> layer_records(int layer) const {
    std::vector<CellRecord> cells;
    check(map_->export_layer(layer, &cells), "cannot export layer " + std::to_string(layer));
    std::vector<LayerRecord> rows;
    rows.reserve(cells.size());
    for (const CellRecord& c : cells) rows.push_back(LayerRecord{layer, map_->layer_cell_width(layer), c});
    return rows;
  }

  py::array layer(py::handle k) const { return to_structured(layer_records(layer_arg(k)), kLayerFields); }

  /// (side, side) float32 over the layer window: grid[iy - iy_min, ix - ix_min], NaN where no
  /// cell was observed (weight 0). `field`: a float column of layer(), or "class" (the code).
  py::array layer_grid(py::handle k, const std::string& field) const {
    const int layer_index = layer_arg(k);
    const Field<LayerRecord>* chosen = nullptr;
    std::string allowed;
    for (const Field<LayerRecord>& f : kLayerFields) {
      if (f.kind != Kind::kFloat32 && f.kind != Kind::kClassName) continue;
      allowed += (allowed.empty() ? "" : ", ") + std::string(f.name);
      if (field == f.name) chosen = &f;
    }
    if (chosen == nullptr) {
      throw StatusError(Status::kInvalidArgument, "layer_grid field '" + field + "' (expected one of: " + allowed + ")");
    }
    const std::int32_t side = map_->layer_side(layer_index);
    const CellIndex lowest = window_lowest(layer_index);
    py::array_t<float> grid({static_cast<py::ssize_t>(side), static_cast<py::ssize_t>(side)});
    float* g = grid.mutable_data();
    for (std::int32_t i = 0; i < side * side; ++i) g[i] = std::numeric_limits<float>::quiet_NaN();
    for (const LayerRecord& r : layer_records(layer_index)) {
      const std::int64_t row = static_cast<std::int64_t>(r.cell.index.y) - lowest.y;
      const std::int64_t col = static_cast<std::int64_t>(r.cell.index.x) - lowest.x;
      g[row * side + col] = static_cast<float>(chosen->get(r));
    }
    return std::move(grid);
  }

  /// (x_min, x_max, y_min, y_max) of the layer window, metres (matplotlib's imshow extent).
  py::tuple layer_extent(py::handle k) const {
    const int layer_index = layer_arg(k);
    const CellIndex lowest = window_lowest(layer_index);
    const double w = static_cast<double>(map_->layer_cell_width(layer_index));
    const double side = map_->layer_side(layer_index);
    return py::make_tuple(lowest.x * w, (lowest.x + side) * w, lowest.y * w, (lowest.y + side) * w);
  }

  py::bytes snapshot() const {
    std::vector<std::uint8_t> bytes;
    check(map_->save(&bytes), "cannot save the map");
    return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  // ---- properties ----
  const char* preset_name() const { return preset_->name; }
  bool paper_cell() const { return paper_cell_; }
  int layer_count() const { return map_->layer_count(); }
  template <typename T>
  std::vector<T> per_layer(T (MapAdapter::*get)(int) const) const {
    std::vector<T> out;
    for (int k = 0; k < map_->layer_count(); ++k) out.push_back(((*map_).*get)(k));
    return out;
  }
  std::vector<float> cell_widths() const { return per_layer(&MapAdapter::layer_cell_width); }
  std::vector<std::int32_t> sides() const { return per_layer(&MapAdapter::layer_side); }
  std::vector<bool> layer_is_ccm() const { return per_layer(&MapAdapter::layer_is_ccm); }
  std::vector<float> thresholds() const { return per_layer(&MapAdapter::normal_variance_threshold); }
  std::vector<py::tuple> window_centres() const {
    std::vector<py::tuple> out;
    for (const CellIndex c : per_layer(&MapAdapter::layer_centre)) out.push_back(py::make_tuple(c.x, c.y));
    return out;
  }
  std::vector<py::tuple> window_centres_m() const {
    std::vector<py::tuple> out;
    for (int k = 0; k < map_->layer_count(); ++k) {
      const CellIndex c = map_->layer_centre(k);
      const double w = static_cast<double>(map_->layer_cell_width(k));
      out.push_back(py::make_tuple(c.x * w, c.y * w));
    }
    return out;
  }
  py::dict total_counters() const { return counters_dict(map_->total_counters()); }
  std::uint32_t rejected_moves() const { return map_->rejected_moves(); }
  std::uint32_t rejected_frames() const { return map_->rejected_frames(); }
  std::uint64_t last_update_ns() const { return map_->last_update_ns(); }

  py::dict params() const {
    const StackParams& p = map_->params();
    py::dict d;
    d["cell_width"] = p.finest_cell_width_m;
    for (const ParamField& f : kParamFields) d[f.name] = p.*f.member;
    for (const CountField& f : kCountFields) d[f.name] = p.*f.member;
    d["normal_variance_threshold"] = std::vector<float>(p.normal_variance_threshold.begin(), p.normal_variance_threshold.end());
    d["sensor_view_axis"] = std::vector<float>(p.sensor_view_axis.begin(), p.sensor_view_axis.end());
    const sensor::NoiseModel& n = p.noise;
    if (n.kind() == sensor::SensorKind::kLidar) {
      d["sensor"] = "lidar";
      d["lidar_sigma_m"] = n.lidar_sigma0_m();
      d["lidar_sigma_per_m"] = n.lidar_sigma_per_m();
    } else {
      d["sensor"] = "stereo";
      d["stereo_sigma_per_range_sq"] = n.stereo_sigma_per_range_sq();  // sigma_d / (f b), 1/m
    }
    d["weight_mode"] = n.weight_mode() == sensor::WeightMode::kConstant ? "constant" : "inverse_variance";
    d["reference_range_m"] = n.reference_range_m();
    return d;
  }

  // ---- the flight interface (docs/integration.md, "Flight interface") ----
  /// Keyword overrides of the running parameters, applied keeping every cell (Stack::set_params).
  void set_params(const py::kwargs& kwargs) {
    py::object cell_width = py::none();
    py::kwargs rest;
    for (const auto& item : kwargs) {
      if (std::string(py::str(item.first)) == "cell_width") {
        cell_width = py::reinterpret_borrow<py::object>(item.second);
      } else {
        rest[item.first] = item.second;
      }
    }
    const StackParams params = build_params(*preset_, cell_width, rest, &map_->params());
    std::uint32_t needs_reinit = 0U;
    const Status status = map_->set_params(params, &needs_reinit);
    if (needs_reinit != 0U) {
      std::string names;
      for (const std::string& n : param_field_names(needs_reinit)) names += (names.empty() ? "" : ", ") + n;
      throw StatusError(status, "these changes need a re-init (a new Map): " + names);
    }
    check(status, "the map refused the parameters (it is unchanged)");
  }
  void reset_counters() { check(map_->reset_counters(), "reset_counters"); }
  /// ccmap_health's fields by name (layers: one dict per layer).
  py::dict health() const {
    const Status state = map_->state_status();
    const FrameCounters& totals = map_->total_counters();
    py::dict d;
    d["initialised"] = map_->initialised();
    d["state"] = to_string(state);
    d["preset"] = preset_->name;
    d["layer_count"] = map_->layer_count();
    d["frames_accepted"] = map_->frames_since_reset();
    d["frames_refused"] = map_->rejected_frames();
    d["moves_refused"] = map_->rejected_moves();
    d["points_received"] = totals.received;
    d["points_used"] = totals.used;
    d["points_skipped_budget"] = totals.skipped_budget;
    d["corrupted_cells"] = totals.corrupted_cells;
    d["corrupted_slots"] = totals.corrupted_slots;
    d["params_changes"] = map_->params_changes();
    d["products_published"] = 0U;  // a Python map publishes through product(), not into shared buffers
    d["last_frame_ns"] = map_->last_update_ns();
    d["last_frame_points"] = map_->last_frame().received;
    d["last_frame_used"] = map_->last_frame().used;
    d["params_crc"] = params_crc();
    d["map_sequence"] = map_->accepted_frames();
    d["fault_count"] = assert_failure_count();
    py::list layers;
    for (int k = 0; k < map_->layer_count(); ++k) {
      const CellIndex c = map_->layer_centre(k);
      const float w = map_->layer_cell_width(k);
      py::dict l;
      l["cell_width_m"] = w;
      l["centre_index_x"] = c.x;
      l["centre_index_y"] = c.y;
      l["centre_x_m"] = static_cast<float>(c.x) * w;
      l["centre_y_m"] = static_cast<float>(c.y) * w;
      l["observed_cells"] = map_->observed_cells(k);
      l["normal_variance_threshold"] = map_->normal_variance_threshold(k);
      layers.append(l);
    }
    d["layers"] = layers;
    return d;
  }
  /// The map product of layer k's window (bytes; ccmap.decode_product reads it).
  py::bytes product(py::handle k, const std::string& answer, py::handle pose_obj, std::uint32_t tag) const {
    const int layer = layer_arg(k);
    if (answer != "stack" && answer != "layer") {
      throw StatusError(Status::kInvalidArgument, "answer must be 'stack' or 'layer', not '" + answer + "'");
    }
    float pose[4] = {0.0F, 0.0F, 0.0F, 0.0F};
    if (!pose_obj.is_none()) {
      if (PyUnicode_Check(pose_obj.ptr()) || !PySequence_Check(pose_obj.ptr()) ||
          py::reinterpret_borrow<py::sequence>(pose_obj).size() != 4U) {
        throw py::type_error("pose must be a sequence (x, y, z, yaw)");
      }
      const auto values = py::reinterpret_borrow<py::sequence>(pose_obj);
      for (std::size_t i = 0; i < 4U; ++i) pose[i] = number_arg(values[i], "pose");
    }
    std::vector<std::uint8_t> bytes;
    check(map_->product(layer, answer == "layer", pose, tag, params_crc(), &bytes), "product");
    return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  std::string repr() const {
    std::string widths;
    for (const float w : cell_widths()) {
      char text[32];
      std::snprintf(text, sizeof text, "%g", static_cast<double>(w));  // float32 shown to 6 digits
      widths += (widths.empty() ? "" : ", ") + std::string(text);
    }
    return "<ccmap.Map preset='" + std::string(preset_->name) + "'" + (paper_cell_ ? " paper_cell=True" : "") +
           " layers=" + std::to_string(layer_count()) + " cell_widths=[" + widths + "]>";
  }

 private:
  /// ccmap_health.params_crc of a map given no C parameters: the CRC of what ccmap_get_params answers.
  std::uint32_t params_crc() const {
    ccmap_params c{};
    stack_params_to_c(map_->params(), &c);
    return c_params_crc(c);
  }
  int layer_arg(py::handle k) const {
    if (PyBool_Check(k.ptr()) || !PyIndex_Check(k.ptr())) throw py::type_error("layer must be an int");
    const auto value = k.cast<long long>();
    if (value < 0 || value >= map_->layer_count()) {
      throw StatusError(Status::kInvalidArgument, "layer " + std::to_string(value) + " (the map has layers 0.." +
                                                      std::to_string(map_->layer_count() - 1) + ")");
    }
    return static_cast<int>(value);
  }
  CellIndex window_lowest(int layer) const {
    const CellIndex c = map_->layer_centre(layer);
    const std::int32_t half = map_->layer_side(layer) / 2;
    return CellIndex{c.x - half, c.y - half};
  }

  const Preset* preset_;
  bool paper_cell_;
  std::unique_ptr<MapAdapter> map_;
};

/// ccmap.read_global_map: the global map of a patch directory (tools/global_map/global_map.hpp).
py::dict read_global_map(const std::string& directory, int layer, bool corrected) {
  if (layer < 0 || layer >= kMaxLayers) {
    throw StatusError(Status::kInvalidArgument, "layer " + std::to_string(layer) + " (expected 0 .. 7)");
  }
  std::vector<tools::GlobalPatch> patches;
  tools::PatchDirectoryCounts counts;
  std::string error;
  if (!tools::read_patch_directory(directory, layer, &patches, &counts, &error)) {
    throw StatusError(Status::kInvalidArgument, error);
  }
  tools::GlobalMapOptions options;
  options.apply_corrections = corrected;
  tools::GlobalRaster raster;
  if (!tools::assemble_global_map(patches, options, &raster, &error)) {
    throw StatusError(Status::kInvalidArgument, error);
  }
  const auto band = [&raster](const std::vector<float>& values) {
    py::array_t<float> grid({static_cast<py::ssize_t>(raster.ny), static_cast<py::ssize_t>(raster.nx)});
    std::copy(values.begin(), values.end(), grid.mutable_data());
    return grid;
  };
  py::dict out;
  out["height"] = band(raster.height);
  out["slope_x"] = band(raster.slope_x);
  out["slope_y"] = band(raster.slope_y);
  out["normal_var"] = band(raster.normal_var);
  out["weight"] = band(raster.weight);
  out["cell_class"] = band(raster.cell_class);
  out["cell_width"] = raster.cell_width_m;
  out["x_min"] = static_cast<double>(raster.ix_min) * raster.cell_width_m;
  out["y_min"] = static_cast<double>(raster.iy_min) * raster.cell_width_m;
  out["patches"] = counts.used;
  out["refused"] = py::cast(counts.refused_names);
  out["hazard_pixels"] = raster.hazard_pixels;
  return out;
}

}  // namespace
}  // namespace ccmap::python

PYBIND11_MODULE(ccmap, m) {
  using ccmap::python::Map;
  namespace cp = ccmap::python;
  m.doc() =
      "ccmap: Converging Covariance terrain maps (the C++ library's Stack presets).\n\n"
      "    m = ccmap.Map('cadre')                       # or 'ccm', 'kf', 'omg'; keywords set StackParams\n"
      "    m.move_to(x, y)                              # map frame, metres\n"
      "    m.update(points_n3, sensor_origin)           # -> frame counters (dict)\n"
      "    m.query(x, y); m.query_many(xy); m.layer(k); m.layer_grid(k, 'height')\n"
      "    m.save(path); ccmap.Map.load(path)\n\n"
      "See docs/python.md.";

  cp::g_status_error_type = PyErr_NewExceptionWithDoc(
      "ccmap.StatusError",
      "A refusal by the map (or of an argument before the map saw it). A ValueError; .status is the\n"
      "library's status name, e.g. 'non_finite_input', 'invalid_argument', 'corrupt'.",
      PyExc_ValueError, nullptr);
  m.attr("StatusError") = py::reinterpret_borrow<py::object>(cp::g_status_error_type);
  py::register_exception_translator(&cp::translate_status_error);

  py::list preset_names;
  for (const cp::Preset& p : cp::presets()) preset_names.append(p.name);
  m.attr("PRESETS") = py::tuple(preset_names);
  py::list class_names;
  for (int c = 0; c <= static_cast<int>(ccmap::CellClass::kDropOff); ++c) {
    class_names.append(ccmap::to_string(static_cast<ccmap::CellClass>(c)));
  }
  m.attr("CLASS_NAMES") = py::tuple(class_names);
  m.def(
      "snapshot_size",
      [](const std::string& preset, bool paper_cell) {
        const cp::Preset& p = cp::preset_arg(preset);
        if (paper_cell && p.make_paper == nullptr) {
          throw cp::StatusError(ccmap::Status::kInvalidArgument, "paper_cell: preset '" + preset + "' has no CCM layer");
        }
        return paper_cell ? p.paper_snapshot_bytes : p.snapshot_bytes;
      },
      py::arg("preset"), py::arg("paper_cell") = false,
      "Bytes of a snapshot of the preset (fixed by its configuration and CCM cell kind).");

  m.def(
      "validate_params",
      [](const std::string& preset, py::object cell_width, const py::kwargs& kwargs) {
        const cp::Preset& p = cp::preset_arg(preset);
        const ccmap::StackParams params = cp::build_params(p, cell_width, kwargs);
        return std::string(ccmap::to_string(p.make()->validate_params(params)));
      },
      py::arg("preset") = "cadre", py::arg("cell_width") = py::none(),
      "Map()'s parameter checks without a map: 'ok' if Map(preset, cell_width, **params) would accept\n"
      "them, else the status name it would refuse them with.");
  m.def("read_global_map", &cp::read_global_map, py::arg("directory"), py::arg("layer") = 0,
        py::arg("corrected") = true,
        "The global map of a patch directory (PatchKeeper files L<layer>_<tx>_<ty>.ccp): every patch of\n"
        "the CCM layer placed at its corrected pose (corrected=False: at its writing pose), as a dict of\n"
        "(ny, nx) float32 arrays height, slope_x, slope_y, normal_var, weight, cell_class (NaN: no cell;\n"
        "row 0 = the lowest y), x_min, y_min (the raster's lower-left corner, m), cell_width, patches\n"
        "(used), refused (names of the files that failed a check: skipped), hazard_pixels. The same\n"
        "raster as ccmap_global_map's GeoTIFF (whose row 0 is the highest y).");
  m.def("decode_product", &cp::decode_product, py::arg("data"),
        "Check and decode a map product (bytes from Map.product, ccmap_product_read or the ground link):\n"
        "a dict of the header fields (docs/icd.md) and 'cells', a (side_y, side_x) structured array\n"
        "(cell_class, cost, status, layer, height_m, inclination; row 0 = the lowest y). StatusError\n"
        "'corrupt' / 'version_mismatch' for bytes that are not a whole product of this version.");
  {
    py::list fields;
    for (const char* name : cp::kParamFieldNames) fields.append(name);
    m.attr("PARAM_FIELDS") = py::tuple(fields);
    py::list statuses;
    for (int st = 0; st <= static_cast<int>(ccmap::Status::kBusy); ++st) {
      statuses.append(ccmap::to_string(static_cast<ccmap::Status>(st)));
    }
    m.attr("STATUS_NAMES") = py::tuple(statuses);
    m.attr("PRODUCT_VERSION") = ccmap::kProductVersion;
  }

  py::class_<Map>(m, "Map",
                  "A robot-centric multi-resolution terrain map: one of the library's Stack presets.\n\n"
                  "Map(preset='cadre', cell_width=None, paper_cell=False, **params)\n"
                  "  preset: 'cadre' (4 cm Kalman + 8..64 cm CCM), 'ccm' (one CCM layer 256x256),\n"
                  "          'kf' (one Kalman layer), 'omg' (one OMG layer); the ccmap CLI's presets.\n"
                  "  paper_cell: the paper's 9-float CCM cells (no lateral covariance; the CLI's\n"
                  "          --paper-cell), cadre and ccm only; default: the full cell.\n"
                  "  cell_width: finest cell width (m); None: the preset's default (0.04 / 0.08).\n"
                  "  params: StackParams by name: weight_limit, coverage_tau, min_weight,\n"
                  "          obstacle_fraction, max_inclination, kalman_min_variance,\n"
                  "          finest_max_sigma_m, outlier_gate_sigma (0 = off), change_min_points,\n"
                  "          change_share, normal_variance_threshold (sequence, <= 0 calibrates),\n"
                  "          frame_point_budget, frame_time_budget_us (ints; 0 = no limit);\n"
                  "          sensor='stereo' (default: CADRE stereo; focal_px, baseline_m,\n"
                  "          disparity_sigma_px) or 'lidar' (lidar_sigma_m = 0.005, lidar_sigma_per_m = 0);\n"
                  "          weight_mode='constant' | 'inverse_variance', reference_range_m.\n"
                  "Unknown keyword: TypeError. Parameters the library refuses: StatusError (ValueError).")
      .def(py::init([](const std::string& preset, py::object cell_width, const py::kwargs& kwargs) {
             return Map::create(preset, cell_width, kwargs);
           }),
           py::arg("preset") = "cadre", py::arg("cell_width") = py::none())
      .def("move_to", &Map::move_to, py::arg("x"), py::arg("y"),
           "Re-centre every layer on (x, y) (map frame, m). Refused (StatusError, map unchanged): NaN/Inf or\n"
           "beyond 1e5 m.")
      .def("update", &Map::update, py::arg("points"), py::arg("sensor_origin"), py::arg("weights") = py::none(),
           "Fold one frame of map-frame points ((N, 3) float32/float64) seen from sensor_origin (3 numbers).\n"
           "weights: None (the sensor model weighs) or (N,) float32/float64. Returns the frame counters.\n"
           "Bad points/weights inside a good array are counted and skipped; a bad array or origin raises\n"
           "StatusError and leaves the map unchanged.")
      .def("update_sensor", &Map::update_sensor, py::arg("points"), py::arg("rotation"), py::arg("translation"),
           "Fold one frame of sensor-frame points: p_map = rotation @ p + translation (3x3, 3). Returns the\n"
           "frame counters; refusals as update().")
      .def("register", &Map::register_frame, py::arg("points"), py::arg("sensor_origin"),
           "Registers map-frame points (N, 3) seen from sensor_origin against the map before they are\n"
           "folded in (the map is unchanged): a dict with dx, dy, dz (m), dyaw (rad) about the vertical\n"
           "through sensor_origin, sigma_dx .. sigma_dyaw (inf where not observable), observable (four\n"
           "booleans: dx, dy, dz, dyaw), iterations, status ('ok', or why nothing is claimed), rank,\n"
           "points_sampled/_rejected/_matched, lever_m, residual_sigma, centre. Keywords set\n"
           "RegistrationParams (max_points, max_iterations, min_matches, max_translation_m, max_yaw_rad,\n"
           "max_sigma_m, robust_sigmas, model_variance_m2, convergence_m).")
      .def("register_sensor", &Map::register_sensor, py::arg("points"), py::arg("rotation"), py::arg("translation"),
           "The same for sensor-frame points with the pose (rotation (3, 3), translation (3,)):\n"
           "the rotation centre is the translation.")
      .def("align_snapshot", &Map::align_snapshot, py::arg("data"), py::arg("offset"),
           "Team alignment: the correction of another map's snapshot (bytes, the same preset) whose\n"
           "map-frame point p lies at p + offset in this map; the dict of register, centre = the\n"
           "rotation centre (the mean of their cells' positions), cells = their usable cells.")
      .def("query", &Map::query, py::arg("x"), py::arg("y"), py::arg("layer") = py::none(),
           "The map's answer at (x, y) as a dict with the keys of `ccmap query` (status, layer, cell_width_m,\n"
           "height_m (NaN unless status is 'ok'), slope_x, slope_y, inclination, inclination_deg,\n"
           "normal_variance_m2, elevation_variance_m2, weight, class) plus x, y. layer=k asks one layer.")
      .def("query_many", &Map::query_many, py::arg("xy"), py::arg("layer") = py::none(),
           "query() for every row of an (N, 2) float32/float64 array: a NumPy structured array with the same\n"
           "fields (float32 numbers, int32 layer, text status and class; inclination_deg float64).")
      .def("layer", &Map::layer, py::arg("k"),
           "Every observed cell (weight > 0) of layer k as a NumPy structured array with the columns of the\n"
           "CSV of `ccmap map`: layer, ix, iy, cx, cy, res, weight, height, slope_x, slope_y, normal_var,\n"
           "elev_var, class (map frame; rows of increasing iy, then ix).")
      .def("layer_grid", &Map::layer_grid, py::arg("k"), py::arg("field") = "height",
           "A (side, side) float32 array of one layer() column over layer k's window: grid[row, col] is the\n"
           "cell ix = ix_min + col, iy = iy_min + row (row 0 = the window's lowest iy, i.e. south; use\n"
           "imshow(origin='lower', extent=m.layer_extent(k))). NaN where no cell was observed.\n"
           "field: cx, cy, res, weight, height, slope_x, slope_y, normal_var, elev_var, or class (the code,\n"
           "an index into ccmap.CLASS_NAMES).")
      .def("layer_extent", &Map::layer_extent, py::arg("k"),
           "(x_min, x_max, y_min, y_max) of layer k's window, metres.")
      .def("snapshot", &Map::snapshot, "The library's snapshot (include/ccmap/persistence/snapshot.hpp) as bytes.")
      .def_static("from_snapshot", &Map::from_snapshot, py::arg("data"), py::arg("preset") = py::none(),
                  "A map from snapshot bytes. preset=None tries the four presets, each with the full and\n"
                  "the paper CCM cell (a snapshot of another preset or cell is refused with 'version_mismatch');\n"
                  "StatusError if none accepts it.")
      .def(
          "save",
          [](const Map& self, py::object path) {
            const py::bytes data = self.snapshot();  // before the file is opened: a refusal leaves it alone
            py::object f = py::module_::import("builtins").attr("open")(path, "wb");
            try {
              f.attr("write")(data);
            } catch (...) {
              f.attr("close")();
              throw;
            }
            f.attr("close")();
          },
          py::arg("path"), "Write snapshot() to a file.")
      .def_static(
          "load",
          [](py::object path, py::object preset) {
            py::object f = py::module_::import("builtins").attr("open")(path, "rb");
            py::object data;
            try {
              data = f.attr("read")();
            } catch (...) {
              f.attr("close")();
              throw;
            }
            f.attr("close")();
            return Map::from_snapshot(data, preset);
          },
          py::arg("path"), py::arg("preset") = py::none(),
          "A map from a file written by save() (or by the C++ save_snapshot). preset=None tries the four\n"
          "presets in turn.")
      .def_property_readonly("preset", &Map::preset_name)
      .def_property_readonly("paper_cell", &Map::paper_cell,
                             "True if the CCM layers keep the paper's 9-float cell (no lateral covariance).")
      .def_property_readonly("layer_count", &Map::layer_count)
      .def_property_readonly("cell_widths", &Map::cell_widths, "Cell width of each layer (m), finest first.")
      .def_property_readonly("sides", &Map::sides, "Cells per axis of each layer.")
      .def_property_readonly("layer_is_ccm", &Map::layer_is_ccm)
      .def_property_readonly("window_centres", &Map::window_centres,
                             "Centre of each layer window as a global cell index (ix, iy).")
      .def_property_readonly("window_centres_m", &Map::window_centres_m,
                             "Centre of each layer window in metres (index * cell width).")
      .def_property_readonly("normal_variance_thresholds", &Map::thresholds,
                             "Obstacle threshold of each layer (m^2), as calibrated at init.")
      .def_property_readonly("params", &Map::params, "The parameters the map runs with.")
      .def_property_readonly("total_counters", &Map::total_counters, "Frame counters summed over the map's life.")
      .def_property_readonly("rejected_moves", &Map::rejected_moves)
      .def_property_readonly("rejected_frames", &Map::rejected_frames)
      .def_property_readonly("last_update_ns", &Map::last_update_ns, "Duration of the last accepted update (ns).")
      .def("set_params", &Map::set_params,
           "Change the running parameters by keyword (the Map() keywords, cell_width included), keeping\n"
           "every cell. Refused (StatusError, the map unchanged): parameters Map() would refuse, or\n"
           "changes that need a new map (the message names them: the cell width; a noise model or\n"
           "finest_max_sigma_m that changes which layer a range goes to).")
      .def("reset_counters", &Map::reset_counters,
           "Zero the counters health() counts since a reset; cells, parameters and map_sequence stay.")
      .def("health", &Map::health,
           "The map's health as a dict with ccmap_health's fields (docs/icd.md): initialised, state (the\n"
           "state check run now), frames_accepted/refused, moves_refused, points_*, corrupted_cells/slots,\n"
           "params_changes, last_frame_ns/points/used, params_crc, map_sequence, fault_count, layers (per\n"
           "layer: cell_width_m, centre_index_x/y, centre_x/y_m, observed_cells, normal_variance_threshold).")
      .def("product", &Map::product, py::arg("layer") = 0, py::arg("answer") = "stack", py::arg("pose") = py::none(),
           py::arg("tag") = 0U,
           "The map product of one layer's window as bytes (the format ccmap_publish writes; read it with\n"
           "ccmap.decode_product). answer: 'stack' (each cell: the map's answer at its centre) or 'layer'\n"
           "(that layer's own); pose (x, y, z, yaw) and tag are echoed into the header.")
      .def("__repr__", &Map::repr);
}
