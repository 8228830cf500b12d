// The product double buffer under a writer and a reader thread, with no map: the writer
// publishes products whose every byte is a function of their sequence number (sizes vary, so
// slots are reused at other lengths), the reader copies as fast as it can and checks each copy
// against that function, independently of the CRC and the sequence lock. A torn or stale copy
// accepted as whole, or a false CCMAP_CORRUPT, fails the run.
//
// Plain main, no GoogleTest: the same file is built once more with -fsanitize=thread
// (tests/capi/CMakeLists.txt, ccmap_product_tsan), which checks that the exchange has no data
// race in the C++ memory model. Argument: reads (default 2,000,000).
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

#include "ccmap/product/product_buffers.hpp"
#include "ccmap/product/product_format.hpp"

namespace {

/// Side of the product with sequence s: 2 .. 5 cells, so consecutive products differ in length.
std::uint16_t side_of(std::uint32_t s) { return static_cast<std::uint16_t>(2U + s % 4U); }

ccmap::ProductCell cell_of(std::uint32_t s, std::uint32_t i) {
  ccmap::ProductCell c{};
  c.cell_class = static_cast<std::uint8_t>((s + i) % 5U);
  c.cost = static_cast<std::uint8_t>((s * 7U + i) & 0xFFU);
  c.status = static_cast<std::uint8_t>(i % 3U);
  c.layer = static_cast<std::uint8_t>(s & 0xFFU);
  c.height_m = static_cast<float>(s % 10007U) * 0.001F + static_cast<float>(i);
  c.inclination = static_cast<float>(i) * 0.5F;
  return c;
}

void compose(std::uint8_t* out, std::uint32_t s) {
  const std::uint16_t side = side_of(s);
  ccmap::ProductHeader h{};
  h.total_bytes = ccmap::product_size(side, side);
  h.product_sequence = s;
  h.map_sequence = s * 3U;
  h.side_x = side;
  h.side_y = side;
  h.tag = ~s;
  h.pose_x = static_cast<float>(s % 1000U);
  ccmap::encode_product_header(h, out);
  for (std::uint32_t i = 0; i < std::uint32_t{side} * side; ++i) {
    ccmap::encode_product_cell(cell_of(s, i), out, i);
  }
  ccmap::product_detail::put_u32(out + h.total_bytes - 4U, ccmap::product_crc32(out, h.total_bytes - 4U));
}

/// True if `copy` is exactly the product compose() wrote for its sequence number.
bool exact(const std::uint8_t* copy, std::size_t size, std::uint32_t* sequence) {
  ccmap::ProductHeader h{};
  if (ccmap::decode_product_header(copy, size, &h) != ccmap::Status::kOk) {
    return false;
  }
  std::vector<std::uint8_t> expected(size);
  compose(expected.data(), h.product_sequence);
  *sequence = h.product_sequence;
  return std::memcmp(expected.data(), copy, size) == 0 && h.map_sequence == 3U * h.product_sequence &&
         size == ccmap::product_size(side_of(h.product_sequence), side_of(h.product_sequence));
}

}  // namespace

int main(int argc, char** argv) {
  const unsigned long reads = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 2000000UL;
  static std::uint32_t storage[3U * ccmap::product_size(5U, 5U) / 4U];
  ccmap::ProductBuffers buffers{};
  if (ccmap::product_buffers_init(&buffers, storage, sizeof storage) != ccmap::Status::kOk) {
    std::puts("product_stress: buffers refused");
    return 1;
  }
  std::atomic<bool> done{false};
  std::atomic<std::uint32_t> published{0U};
  unsigned long ok = 0, busy = 0, corrupt = 0, wrong = 0, backwards = 0, before_first = 0;
  std::thread reader([&] {
    std::uint8_t copy[ccmap::product_size(5U, 5U)];
    std::uint32_t last = 0U;
    for (unsigned long r = 0; r < reads;) {
      std::size_t written = 0U;
      const ccmap::Status status = ccmap::product_read(buffers, copy, sizeof copy, &written);
      if (status == ccmap::Status::kOk) {
        std::uint32_t sequence = 0U;
        if (!exact(copy, written, &sequence)) {
          ++wrong;
        } else if (sequence < last) {
          ++backwards;
        } else {
          last = sequence;
          ++ok;
        }
      } else if (status == ccmap::Status::kBusy) {
        ++busy;
      } else if (status == ccmap::Status::kNotInitialised) {
        ++before_first;
        std::this_thread::yield();
        continue;  // reads count from the first product on
      } else {
        ++corrupt;
      }
      ++r;
    }
    done.store(true);
  });
  std::uint32_t s = 0U;
  while (!done.load()) {
    ++s;
    if (ccmap::product_next_sequence(buffers) != s) {
      std::puts("product_stress: writer sequence off");
      return 1;
    }
    std::uint8_t* staging = ccmap::product_staging(buffers);
    compose(staging, s);
    if (ccmap::product_commit(buffers, ccmap::product_size(side_of(s), side_of(s))) != ccmap::Status::kOk) {
      std::puts("product_stress: commit refused");
      return 1;
    }
    published.store(s);
    if (s % 8U == 0U) {
      std::this_thread::yield();  // the reader's core may be shared: let it run
    }
  }
  reader.join();
  std::printf("product_stress: %lu reads: %lu whole, %lu busy, %lu before the first product; %u products "
              "published; %lu torn or wrong, %lu out of order, %lu corrupt\n",
              reads, ok, busy, before_first, published.load(), wrong, backwards, corrupt);
  const unsigned long enough = reads / 100U < 1000U ? reads / 100U : 1000U;
  return (wrong == 0 && backwards == 0 && corrupt == 0 && ok >= enough) ? 0 : 1;
}
