// Host I/O of the tools: point-cloud readers (PLY, LAS, text), poses, layer CSV, pictures.
#include <gtest/gtest.h>
#include <gtest/gtest-spi.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "layer_images.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using ccmap::tools::Cloud;

namespace {

using TempDir = ccmap::test::TempDir;
const char* const kTempPrefix = "ccmap_io_test_";

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

template <typename T>
void put(std::vector<std::uint8_t>& b, T v) {
  std::uint8_t raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  b.insert(b.end(), raw, raw + sizeof(T));  // host (x86-64/aarch64) is little endian
}
template <typename T>
void put_be(std::vector<std::uint8_t>& b, T v) {
  std::uint8_t raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  for (std::size_t i = sizeof(T); i > 0; --i) b.push_back(raw[i - 1]);
}
template <typename T>
void poke(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}
std::vector<std::uint8_t> bytes_of(const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); }

/// Reads a prefix of `bytes` through an exact-size heap copy (so ASan sees any over-read).
Cloud read_prefix(const std::vector<std::uint8_t>& bytes, std::size_t n, const std::string& name) {
  std::vector<std::uint8_t> copy(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
  static const std::uint8_t kNothing = 0;
  return ccmap::tools::read_cloud_buffer(copy.empty() ? &kNothing : copy.data(), copy.size(), name);
}

struct Pt {
  double x, y, z, w;
};
const std::vector<Pt> kPoints = {
    {1.5, -2.25, 0.125, 1.0}, {515386.625, 4918368.375, 2235.0625, 2.5}, {-0.1, 0.2, -0.3, 0.75}, {0.0, 0.0, 0.0, 1.0}};

// --- PLY builders -----------------------------------------------------------------------------

std::string ply_ascii() {
  std::string s =
      "ply\nformat ascii 1.0\ncomment made by ccmap tests\nelement vertex 4\nproperty float nx\n"
      "property double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty float weight\n"
      "property list uchar int extra\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  char line[256];
  for (const Pt& p : kPoints) {
    std::snprintf(line, sizeof line, "0.5 %.17g %.17g %.17g 200 %.17g 2 7 8\n", p.x, p.y, p.z, p.w);
    s += line;
  }
  s += "3 0 1 2\n";
  return s;
}

/// Binary PLY: an element before the vertices (with a list), vertices with double x/y/z between
/// other properties of several sizes, and faces after them.
std::vector<std::uint8_t> ply_binary(bool big_endian) {
  const std::string header = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                             " 1.0\nelement camera 2\nproperty short id\nproperty list uchar float params\n"
                             "element vertex 4\nproperty uchar flags\nproperty double x\nproperty short label\n"
                             "property double y\nproperty double z\nproperty float weight\nproperty uint extra\n"
                             "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::vector<std::uint8_t> b = bytes_of(header);
  auto p16 = [&](std::int16_t v) { big_endian ? put_be(b, v) : put(b, v); };
  auto pf = [&](float v) { big_endian ? put_be(b, v) : put(b, v); };
  auto pd = [&](double v) { big_endian ? put_be(b, v) : put(b, v); };
  auto pu = [&](std::uint32_t v) { big_endian ? put_be(b, v) : put(b, v); };
  for (int c = 0; c < 2; ++c) {  // camera: id, list of c+1 floats
    p16(static_cast<std::int16_t>(c));
    b.push_back(static_cast<std::uint8_t>(c + 1));
    for (int k = 0; k <= c; ++k) pf(1.0F);
  }
  for (const Pt& p : kPoints) {
    b.push_back(7);
    pd(p.x);
    p16(-3);
    pd(p.y);
    pd(p.z);
    pf(static_cast<float>(p.w));
    pu(0xDEADBEEFU);
  }
  b.push_back(3);
  for (int k = 0; k < 3; ++k) pu(static_cast<std::uint32_t>(k));
  return b;
}

void expect_points(const Cloud& c, bool weights, bool float_weights = false) {
  ASSERT_TRUE(c.ok()) << c.error;
  ASSERT_EQ(c.size(), kPoints.size());
  ASSERT_EQ(c.has_weight, weights);
  for (std::size_t i = 0; i < kPoints.size(); ++i) {
    EXPECT_EQ(c.x[i], kPoints[i].x) << "point " << i;
    EXPECT_EQ(c.y[i], kPoints[i].y) << "point " << i;
    EXPECT_EQ(c.z[i], kPoints[i].z) << "point " << i;
    if (weights) {
      const double w = float_weights ? static_cast<double>(static_cast<float>(kPoints[i].w)) : kPoints[i].w;
      EXPECT_EQ(c.w[i], w) << "point " << i;
    }
  }
}

// --- LAS builder ------------------------------------------------------------------------------

struct LasSpec {
  int minor = 2;
  int format = 1;
  int record_length = 28;
  std::size_t vlr_bytes = 60;
  bool legacy_count = true;   // LAS 1.4: also fill the legacy 32-bit count
  double scale[3] = {0.00025, 0.00025, 0.001};
  double offset[3] = {515000.0, 4918000.0, 2000.0};
};
const std::int32_t kLasInts[4][3] = {{0, 0, 0}, {1546500, 1473500, 235062}, {-4, 7, -1}, {2147483647, -2147483647 - 1, 5}};

std::vector<std::uint8_t> make_las(const LasSpec& s) {
  const std::size_t header = s.minor >= 4 ? 375 : (s.minor == 3 ? 235 : 227);
  std::vector<std::uint8_t> b(header, 0);
  std::memcpy(b.data(), "LASF", 4);
  b[24] = 1;
  b[25] = static_cast<std::uint8_t>(s.minor);
  poke<std::uint16_t>(b, 94, static_cast<std::uint16_t>(header));
  poke<std::uint32_t>(b, 96, static_cast<std::uint32_t>(header + s.vlr_bytes));
  poke<std::uint32_t>(b, 100, s.vlr_bytes > 0 ? 1U : 0U);
  b[104] = static_cast<std::uint8_t>(s.format);
  poke<std::uint16_t>(b, 105, static_cast<std::uint16_t>(s.record_length));
  if (s.minor < 4 || s.legacy_count) poke<std::uint32_t>(b, 107, 4U);
  for (int i = 0; i < 3; ++i) {
    poke<double>(b, 131 + 8 * static_cast<std::size_t>(i), s.scale[i]);
    poke<double>(b, 155 + 8 * static_cast<std::size_t>(i), s.offset[i]);
  }
  if (s.minor >= 4) poke<std::uint64_t>(b, 247, 4U);
  b.resize(b.size() + s.vlr_bytes, 0xAB);
  for (const auto& p : kLasInts) {
    const std::size_t at = b.size();
    b.resize(at + static_cast<std::size_t>(s.record_length), 0x5A);  // filler must be skipped
    for (int k = 0; k < 3; ++k) poke<std::int32_t>(b, at + 4U * static_cast<std::size_t>(k), p[k]);
  }
  return b;
}

void expect_las_points(const Cloud& c, const LasSpec& s) {
  ASSERT_TRUE(c.ok()) << c.error;
  ASSERT_EQ(c.size(), 4U);
  EXPECT_FALSE(c.has_weight);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(c.x[i], static_cast<double>(kLasInts[i][0]) * s.scale[0] + s.offset[0]);
    EXPECT_EQ(c.y[i], static_cast<double>(kLasInts[i][1]) * s.scale[1] + s.offset[1]);
    EXPECT_EQ(c.z[i], static_cast<double>(kLasInts[i][2]) * s.scale[2] + s.offset[2]);
  }
  EXPECT_DOUBLE_EQ(c.x[1], 515386.625);
  EXPECT_DOUBLE_EQ(c.y[1], 4918368.375);
  EXPECT_DOUBLE_EQ(c.z[1], 2235.062);
}

}  // namespace

// =============================================================================================
// PLY
// =============================================================================================

TEST(IoReaderPly, AsciiWithExtraPropertiesListsAndFaces) {
  const TempDir dir(kTempPrefix);
  const fs::path path = dir / "cloud.ply";
  write_text(path, ply_ascii());
  const Cloud c = ccmap::tools::read_cloud(path.string());
  expect_points(c, true);
  EXPECT_EQ(c.format, "PLY ascii");
  EXPECT_EQ(c.declared, 4U);
}

TEST(IoReaderPly, AsciiWithCrLfLineEnds) {
  std::string s = ply_ascii();
  std::string crlf;
  for (char ch : s) {
    if (ch == '\n') crlf += '\r';
    crlf += ch;
  }
  const std::vector<std::uint8_t> b = bytes_of(crlf);
  expect_points(ccmap::tools::read_ply(b.data(), b.size()), true);
}

TEST(IoReaderPly, BinaryLittleEndianDoubleCoordinatesSkipsOtherProperties) {
  const TempDir dir(kTempPrefix);
  const fs::path path = dir / "cloud.ply";
  write_bytes(path, ply_binary(false));
  const Cloud c = ccmap::tools::read_cloud(path.string());
  expect_points(c, true, /*float_weights=*/true);
  EXPECT_EQ(c.format, "PLY binary_little_endian");
}

TEST(IoReaderPly, BinaryBigEndian) {
  const std::vector<std::uint8_t> b = ply_binary(true);
  expect_points(ccmap::tools::read_ply(b.data(), b.size()), true, true);
}

TEST(IoReaderPly, BinaryFloatCoordinatesWithoutWeight) {
  std::vector<std::uint8_t> b = bytes_of(
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar intensity\nend_header\n");
  const float v[2][3] = {{1.25F, -3.5F, 0.0625F}, {100.1F, 200.2F, 300.3F}};
  for (const auto& p : v) {
    for (float f : p) put(b, f);
    b.push_back(255);
  }
  const Cloud c = ccmap::tools::read_ply(b.data(), b.size());
  ASSERT_TRUE(c.ok()) << c.error;
  ASSERT_EQ(c.size(), 2U);
  EXPECT_FALSE(c.has_weight);
  EXPECT_TRUE(c.w.empty());
  EXPECT_EQ(c.x[1], static_cast<double>(100.1F));
  EXPECT_EQ(c.z[1], static_cast<double>(300.3F));
  EXPECT_EQ(c.y[0], -3.5);
}

TEST(IoReaderPly, NonFinitePointsAreSkippedAndCounted) {
  std::vector<std::uint8_t> b = bytes_of(
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n");
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float v[4][3] = {{1, 2, 3}, {nan, 0, 0}, {0, -inf, 0}, {4, 5, 6}};
  for (const auto& p : v) {
    for (float f : p) put(b, f);
  }
  const Cloud c = ccmap::tools::read_ply(b.data(), b.size());
  ASSERT_TRUE(c.ok()) << c.error;
  EXPECT_EQ(c.size(), 2U);
  EXPECT_EQ(c.declared, 4U);
  EXPECT_EQ(c.skipped_non_finite, 2U);
  EXPECT_EQ(c.x[1], 4.0);

  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "end_header\n1 2 3\nnan 1 1\n1 inf 1\n";
  const std::vector<std::uint8_t> a = bytes_of(ascii);
  const Cloud ca = ccmap::tools::read_ply(a.data(), a.size());
  ASSERT_TRUE(ca.ok()) << ca.error;
  EXPECT_EQ(ca.size(), 1U);
  EXPECT_EQ(ca.skipped_non_finite, 2U);
}

TEST(IoReaderPly, TruncatedAtEveryByteGivesErrorOrTheCompleteCloud) {
  // Cutting inside the trailing face element leaves every vertex intact (faces are ignored);
  // any other cut must be reported, never returned as a shorter or different cloud.
  for (const bool ascii : {true, false}) {
    const std::vector<std::uint8_t> full = ascii ? bytes_of(ply_ascii()) : ply_binary(false);
    std::size_t complete = 0;
    for (std::size_t n = 0; n < full.size(); ++n) {
      const Cloud c = read_prefix(full, n, "cut.ply");
      if (c.ok()) {
        ++complete;
        ASSERT_EQ(c.size(), kPoints.size()) << (ascii ? "ascii" : "binary") << " cut at " << n;
        for (std::size_t i = 0; i < kPoints.size(); ++i) {
          ASSERT_EQ(c.x[i], kPoints[i].x) << "cut at " << n;
          ASSERT_EQ(c.z[i], kPoints[i].z) << "cut at " << n;
        }
      } else {
        ASSERT_FALSE(c.error.empty());
        ASSERT_EQ(c.error.find('\n'), std::string::npos) << "error must be one line";
        ASSERT_EQ(c.size(), 0U);
      }
    }
    EXPECT_LE(complete, ascii ? 8U : 13U) << "only cuts inside the face data may succeed";
  }
}

TEST(IoReaderPly, HostileHeadersAreRefusedWithoutHugeAllocations) {
  const std::vector<std::string> bad = {
      "ply\nformat binary_little_endian 1.0\nelement vertex 1152921504606846976\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n",
      "ply\nformat ascii 1.0\nelement vertex 1152921504606846976\nproperty double x\nproperty double y\n"
      "property double z\nend_header\n1 2 3\n",
      "ply\nformat binary_little_endian 1.0\nelement junk 99999999999\nproperty list uint double v\n"
      "element vertex 1\nproperty double x\nproperty double y\nproperty double z\nend_header\n\xff\xff\xff\xff",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nend_header\n1 2\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\n"
      "end_header\n1 2\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\n"
      "end_header\n1 2 3 4\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\n"
      "end_header\n1 zwei 3\n",
      "ply\nformat ascii 2.0\nelement vertex 0\nend_header\n",
      "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
      "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty list float int x\nend_header\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n",
      "ply\nelement vertex 0\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
      "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\n"
      "end_header\n1 2 3",  // last line cut (maybe inside a number)
      "PLY\n",
  };
  for (const std::string& s : bad) {
    const std::vector<std::uint8_t> b = bytes_of(s);
    const Cloud c = ccmap::tools::read_cloud_buffer(b.data(), b.size(), "x.ply");
    EXPECT_FALSE(c.ok()) << "accepted: " << s;
    EXPECT_EQ(c.size(), 0U);
    EXPECT_LT(c.x.capacity(), 1000U);
  }
}

TEST(IoReaderPly, ZeroVerticesIsAnEmptyCloudNotAnError) {
  const std::vector<std::uint8_t> b = bytes_of(
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n");
  const Cloud c = ccmap::tools::read_ply(b.data(), b.size());
  EXPECT_TRUE(c.ok()) << c.error;
  EXPECT_EQ(c.size(), 0U);
}

// =============================================================================================
// LAS
// =============================================================================================

TEST(IoReaderLas, Las12Format1WithVlrAndPaddedRecords) {
  LasSpec s;
  s.record_length = 32;  // 28 + 4 extra bytes per record
  const TempDir dir(kTempPrefix);
  const fs::path path = dir / "scan.las";
  write_bytes(path, make_las(s));
  const Cloud c = ccmap::tools::read_cloud(path.string());
  expect_las_points(c, s);
  EXPECT_EQ(c.format, "LAS 1.2 format 1");
}

TEST(IoReaderLas, Las14Format3With64BitCountOnly) {
  LasSpec s;
  s.minor = 4;
  s.format = 3;
  s.record_length = 34;
  s.legacy_count = false;
  const std::vector<std::uint8_t> b = make_las(s);
  const Cloud c = ccmap::tools::read_las(b.data(), b.size());
  expect_las_points(c, s);
  EXPECT_EQ(c.format, "LAS 1.4 format 3");
  EXPECT_EQ(c.declared, 4U);
}

TEST(IoReaderLas, Las14WithBothCountsAndFormats0To3) {
  for (int format = 0; format <= 3; ++format) {
    LasSpec s;
    s.minor = format == 0 ? 0 : (format == 1 ? 1 : (format == 2 ? 3 : 4));
    s.format = format;
    s.record_length = format == 0 ? 20 : (format == 1 ? 28 : (format == 2 ? 26 : 34));
    s.vlr_bytes = 0;
    const std::vector<std::uint8_t> b = make_las(s);
    expect_las_points(ccmap::tools::read_las(b.data(), b.size()), s);
  }
}

TEST(IoReaderLas, TruncatedAtEveryByteIsAnError) {
  for (const int minor : {2, 4}) {
    LasSpec s;
    s.minor = minor;
    s.format = minor == 4 ? 3 : 1;
    s.record_length = minor == 4 ? 34 : 28;
    const std::vector<std::uint8_t> full = make_las(s);
    ASSERT_TRUE(read_prefix(full, full.size(), "a.las").ok());
    for (std::size_t n = 0; n < full.size(); ++n) {
      const Cloud c = read_prefix(full, n, "a.las");
      ASSERT_FALSE(c.ok()) << "LAS 1." << minor << " cut at " << n << " accepted";
      ASSERT_EQ(c.size(), 0U);
      ASSERT_EQ(c.error.find('\n'), std::string::npos);
    }
  }
}

TEST(IoReaderLas, HostileHeadersAreRefused) {
  LasSpec s;
  const std::vector<std::uint8_t> good = make_las(s);
  auto refused = [](std::vector<std::uint8_t> b, const char* what) {
    const Cloud c = ccmap::tools::read_las(b.data(), b.size());
    EXPECT_FALSE(c.ok()) << what;
    EXPECT_LT(c.x.capacity(), 1000U) << what;
  };
  { auto b = good; poke<std::uint32_t>(b, 107, 0xFFFFFFFFU); refused(b, "huge count"); }
  { auto b = good; poke<std::uint16_t>(b, 105, 12); refused(b, "record shorter than the format"); }
  { auto b = good; poke<std::uint16_t>(b, 94, 100); refused(b, "header size below 227"); }
  { auto b = good; poke<std::uint16_t>(b, 94, 60000); refused(b, "header size beyond the file"); }
  { auto b = good; poke<std::uint32_t>(b, 96, 0xFFFFFFF0U); refused(b, "point offset beyond the file"); }
  { auto b = good; poke<std::uint32_t>(b, 96, 100); refused(b, "point offset inside the header"); }
  { auto b = good; b[104] = 0x81; refused(b, "LAZ compressed"); }
  { auto b = good; b[104] = 11; refused(b, "unknown format"); }
  { auto b = good; b[25] = 5; refused(b, "LAS 1.5"); }
  { auto b = good; poke<double>(b, 131, 0.0); refused(b, "zero scale"); }
  { auto b = good; poke<double>(b, 163, std::numeric_limits<double>::quiet_NaN()); refused(b, "NaN offset"); }
  LasSpec s14;
  s14.minor = 4;
  s14.format = 3;
  s14.record_length = 34;
  { auto b = make_las(s14); poke<std::uint64_t>(b, 247, 5U); refused(b, "inconsistent 1.4 counts"); }
  { auto b = make_las(s14); poke<std::uint64_t>(b, 247, ~0ULL); poke<std::uint32_t>(b, 107, 0U); refused(b, "huge 64-bit count"); }
}

TEST(IoReaderLas, ExtremeScaleGivesNonFinitePointsThatAreCounted) {
  LasSpec s;
  s.scale[0] = 1e308;
  const std::vector<std::uint8_t> b = make_las(s);
  const Cloud c = ccmap::tools::read_las(b.data(), b.size());
  ASSERT_TRUE(c.ok()) << c.error;
  EXPECT_EQ(c.skipped_non_finite, 3U);  // every non-zero X times 1e308 overflows
  EXPECT_EQ(c.size(), 1U);
}

// =============================================================================================
// Text
// =============================================================================================

TEST(IoReaderText, CommentsBlankLinesSeparatorsAndWeights) {
  const TempDir dir(kTempPrefix);
  const fs::path path = dir / "cloud.xyz";
  write_text(path,
             "# x y z w\n\n1.5 -2.25 0.125 1\r\n515386.625,4918368.375,2235.0625,2.5  # trailing comment\n"
             "\t-0.1  0.2\t-0.3 0.75\n0 0 0 1");
  const Cloud c = ccmap::tools::read_cloud(path.string());
  expect_points(c, true);
  EXPECT_EQ(c.format, "text");
}

TEST(IoReaderText, NonFiniteCountedAndMalformedLinesReported) {
  const std::vector<std::uint8_t> ok = bytes_of("1 2 3\nnan 1 1\n1 -inf 2\n1e999 0 0\n4 5 6\n");
  const Cloud c = ccmap::tools::read_text(ok.data(), ok.size());
  ASSERT_TRUE(c.ok()) << c.error;
  EXPECT_EQ(c.size(), 2U);
  EXPECT_EQ(c.skipped_non_finite, 3U);
  EXPECT_EQ(c.declared, 5U);

  const std::vector<std::string> bad = {"1 2 3\n1 2\n", "1 2 3\n4 5 6 7\n", "1 2 3 4 5 6\n", "1 2 x\n",
                                        "1 2 3\n1 2 3abc\n", std::string("1 2 3\n\0\x01\x02", 9)};
  for (const std::string& s : bad) {
    const std::vector<std::uint8_t> b = bytes_of(s);
    const Cloud e = ccmap::tools::read_text(b.data(), b.size());
    EXPECT_FALSE(e.ok()) << "accepted: " << s;
    EXPECT_EQ(e.error.find('\n'), std::string::npos);
  }
  const std::vector<std::uint8_t> b = bytes_of("1 2 3\n\n1 2 x\n");
  EXPECT_NE(ccmap::tools::read_text(b.data(), b.size()).error.find("line 3"), std::string::npos);
}

TEST(IoReaderText, EmptyFileIsAnEmptyCloud) {
  const std::vector<std::uint8_t> b = bytes_of("# nothing\n\n");
  const Cloud c = ccmap::tools::read_text(b.data(), b.size());
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.size(), 0U);
}

// =============================================================================================
// Dispatch and files
// =============================================================================================

TEST(IoReaderFiles, FormatDetectionAndFileErrors) {
  const TempDir dir(kTempPrefix);
  // PLY content behind a .txt name is read as PLY (magic wins).
  write_text(dir / "really_ply.txt", ply_ascii());
  expect_points(ccmap::tools::read_cloud((dir / "really_ply.txt").string()), true);
  // A .ply/.las name without the magic is an error, not text.
  write_text(dir / "fake.ply", "1 2 3\n");
  write_text(dir / "fake.las", "1 2 3\n");
  write_text(dir / "scan.laz", "LASF");
  for (const char* name : {"fake.ply", "fake.las", "scan.laz", "missing.xyz"}) {
    const Cloud c = ccmap::tools::read_cloud((dir / name).string());
    EXPECT_FALSE(c.ok()) << name;
    EXPECT_NE(c.error.find(name), std::string::npos) << "error names the file: " << c.error;
  }
  EXPECT_FALSE(ccmap::tools::read_cloud(dir.path().string()).ok()) << "a directory is not a cloud";
  write_text(dir / "empty.las", "");
  EXPECT_FALSE(ccmap::tools::read_cloud((dir / "empty.las").string()).ok());
}

TEST(IoReaderFiles, Poses) {
  const TempDir dir(kTempPrefix);
  write_text(dir / "poses.txt", "# x y z yaw\n515386.5 4918368.25 2236 0.5\n\n1 2 3 -1.5\n");
  std::vector<ccmap::tools::Pose> poses;
  std::string error;
  ASSERT_TRUE(ccmap::tools::read_poses((dir / "poses.txt").string(), &poses, &error)) << error;
  ASSERT_EQ(poses.size(), 2U);
  EXPECT_EQ(poses[0].x, 515386.5);
  EXPECT_EQ(poses[0].y, 4918368.25);
  EXPECT_EQ(poses[1].yaw, -1.5);
  write_text(dir / "bad.txt", "1 2 3\n");
  EXPECT_FALSE(ccmap::tools::read_poses((dir / "bad.txt").string(), &poses, &error));
  write_text(dir / "nan.txt", "1 2 nan 0\n");
  EXPECT_FALSE(ccmap::tools::read_poses((dir / "nan.txt").string(), &poses, &error));
  EXPECT_FALSE(ccmap::tools::read_poses((dir / "none.txt").string(), &poses, &error));
}

// =============================================================================================
// CSV and pictures
// =============================================================================================

TEST(IoLayerCsv, HeaderAndRoundTripKeepUtmDigits) {
  const TempDir dir(kTempPrefix);
  const fs::path path = dir / "layer_0.csv";
  ccmap::tools::LayerCellRow r;
  r.layer = 2;
  r.ix = 3221166;
  r.iy = -30739803;
  r.cx = 515386.68;
  r.cy = 4918368.44;
  r.res = 0.16;
  r.weight = 37;
  r.height = 2235.1234;
  r.slope_x = 0.125;
  r.slope_y = -0.0625;
  r.normal_var = 1.5e-5;
  r.elev_var = 2.5e-6;
  r.cell_class = "steep";
  std::string error;
  ASSERT_TRUE(ccmap::tools::write_layer_csv(path.string(), {r, r}, &error)) << error;
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "layer,ix,iy,cx,cy,res,weight,height,slope_x,slope_y,normal_var,elev_var,class");
  std::vector<ccmap::tools::LayerCellRow> rows;
  ASSERT_TRUE(ccmap::tools::read_layer_csv(path.string(), &rows, &error)) << error;
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0].ix, r.ix);
  EXPECT_EQ(rows[0].iy, r.iy);
  EXPECT_NEAR(rows[0].cx, r.cx, 1e-6);
  EXPECT_NEAR(rows[0].cy, r.cy, 1e-6);
  EXPECT_NEAR(rows[0].height, r.height, 1e-6);
  EXPECT_EQ(rows[0].slope_y, r.slope_y);
  EXPECT_EQ(rows[0].normal_var, r.normal_var);
  EXPECT_EQ(rows[0].cell_class, "steep");
  EXPECT_FALSE(ccmap::tools::write_layer_csv("/nonexistent_dir/x.csv", {}, &error));
}

TEST(IoLayerImages, ClassColoursNorthUpUnobservedBlackAndScaledUp) {
  std::vector<ccmap::tools::LayerCellRow> rows(2);
  rows[0].ix = 10; rows[0].iy = 20; rows[0].res = 0.1; rows[0].cell_class = "obstacle"; rows[0].weight = 5;
  rows[1].ix = 11; rows[1].iy = 21; rows[1].res = 0.1; rows[1].cell_class = "traversable"; rows[1].weight = 5;
  rows[1].height = 1.0;
  ccmap::tools::RgbImage images[4];
  std::string error;
  ASSERT_TRUE(ccmap::tools::render_layer_images(rows, ccmap::tools::LayerWindow{10, 20, 4, 4}, images, &error));
  const ccmap::tools::RgbImage& cls = images[3];
  ASSERT_GE(cls.width, 512);
  ASSERT_EQ(cls.width, cls.height);
  const int s = cls.width / 4;
  auto px = [&](int gx, int gy, int ch) {  // centre pixel of cell (gx, gy), y up
    const int x = gx * s + s / 2, y = (3 - gy) * s + s / 2;
    return cls.rgb[3U * (static_cast<std::size_t>(y) * static_cast<std::size_t>(cls.width) + static_cast<std::size_t>(x)) + static_cast<std::size_t>(ch)];
  };
  EXPECT_EQ(px(0, 0, 0), 220);  // obstacle red, bottom left
  EXPECT_EQ(px(1, 1, 1), 170);  // traversable green above and right of it
  EXPECT_EQ(px(3, 3, 0) + px(3, 3, 1) + px(3, 3, 2), 0);  // unobserved black
  std::uint8_t c[3];
  ccmap::tools::class_colour("unknown", c);
  EXPECT_EQ(c[0], 128);
  ccmap::tools::class_colour("steep", c);
  EXPECT_EQ(c[0], 255);
  EXPECT_EQ(c[1], 150);
  const TempDir dir(kTempPrefix);
  const fs::path prefix = dir / "layer_0";
  ASSERT_TRUE(ccmap::tools::write_layer_images(prefix.string(), rows, ccmap::tools::LayerWindow{}, &error)) << error;
  for (const char* suffix : {"_height.png", "_slope.png", "_normal_var.png", "_class.png"}) {
    EXPECT_GT(fs::file_size(prefix.string() + suffix), 50U) << suffix;
  }
}

// =============================================================================================
// The tests' temporary directories (tests/tools/temp_dir.hpp)
// =============================================================================================

namespace {
fs::path g_failed_test_dir;  // EXPECT_FATAL_FAILURE's statement may only use statics
void fail_inside_a_temp_dir() {
  const TempDir dir(kTempPrefix);
  g_failed_test_dir = dir.path();
  write_text(dir / "a", "x");
  fs::create_directories(dir / "sub" / "deeper");
  write_text(dir / "sub" / "deeper" / "b", "y");
  ASSERT_TRUE(false) << "forced failure inside a TempDir";
}
}  // namespace

TEST(TestTempDir, RemovedWithItsContentAlsoWhenTheTestFails) {
  fs::path kept;
  {
    const TempDir dir(kTempPrefix);
    kept = dir.path();
    ASSERT_TRUE(fs::is_directory(kept));
    EXPECT_EQ(kept.parent_path(), fs::temp_directory_path());
    EXPECT_EQ(kept.filename().string().rfind(kTempPrefix, 0), 0U) << kept;
    write_text(dir / "file", "z");
    const TempDir other(kTempPrefix);
    EXPECT_NE(other.path(), kept) << "two directories with one prefix must not collide";
  }
  EXPECT_FALSE(fs::exists(kept)) << "a TempDir must be removed when it goes out of scope";
  EXPECT_FATAL_FAILURE(fail_inside_a_temp_dir(), "forced failure inside a TempDir");
  ASSERT_FALSE(g_failed_test_dir.empty());
  EXPECT_FALSE(fs::exists(g_failed_test_dir)) << "a failed ASSERT must still remove the directory and its files";
}
