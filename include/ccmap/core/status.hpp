// Status codes returned by every ccmap operation that can refuse its input.
//
// The core never throws and never crashes on bad input: it answers with a Status, counts the
// event (see the owning object's counters) and leaves its state unchanged.
#pragma once

#include <cstdint>

// Every refusal of NaN and Inf (kNonFiniteInput) is a comparison or std::isfinite, which
// -ffinite-math-only (implied by -ffast-math) folds to "finite"; -ffast-math also reorders sums,
// so host and target results would differ. Most of the core is templates compiled in the
// consumer's translation units: refuse to compile them so (tested in tests/core/CMakeLists.txt).
#if (defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__) || defined(__FAST_MATH__)
#error "ccmap needs IEEE float semantics: compile its headers without -ffast-math / -ffinite-math-only"
#endif

namespace ccmap {

enum class Status : std::uint8_t {
  kOk = 0,
  kNonFiniteInput,     ///< NaN or Inf in a coordinate, pose or parameter
  kOutOfRange,         ///< finite but beyond the documented range (|coordinate| > kMaxAbsCoordinateM)
  kBadWeight,          ///< weight <= 0, NaN, Inf or above kMaxMeasurementWeight
  kOutsideMap,         ///< position not covered by the layer or stack
  kUnknown,            ///< cell not observed (or not adequately covered) for a query
  kInvalidArgument,    ///< null pointer, inconsistent sizes, bad configuration
  kBufferTooSmall,     ///< caller's buffer cannot hold the result
  kNotInitialised,     ///< object used before a successful init()
  kCorrupt,            ///< serialized data failed its integrity check, or the map's own state did
                       ///< (a single-event upset: Stack::state_status)
  kVersionMismatch,    ///< serialized data written by an incompatible version
  kDuplicate,          ///< map exchange: data already merged (same sender and sequence), or this map's own
  kMisaligned,         ///< map exchange: the grids disagree (cell width, or an origin offset that is not a
                       ///< whole number of the coarsest layer's cells)
  kInsufficientOverlap,  ///< registration: too few samples on known cells of the map
  kDegenerateInput,      ///< registration: no usable points, or all of them at one spot
  kNotConverged,         ///< registration: no solution within the iteration or search bounds
  kBusy,                 ///< product read: the writer replaced the product during every try (read again)
};

/// Short, stable, lower-case name of a status ("ok", "non_finite_input", ...). Never nullptr.
[[nodiscard]] const char* to_string(Status status) noexcept;

[[nodiscard]] constexpr bool ok(Status status) noexcept { return status == Status::kOk; }

}  // namespace ccmap
