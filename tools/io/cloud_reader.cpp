#include "cloud_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sys/stat.h>

namespace ccmap::tools {
namespace {

// ---------------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------------

std::string lower_extension(const std::string& name) {
  const std::size_t slash = name.find_last_of('/');
  const std::size_t dot = name.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = name.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Parses the whole of [b, e) as a double (strtod syntax, so "nan" and "inf" are accepted and
/// reported as such). False if the token is empty, too long or has trailing characters.
bool parse_double(const char* b, const char* e, double* out) {
  const std::size_t n = static_cast<std::size_t>(e - b);
  if (n == 0 || n >= 96) return false;
  char buf[96];
  std::memcpy(buf, b, n);
  buf[n] = '\0';
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(buf, &end);
  if (end != buf + n) return false;
  // ERANGE on overflow gives +-HUGE_VAL = Inf, which the caller counts as non-finite.
  *out = v;
  return true;
}

/// Parses an unsigned decimal integer (digits only, at most 19 of them).
bool parse_u64(const std::string& s, std::uint64_t* out) {
  if (s.empty() || s.size() > 19) return false;
  std::uint64_t v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10U + static_cast<std::uint64_t>(c - '0');
  }
  *out = v;
  return true;
}

/// Splits [b, e) into tokens separated by whitespace (and, for text clouds, commas/semicolons).
void tokenize(const char* b, const char* e, bool commas, std::vector<std::pair<const char*, const char*>>* tokens) {
  tokens->clear();
  const char* p = b;
  while (p < e) {
    while (p < e && (is_space(*p) || (commas && (*p == ',' || *p == ';')))) ++p;
    if (p >= e) break;
    const char* start = p;
    while (p < e && !is_space(*p) && !(commas && (*p == ',' || *p == ';'))) ++p;
    tokens->emplace_back(start, p);
  }
}

/// Line cursor over a buffer: returns [b, e) of the next line without its '\n' (a trailing
/// '\r' stays; tokenize() treats it as space).
struct LineCursor {
  const char* p;
  const char* end;
  bool next(const char** b, const char** e) {
    if (p >= end) return false;
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    *b = p;
    *e = nl != nullptr ? nl : end;
    p = nl != nullptr ? nl + 1 : end;
    return true;
  }
};

void push_point(Cloud* cloud, double x, double y, double z, double w) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    ++cloud->skipped_non_finite;
    return;
  }
  cloud->x.push_back(x);
  cloud->y.push_back(y);
  cloud->z.push_back(z);
  if (cloud->has_weight) cloud->w.push_back(w);
}

void reserve_points(Cloud* cloud, std::uint64_t n) {
  const std::size_t r = static_cast<std::size_t>(n);
  cloud->x.reserve(r);
  cloud->y.reserve(r);
  cloud->z.reserve(r);
  if (cloud->has_weight) cloud->w.reserve(r);
}

Cloud fail(Cloud cloud, const std::string& message) {
  cloud.x.clear();
  cloud.y.clear();
  cloud.z.clear();
  cloud.w.clear();
  cloud.x.shrink_to_fit();
  cloud.y.shrink_to_fit();
  cloud.z.shrink_to_fit();
  cloud.w.shrink_to_fit();
  cloud.error = message;
  return cloud;
}

std::uint16_t le_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t le_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t le_u64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le_u32(p)) | (static_cast<std::uint64_t>(le_u32(p + 4)) << 32);
}
std::int32_t le_i32(const std::uint8_t* p) {
  const std::uint32_t u = le_u32(p);
  std::int32_t v;
  std::memcpy(&v, &u, sizeof v);
  return v;
}
double le_f64(const std::uint8_t* p) {
  const std::uint64_t u = le_u64(p);
  double v;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------

enum class PlyType : std::uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool ply_type_from_name(const std::string& name, PlyType* type) {
  struct Entry {
    const char* name;
    PlyType type;
  };
  static const Entry kTypes[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},   {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16}, {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const Entry& e : kTypes) {
    if (name == e.name) {
      *type = e.type;
      return true;
    }
  }
  return false;
}

std::size_t ply_type_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8: return 1;
    case PlyType::kInt16:
    case PlyType::kUint16: return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 1;
}

/// Reads one binary value; the caller has checked that ply_type_size(t) bytes are available.
double ply_read_binary(const std::uint8_t* p, PlyType t, bool big_endian) {
  std::uint8_t b[8];
  const std::size_t n = ply_type_size(t);
  for (std::size_t i = 0; i < n; ++i) b[i] = big_endian ? p[n - 1 - i] : p[i];
  switch (t) {
    case PlyType::kInt8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
    case PlyType::kUint8: return b[0];
    case PlyType::kInt16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::kUint16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case PlyType::kInt32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case PlyType::kUint32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case PlyType::kFloat32: { float v; std::memcpy(&v, b, 4); return static_cast<double>(v); }
    case PlyType::kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0.0;
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::kFloat32;        // scalar type, or list item type
  PlyType count_type = PlyType::kUint8;    // list count type
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyEncoding : std::uint8_t { kAscii, kBinaryLe, kBinaryBe };

/// Binary: skips (or, for the vertex element, decodes) one element instance starting at *pos.
/// `slots` maps property index -> 0..3 (x, y, z, weight) or -1. False if the data ends early
/// or a list count is negative / not an integer.
bool ply_binary_instance(const std::uint8_t* data, std::size_t size, std::size_t* pos, const PlyElement& el,
                         bool big_endian, const std::vector<int>& slots, double values[4]) {
  for (std::size_t i = 0; i < el.properties.size(); ++i) {
    const PlyProperty& prop = el.properties[i];
    if (prop.is_list) {
      const std::size_t cs = ply_type_size(prop.count_type);
      if (size - *pos < cs) return false;
      const double count = ply_read_binary(data + *pos, prop.count_type, big_endian);
      *pos += cs;
      if (!(count >= 0.0) || count != std::floor(count)) return false;
      const std::size_t item = ply_type_size(prop.type);
      if (count > static_cast<double>((size - *pos) / item)) return false;
      *pos += static_cast<std::size_t>(count) * item;
    } else {
      const std::size_t s = ply_type_size(prop.type);
      if (size - *pos < s) return false;
      if (!slots.empty() && slots[i] >= 0) values[slots[i]] = ply_read_binary(data + *pos, prop.type, big_endian);
      *pos += s;
    }
  }
  return true;
}

/// ASCII: parses one element instance from the tokens of one line. False if the tokens do
/// not match the declared properties.
bool ply_ascii_instance(const std::vector<std::pair<const char*, const char*>>& tokens, const PlyElement& el,
                        const std::vector<int>& slots, double values[4]) {
  std::size_t t = 0;
  for (std::size_t i = 0; i < el.properties.size(); ++i) {
    const PlyProperty& prop = el.properties[i];
    if (t >= tokens.size()) return false;
    double v = 0.0;
    if (!parse_double(tokens[t].first, tokens[t].second, &v)) return false;
    ++t;
    if (prop.is_list) {
      if (!(v >= 0.0) || v != std::floor(v) || v > static_cast<double>(tokens.size() - t)) return false;
      t += static_cast<std::size_t>(v);
    } else if (!slots.empty() && slots[i] >= 0) {
      values[slots[i]] = v;
    }
  }
  return t == tokens.size();
}

}  // namespace

Cloud read_ply(const std::uint8_t* data, std::size_t size) {
  Cloud cloud;
  cloud.format = "PLY";
  const char* text = reinterpret_cast<const char*>(data);
  if (size < 4 || std::memcmp(text, "ply", 3) != 0 || (text[3] != '\n' && text[3] != '\r')) {
    return fail(cloud, "not a PLY file (missing 'ply' magic line)");
  }
  // Header: lines up to "end_header".
  LineCursor lines{text, text + size};
  const char* b = nullptr;
  const char* e = nullptr;
  std::vector<std::pair<const char*, const char*>> tok;
  bool have_format = false, have_end = false;
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  int line_no = 0;
  lines.next(&b, &e);  // "ply"
  ++line_no;
  while (lines.next(&b, &e)) {
    ++line_no;
    if (line_no > 100000) return fail(cloud, "PLY header too long (no end_header)");
    tokenize(b, e, false, &tok);
    if (tok.empty()) continue;
    const std::string key(tok[0].first, tok[0].second);
    auto word = [&tok](std::size_t i) { return std::string(tok[i].first, tok[i].second); };
    const std::string where = "PLY header line " + std::to_string(line_no) + ": ";
    if (key == "end_header") {
      if (tok.size() != 1) return fail(cloud, where + "junk after end_header");
      have_end = true;
      break;
    }
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      if (tok.size() != 3) return fail(cloud, where + "expected 'format <encoding> 1.0'");
      const std::string enc = word(1);
      if (enc == "ascii") encoding = PlyEncoding::kAscii;
      else if (enc == "binary_little_endian") encoding = PlyEncoding::kBinaryLe;
      else if (enc == "binary_big_endian") encoding = PlyEncoding::kBinaryBe;
      else return fail(cloud, where + "unknown format '" + enc + "'");
      if (word(2) != "1.0") return fail(cloud, where + "unsupported PLY version '" + word(2) + "'");
      have_format = true;
    } else if (key == "element") {
      PlyElement el;
      if (tok.size() != 3 || !parse_u64(word(2), &el.count)) {
        return fail(cloud, where + "expected 'element <name> <count>'");
      }
      el.name = word(1);
      elements.push_back(el);
    } else if (key == "property") {
      if (elements.empty()) return fail(cloud, where + "property before any element");
      PlyProperty prop;
      if (tok.size() == 5 && word(1) == "list") {
        prop.is_list = true;
        if (!ply_type_from_name(word(2), &prop.count_type) || !ply_type_from_name(word(3), &prop.type)) {
          return fail(cloud, where + "unknown list type");
        }
        if (prop.count_type == PlyType::kFloat32 || prop.count_type == PlyType::kFloat64) {
          return fail(cloud, where + "list count type must be an integer type");
        }
        prop.name = word(4);
      } else if (tok.size() == 3) {
        if (!ply_type_from_name(word(1), &prop.type)) return fail(cloud, where + "unknown type '" + word(1) + "'");
        prop.name = word(2);
      } else {
        return fail(cloud, where + "expected 'property <type> <name>'");
      }
      if (elements.back().properties.size() >= 1000) return fail(cloud, where + "too many properties");
      elements.back().properties.push_back(prop);
    } else {
      return fail(cloud, where + "unknown keyword '" + key + "'");
    }
  }
  if (!have_end) return fail(cloud, "truncated PLY header (no end_header)");
  if (!have_format) return fail(cloud, "PLY header has no format line");
  static const char* kEncodingNames[] = {"ascii", "binary_little_endian", "binary_big_endian"};
  cloud.format = std::string("PLY ") + kEncodingNames[static_cast<int>(encoding)];

  // The vertex element and its x, y, z (and optional weight) properties.
  std::size_t vertex_index = elements.size();
  for (std::size_t i = 0; i < elements.size(); ++i) {
    if (elements[i].name == "vertex") {
      vertex_index = i;
      break;
    }
  }
  if (vertex_index == elements.size()) return fail(cloud, "PLY file has no 'vertex' element");
  const PlyElement& vertex = elements[vertex_index];
  std::vector<int> slots(vertex.properties.size(), -1);
  int found[4] = {-1, -1, -1, -1};
  static const char* kSlotNames[4] = {"x", "y", "z", "weight"};
  for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
    for (int s = 0; s < 4; ++s) {
      if (vertex.properties[i].name == kSlotNames[s]) {
        if (found[s] >= 0) return fail(cloud, std::string("PLY vertex property '") + kSlotNames[s] + "' declared twice");
        if (vertex.properties[i].is_list) {
          return fail(cloud, std::string("PLY vertex property '") + kSlotNames[s] + "' is a list");
        }
        found[s] = static_cast<int>(i);
        slots[i] = s;
      }
    }
  }
  for (int s = 0; s < 3; ++s) {
    if (found[s] < 0) return fail(cloud, std::string("PLY vertex element has no '") + kSlotNames[s] + "' property");
  }
  cloud.has_weight = found[3] >= 0;
  cloud.declared = vertex.count;

  const std::size_t data_start = static_cast<std::size_t>(lines.p - text);
  double values[4] = {0.0, 0.0, 0.0, 1.0};
  const std::vector<int> no_slots;
  if (encoding == PlyEncoding::kAscii) {
    LineCursor body{text + data_start, text + size};
    for (std::size_t ei = 0; ei <= vertex_index; ++ei) {
      const PlyElement& el = elements[ei];
      const bool is_vertex = ei == vertex_index;
      if (is_vertex) reserve_points(&cloud, std::min<std::uint64_t>(el.count, (size - data_start) / 6U + 1U));
      for (std::uint64_t n = 0; n < el.count; ++n) {
        // One instance per non-blank line.
        bool got = false;
        while (body.next(&b, &e)) {
          tokenize(b, e, false, &tok);
          if (!tok.empty()) {
            got = true;
            break;
          }
        }
        if (!got) {
          return fail(cloud, "truncated PLY data: element '" + el.name + "' declares " + std::to_string(el.count) +
                                 " entries, file ends after " + std::to_string(n));
        }
        if (e == text + size) {
          // No newline after this entry: the file was cut, possibly inside a number.
          return fail(cloud, "truncated PLY data: element '" + el.name + "' entry " + std::to_string(n) +
                                 " is not terminated by a newline");
        }
        values[3] = 1.0;
        if (!ply_ascii_instance(tok, el, is_vertex ? slots : no_slots, values)) {
          return fail(cloud, "malformed PLY data: element '" + el.name + "' entry " + std::to_string(n) +
                                 " does not match its properties");
        }
        if (is_vertex) push_point(&cloud, values[0], values[1], values[2], values[3]);
      }
    }
  } else {
    const bool big = encoding == PlyEncoding::kBinaryBe;
    std::size_t pos = data_start;
    for (std::size_t ei = 0; ei <= vertex_index; ++ei) {
      const PlyElement& el = elements[ei];
      const bool is_vertex = ei == vertex_index;
      if (el.properties.empty()) continue;  // zero bytes per entry, whatever the count
      bool fixed = true;
      std::size_t stride = 0;
      for (const PlyProperty& p : el.properties) {
        if (p.is_list) fixed = false;
        else stride += ply_type_size(p.type);
      }
      if (fixed && el.count > (size - pos) / stride) {
        return fail(cloud, "truncated PLY data: element '" + el.name + "' declares " + std::to_string(el.count) +
                               " entries of " + std::to_string(stride) + " bytes, only " +
                               std::to_string(size - pos) + " bytes follow the header");
      }
      if (fixed && !is_vertex) {
        pos += static_cast<std::size_t>(el.count) * stride;
        continue;
      }
      if (is_vertex) reserve_points(&cloud, std::min<std::uint64_t>(el.count, size - pos));
      for (std::uint64_t n = 0; n < el.count; ++n) {
        values[3] = 1.0;
        if (!ply_binary_instance(data, size, &pos, el, big, is_vertex ? slots : no_slots, values)) {
          return fail(cloud, "truncated or malformed PLY data: element '" + el.name + "' entry " + std::to_string(n) +
                                 " of " + std::to_string(el.count));
        }
        if (is_vertex) push_point(&cloud, values[0], values[1], values[2], values[3]);
      }
    }
  }
  return cloud;
}

// ---------------------------------------------------------------------------------------------
// LAS
// ---------------------------------------------------------------------------------------------

Cloud read_las(const std::uint8_t* data, std::size_t size) {
  Cloud cloud;
  cloud.format = "LAS";
  constexpr std::size_t kHeader12 = 227;  // LAS 1.0-1.2 public header block size
  constexpr std::size_t kHeader14 = 375;  // LAS 1.4
  if (size < 4 || std::memcmp(data, "LASF", 4) != 0) return fail(cloud, "not a LAS file (missing 'LASF' signature)");
  if (size < kHeader12) return fail(cloud, "truncated LAS header (" + std::to_string(size) + " bytes, need 227)");
  const int major = data[24], minor = data[25];
  if (major != 1 || minor > 4) {
    return fail(cloud, "unsupported LAS version " + std::to_string(major) + "." + std::to_string(minor));
  }
  const std::size_t header_size = le_u16(data + 94);
  const std::uint64_t point_offset = le_u32(data + 96);
  const int raw_format = data[104];
  const std::size_t record_length = le_u16(data + 105);
  const std::uint64_t legacy_count = le_u32(data + 107);
  const double scale[3] = {le_f64(data + 131), le_f64(data + 139), le_f64(data + 147)};
  const double offset[3] = {le_f64(data + 155), le_f64(data + 163), le_f64(data + 171)};
  cloud.format = "LAS " + std::to_string(major) + "." + std::to_string(minor) + " format " + std::to_string(raw_format & 0x3F);
  if (header_size < kHeader12 || header_size > size) {
    return fail(cloud, "bad LAS header size " + std::to_string(header_size) + " (file has " + std::to_string(size) + " bytes)");
  }
  if ((raw_format & 0xC0) != 0) {
    return fail(cloud, "compressed (LAZ) point data is not supported: decompress first (laszip, pdal translate)");
  }
  const int format = raw_format;
  static const std::size_t kMinRecord[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  if (format > 10) return fail(cloud, "unsupported LAS point data format " + std::to_string(format));
  if (record_length < kMinRecord[format]) {
    return fail(cloud, "LAS point record length " + std::to_string(record_length) + " too short for format " +
                           std::to_string(format) + " (needs " + std::to_string(kMinRecord[format]) + ")");
  }
  std::uint64_t count = legacy_count;
  if (minor >= 4) {
    if (header_size < kHeader14) return fail(cloud, "LAS 1.4 header too short (" + std::to_string(header_size) + " bytes, need 375)");
    const std::uint64_t count64 = le_u64(data + 247);
    // LAS 1.4: the 64-bit count is authoritative; the legacy field is 0 for formats 6-10 or
    // for more than 2^32-1 points and must otherwise agree.
    if (count64 != 0 || legacy_count == 0) count = count64;
    if (legacy_count != 0 && count64 != 0 && legacy_count != count64) {
      return fail(cloud, "inconsistent LAS 1.4 point counts (legacy " + std::to_string(legacy_count) + ", 64-bit " +
                             std::to_string(count64) + ")");
    }
  }
  cloud.declared = count;
  if (point_offset < header_size || point_offset > size) {
    return fail(cloud, "bad LAS offset to point data " + std::to_string(point_offset) + " (header " +
                           std::to_string(header_size) + " bytes, file " + std::to_string(size) + " bytes)");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(scale[i]) || scale[i] == 0.0 || !std::isfinite(offset[i])) {
      return fail(cloud, "bad LAS scale/offset in header (must be finite, scale non-zero)");
    }
  }
  const std::uint64_t available = size - point_offset;
  if (count > available / record_length) {
    return fail(cloud, "truncated LAS file: header declares " + std::to_string(count) + " points of " +
                           std::to_string(record_length) + " bytes, only " + std::to_string(available) +
                           " bytes of point data");
  }
  reserve_points(&cloud, count);
  const std::uint8_t* p = data + point_offset;
  for (std::uint64_t i = 0; i < count; ++i, p += record_length) {
    const double x = static_cast<double>(le_i32(p)) * scale[0] + offset[0];
    const double y = static_cast<double>(le_i32(p + 4)) * scale[1] + offset[1];
    const double z = static_cast<double>(le_i32(p + 8)) * scale[2] + offset[2];
    push_point(&cloud, x, y, z, 1.0);
  }
  return cloud;
}

// ---------------------------------------------------------------------------------------------
// Text
// ---------------------------------------------------------------------------------------------

Cloud read_text(const std::uint8_t* data, std::size_t size) {
  Cloud cloud;
  cloud.format = "text";
  const char* text = reinterpret_cast<const char*>(data);
  if (std::memchr(text, '\0', size) != nullptr) return fail(cloud, "not a text point cloud (binary data)");
  LineCursor lines{text, text + size};
  const char* b = nullptr;
  const char* e = nullptr;
  std::vector<std::pair<const char*, const char*>> tok;
  std::uint64_t line_no = 0;
  int columns = 0;  // 3 or 4, fixed by the first point line
  while (lines.next(&b, &e)) {
    ++line_no;
    const char* hash = static_cast<const char*>(std::memchr(b, '#', static_cast<std::size_t>(e - b)));
    if (hash != nullptr) e = hash;
    tokenize(b, e, true, &tok);
    if (tok.empty()) continue;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    if (tok.size() != 3 && tok.size() != 4) {
      return fail(cloud, where + "expected 'x y z [weight]', found " + std::to_string(tok.size()) + " values");
    }
    if (columns == 0) {
      columns = static_cast<int>(tok.size());
      cloud.has_weight = columns == 4;
      reserve_points(&cloud, size / 16U + 1U);
    } else if (static_cast<int>(tok.size()) != columns) {
      return fail(cloud, where + "found " + std::to_string(tok.size()) + " values, earlier lines have " +
                             std::to_string(columns));
    }
    double v[4] = {0.0, 0.0, 0.0, 1.0};
    for (std::size_t i = 0; i < tok.size(); ++i) {
      if (!parse_double(tok[i].first, tok[i].second, &v[i])) {
        return fail(cloud, where + "'" + std::string(tok[i].first, std::min<std::size_t>(40, static_cast<std::size_t>(tok[i].second - tok[i].first))) +
                               "' is not a number");
      }
    }
    ++cloud.declared;
    push_point(&cloud, v[0], v[1], v[2], v[3]);
  }
  return cloud;
}

// ---------------------------------------------------------------------------------------------
// Dispatch and files
// ---------------------------------------------------------------------------------------------

Cloud read_cloud_buffer(const std::uint8_t* data, std::size_t size, const std::string& name, CloudFormat format) {
  if (format == CloudFormat::kAuto) {
    const std::string ext = lower_extension(name);
    const bool ply_magic = size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r');
    const bool las_magic = size >= 4 && std::memcmp(data, "LASF", 4) == 0;
    if (ext == "laz") {
      Cloud c;
      return fail(c, "compressed LAZ files are not supported: decompress first (laszip, pdal translate)");
    }
    if (ply_magic) format = CloudFormat::kPly;
    else if (las_magic) format = CloudFormat::kLas;
    else if (ext == "ply") format = CloudFormat::kPly;  // reports the missing magic
    else if (ext == "las") format = CloudFormat::kLas;
    else format = CloudFormat::kText;
  }
  switch (format) {
    case CloudFormat::kPly: return read_ply(data, size);
    case CloudFormat::kLas: return read_las(data, size);
    case CloudFormat::kText:
    case CloudFormat::kAuto: break;
  }
  return read_text(data, size);
}

namespace {
bool read_file(const std::string& path, std::vector<std::uint8_t>* bytes, std::string* error) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    *error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *error = "'" + path + "' is not a regular file";
    return false;
  }
  if (static_cast<std::uint64_t>(st.st_size) > kMaxCloudFileBytes) {
    *error = "'" + path + "' is too large (" + std::to_string(st.st_size) + " bytes)";
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    *error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  bytes->resize(static_cast<std::size_t>(st.st_size));
  const std::size_t got = bytes->empty() ? 0 : std::fread(bytes->data(), 1, bytes->size(), f);
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  if (read_error || got != bytes->size()) {
    *error = "cannot read '" + path + "'";
    return false;
  }
  return true;
}
}  // namespace

Cloud read_cloud(const std::string& path, CloudFormat format) {
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (!read_file(path, &bytes, &error)) {
    Cloud c;
    c.error = error;
    return c;
  }
  static const std::uint8_t kEmpty = 0;
  Cloud cloud = read_cloud_buffer(bytes.empty() ? &kEmpty : bytes.data(), bytes.size(), path, format);
  if (!cloud.ok()) cloud.error = path + ": " + cloud.error;
  return cloud;
}

bool read_poses(const std::string& path, std::vector<Pose>* poses, std::string* error) {
  std::vector<std::uint8_t> bytes;
  if (!read_file(path, &bytes, error)) return false;
  poses->clear();
  const char* text = reinterpret_cast<const char*>(bytes.data());
  LineCursor lines{text, text + bytes.size()};
  const char* b = nullptr;
  const char* e = nullptr;
  std::vector<std::pair<const char*, const char*>> tok;
  std::uint64_t line_no = 0;
  while (lines.next(&b, &e)) {
    ++line_no;
    const char* hash = static_cast<const char*>(std::memchr(b, '#', static_cast<std::size_t>(e - b)));
    if (hash != nullptr) e = hash;
    tokenize(b, e, true, &tok);
    if (tok.empty()) continue;
    const std::string where = path + ": line " + std::to_string(line_no) + ": ";
    if (tok.size() != 4) {
      *error = where + "expected 'x y z yaw', found " + std::to_string(tok.size()) + " values";
      return false;
    }
    double v[4];
    for (int i = 0; i < 4; ++i) {
      if (!parse_double(tok[static_cast<std::size_t>(i)].first, tok[static_cast<std::size_t>(i)].second, &v[i]) ||
          !std::isfinite(v[i])) {
        *error = where + "value " + std::to_string(i + 1) + " is not a finite number";
        return false;
      }
    }
    poses->push_back(Pose{v[0], v[1], v[2], v[3]});
  }
  return true;
}

}  // namespace ccmap::tools
