#include "ccmap/core/status.hpp"

namespace ccmap {

const char* to_string(Status status) noexcept {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kNonFiniteInput: return "non_finite_input";
    case Status::kOutOfRange: return "out_of_range";
    case Status::kBadWeight: return "bad_weight";
    case Status::kOutsideMap: return "outside_map";
    case Status::kUnknown: return "unknown";
    case Status::kInvalidArgument: return "invalid_argument";
    case Status::kBufferTooSmall: return "buffer_too_small";
    case Status::kNotInitialised: return "not_initialised";
    case Status::kCorrupt: return "corrupt";
    case Status::kVersionMismatch: return "version_mismatch";
    case Status::kDuplicate: return "duplicate";
    case Status::kMisaligned: return "misaligned";
    case Status::kInsufficientOverlap: return "insufficient_overlap";
    case Status::kDegenerateInput: return "degenerate_input";
    case Status::kNotConverged: return "not_converged";
    case Status::kBusy: return "busy";
  }
  return "invalid_status";
}

}  // namespace ccmap
