// The instruction classes of the QEMU instruction-count plugin (tools/qemu-icount/a64_class.c)
// against an independent decoder: binutils' aarch64 disassembler. reference_class() below
// derives the class from the mnemonic and operand shapes objdump prints (rules written from the
// Arm ARM's instruction names, not from encodings), so a wrong bit field in a64_class.c shows
// as a disagreement. Corpora: fixed random samples of SIMD&FP words and of all words, and
// every instruction of the aarch64 C, math, C++ and gcc runtime libraries. Unallocated words
// (objdump: .inst/udf) and SVE/SME (armv8-a code has none) are left out.
#include <gtest/gtest.h>

#include <array>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../../tools/qemu-icount/a64_class.h"
#include "../../tools/qemu-icount/icount_marker_encoding.h"

namespace {

const std::string kObjdump = CCMAP_AARCH64_OBJDUMP;   // empty when not found at configure time
const std::string kTargetLibDir = CCMAP_AARCH64_LIB_DIR;

enum class Ref { kSkip, kOther, kLdst, kFp, kSimdInt, kSimdFp };

const char* name_of(Ref r) {
  switch (r) {
    case Ref::kSkip:
      return "skip";
    case Ref::kOther:
      return "other";
    case Ref::kLdst:
      return "ldst";
    case Ref::kFp:
      return "fp";
    case Ref::kSimdInt:
      return "simd_int";
    case Ref::kSimdFp:
      return "simd_fp";
  }
  return "?";
}

Ref from_plugin(enum a64_class c) {
  switch (c) {
    case A64_CLASS_LDST:
      return Ref::kLdst;
    case A64_CLASS_FP:
      return Ref::kFp;
    case A64_CLASS_SIMD_INT:
      return Ref::kSimdInt;
    case A64_CLASS_SIMD_FP:
      return Ref::kSimdFp;
    default:
      return Ref::kOther;
  }
}

struct Insn {
  std::uint32_t word;
  std::string mnemonic;
  std::string operands;
};

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// A register number: 0 .. 31, at most two digits, from position `from` to the end.
bool register_number(const std::string& s, std::size_t from) {
  if (from >= s.size() || s.size() - from > 2U) {
    return false;
  }
  for (std::size_t i = from; i < s.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(s[i])) == 0) {
      return false;
    }
  }
  return std::stoi(s.substr(from)) <= 31;
}

bool all_digits(const std::string& s, std::size_t from) {
  if (from >= s.size()) {
    return false;
  }
  for (std::size_t i = from; i < s.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(s[i])) == 0) {
      return false;
    }
  }
  return true;
}

// Register-like tokens of an operand string: maximal runs of [a-z0-9._] (system register
// names such as s3_0_c4_c2_2 stay one token).
std::vector<std::string> tokens_of(const std::string& operands) {
  std::vector<std::string> out;
  std::string cur;
  for (const char c : operands) {
    if (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '_') {
      cur += c;
    } else if (!cur.empty()) {
      out.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) {
    out.push_back(cur);
  }
  return out;
}

// The class of one disassembled instruction, from its mnemonic and operands only.
Ref reference_class(const std::string& mnemonic, const std::string& operands) {
  if (mnemonic.empty() || mnemonic[0] == '.' || mnemonic == "udf") {
    return Ref::kSkip;  // unallocated
  }
  // Branches and PC-relative addresses: general registers only; their label operand is a
  // hexadecimal address that could read like a register name (b10, d20).
  if (mnemonic == "b" || mnemonic == "bl" || mnemonic == "cbz" || mnemonic == "cbnz" || mnemonic == "tbz" ||
      mnemonic == "tbnz" || mnemonic == "adr" || mnemonic == "adrp" || starts_with(mnemonic, "b.") ||
      starts_with(mnemonic, "bc.")) {
    return Ref::kOther;
  }
  bool vector_arrangement = false;  // v0.4s, v1.2d, v2.16b, v3.1q
  bool vector_element = false;      // v2.s (in v2.s[1])
  bool fp_register = false;         // b0 h0 s0 d0 q0
  bool general_register = false;    // w0 x0 wzr xzr sp wsp
  for (const std::string& t : tokens_of(operands)) {
    if (starts_with(t, "za") || starts_with(t, "zt") || ((t[0] == 'z' || t[0] == 'p') && all_digits(t.substr(0, t.find('.')), 1)) ||
        (starts_with(t, "pn") && all_digits(t.substr(0, t.find('.')), 2))) {
      return Ref::kSkip;  // SVE / SME
    }
    const std::size_t dot = t.find('.');
    if (t[0] == 'v' && dot != std::string::npos && all_digits(t.substr(0, dot), 1)) {
      (std::isdigit(static_cast<unsigned char>(t[dot + 1])) != 0 ? vector_arrangement : vector_element) = true;
    } else if (std::string("bhsdq").find(t[0]) != std::string::npos && register_number(t, 1)) {
      fp_register = true;
    } else if (((t[0] == 'w' || t[0] == 'x') && (register_number(t, 1) || t.substr(1) == "zr")) || t == "sp" ||
               t == "wsp") {
      general_register = true;
    }
  }
  // Loads and stores, including prefetch, atomics and the FEAT_MOPS copy/set instructions
  // (SETF8/SETF16 are flag manipulation).
  if (starts_with(mnemonic, "ld") || starts_with(mnemonic, "st") || starts_with(mnemonic, "prf") ||
      starts_with(mnemonic, "cas") || starts_with(mnemonic, "swp") || starts_with(mnemonic, "cpy") ||
      (starts_with(mnemonic, "set") && !starts_with(mnemonic, "setf"))) {
    return Ref::kLdst;
  }
  if (!vector_arrangement && !vector_element && !fp_register) {
    return Ref::kOther;  // no SIMD&FP register
  }
  // The scalar floating-point instructions (Arm ARM: "Floating-point" data processing, the
  // conversions between floating-point and integer or fixed-point). Their names also exist in
  // Advanced SIMD, with a vector arrangement, an indexed element, or (conversions) without a
  // general register: those are SIMD.
  static const char* const kScalarFp[] = {
      "fabs",    "fadd",     "fccmp",    "fccmpe",   "fcmp",     "fcmpe",  "fcsel",  "fcvt",   "fdiv",
      "fmadd",   "fmax",     "fmaxnm",   "fmin",     "fminnm",   "fmov",   "fmsub",  "fmul",   "fneg",
      "fnmadd",  "fnmsub",   "fnmul",    "fsqrt",    "fsub",     "frinta", "frinti", "frintm", "frintn",
      "frintp",  "frintx",   "frintz",   "frint32x", "frint32z", "frint64x", "frint64z", "bfcvt", "fjcvtzs"};
  static const char* const kConversions[] = {"scvtf",  "ucvtf",  "fcvtas", "fcvtau", "fcvtms", "fcvtmu", "fcvtns",
                                             "fcvtnu", "fcvtps", "fcvtpu", "fcvtzs", "fcvtzu"};
  bool scalar_fp = false;
  for (const char* m : kScalarFp) {
    if (mnemonic == m && !vector_arrangement && (!vector_element || (mnemonic == "fmov" && general_register))) {
      scalar_fp = true;
    }
  }
  for (const char* m : kConversions) {
    if (mnemonic == m && general_register && !vector_arrangement) {
      scalar_fp = true;
    }
  }
  if (scalar_fp) {
    return Ref::kFp;
  }
  // Advanced SIMD: floating point when the operation is (F*, [SU]CVTF, BF16 instructions).
  if (mnemonic[0] == 'f' || mnemonic == "scvtf" || mnemonic == "ucvtf" || starts_with(mnemonic, "bf")) {
    return Ref::kSimdFp;
  }
  return Ref::kSimdInt;
}

// Runs objdump with the given arguments and parses "addr:\tWORD \tmnemonic\toperands".
bool disassemble(const std::string& args, std::vector<Insn>* out) {
  const std::string cmd = kObjdump + " " + args + " 2>/dev/null";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  if (!pipe) {
    return false;
  }
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe.get()) != nullptr) {
    std::string line(buf.data());
    if (!line.empty() && line.back() == '\n') {
      line.pop_back();
    }
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, '\t')) {
      fields.push_back(f);
    }
    if (fields.size() < 3 || fields[0].empty() || fields[0].back() != ':') {
      continue;
    }
    std::string hex = fields[1];
    while (!hex.empty() && hex.back() == ' ') {
      hex.pop_back();
    }
    if (hex.size() != 8 || hex.find_first_not_of("0123456789abcdef") != std::string::npos) {
      continue;
    }
    Insn insn{static_cast<std::uint32_t>(std::stoul(hex, nullptr, 16)), fields[2], fields.size() > 3 ? fields[3] : ""};
    const std::size_t cut = insn.operands.find_first_of("</");  // symbol names, // comments
    if (cut != std::string::npos) {
      insn.operands.resize(cut);
    }
    out->push_back(insn);
  }
  return pclose(pipe.release()) == 0;
}

struct Agreement {
  std::array<std::size_t, 6> per_class{};  // instructions compared, by reference class
  std::size_t compared = 0;
  std::size_t mismatches = 0;
  std::string examples;
};

std::size_t& count_of(Agreement& a, Ref r) { return a.per_class[static_cast<std::size_t>(r)]; }
std::size_t count_of(const Agreement& a, Ref r) { return a.per_class[static_cast<std::size_t>(r)]; }

void print_agreement(const std::string& corpus, const Agreement& a) {
  std::printf("[ icount ] %s: %zu instructions compared (other %zu, ldst %zu, fp %zu, simd_int %zu, simd_fp %zu), "
              "%zu disagree\n",
              corpus.c_str(), a.compared, count_of(a, Ref::kOther), count_of(a, Ref::kLdst), count_of(a, Ref::kFp),
              count_of(a, Ref::kSimdInt), count_of(a, Ref::kSimdFp), a.mismatches);
}

Agreement compare(const std::vector<Insn>& insns) {
  Agreement a;
  std::map<std::string, int> shown;  // at most 3 examples per (mnemonic, classes)
  for (const Insn& insn : insns) {
    const Ref want = reference_class(insn.mnemonic, insn.operands);
    if (want == Ref::kSkip) {
      continue;
    }
    ++a.compared;
    ++count_of(a, want);
    const Ref got = from_plugin(a64_classify(insn.word));
    if (got != want) {
      ++a.mismatches;
      const std::string key = insn.mnemonic + name_of(got) + name_of(want);
      if (++shown[key] <= 3 && a.examples.size() < 6000) {
        char line[256];
        std::snprintf(line, sizeof line, "\n  %08x %-10s %-40s a64_class: %-8s binutils: %s", insn.word,
                      insn.mnemonic.c_str(), insn.operands.c_str(), name_of(got), name_of(want));
        a.examples += line;
      }
    }
  }
  return a;
}

// Deterministic sample: xorshift64, `count` words with `set_bits` forced on.
std::string write_random_words(const std::string& name, std::size_t count, std::uint32_t set_bits) {
  const std::string path = testing::TempDir() + name;
  std::ofstream f(path, std::ios::binary);
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  for (std::size_t i = 0; i < count; ++i) {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    const auto w = static_cast<std::uint32_t>(state >> 32) | set_bits;
    const char bytes[4] = {static_cast<char>(w & 0xFFU), static_cast<char>((w >> 8) & 0xFFU),
                           static_cast<char>((w >> 16) & 0xFFU), static_cast<char>(w >> 24)};
    f.write(bytes, 4);  // little-endian, as A64 code
  }
  return path;
}

#define CCMAP_REQUIRE_OBJDUMP()                                                                      \
  do {                                                                                               \
    if (kObjdump.empty()) {                                                                          \
      GTEST_SKIP() << "aarch64-linux-gnu-objdump not found (apt-get install binutils-aarch64-linux-gnu)"; \
    }                                                                                                \
  } while (false)

TEST(IcountClassify, MarkersDecodeTheirKindAndRegionId) {
  for (const std::uint32_t id : {0U, 1U, 2U, 4097U, 65535U}) {
    std::uint32_t got = 123456U;
    EXPECT_EQ(a64_marker(CCMAP_ICOUNT_MARKER_BEGIN | (id << 5), &got), 1) << "begin marker of region " << id;
    EXPECT_EQ(got, id);
    got = 123456U;
    EXPECT_EQ(a64_marker(CCMAP_ICOUNT_MARKER_END | (id << 5), &got), 2) << "end marker of region " << id;
    EXPECT_EQ(got, id);
  }
  std::uint32_t unused = 0;
  EXPECT_EQ(a64_marker(0xD2C0001FU, &unused), 0) << "MOVZ XZR, LSL #32 is not a marker";
  EXPECT_EQ(a64_marker(0xD280003EU, &unused), 0) << "MOVZ X30, #1 is not a marker";
  EXPECT_EQ(a64_marker(0x5280003FU, &unused), 0) << "MOVZ WZR, #1 is not a marker";
  EXPECT_EQ(a64_marker(0xD503201FU, &unused), 0) << "NOP is not a marker";
}

// Readable examples (encodings from GNU as 2.40, -march=armv8.2-a+crypto).
TEST(IcountClassify, ExamplesOfEachClass) {
  struct Case {
    std::uint32_t word;
    const char* text;
    enum a64_class want;
  };
  const Case cases[] = {
      {0x1E222820U, "fadd s0, s1, s2", A64_CLASS_FP},
      {0x1F420C20U, "fmadd d0, d1, d2, d3", A64_CLASS_FP},
      {0x1E380020U, "fcvtzs w0, s1", A64_CLASS_FP},
      {0x9E620020U, "scvtf d0, x1", A64_CLASS_FP},
      {0x9E660020U, "fmov x0, d1", A64_CLASS_FP},
      {0x4E22D420U, "fadd v0.4s, v1.4s, v2.4s", A64_CLASS_SIMD_FP},
      {0x4FA21020U, "fmla v0.4s, v1.4s, v2.s[1]", A64_CLASS_SIMD_FP},
      {0x5EA0C820U, "fcmgt s0, s1, #0.0", A64_CLASS_SIMD_FP},
      {0x5E21D820U, "scvtf s0, s1", A64_CLASS_SIMD_FP},
      {0x7E30D820U, "faddp s0, v1.2s", A64_CLASS_SIMD_FP},
      {0x4F03F600U, "fmov v0.4s, #1.0", A64_CLASS_SIMD_FP},
      {0x4EA28420U, "add v0.4s, v1.4s, v2.4s", A64_CLASS_SIMD_INT},
      {0x0E0C3C20U, "umov w0, v1.s[1]", A64_CLASS_SIMD_INT},
      {0x6F00E400U, "movi v0.2d, #0", A64_CLASS_SIMD_INT},
      {0x4EA09820U, "cmeq v0.4s, v1.4s, #0", A64_CLASS_SIMD_INT},
      {0x4E284820U, "aese v0.16b, v1.16b", A64_CLASS_SIMD_INT},
      {0xB9400020U, "ldr w0, [x1]", A64_CLASS_LDST},
      {0x3DC00420U, "ldr q0, [x1, #16]", A64_CLASS_LDST},
      {0x4C407800U, "ld1 {v0.4s}, [x0]", A64_CLASS_LDST},
      {0xA9BF7BFDU, "stp x29, x30, [sp, #-16]!", A64_CLASS_LDST},
      {0xF9800000U, "prfm pldl1keep, [x0]", A64_CLASS_LDST},
      {0xB8200041U, "ldadd w0, w1, [x2]", A64_CLASS_LDST},
      {0x8B020020U, "add x0, x1, x2", A64_CLASS_OTHER},
      {0x9B020C20U, "madd x0, x1, x2, x3", A64_CLASS_OTHER},
      {0x54000001U, "b.ne .", A64_CLASS_OTHER},
      {0xD65F03C0U, "ret", A64_CLASS_OTHER},
      {0xD53B4400U, "mrs x0, fpcr", A64_CLASS_OTHER},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(a64_classify(c.word), c.want) << c.text;
  }
}

// Disassembles `count` random words with `set_bits` forced on and compares; false when objdump
// fails.
bool random_sample_agreement(const std::string& name, std::size_t count, std::uint32_t set_bits, Agreement* a) {
  const std::string path = write_random_words(name + ".bin", count, set_bits);
  std::vector<Insn> insns;
  if (!disassemble("-D -b binary -m aarch64 " + path, &insns)) {
    return false;
  }
  *a = compare(insns);
  print_agreement(name, *a);
  return true;
}

TEST(IcountClassify, AgreesWithBinutilsOnRandomSimdAndFpWords) {
  CCMAP_REQUIRE_OBJDUMP();
  // op0 = x111 forced: the SIMD&FP encoding space, where the split into classes is subtle.
  Agreement a;
  ASSERT_TRUE(random_sample_agreement("icount_random_simd_fp_words", 1000000, 0x0E000000U, &a)) << kObjdump << " failed";
  EXPECT_GT(count_of(a, Ref::kFp), 1000U) << "too few scalar FP words in the sample to mean anything";
  EXPECT_GT(count_of(a, Ref::kSimdFp), 1000U) << "too few SIMD FP words in the sample";
  EXPECT_GT(count_of(a, Ref::kSimdInt), 1000U) << "too few SIMD integer words in the sample";
  EXPECT_EQ(a.mismatches, 0U) << a.mismatches << " of " << a.compared << " allocated SIMD&FP words classified "
                              << "differently from binutils:" << a.examples;
}

TEST(IcountClassify, AgreesWithBinutilsOnRandomWords) {
  CCMAP_REQUIRE_OBJDUMP();
  Agreement a;
  ASSERT_TRUE(random_sample_agreement("icount_random_words", 200000, 0U, &a)) << kObjdump << " failed";
  EXPECT_GT(count_of(a, Ref::kLdst), 1000U) << "too few loads/stores in the sample";
  EXPECT_GT(count_of(a, Ref::kOther), 1000U) << "too few other instructions in the sample";
  EXPECT_EQ(a.mismatches, 0U) << a.mismatches << " of " << a.compared << " allocated words classified "
                              << "differently from binutils:" << a.examples;
}

// The aarch64 libraries every counted program links, disassembled once for the tests below.
struct TargetLibrary {
  std::string path;
  std::vector<Insn> insns;
};

// Empty, with *why set, when the libraries or objdump are missing or fail.
const std::vector<TargetLibrary>& target_libraries(std::string* why) {
  static std::vector<TargetLibrary> libraries;
  static std::string failure;
  static bool loaded = false;
  if (!loaded) {
    loaded = true;
    for (const char* lib : {"libc.so.6", "libm.so.6", "libstdc++.so.6", "libgcc_s.so.1"}) {
      TargetLibrary l{kTargetLibDir + "/" + lib, {}};
      if (!std::ifstream(l.path).good()) {
        failure = l.path + " not found (apt-get install g++-aarch64-linux-gnu)";
      } else if (!disassemble("-d " + l.path, &l.insns) || l.insns.size() < 1000U) {
        failure = kObjdump + " -d " + l.path + " failed";
      }
      if (!failure.empty()) {
        libraries.clear();
        break;
      }
      libraries.push_back(std::move(l));
    }
  }
  *why = failure;
  return libraries;
}

// Declares `name`, the disassembled libraries, or skips the test saying why.
#define CCMAP_REQUIRE_TARGET_LIBRARIES(name)                                   \
  std::string why_##name;                                                      \
  const std::vector<TargetLibrary>& name = target_libraries(&why_##name);      \
  if ((name).empty()) {                                                        \
    GTEST_SKIP() << why_##name;                                                \
  }

TEST(IcountClassify, AgreesWithBinutilsOnTheAarch64SystemLibraries) {
  CCMAP_REQUIRE_OBJDUMP();
  CCMAP_REQUIRE_TARGET_LIBRARIES(libraries);
  for (const TargetLibrary& lib : libraries) {
    const Agreement a = compare(lib.insns);
    print_agreement(lib.path, a);
    EXPECT_EQ(a.mismatches, 0U) << lib.path << ": " << a.mismatches << " of " << a.compared
                                << " instructions classified differently from binutils:" << a.examples;
  }
}

// The marker encodings never occur in compiled code (icount_marker_encoding.h): none in the
// system libraries.
TEST(IcountClassify, NoMarkerInTheAarch64SystemLibraries) {
  CCMAP_REQUIRE_OBJDUMP();
  CCMAP_REQUIRE_TARGET_LIBRARIES(libraries);
  for (const TargetLibrary& lib : libraries) {
    std::size_t markers = 0;
    for (const Insn& insn : lib.insns) {
      std::uint32_t id = 0;
      markers += a64_marker(insn.word, &id) != 0 ? 1U : 0U;
    }
    EXPECT_EQ(markers, 0U) << lib.path << " contains icount marker encodings (MOVZ XZR, #imm, LSL #0/#16)";
  }
}

}  // namespace
