// libFuzzer target for the host point-cloud readers (tools/io/cloud_reader.hpp), one binary per
// format: CCMAP_FUZZ_READER = 1 (PLY), 2 (LAS), 3 (text). The bytes go through an exact-size
// copy so that ASan sees any read past the buffer. Invariants (a violation aborts), from the
// readers' robustness contract:
//  - an error gives an empty cloud with a message, never a partial cloud;
//  - a cloud has x, y, z of equal length, w of the same length iff has_weight, finite points;
//  - every declared point is either returned or counted as skipped (non-finite).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "cloud_reader.hpp"

#ifndef CCMAP_FUZZ_READER
#error "define CCMAP_FUZZ_READER (1 PLY, 2 LAS, 3 text)"
#endif

namespace {
[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "ccmap cloud fuzz: invariant violated: %s\n", what);
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> copy(data, data + size);
  static const std::uint8_t kNothing = 0;
  const std::uint8_t* p = copy.empty() ? &kNothing : copy.data();
#if CCMAP_FUZZ_READER == 1
  const ccmap::tools::Cloud cloud = ccmap::tools::read_ply(p, copy.size());
#elif CCMAP_FUZZ_READER == 2
  const ccmap::tools::Cloud cloud = ccmap::tools::read_las(p, copy.size());
#else
  const ccmap::tools::Cloud cloud = ccmap::tools::read_text(p, copy.size());
#endif
  if (!cloud.ok()) {
    if (cloud.size() != 0U || !cloud.y.empty() || !cloud.z.empty() || !cloud.w.empty()) {
      fail("an error returned a partial cloud");
    }
    return 0;
  }
  if (cloud.y.size() != cloud.x.size() || cloud.z.size() != cloud.x.size()) fail("x, y, z lengths differ");
  if (cloud.has_weight ? cloud.w.size() != cloud.x.size() : !cloud.w.empty()) fail("weights do not match points");
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!std::isfinite(cloud.x[i]) || !std::isfinite(cloud.y[i]) || !std::isfinite(cloud.z[i])) {
      fail("a non-finite point was returned");
    }
  }
  if (static_cast<std::uint64_t>(cloud.size()) + cloud.skipped_non_finite != cloud.declared) {
    fail("returned + skipped points differ from the declared count");
  }
  return 0;
}
